"""What a car shows from above over its shell (`camgen.vehicles.roof`), against the shell's own surface.

- The roof kit (glass roof, rails, shark fin) is drawn from the identity seed at its shares, the same for the same
  seed; vans, trucks and buses carry none of it.
- A glass roof is the shell's own roof between its edge rows, the darkest glass of the car (`ROOF_GLASS_T`, under
  the 15–26 % of makers' privacy glass): its faces face up, it lies behind the windscreen and
  ahead of the rear window, at most `GLASS_ROOF_LENGTH_M` long, and its outline is a rectangle of the mesh's lines
  (four corners, no stairs); the paint, glass and underbody stay one closed shell.
- Roof rails stand on the roof's edges (their undersides in the roof, their tops `RAIL_SIZE_M` over it) along most
  of the roof; a shark fin stands on the roof's centre line near its rear, 5–7 cm tall.
- The cowl and the bonnet's shut lines lie on the shell's surface, a few millimetres out (never under the paint);
  the shut lines run `BONNET_EDGE_INSET_M` inside the body's plan outline on both sides; the wipers lie over the
  windscreen's glass, their blades the listed lengths.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from camgen.vehicles import roof
from camgen.vehicles.body import (
    GREENHOUSE_SIDE_QUADS,
    LOWER_POINTS,
    PROFILES,
    STATION_SPACING_M,
    UNDERBODY_RGB,
    UPPER_POINTS,
    _windscreen_foot_m,
    build_vehicle,
    plan_half_width_m,
    shell,
)
from camgen.vehicles.look import draw_look
from camgen.vehicles.roof import (
    BONNET_EDGE_INSET_M,
    CAR_BODIES,
    GLASS_ROOF_LENGTH_M,
    GLASS_ROOF_MIN_M,
    GLASS_ROOF_SHARE,
    RAIL_SIZE_M,
    ROOF_NORMAL_Z,
    ROOF_RAIL_SHARE,
    SHARK_FIN_M,
    SHARK_FIN_PAINTED_SHARE,
    SHARK_FIN_SHARE,
    WIPER_LENGTHS_CAR_M,
    roof_details,
    roof_kit,
)
from tests.vehicles.test_window_outlines import outline, stair_steps

CLASS_OF = {"van": "truck", "box_truck": "truck", "bus": "bus"}
COUNT = UPPER_POINTS + LOWER_POINTS
SURFACE_GAP_M = 0.015
"""The most the cowl stands over the shell straight up, m: it lies 3 mm out along the shell's normals, which is
further up where the windscreen's foot is steep."""


def _look(body: str, seed: int):
    return draw_look(seed, CLASS_OF.get(body, "car"), pinned={"body_type": body})


def _seeds_with(body: str, want, count: int = 2) -> list[int]:
    """The first `count` identity seeds whose roof kit satisfies `want`."""
    seeds = [seed for seed in range(200) if want(roof_kit(_look(body, seed)))]
    return seeds[:count]


