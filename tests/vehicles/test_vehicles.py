"""Procedural vehicles as geometry: identity, cited dimensions, closed shells, rolling and steering
wheels, lamps and plates (`camgen.vehicles`). No OpenGL."""

from __future__ import annotations

import itertools
import math
import re
from dataclasses import replace

import numpy as np
import pytest
import trimesh

from camgen.config.placement import box_corners, local_bounds, placement
from camgen.config.scene import VEHICLE_BODY_TYPES, VEHICLE_ENVELOPE_M, Actor, actor_shape
from camgen.motion.trajectory import Route
from camgen.vehicles import VehicleRig, ackermann_rad, vehicle_look, vehicle_rig
from camgen.vehicles.body import PROFILES, UNDERBODY_RGB, build_vehicle, shell, wheel_meshes
from camgen.vehicles.look import BODY_TYPES, CLASS_BODY_TYPES, PAINT_SHARES, SIZE_JITTER, TWO_WHEELERS, draw_look
from camgen.vehicles.plate import PLATE_SIZE_M, UK_PLATE_PATTERN, draw_plate_text, plate_image

CLASS_OF = {body: cls for cls, bodies in VEHICLE_BODY_TYPES.items() for body in bodies}


def _actor(cls="car", **vehicle) -> Actor:
    return Actor.model_validate(
        {"name": "v", "class": cls, "path": {"waypoints_m": [[0, 0]]}, **({"vehicle": vehicle} if vehicle else {})}
    )


def test_the_schema_and_the_statistics_name_the_same_body_types_and_classes():
    assert {cls: set(bodies) for cls, bodies in VEHICLE_BODY_TYPES.items()} == {
        cls: set(shares) for cls, shares in CLASS_BODY_TYPES.items()
    }
    assert set(BODY_TYPES) == set(PROFILES) | set(TWO_WHEELERS) == set(CLASS_OF)
    for shares in PAINT_SHARES.values():
        assert sum(shares.values()) == pytest.approx(100.0)


def test_one_seed_is_one_vehicle_and_two_seeds_differ():
    a, b = draw_look(7, "car"), draw_look(7, "car")
    assert a == b
    assert np.array_equal(build_vehicle(a).parts[0].vertices_m, build_vehicle(b).parts[0].vertices_m)
    looks = [draw_look(seed, "car") for seed in range(20)]
    assert len({(x.plate_text, x.length_m) for x in looks}) == 20
    # Derived from the scene's seed and the actor's place: stable, and different for another place.
    first = vehicle_look(_actor(), scene_seed=3, actor_index=0)
    assert first == vehicle_look(_actor(), scene_seed=3, actor_index=0)
    assert first != vehicle_look(_actor(), scene_seed=3, actor_index=1)


def test_pinning_one_attribute_leaves_the_others_as_drawn():
    free = draw_look(11, "car")
    pinned = draw_look(11, "car", pinned={"colour": "orange", "plate_text": "CG26 VEH"})
    assert (pinned.colour, pinned.plate_text) == ("orange", "CG26 VEH")
    assert (pinned.body_type, pinned.length_m, pinned.wheelbase_m) == (free.body_type, free.length_m, free.wheelbase_m)
    look = vehicle_look(_actor("truck", seed=5, body_type="box_truck"), scene_seed=0, actor_index=0)
    assert look.body_type == "box_truck" and look.identity_seed == 5


def test_body_types_follow_their_class_shares():
    counts = {}
    for seed in range(2000):
        body = draw_look(seed, "car").body_type
        counts[body] = counts.get(body, 0) + 1
    for body, share in CLASS_BODY_TYPES["car"].items():
        # Binomial 99.9 % bounds around the cited share.
        p = share / 100
        assert abs(counts.get(body, 0) / 2000 - p) < 3.3 * math.sqrt(p * (1 - p) / 2000) + 1e-9, (body, counts)


