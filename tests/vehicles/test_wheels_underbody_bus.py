"""Wheels, underbody and the bus's glass against published references.

- Each wheel's rim ring lies at the rim's diameter of its body type's tyre (ETRTO designation, the
  rim's diameter in inches × 25.4 mm over the tyre's outer diameter), computed here from the
  designations themselves, and the outer diameter agrees with `look.BODY_TYPES`' wheel radius.
- The shell's faces that face the ground are drawn as the black underbody, never in the paint, and
  paint, glass and underbody together are still the closed shell.
- Over each wheel the side's paint comes down to the arch, its lower edge a smooth arc a liner's depth over it
  (the bottom's corner a row of the section's points: no facet chamfers it into a jagged black patch); a van's
  and a box truck's, flat sides with a rounded bottom edge, end on a round cut-out at one height over the arch
  (the edge's radius less its first facet's sagitta), and their flat side's smooth normals over the arch are the
  flat side's own (no shading streaks).
- The shaded ground under a vehicle covers its whole footprint, inside its plan outline: the vehicle's
  extent in its own frame is the same with and without it (its box in an image leaves it out:
  tests/vehicles/test_vehicle_render.py).
- The bus: its beltline at the Citaro's 950 mm waistline over a 370 mm floor (1.32 m of 3.076 m), two
  glazed doors on the nearside only (the left for a UK-format plate), none on the offside.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from camgen.vehicles.body import (
    ARCH_GAP_M,
    LOWER_POINTS,
    PROFILES,
    RIM_RGB,
    RIM_SHARE,
    STATION_SPACING_M,
    TYRE_WIDTH_SHARE,
    UNDERBODY_RGB,
    UPPER_POINTS,
    build_vehicle,
    floor_start_x_m,
    nearside_sign,
    plan_half_width_m,
    shell,
    wheel_meshes,
)
from camgen.vehicles.look import BODY_TYPES, draw_look

TYRES = {
    "hatchback": (185, 65, 15),
    "sedan": (205, 55, 16),
    "estate": (205, 55, 16),
    "suv": (225, 65, 17),
    "pickup": (265, 65, 17),
    "van": (215, 65, 16),
    "box_truck": (215, 75, 17.5),
    "bus": (275, 70, 22.5),
}
"""ETRTO designations (section mm / aspect % R rim inches) of each body type's typical tyre."""
CLASS_OF = {"van": "truck", "box_truck": "truck", "bus": "bus"}


def _look(body: str, seed: int = 1, **pinned):
    return draw_look(seed, CLASS_OF.get(body, "car"), pinned={"body_type": body, **pinned})


@pytest.mark.parametrize("body", sorted(TYRES))
def test_rim_ring_lies_at_the_rim_diameter_of_the_tyre(body):
    section_mm, aspect_pct, rim_in = TYRES[body]
    rim_mm = 25.4 * rim_in
    outer_mm = rim_mm + 2 * section_mm * aspect_pct / 100
    assert BODY_TYPES[body].wheel_radius_m == pytest.approx(outer_mm / 2000, abs=0.002)
    look = _look(body)
    model = build_vehicle(look)
    gear = next(part for part in model.parts if part.name == "running_gear")
    rim = (gear.wheel == 0) & np.all(np.isclose(gear.colours, RIM_RGB), axis=1)
    radius = np.hypot(*gear.vertices_m[rim][:, [0, 2]].T)  # a wheel's vertices are in its own frame
    assert radius.max() == pytest.approx(look.wheel_radius_m * rim_mm / outer_mm, rel=0.01)
    # A ring, not only spokes: rim vertices all round the circle at the rim's diameter.
    outer = gear.vertices_m[rim][radius > 0.99 * radius.max()]
    angles = np.sort(np.arctan2(outer[:, 2], outer[:, 0]))
    assert np.diff(np.concatenate([angles, [angles[0] + 2 * np.pi]])).max() < np.radians(15)
    tyre, _ = wheel_meshes(look.wheel_radius_m, 0.2, RIM_SHARE[body])
    assert tyre.is_watertight


@pytest.mark.parametrize("body", sorted(PROFILES))
def test_faces_facing_the_ground_are_underbody_and_the_shell_stays_closed(body):
    look = _look(body)
    model = build_vehicle(look)
    parts = {part.name: part for part in model.parts}
    paint = parts["body_paint"]
    corners = paint.vertices_m[paint.faces]
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    assert n[:, 2].min() >= -0.5 - 1e-9  # no paint faces the ground
    gear = parts["running_gear"]
    dark = np.all(np.isclose(gear.colours, UNDERBODY_RGB), axis=1)
    # The underbody faces of the running gear, with the paint and the glass: the whole closed shell.
    under = gear.faces[dark[gear.faces].all(axis=1)]
    assert len(under) > 10
    pieces = [
        trimesh.Trimesh(paint.vertices_m, paint.faces, process=False),
        trimesh.Trimesh(parts["body_glass"].vertices_m, parts["body_glass"].faces, process=False),
        trimesh.Trimesh(gear.vertices_m, under, process=False),
    ]
    union = trimesh.util.concatenate(pieces)
    union.merge_vertices()
    _, faces, _, _ = shell(look)
    assert union.is_watertight and len(union.faces) == len(faces)


