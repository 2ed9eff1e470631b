"""Vehicle routes: curvature within the turning circle, speed within the comfort limits, exact times.

References are closed forms: a fillet of radius R rounding a turn θ is R·|θ| long, starts R·tan(|θ|/2)
before its corner and passes it at R·(1/cos(θ/2) − 1); a ramp from rest to v at a takes v/a and v²/2a;
an arc at speed v takes R·|θ|/v. Random routes are built leg by leg with room for their fillets.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from camgen.config.scene import VEHICLE_CLASSES, Scene
from camgen.errors import ConfigError
from camgen.motion.trajectory import Route, actor_routes
from camgen.motion.vehicle_route import (
    VEHICLE_DYNAMICS,
    RouteTooTightError,
    VehicleDynamics,
    VehicleRoute,
    rear_axle_radius_m,
    waypoint_miss_m,
)
from tests.stress import stress_settings

SETTINGS = stress_settings(25)
CAR = VEHICLE_DYNAMICS["car"]
DT_S = 0.005


@st.composite
def vehicle_routes(draw):
    """An open or looping route whose legs leave room for the fillets at their ends."""
    cls = draw(st.sampled_from(sorted(VEHICLE_DYNAMICS)))
    dyn = VEHICLE_DYNAMICS[cls]
    radius = dyn.min_turn_radius_m
    count = draw(st.integers(2, 6))
    turns = [0.0] + [draw(st.floats(-2.6, 2.6)) for _ in range(count - 2)] + [0.0]
    heading = draw(st.floats(-math.pi, math.pi))
    points = [np.array([draw(st.floats(-30, 30)), draw(st.floats(-30, 30))])]
    for k in range(count - 1):
        need = radius * (math.tan(abs(turns[k]) / 2) + math.tan(abs(turns[k + 1]) / 2))
        length = need + draw(st.floats(0.0, 25.0))
        if length < 0.5:
            length += 0.5
        heading += turns[k]
        points.append(points[-1] + length * np.array([math.cos(heading), math.sin(heading)]))
    pauses = [draw(st.sampled_from([0.0, 0.0, 1.5])) for _ in range(count)]
    speed = draw(st.floats(1.0, 15.0))
    start = draw(st.floats(0.0, 2.0))
    loop = draw(st.booleans())
    try:
        return VehicleRoute(np.array(points), np.array(pauses), speed, dyn, start, loop)
    except RouteTooTightError:  # a loop's closing leg may be too short for its turns
        return VehicleRoute(np.array(points), np.array(pauses), speed, dyn, start, False)


def sample_times(route: VehicleRoute) -> np.ndarray:
    return np.arange(0.0, route.start_s + 1.2 * route.duration_s + 1.0, DT_S)


@SETTINGS
@given(vehicle_routes())
def test_curvature_and_lateral_acceleration_stay_within_the_limits(route):
    t = sample_times(route)
    kappa = route.curvature_at(t)
    v = route.speed_at(t)
    dyn = route.dynamics
    assert np.all(np.abs(kappa) <= 1 / dyn.min_turn_radius_m * (1 + 1e-12))
    assert np.all(v**2 * np.abs(kappa) <= dyn.lateral_accel_m_s2 * (1 + 1e-9))
    assert np.all(v <= route.speed_m_s * (1 + 1e-12))
    steer = route.steer_rad_at(t)
    assert np.all(np.abs(steer) <= dyn.max_steer_rad + 1e-12)
    np.testing.assert_allclose(np.tan(steer), dyn.wheelbase_m * kappa, atol=1e-12)


@SETTINGS
@given(vehicle_routes())
def test_speed_is_continuous_and_its_changes_within_the_acceleration_limits(route):
    t = sample_times(route)
    v = route.speed_at(t)
    dv = np.diff(v)
    dyn = route.dynamics
    assert np.all(dv <= dyn.accel_m_s2 * DT_S * (1 + 1e-9) + 1e-12)
    assert np.all(-dv <= dyn.decel_m_s2 * DT_S * (1 + 1e-9) + 1e-12)
    # The speed is the derivative of the distance driven (midpoint rule, exact for constant acceleration
    # except where a piece changes within the step).
    d = route.distance_at(t)
    rate = np.diff(d) / DT_S
    middle = route.speed_at(t[:-1] + DT_S / 2)
    assert np.mean(np.abs(rate - middle) < 1e-6) > 0.97
    assert np.all(np.abs(rate - middle) <= max(dyn.accel_m_s2, dyn.decel_m_s2) * DT_S)
    # Positions move no farther than the distance driven (a chord is no longer than its arc).
    xy, _ = route.at(t)
    assert np.all(np.hypot(*np.diff(xy, axis=0).T) <= np.diff(d) + 1e-9)


@SETTINGS
@given(vehicle_routes())
def test_curve_passes_each_waypoint_within_its_fillet_tolerance_and_ends_exactly(route):
    points = route.waypoints_m
    s = np.linspace(0.0, route.length_m, 4001)
    curve = route.at_distance(s)
    np.testing.assert_allclose(route.at(0.0)[0], route.at_distance(0.0))
    if not route.loop:
        np.testing.assert_allclose(curve[0], points[0], atol=1e-9)
        np.testing.assert_allclose(route.at(route.start_s + route.duration_s + 5)[0], points[-1], atol=1e-9)
    radius = route.dynamics.min_turn_radius_m
    step = route.length_m / 4000
    n = len(points)
    for k in range(n):
        if not route.loop and k in (0, n - 1):
            continue
        into, out = points[k] - points[k - 1], points[(k + 1) % n] - points[k]
        turn = math.remainder(math.atan2(out[1], out[0]) - math.atan2(into[1], into[0]), 2 * math.pi)
        miss = float(np.min(np.hypot(*(curve - points[k]).T)))  # another part of the curve may pass nearer
        assert miss <= waypoint_miss_m(turn, radius) + step


@SETTINGS
@given(vehicle_routes())
def test_heading_is_the_tangent_of_the_curve(route):
    s = np.linspace(0.0, route.length_m, 400)[1:-1]
    h = 1e-5
    ahead, behind = route.at_distance(s + h), route.at_distance(s - h)
    tangent = np.arctan2(*(ahead - behind).T[::-1])
    heading = route._pose_at_distance(s)[1]
    assert np.all(np.abs(np.angle(np.exp(1j * (tangent - heading)))) < 1e-5)
    # And at times: the heading `at` reports is the tangent where the vehicle is.
    t = sample_times(route)[::7]
    xy, psi = route.at(t)
    d = route.distance_at(t)
    np.testing.assert_allclose(xy, route.at_distance(d), atol=1e-9)
    _, expected, _ = route._pose_at_distance(np.mod(d, route.length_m) if route.loop else d)
    moving = route.speed_at(t) > 0
    assert np.all(np.abs(np.angle(np.exp(1j * (psi - expected))))[moving] < 1e-9)


@SETTINGS
@given(vehicle_routes())
def test_pauses_stand_still_for_their_stated_time(route):
    t = sample_times(route)[::5]
    standing = [route.standing(float(x)) for x in t]
    xy, _ = route.at(t)
    for x, state, p in zip(t, standing, xy, strict=True):
        if state is None:
            continue
        since, until = state
        assert route.speed_at(x) == 0
        if math.isfinite(since) and math.isfinite(until):
            assert since + until == pytest.approx(1.5 if route.pauses_s.max() > 0 else 0.0, abs=1e-9) or (
                route.loop and since + until == pytest.approx(route.pauses_s[0], abs=1e-9)
            )
            np.testing.assert_allclose(route.at(x + until * 0.999)[0], p, atol=1e-9)


@SETTINGS
@given(vehicle_routes(), st.floats(0.0, 40.0))
def test_the_grown_footprint_slid_along_the_legs_covers_the_vehicle(route, until_s):
    half_length_m, half_width_m = 2.3, 0.9  # a car's box about the route point
    footprint = np.array([[sx * half_length_m, sy * half_width_m] for sx in (-1, 1) for sy in (-1, 1)])
    pad = route.leg_pad_m(float(np.max(np.hypot(*footprint.T))))
    starts, headings, lengths = route.legs_until(until_s)
    for time_s in np.linspace(0.0, until_s, 60):
        xy, psi = route.at(time_s)
        rot = np.array([[math.cos(psi), -math.sin(psi)], [math.sin(psi), math.cos(psi)]])
        corners = xy + footprint @ rot.T
        covered = False
        for start, heading, length in zip(starts, headings, lengths, strict=True):
            c, s = math.cos(heading), math.sin(heading)
            local = (corners - start) @ np.array([[c, -s], [s, c]])
            along = (local[:, 0] >= -half_length_m - pad - 1e-9) & (local[:, 0] <= half_length_m + length + pad + 1e-9)
            across = np.abs(local[:, 1]) <= half_width_m + pad + 1e-9
            if np.all(along & across):
                covered = True
                break
        assert covered, (time_s, xy, psi)


def test_a_right_angle_corner_matches_the_closed_form():
    # Slow enough that the arc takes the cruise speed: √(a_lat·R) = √(2.5 × 3.995) = 3.16 m/s > 3 m/s.
    radius, v = CAR.min_turn_radius_m, 3.0
    route = VehicleRoute(np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 20.0]]), np.zeros(3), v, CAR, start_s=1.0)
    arc_m = radius * math.pi / 2
    assert route.length_m == pytest.approx(40.0 - 2 * radius + arc_m, rel=1e-12)
    ramps_s = v / (2 * CAR.accel_m_s2) + v / (2 * CAR.decel_m_s2)  # time lost to reaching and leaving v
    assert route.duration_s == pytest.approx(route.length_m / v + ramps_s, rel=1e-12)
    # The arc from (20 − R, 0) to (20, R), centre (20 − R, R), driven at 3 m/s, steering left at δ_max.
    enter_s = 1.0 + v / CAR.accel_m_s2 + (20.0 - radius - v**2 / (2 * CAR.accel_m_s2)) / v
    t = enter_s + np.linspace(0.0, arc_m / v, 9)
    xy, heading = route.at(t)
    np.testing.assert_allclose(xy[0], [20.0 - radius, 0.0], atol=1e-9)
    np.testing.assert_allclose(xy[-1], [20.0, radius], atol=1e-9)
    np.testing.assert_allclose(np.hypot(*(xy - [20.0 - radius, radius]).T), radius, atol=1e-9)
    np.testing.assert_allclose(heading, np.linspace(0.0, math.pi / 2, 9), atol=1e-9)
    np.testing.assert_allclose(route.speed_at(t), v, atol=1e-12)
    np.testing.assert_allclose(route.steer_rad_at(t[1:-1]), CAR.max_steer_rad, atol=1e-12)
    assert route.steer_rad_at(enter_s - 0.1) == 0.0
    # The corner is cut: the middle of the arc is R(√2 − 1) from the waypoint.
    middle, _ = route.at(enter_s + arc_m / (2 * v))
    assert math.dist(middle, (20.0, 0.0)) == pytest.approx(radius * (math.sqrt(2) - 1), abs=1e-9)


def test_a_fast_corner_slows_to_the_lateral_limit():
    route = VehicleRoute(np.array([[0.0, 0.0], [80.0, 0.0], [80.0, -80.0]]), np.zeros(3), 12.0, CAR)
    arc_speed = math.sqrt(CAR.lateral_accel_m_s2 * CAR.min_turn_radius_m)
    t = np.arange(0.0, route.duration_s, 0.001)
    v, kappa = route.speed_at(t), route.curvature_at(t)
    on_arc = kappa != 0
    np.testing.assert_allclose(v[on_arc], arc_speed, atol=1e-9)
    assert np.all(kappa[on_arc] == -1 / CAR.min_turn_radius_m)  # a right turn
    assert np.all(route.steer_rad_at(t[on_arc]) < 0)
    arc_time_s = np.count_nonzero(on_arc) * 0.001
    assert arc_time_s == pytest.approx(CAR.min_turn_radius_m * math.pi / 2 / arc_speed, abs=0.002)
    assert v.max() == pytest.approx(12.0)


def test_a_straight_drive_is_the_constant_speed_route_but_for_its_ramps():
    v, a, b = 8.0, CAR.accel_m_s2, CAR.decel_m_s2
    points = np.array([[-30.0, 5.0], [50.0, 5.0]])
    vehicle = VehicleRoute(points, np.zeros(2), v, CAR, start_s=0.5)
    linear = Route(points, np.zeros(2), v, start_s=0.5)
    assert vehicle.duration_s == pytest.approx(linear.duration_s + v / (2 * a) + v / (2 * b), rel=1e-12)
    # Between the ramps the vehicle is where the constant-speed actor was v/2a earlier.
    t = np.linspace(0.5 + v / a, 0.5 + vehicle.duration_s - v / b, 50)
    np.testing.assert_allclose(vehicle.at(t)[0], linear.at(t - v / (2 * a))[0], atol=1e-9)
    np.testing.assert_allclose(vehicle.speed_at(t), v, atol=1e-12)
    # The ramps are s = a t²/2 from rest and the mirror image into the stop.
    ramp = np.linspace(0.0, v / a, 9)
    np.testing.assert_allclose(vehicle.at(0.5 + ramp)[0][:, 0], -30.0 + a * ramp**2 / 2, atol=1e-9)
    end = 0.5 + vehicle.duration_s
    brake = np.linspace(0.0, v / b, 9)
    np.testing.assert_allclose(vehicle.at(end - brake)[0][:, 0], 50.0 - b * brake**2 / 2, atol=1e-9)
    assert np.all(vehicle.at(t)[1] == 0.0) and np.all(vehicle.steer_rad_at(t) == 0.0)


def test_a_short_straight_never_reaches_cruise_speed():
    route = VehicleRoute(np.array([[0.0, 0.0], [10.0, 0.0]]), np.zeros(2), 15.0, CAR)
    # Accelerate at a, brake at b, meeting where a·t₁ = b·t₂ and a t₁²/2 + b t₂²/2 = 10 m.
    a, b = CAR.accel_m_s2, CAR.decel_m_s2
    peak = math.sqrt(2 * 10.0 * a * b / (a + b))
    assert route.duration_s == pytest.approx(peak / a + peak / b, rel=1e-12)
    assert float(np.max(route.speed_at(np.linspace(0, route.duration_s, 2001)))) == pytest.approx(peak, abs=1e-2)


def test_a_pause_stops_at_the_middle_of_its_fillet():
    route = VehicleRoute(np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 20.0]]), np.array([0.0, 2.0, 0.0]), 5.0, CAR)
    t = np.arange(0.0, route.duration_s, 0.01)
    still = [route.standing(float(x)) is not None for x in t]
    stop_s = t[np.flatnonzero(still)[0]]
    xy, heading = route.at(stop_s)
    radius = CAR.min_turn_radius_m
    assert math.dist(xy, (20.0, 0.0)) == pytest.approx(radius * (math.sqrt(2) - 1), abs=1e-9)
    assert heading == pytest.approx(math.pi / 4)
    assert sum(still) * 0.01 == pytest.approx(2.0, abs=0.011)
    assert route.steer_rad_at(stop_s + 1.0) == pytest.approx(CAR.max_steer_rad)  # it waits with the wheels turned


def test_a_loop_repeats_its_laps_from_rest():
    points = np.array([[0.0, 0.0], [30.0, 0.0], [30.0, 20.0], [0.0, 20.0]])
    route = VehicleRoute(points, np.array([1.0, 0, 0, 0]), 6.0, CAR, start_s=2.0, loop=True)
    lap = route.duration_s
    t = 2.0 + np.linspace(0.0, lap, 50)
    np.testing.assert_allclose(route.at(t)[0], route.at(t + 3 * lap)[0], atol=1e-9)
    assert route.distance_at(2.0 + 3 * lap) == pytest.approx(3 * route.length_m)
    assert route.length_m == pytest.approx(100.0 - 8 * CAR.min_turn_radius_m + 2 * math.pi * CAR.min_turn_radius_m)
    assert route.standing(2.0 + lap - 0.5) == pytest.approx((0.5, 0.5))


def test_at_keeps_the_shape_of_time():
    route = VehicleRoute(np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 20.0]]), np.zeros(3), 5.0, CAR)
    xy, heading = route.at(np.zeros((3, 4)))
    assert xy.shape == (3, 4, 2) and heading.shape == (3, 4)
    assert route.speed_at(1.0).shape == () and route.steer_rad_at(np.zeros(5)).shape == (5,)
    still = VehicleRoute(np.array([[3.0, 4.0]]), np.zeros(1), 5.0, CAR)
    assert not still.moves and np.all(still.at(np.arange(3.0))[0] == [3.0, 4.0])


def test_turns_tighter_than_the_turning_circle_are_refused():
    with pytest.raises(RouteTooTightError, match="needs") as caught:
        VehicleRoute(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 3.0]]), np.zeros(3), 5.0, CAR)
    assert caught.value.waypoint == 1
    with pytest.raises(RouteTooTightError, match="straight back"):
        VehicleRoute(np.array([[0.0, 0.0], [30.0, 0.0], [0.0, 0.0]]), np.zeros(3), 5.0, CAR)


def test_class_turning_radii_follow_their_published_turning_circles():
    # VW Golf VII kerb-to-kerb 10.9 m with wheelbase 2.637 m and track 1.549 m: the outer front tyre
    # circles (R + track/2, L) about the turn centre.
    car = VEHICLE_DYNAMICS["car"]
    assert math.hypot(car.min_turn_radius_m + 1.549 / 2, car.wheelbase_m) == pytest.approx(10.9 / 2)
    # UN ECE R107: a bus's outer front corner stays within 12.5 m.
    bus = VEHICLE_DYNAMICS["bus"]
    assert math.hypot(bus.min_turn_radius_m + 2.55 / 2, bus.wheelbase_m + 2.7) == pytest.approx(12.5)
    assert rear_axle_radius_m(5.0, 3.0, 0.0) == pytest.approx(4.0)
    assert set(VEHICLE_DYNAMICS) == set(VEHICLE_CLASSES)
    for dyn in VEHICLE_DYNAMICS.values():
        assert math.radians(20) < dyn.max_steer_rad < math.radians(45)
        assert 1.0 <= dyn.lateral_accel_m_s2 <= 3.0
    with pytest.raises(ValueError, match="wheelbase_m"):
        VehicleDynamics(0.0, 4.0, 2.5, 2.0, 3.0)


SCENE = {
    "duration_s": 4.0,
    "fps": 10,
    "actors": [
        {"name": "car", "class": "car", "path": {"waypoints_m": [[0, 0], [20, 0], [20, 20]], "speed_m_s": 6}},
        {"name": "bus", "class": "bus", "path": {"waypoints_m": [[0, 5], [30, 5]], "motion": "linear"}},
        {"name": "walker", "class": "person", "path": {"waypoints_m": [[0, 0], [5, 0], [5, 5]]}},
    ],
    "lights": [{"type": "ambient", "illuminance_lux": 1000}],
    "cameras": [{"name": "cam", "profile": "fixed", "mount": {"position_m": [0, -5, 3]}}],
}


def test_scene_vehicles_drive_by_default_and_linear_opts_out():
    scene = Scene.model_validate(SCENE)
    routes = actor_routes(scene)
    assert isinstance(routes["car"], VehicleRoute) and routes["car"].dynamics == CAR
    assert isinstance(routes["bus"], Route) and isinstance(routes["walker"], Route)


def test_a_scene_path_too_tight_for_its_vehicle_names_the_waypoint():
    actors = [{"name": "car", "class": "car", "path": {"waypoints_m": [[0, 0], [3, 0], [3, 3]]}}]
    scene = Scene.model_validate({**SCENE, "actors": actors})
    with pytest.raises(ConfigError, match=r"actors\[0\]\.path\.waypoints_m\[1\] cannot be driven by car"):
        actor_routes(scene)
