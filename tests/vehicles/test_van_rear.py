"""A panel van's rear (`camgen.vehicles.body`): its rear overhang as high as the maker's departure angle puts it
(`Profile.departure_angle_deg`), its black plastic rear bumper with a step, the rear plate over it and upright lamp
clusters on its rear pillars. Checked on `build_vehicle`'s parts against the departure angle measured on them (the
steepest line from under the rear tyre that clears every point behind the axle), not against the formula the body
uses. No OpenGL."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.vehicles.body import (
    REAR_BUMPER_M,
    REAR_STEP_M,
    TRIM_RGB,
    VAN_DEPARTURE_ANGLE_DEG,
    VAN_REAR_CLUSTER_M,
    build_vehicle,
)
from camgen.vehicles.look import draw_look

SEEDS = range(12)


def _van(seed: int):
    look = draw_look(seed, "truck", pinned={"body_type": "van"})
    return look, build_vehicle(look)


def _body_points_m(model) -> np.ndarray:
    """Every vertex of the vehicle but its wheels and the shaded ground under it, (V, 3)."""
    return np.concatenate(
        [p.vertices_m[p.wheel < 0] for p in model.parts if p.surface != "shade" and (p.wheel < 0).any()]
    )


def _departure_angle_deg(points_m: np.ndarray, rear_axle_x_m: float, wheel_radius_m: float) -> float:
    """The departure angle of a side view: the least, over the points behind the rear axle, of the angle to the road
    of the line through the point tangent to the tyre from below. For a point p and the wheel's centre c at distance
    d, that line leaves the direction from p to c by asin(r / d)."""
    s = rear_axle_x_m - points_m[:, 0]
    h = points_m[:, 2]
    behind = s > wheel_radius_m
    s, h = s[behind], h[behind]
    angles = np.arctan2(h - wheel_radius_m, s) + np.arcsin(wheel_radius_m / np.hypot(s, h - wheel_radius_m))
    return math.degrees(float(angles.min()))


@pytest.mark.parametrize("seed", SEEDS)
def test_the_rear_overhang_clears_the_departure_angle_and_the_bumper_touches_its_line(seed):
    look, model = _van(seed)
    points = _body_points_m(model)
    angle = _departure_angle_deg(points, look.rear_axle_x_m, look.wheel_radius_m)
    assert angle == pytest.approx(VAN_DEPARTURE_ANGLE_DEG, abs=0.2)
    # The bumper's lower rear edge is what sets it: the lowest point at the very rear, 0.30-0.42 m up (the earlier
    # shell's rear end was 0.20-0.27 m up, a departure angle of 11-14 deg).
    rear = points[points[:, 0] < -look.length_m / 2 - REAR_BUMPER_M[0] / 2 + 1e-6]
    assert 0.30 < rear[:, 2].min() < 0.42


@pytest.mark.parametrize("seed", SEEDS[:4])
def test_the_rear_bumper_is_black_plastic_across_the_rear_with_a_step(seed):
    look, model = _van(seed)
    gear = next(p for p in model.parts if p.name == "running_gear")
    depth, height = REAR_BUMPER_M
    step_depth, step_width, _ = REAR_STEP_M
    face = gear.vertices_m[:, 0] < -look.length_m / 2 - depth / 2 + 1e-6
    bumper = gear.vertices_m[face]
    assert len(bumper)
    # Black: the trim's albedo, a few per cent.
    assert np.allclose(gear.colours[face], TRIM_RGB) and max(TRIM_RGB) < 0.05
    # Across most of the rear (a van's flat rear face is 0.85 of its width), and nothing behind it in its band.
    assert 2 * np.abs(bumper[:, 1]).max() > 0.8 * look.width_m
    low = bumper[:, 2].min()
    band = _body_points_m(model)
    band = band[(band[:, 2] > low) & (band[:, 2] < low + height)]
    assert band[:, 0].min() == pytest.approx(-look.length_m / 2 - step_depth / 2)
    # Its lower edge is the painted end face's: the paint does not show under it (the end face showed a white sliver
    # under a bumper lifted onto the line at its rear face).
    paint = next(p for p in model.parts if p.name == "body_paint").vertices_m
    assert paint[paint[:, 0] < -look.length_m / 2 + 1e-9][:, 2].min() == pytest.approx(low)
    # The step: a tread at the bumper's top, standing out past its face across the middle.
    step = gear.vertices_m[gear.vertices_m[:, 0] < -look.length_m / 2 - depth / 2 - 0.01]
    assert np.abs(step[:, 1]).max() == pytest.approx(step_width / 2)
    assert step[:, 2].max() == pytest.approx(low + height)
    assert step[:, 2].min() > low + height / 2


@pytest.mark.parametrize("seed", SEEDS[:4])
def test_the_rear_plate_is_over_the_bumper_and_the_lamps_stand_on_the_pillars(seed):
    look, model = _van(seed)
    gear = next(p for p in model.parts if p.name == "running_gear")
    bumper_top = gear.vertices_m[gear.vertices_m[:, 0] < -look.length_m / 2 - REAR_BUMPER_M[0] / 2 + 1e-6][:, 2].max()
    assert model.plate_corners_m["rear"][:, 2].min() > bumper_top
    units = next(p for p in model.parts if p.name == "lamp_units")
    red = units.vertices_m[(units.colours[:, 0] > 0.1) & (units.colours[:, 1] < 0.05)]
    rear = red[red[:, 0] < 0]
    width, height = VAN_REAR_CLUSTER_M
    # Upright: taller than wide, at the rear face's sides, over the bumper and the plate.
    for side in (1, -1):
        cluster = rear[np.sign(rear[:, 1]) == side]
        extent = cluster.max(axis=0) - cluster.min(axis=0)
        assert extent[2] == pytest.approx(height) and extent[1] == pytest.approx(width)
        assert extent[2] > 2 * extent[1]
        assert cluster[:, 2].min() > model.plate_corners_m["rear"][:, 2].max()
    for name in ("tail_lamps", "brake_lamps"):
        lit = next(p for p in model.parts if p.name == name).vertices_m
        assert np.abs(lit[:, 1]).min() > np.abs(rear[:, 1]).min() - 1e-9