@pytest.mark.parametrize("body", sorted(PROFILES))
def test_dimensions_lie_in_the_cited_ranges_and_the_shell_has_them(body):
    dims = BODY_TYPES[body]
    for seed in range(40):
        look = draw_look(seed, CLASS_OF[body], pinned={"body_type": body})
        for key in ("length_m", "width_m", "height_m", "wheelbase_m"):
            low, high = getattr(dims, key)
            assert low <= getattr(look, key) <= high, (key, getattr(look, key))
    vertices, _, _, _ = shell(look)
    extent = vertices.max(axis=0) - vertices.min(axis=0)
    assert extent[0] == pytest.approx(look.length_m, rel=1e-9)
    assert extent[1] == pytest.approx(look.width_m, rel=0.02)
    # The paint reaches the height: the shell's roof, or a bus's air-conditioning unit on it.
    paint = [part.vertices_m for part in build_vehicle(look).parts if part.surface == "paint"]
    assert np.concatenate(paint)[:, 2].max() == pytest.approx(look.height_m, rel=0.01)
    assert vertices[:, 2].max() <= look.height_m * (1 + 1e-9)


@pytest.mark.parametrize("body", sorted(PROFILES))
def test_the_shell_is_closed_and_its_glass_sits_above_the_beltline(body):
    look = draw_look(1, CLASS_OF[body], pinned={"body_type": body})
    vertices, faces, normals, glass = shell(look)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    mesh.merge_vertices()
    assert mesh.is_watertight and mesh.is_winding_consistent
    # Outward: a positive volume, and less than the bounding box's.
    assert (
        0.4 * look.length_m * look.width_m * look.height_m < mesh.volume < look.length_m * look.width_m * look.height_m
    )
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
    assert glass.sum() > 0
    # Every section has a row of points on the beltline, so the side windows end on it.
    corners = vertices[faces[glass == 1]]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    side = np.abs(normal[:, 1]) > 0.75 * np.linalg.norm(normal, axis=1)
    assert side.sum() > 10
    # (a bus's glazed doors reach below it: tests/vehicles/test_wheels_underbody_bus.py)
    u = corners.mean(axis=1)[:, 0] / look.length_m + 0.5
    doors = np.any([(u > a - 0.01) & (u < b + 0.01) for a, b in PROFILES[body].doors] + [u < -1], axis=0)
    assert corners[side & ~doors][:, :, 2].min() >= PROFILES[body].belt * look.height_m - 1e-9
    model = build_vehicle(look)
    parts = {part.name: part for part in model.parts}
    # The paint, glass and underbody primitives together are the shell, still closed.
    gear = parts["running_gear"]
    dark = np.all(np.isclose(gear.colours, UNDERBODY_RGB), axis=1)
    body_parts = [parts[name] for name in ("body_paint", "body_glass")]
    union = trimesh.util.concatenate(
        [trimesh.Trimesh(p.vertices_m, p.faces, process=False) for p in body_parts]
        + [trimesh.Trimesh(gear.vertices_m, gear.faces[dark[gear.faces].all(axis=1)], process=False)]
    )
    union.merge_vertices()
    assert union.is_watertight
    tyre, _ = wheel_meshes(look.wheel_radius_m, 0.2)  # each tyre a closed cylinder
    assert tyre.is_watertight and tyre.is_winding_consistent
    gear = parts["running_gear"]
    assert {int(w) for w in gear.wheel} == {-1, 0, 1, 2, 3}  # four wheels and the plate backings