def _surface_z(vertices: np.ndarray, faces: np.ndarray, points_xy: np.ndarray) -> np.ndarray:
    """(n,) the height of the shell's upward-facing surface straight over or under each (x, y), m (NaN where none):
    each point's upward triangles whose plan holds it, interpolated, the highest."""
    corners = vertices[faces]
    normal_z = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])[:, 2]
    corners = corners[normal_z > 1e-12]
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    out = np.full(len(points_xy), np.nan)
    for i, (px, py) in enumerate(points_xy):
        v0, v1 = b[:, :2] - a[:, :2], c[:, :2] - a[:, :2]
        v2 = np.array([px, py]) - a[:, :2]
        den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
        s = (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / den
        t = (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / den
        inside = (s >= -1e-9) & (t >= -1e-9) & (s + t <= 1 + 1e-9)
        if inside.any():
            z = a[inside, 2] + s[inside] * (b[inside, 2] - a[inside, 2]) + t[inside] * (c[inside, 2] - a[inside, 2])
            out[i] = z.max()
    return out


def _details(look):
    vertices, faces, normals, kind = shell(look)
    foot = _windscreen_foot_m(vertices, faces[kind == 1])
    details = roof_details(look, (vertices, normals, faces), foot, UPPER_POINTS, GREENHOUSE_SIDE_QUADS, COUNT)
    return vertices, faces, details


@pytest.mark.parametrize("body", [*CAR_BODIES, "van", "box_truck", "bus"])
def test_roof_kits_are_drawn_from_the_identity_seed_at_their_shares(body):
    kits = [roof_kit(_look(body, seed)) for seed in range(1500)]
    assert kits[:20] == [roof_kit(_look(body, seed)) for seed in range(20)]  # the same seed, the same kit
    n = len(kits)
    for share, count in (
        (GLASS_ROOF_SHARE.get(body, 0.0), sum(kit.glass_roof for kit in kits)),
        (ROOF_RAIL_SHARE.get(body, 0.0), sum(kit.rails_rgb is not None for kit in kits)),
        (SHARK_FIN_SHARE if body in CAR_BODIES else 0.0, sum(kit.fin is not None for kit in kits)),
    ):
        assert abs(count - share * n) <= 4 * np.sqrt(n * share * (1 - share)) + 1e-9, (body, share, count)
    fins = [kit.fin for kit in kits if kit.fin is not None]
    if fins:
        share = SHARK_FIN_PAINTED_SHARE
        painted = fins.count("paint")
        assert abs(painted - share * len(fins)) <= 4 * np.sqrt(len(fins) * share * (1 - share))


@pytest.mark.parametrize("body", ["hatchback", "sedan", "estate", "suv"])
def test_a_glass_roof_is_the_roofs_own_faces_between_its_edges(body):
    for seed in _seeds_with(body, lambda kit: kit.glass_roof):
        look = _look(body, seed)
        vertices, faces, _, kind = shell(look)
        corners = vertices[faces]
        n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        with pytest.MonkeyPatch.context() as patch:  # the same vehicle without its glass roof
            patch.setattr(roof, "GLASS_ROOF_SHARE", {})
            _, _, _, plain = shell(look)
        roof_glass = kind == 3  # the glass roof's own kind (its own transmittance)
        assert roof_glass.sum() >= 8 and np.all(n[roof_glass, 2] > ROOF_NORMAL_Z), (body, seed)
        assert np.all(plain[roof_glass] == 0)  # paint without the glass roof
        assert np.array_equal(kind[~roof_glass], plain[~roof_glass])  # nothing else changes
        centres = corners[roof_glass].mean(axis=1)
        # Behind the windscreen and ahead of the rear window, at most the longest glass roof long.
        profile = PROFILES[body]
        x = corners[roof_glass][:, :, 0]
        assert (profile.rear_window[1] - 0.5) * look.length_m < x.min()
        assert x.max() < (profile.windscreen[0] - 0.5) * look.length_m
        assert GLASS_ROOF_MIN_M - STATION_SPACING_M <= np.ptp(x) <= GLASS_ROOF_LENGTH_M + STATION_SPACING_M
        # Across: inside the roof's edges (the shell's width at the roof, less a roof-edge row), most of the roof.
        roof_half_m = np.abs(vertices[np.abs(vertices[:, 0] - centres[:, 0].mean()) < 0.05, 1]).max() * 0.8
        assert np.abs(corners[roof_glass][:, :, 1]).max() < roof_half_m
        assert np.abs(corners[roof_glass][:, :, 1]).max() > 0.5 * roof_half_m
        # Its outline is a rectangle of the mesh's rows and stations.
        sharp, steps, crossings = stair_steps(*outline(vertices, faces, roof_glass.astype(np.int8)))
        # (a corner counts twice where a second station lies within the turn's reach of it)
        assert (steps, crossings) == (0, 0) and 4 <= sharp <= 8, (body, seed, sharp, steps, crossings)
        # Paint, glass and underbody are still the closed shell.
        parts = {part.name: part for part in build_vehicle(look).parts}
        gear = parts["running_gear"]
        dark = np.all(np.isclose(gear.colours, UNDERBODY_RGB), axis=1)
        union = trimesh.util.concatenate(
            [trimesh.Trimesh(parts[name].vertices_m, parts[name].faces, process=False)
             for name in ("body_paint", "body_glass")]
            + [trimesh.Trimesh(gear.vertices_m, gear.faces[dark[gear.faces].all(axis=1)], process=False)]
        )  # fmt: skip
        union.merge_vertices()
        assert union.is_watertight
    for seed in _seeds_with(body, lambda kit: not kit.glass_roof, 1):  # without one, the windows alone
        look = _look(body, seed)
        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(roof, "GLASS_ROOF_SHARE", {})
            _, _, _, plain = shell(look)
        assert np.array_equal(shell(look)[3], plain)


@pytest.mark.parametrize("body", ["estate", "suv"])
def test_roof_rails_stand_on_the_roof_edges(body):
    for seed in _seeds_with(body, lambda kit: kit.rails_rgb is not None):
        look = _look(body, seed)
        vertices, faces, details = _details(look)
        rails = [mesh for mesh, _ in details["rails"]]
        assert len(rails) == 2
        sides = sorted(np.sign(rail.vertices[:, 1]).mean() for rail in rails)
        assert sides == [-1.0, 1.0]
        for rail in rails:
            v = np.asarray(rail.vertices)
            rings = v.reshape(-1, 4, 3)  # per station: the underside's two corners, then the top's two
            low = rings[:, :2].reshape(-1, 3)
            roof_z = _surface_z(vertices, faces, low[:, :2])
            assert np.all(low[:, 2] < roof_z) and np.all(low[:, 2] > roof_z - 0.02), (body, seed)
            assert np.allclose(rings[:, 2:, 2] - rings[:, 1::-1, 2], RAIL_SIZE_M[1])
            # Near the roof's edge: outside 60 % of the body's half-width, inside it.
            assert np.all(np.abs(v[:, 1]) > 0.3 * look.width_m) and np.all(np.abs(v[:, 1]) < 0.5 * look.width_m)
            assert np.ptp(v[:, 0]) > 0.35 * look.length_m  # along most of the roof
        assert rails[0].is_watertight and rails[1].is_watertight


@pytest.mark.parametrize("body", CAR_BODIES)
def test_a_shark_fin_stands_on_the_roofs_centre_line_near_its_rear(body):
    for seed in _seeds_with(body, lambda kit: kit.fin is not None, 1):
        look = _look(body, seed)
        vertices, faces, details = _details(look)
        (fin,) = [mesh for name in ("fin", "fin_paint") for mesh, _ in details[name]]
        v = np.asarray(fin.vertices)
        assert np.abs(v[:, 1]).max() <= SHARK_FIN_M[1] / 2 + 1e-9
        roof_z = _surface_z(vertices, faces, v[:, :2])
        assert np.nanmin(v[:, 2] - roof_z) < 0.0  # its base sunk into the roof
        assert 0.05 < np.nanmax(v[:, 2] - roof_z) < SHARK_FIN_M[2] + 0.01
        # In the roof's rear half (its tail towards the rear window), over the cabin.
        assert v[:, 0].min() < (PROFILES[body].windscreen[0] - 0.5) * look.length_m - 0.3
        assert v[:, 0].max() < 0.2 * look.length_m
        # Built: a body-coloured fin is paint of its own, a black one part of the running gear.
        names = [part.name for part in build_vehicle(look).parts]
        assert ("roof_fin" in names) == (roof_kit(look).fin == "paint")


@pytest.mark.parametrize("body", [*CAR_BODIES, "van"])
def test_cowl_wipers_and_shut_lines_lie_on_the_shell(body):
    look = _look(body, 1)
    vertices, faces, details = _details(look)
    _, _, _, kind = shell(look)
    foot_m = _windscreen_foot_m(vertices, faces[kind == 1])
    (cowl,) = [mesh for mesh, _ in details["cowl"]]
    c = np.asarray(cowl.vertices)
    gap = c[:, 2] - _surface_z(vertices, faces, c[:, :2])
    assert np.all(gap > 0.0) and np.all(gap < SURFACE_GAP_M), (body, np.nanmin(gap), np.nanmax(gap))
    assert c[:, 0].min() == pytest.approx(foot_m, abs=STATION_SPACING_M)
    # Across the car: the windscreen's foot between the A-pillars' bases, lower on the body and so narrower than
    # the roof (about 0.7 of a car's width; 0.65-0.72 here).
    assert np.ptp(c[:, 1]) > 0.6 * look.width_m
    wipers = [np.asarray(mesh.vertices) for mesh, _ in details["wipers"]]
    lengths = sorted(np.ptp(w[:, 1]) for w in wipers)
    assert lengths == pytest.approx(sorted({"van": (0.65, 0.65)}.get(body, WIPER_LENGTHS_CAR_M)), abs=1e-6)
    for w in wipers:  # over the glass, behind the cowl
        assert np.all(w[:, 0] < foot_m) and np.all(np.abs(w[:, 1]) < look.width_m / 2)
    lines = [np.asarray(mesh.vertices) for mesh, _ in details["shut_lines"]]
    if body == "van":
        assert not lines
        return
    assert len(lines) == 3
    for line in lines:
        gap = line[:, 2] - _surface_z(vertices, faces, line[:, :2])
        assert np.all(gap > 0.0) and np.all(gap < 0.006), (body, np.nanmin(gap), np.nanmax(gap))  # 3 mm up
    left, right = (line.reshape(2, -1, 3).mean(axis=0) for line in lines[:2])  # the ribbons' centre lines
    left[:, 2] = right[:, 2] = 0.0  # (each edge's height is the surface's under it)
    assert np.all(left[:, 1] > 0) and np.allclose(left * (1, -1, 1), right)  # mirror images
    assert np.allclose(left[:, 1], plan_half_width_m(look, left[:, 0]) - BONNET_EDGE_INSET_M)
    assert left[:, 0].min() > foot_m and left[:, 0].max() < look.length_m / 2


@pytest.mark.parametrize("body", ["hatchback", "estate", "suv"])
def test_a_glass_roof_is_darker_than_every_other_pane(body):
    """A glass roof's faces pass `ROOF_GLASS_T`, less than any other pane of the car, and less than the 15 % at the
    dark end of makers' privacy glass; the car's other panes keep their transmittances."""
    from camgen.vehicles.cabin import PRIVACY_T, ROOF_GLASS_T

    assert 0.0 < ROOF_GLASS_T < 0.15 < PRIVACY_T
    (seed,) = _seeds_with(body, lambda kit: kit.glass_roof, 1)
    look = _look(body, seed)
    vertices, faces, _, kind = shell(look)
    glass = {part.name: part for part in build_vehicle(look).parts}["body_glass"]
    transmittance = 1.0 - glass.colours[glass.faces[:, 0], 3]
    centres = glass.vertices_m[glass.faces].mean(axis=1)
    roof_centres = vertices[faces[kind == 3]].mean(axis=1)
    on_roof = (np.abs(centres[:, None, :] - roof_centres[None]).max(axis=2) < 1e-9).any(axis=1)
    assert on_roof.sum() == len(roof_centres) >= 8
    assert np.allclose(transmittance[on_roof], ROOF_GLASS_T)
    assert transmittance[~on_roof].min() > ROOF_GLASS_T
    with pytest.MonkeyPatch.context() as patch:  # the same car without its glass roof: the other panes alike
        patch.setattr(roof, "GLASS_ROOF_SHARE", {})
        plain = {part.name: part for part in build_vehicle(look).parts}["body_glass"]
    assert np.allclose(np.sort(1.0 - plain.colours[plain.faces[:, 0], 3]), np.sort(transmittance[~on_roof]))