ARCH_STEP_M = {"bus": 0.07, "van": 0.002, "box_truck": 0.002}
"""The most the paint's lower edge over an arch may move between stations, m (cars' 2 cm unless named here)."""


@pytest.mark.parametrize("body", ["hatchback", "sedan", "estate", "suv", "pickup", "van", "box_truck", "bus"])
def test_the_paint_comes_down_to_each_wheel_arch_in_a_smooth_arc(body):
    """In a side view the paint's lower edge over a wheel follows the arch (radius: the wheel's and the arch's
    gap): at every station over its middle 80 % the side's lowest paint lies within 0.13 m of the arch (the black
    liner's band under it) and moves less than 2 cm (a bus's 7 cm, at the arch's ends, where its taller rows
    meet the arch's steep sides; a van's and a box truck's 2 mm: their bottom edge is one radius everywhere) from
    one station to the next, for ten looks of each body type. Measured over thirty looks: cars 0.05–0.125 m over
    the arch, steps up to 1.3 cm; the bus 0.10–0.122 m, up to 6.8 cm; vans 0.04 m and box trucks 0.025 m, steps
    under 1 mm. Before the bottom's corners were rows of their own, the cars' edge stepped by 0.10–0.12 m between
    stations and stood up to 0.19 m over the arch, the bus's stepped by 1.6 m; before their flat sides (thirty
    looks), vans' stood up to 0.21 m over it and stepped by up to 0.11 m, box trucks' up to 0.15 m and 0.10 m. A box
    truck's rear wheels run under its load floor (`Profile.rear_floor_m`), in no arch: its side's paint stays over the
    floor there."""
    for seed in range(10):
        look = _look(body, seed)
        paint = next(part for part in build_vehicle(look).parts if part.name == "body_paint")
        corners = paint.vertices_m[paint.faces]
        normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        side = corners[normal[:, 1] > 0.5 * np.linalg.norm(normal, axis=1)].reshape(-1, 3)  # the left side's paint
        r, arch_m = look.wheel_radius_m, look.wheel_radius_m + ARCH_GAP_M
        for axle_m in (look.front_axle_x_m, look.rear_axle_x_m):
            stations = np.unique(side[np.abs(side[:, 0] - axle_m) < 0.8 * arch_m, 0])
            assert len(stations) >= 8
            lowest = np.array([side[side[:, 0] == x, 2].min() for x in stations])
            floor_m = PROFILES[body].rear_floor_m
            if floor_m is not None and axle_m < floor_start_x_m(look):  # under a box truck's floor: no arch
                assert lowest.min() >= floor_m + PROFILES[body].sill_radius_m / 2, (body, seed)
                continue
            over = lowest - (r + np.sqrt(arch_m**2 - (stations - axle_m) ** 2))
            assert np.all(over > 0.0) and over.max() < 0.13, (body, seed, over.round(3))
            assert np.abs(np.diff(over)).max() < ARCH_STEP_M.get(body, 0.02), (body, seed, np.diff(over).round(3))
            radius_m = PROFILES[body].sill_radius_m
            if radius_m is not None:  # a round cut-out: the edge's first facet's lower end, 30° round the edge
                assert over == pytest.approx(radius_m * (1 - np.sin(np.radians(30))), abs=0.002), (body, seed)