def test_every_vehicle_fits_its_class_envelope():
    """The largest and smallest of each body type that `draw_look` can give (one size quantile, each
    dimension jittered by `SIZE_JITTER` of its range), wheels at full lock, fit the class's box (the
    two-wheelers': tests/vehicles/test_two_wheelers.py)."""
    for body, cls in CLASS_OF.items():
        if body in TWO_WHEELERS:
            continue
        shape = actor_shape(_actor(cls))
        corners = box_corners(*local_bounds(shape), placement(shape))
        env_low, env_high = corners.min(axis=0), corners.max(axis=0)
        assert np.allclose((env_low, env_high), VEHICLE_ENVELOPE_M[cls])
        dims = BODY_TYPES[body]
        at = lambda limits, q: limits[0] + (limits[1] - limits[0]) * min(max(q, 0.0), 1.0)  # noqa: E731
        for q, length, wheelbase in itertools.product(
            (0.0, 0.5, 1.0), (-SIZE_JITTER, SIZE_JITTER), (-SIZE_JITTER, SIZE_JITTER)
        ):
            look = replace(
                draw_look(0, cls, pinned={"body_type": body}),
                length_m=at(dims.length_m, q + length),
                wheelbase_m=at(dims.wheelbase_m, q + wheelbase),
                width_m=dims.width_m[1],
                height_m=dims.height_m[1],
            )
            rig = VehicleRig(build_vehicle(look), _circle_route(LOCK_RAD))
            low, high, _ = rig.heading_box()
            # The box in the frame of the rear axle (the route's point).
            low, high = low - [look.rear_axle_x_m, 0, 0], high - [look.rear_axle_x_m, 0, 0]
            assert np.all(low >= env_low) and np.all(high <= env_high), (body, low, high)


LOCK_RAD = 0.6
"""About the largest front-wheel angle of the classes (`camgen.motion.vehicle_route`: a car's 33°)."""


class _Steered(Route):
    """A straight route whose front wheels are turned by a fixed angle (as a vehicle route offers)."""

    steer = 0.3

    def steer_rad_at(self, time_s):
        return self.steer


def _circle_route(steer_rad: float = 0.3) -> _Steered:
    route = _Steered(np.array([[0.0, 0.0], [30.0, 0.0]]), np.zeros(2), 5.0)
    object.__setattr__(route, "steer", steer_rad)
    return route


def _straight() -> Route:
    return Route(np.array([[0.0, 0.0], [40.0, 0.0]]), np.zeros(2), 8.0)


def test_wheels_roll_without_slipping():
    look = draw_look(2, "car", pinned={"body_type": "sedan"})
    rig = VehicleRig(build_vehicle(look), _straight())
    tyres = rig.parts[[p.name for p in rig.model.parts].index("running_gear")]
    wheel = rig._wheel[tyres]
    for t in (0.3, 1.1, 2.6):
        rig.place(t)
        world = rig.vertices_m[tyres].copy()
        # The angle a marker of the rear-left tyre has turned about its axle equals distance / radius.
        rest = rig.model.parts[[p.name for p in rig.model.parts].index("running_gear")].vertices_m
        k = int(np.flatnonzero((wheel == 2) & (np.abs(rest[:, 1]) > 0.01) & (np.abs(rest[:, 0]) > 0.1))[0])
        centre = rig.model.wheel_centres_m[2]
        now = world[k] - (rig.T_world_from_vehicle[:3, :3] @ centre + rig.T_world_from_vehicle[:3, 3])
        angle_rest = math.atan2(-rest[k, 2], rest[k, 0])  # about +y: x towards −z
        angle_now = math.atan2(-now[2], now[0])
        turned = math.remainder(angle_now - angle_rest, 2 * math.pi)
        expected = math.remainder(rig.route.distance_at(t) / look.wheel_radius_m, 2 * math.pi)
        assert turned == pytest.approx(expected, abs=1e-9)
        # The tyre's material point touching the ground stands still: it moves O(dt²), the car v·dt.
        dt = 1e-4
        T, wheels = rig.pose(t)
        touching = wheels[2, :3, :3].T @ [0.0, 0.0, -look.wheel_radius_m]
        where = [T @ W @ [*touching, 1.0] for T, W in ((T, wheels[2]), (lambda p: (p[0], p[1][2]))(rig.pose(t + dt)))]
        assert where[0][2] == pytest.approx(0.0, abs=1e-12)
        assert np.linalg.norm(where[1] - where[0]) < 0.01 * 8.0 * dt


def test_front_wheels_steer_about_one_centre_and_straight_routes_do_not_steer():
    look = draw_look(4, "car", pinned={"body_type": "suv"})
    rig = VehicleRig(build_vehicle(look), _circle_route())
    _, wheels = rig.pose(1.0)
    left, right = (math.atan2(wheels[w, 1, 0], wheels[w, 0, 0]) for w in (0, 1))
    assert left > 0.3 > right > 0
    # Ackermann: both front axles' lines meet the rear axle's line at the turn's centre.
    meets = []
    for w, angle in ((0, left), (1, right)):
        x0, y0, _ = rig.model.wheel_centres_m[w]
        # Along the axle (perpendicular to the wheel's heading) to x = rear axle.
        t = (look.rear_axle_x_m - x0) / -math.sin(angle)
        meets.append(y0 + t * math.cos(angle))
    assert meets[0] == pytest.approx(meets[1], abs=1e-9)
    assert meets[0] == pytest.approx(look.wheelbase_m / math.tan(0.3), rel=1e-9)
    assert ackermann_rad(0.0, 2.7, 1.5) == (0.0, 0.0)
    straight = VehicleRig(build_vehicle(look), _straight())
    _, wheels = straight.pose(1.0)
    assert np.allclose(wheels[:2, :3, :3] @ [1, 0, 0] * [1, 1, 0], wheels[2, :3, :3] @ [1, 0, 0] * [1, 1, 0])


def test_brake_lamps_light_at_a_stop_and_indicators_flash_on_the_turning_side():
    look = draw_look(4, "car")
    stop = Route(np.array([[0.0, 0.0], [10.0, 0.0], [20.0, 0.0]]), np.array([0.0, 2.0, 0.0]), 5.0)
    rig = VehicleRig(build_vehicle(look), stop)
    assert not rig.lamps(1.0)["brake"] and rig.lamps(3.0)["brake"] and not rig.lamps(10.0)["brake"]
    turning = VehicleRig(build_vehicle(look), _circle_route(), lights_on=True)
    flashes = [turning.lamps(t) for t in np.arange(0, 2, 0.05)]
    assert all(f["head"] and f["tail"] and not f["indicator_right"] for f in flashes)
    lit = np.mean([f["indicator_left"] for f in flashes])
    assert 0.4 < lit < 0.6


def test_plates_follow_the_dvla_format_and_carry_their_text():
    rng = np.random.default_rng(0)
    for _ in range(300):
        text = draw_plate_text(rng=rng)
        assert UK_PLATE_PATTERN.match(text)
        assert not set(text[:2]) & set("IQZ") and not set(text[5:]) & set("IQ")
        assert 2 <= int(text[2:4]) <= 25 or 51 <= int(text[2:4]) <= 75
    front, rear = plate_image("AB12 CDE", rear=False), plate_image("AB12 CDE", rear=True)
    assert front.shape == rear.shape == (round(PLATE_SIZE_M[1] * 1000), round(PLATE_SIZE_M[0] * 1000), 3)
    # White at the front, yellow at the rear (blue well under red and green), black characters.
    assert front[2, 2, 2] > 0.6 and rear[2, 2, 2] < 0.1 < rear[2, 2, 1]
    ink = front[..., 0] < 0.3
    columns = np.flatnonzero(ink.any(axis=0))
    # Seven characters in two groups: eight runs of ink columns at most (M, E glyphs are one run each).
    runs = np.count_nonzero(np.diff(columns) > 1) + 1
    assert runs == 7
    # The group gap (33 mm) is the widest gap between runs.
    gaps = np.diff(columns)[np.diff(columns) > 1]
    assert int(np.argmax(gaps)) == 3 and gaps.max() > 25
    rig = vehicle_rig(
        _actor(plate_text="CG26 VEH"), Route(np.zeros((1, 2)), np.zeros(1), 1.0), scene_seed=0, actor_index=0
    )
    assert rig.look.plate_text == "CG26 VEH"
    corners = rig.plate_corners_world()
    width = np.linalg.norm(corners["front"][1] - corners["front"][0])
    assert width == pytest.approx(PLATE_SIZE_M[0]) and re.match(r"^CG26 VEH$", rig.look.plate_text)