@pytest.mark.parametrize("body", ["van", "box_truck"])
def test_a_flat_side_is_flat_and_shaded_flat_over_its_wheel_arches(body):
    """A van's or box truck's side under the belt is a flat panel (`Profile.sill_radius_m`): over each wheel arch
    (and a metre either side) every shell point of the left side from the belt down to the bottom edge's radius
    over the section's bottom lies on the body's half-width (short of the ends' corners in plan), and its smooth
    normal is the flat side's, +y within 0.5° (at the arch's steep ends a normal averaged with the lip's facets
    tilted up to 28° and streaked the paint over it). Before the flat sides (superellipse sections, exponent 5 or
    10, rounded over a fifth or a tenth of the half-width) those points lay up to 0.13 m inside the half-width,
    the lowest on the rounded bottom, their normals leaning up to 89° off +y."""
    for seed in range(5):
        look = _look(body, seed)
        vertices, _, normals, _ = shell(look)
        radius_m = PROFILES[body].sill_radius_m
        belt_m = PROFILES[body].belt * look.height_m
        stations = np.unique(vertices[:, 0])
        bottom = np.array([vertices[vertices[:, 0] == x, 2].min() for x in stations])
        under = np.interp(vertices[:, 0], stations, bottom)
        k = np.arange(len(vertices)) % (UPPER_POINTS + LOWER_POINTS)
        lower = (k == 0) | (k >= UPPER_POINTS)  # the lower arc's points and the +y belt point (a bonnet's top is not)
        for axle_m in (look.front_axle_x_m, look.rear_axle_x_m):
            near = np.abs(vertices[:, 0] - axle_m) < look.wheel_radius_m + ARCH_GAP_M + 1.0
            for reach_m in (-0.1, 0.1):  # clear of the ends' rounded corners in plan, the neighbouring stations too
                near &= np.isclose(plan_half_width_m(look, vertices[:, 0] + reach_m), look.width_m / 2)
            flat = near & lower & (vertices[:, 1] > 0) & (vertices[:, 2] <= belt_m + 1e-9)
            flat &= vertices[:, 2] >= under + radius_m - 1e-9
            assert flat.sum() > 40
            assert np.allclose(vertices[flat, 1], look.width_m / 2, atol=1e-6), (body, seed)
            worst = normals[flat][normals[flat, 1].argmin()]
            assert np.all(normals[flat, 1] > np.cos(np.radians(0.5))), (body, seed, worst)


@pytest.mark.parametrize("body", ["hatchback", "suv", "van", "bus"])
def test_the_shaded_ground_lies_under_the_whole_footprint(body):
    look = _look(body)
    model = build_vehicle(look)
    (shade,) = [part for part in model.parts if part.surface == "shade"]
    points = shade.vertices_m
    # On the ground, under the sill, facing up.
    assert np.all(points[:, 2] < PROFILES[body].clearance_m) and np.all(shade.normals == (0.0, 0.0, 1.0))
    # From bumper to bumper (the overhangs too), within 5 cm of either end.
    assert points[:, 0].min() < -look.length_m / 2 + 0.05 and points[:, 0].max() > look.length_m / 2 - 0.05
    # Inside the shell's plan outline at every station: the shell's own half-width there (its widest section
    # point), so the vehicle's extent in its own frame is the same with and without the shade.
    vertices, _, _, _ = shell(look)
    stations = np.unique(vertices[:, 0])
    widest = np.array([np.abs(vertices[vertices[:, 0] == x, 1]).max() for x in stations])
    assert np.all(np.abs(points[:, 1]) <= np.interp(points[:, 0], stations, widest))
    everything = np.concatenate([part.vertices_m for part in model.parts if part.surface != "shade"])
    with_shade = np.concatenate([everything, points])
    assert np.array_equal(with_shade.max(axis=0), everything.max(axis=0))
    assert np.array_equal(with_shade.min(axis=0)[:2], everything.min(axis=0)[:2])
    # Its triangles face up (wound counter-clockwise seen from above; those of the steps at the tyres have no
    # area) and cover most of the plan.
    corners = points[shade.faces]
    normal_z = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])[:, 2]
    assert np.all(normal_z >= 0)
    assert normal_z.sum() / 2 > 0.75 * look.length_m * look.width_m
    # Clear of the tyres: over each tyre's length, inside their inner faces (2 cm up, the shade would hide
    # the tyres' lowest 2 cm from behind).
    inner = look.track_m / 2 - TYRE_WIDTH_SHARE * look.width_m / 2
    for axle in (look.front_axle_x_m, look.rear_axle_x_m):
        over = np.abs(points[:, 0] - axle) < look.wheel_radius_m
        assert over.any() and np.all(np.abs(points[over, 1]) < inner)


def test_the_bus_has_the_citaros_beltline_and_doors_on_the_nearside():
    assert PROFILES["bus"].belt == pytest.approx((370 + 950) / 3076, abs=0.005)
    for plate, side in (("AB12 CDE", 1.0), ("B-XY 123", -1.0)):
        look = _look("bus", plate_text=plate)
        assert nearside_sign(look) == side
        vertices, faces, _, glass = shell(look)
        corners = vertices[faces[glass == 1]]
        normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        low = corners.mean(axis=1)[:, 2] < PROFILES["bus"].belt * look.height_m
        u = corners.mean(axis=1)[:, 0] / look.length_m + 0.5
        near = normal[:, 1] * side > 0.75
        low_side = low & (np.abs(normal[:, 1]) > 0.75)
        # Side glass below the beltline only in the doors, on the nearside, and in both doors.
        assert not (low_side & ~near).any()
        for u0, u1 in PROFILES["bus"].doors:
            assert (low_side & near & (u > u0) & (u < u1)).sum() >= 4
        # (a triangle's centre may lie half a station outside the band its quad's centre is in)
        slack = STATION_SPACING_M / look.length_m
        doors = np.any([(u > a - slack) & (u < b + slack) for a, b in PROFILES["bus"].doors], axis=0)
        assert not (low_side & ~doors).any()
