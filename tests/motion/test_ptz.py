"""PTZ head kinematics: limits hold for any program (hypothesis), and the discrete braking curve is exact.

Every property is checked on the servo-loop samples (one control step per sample, so velocities are
the commanded ones) and, where it matters, on frame samples: speed |v| ≤ v_max, acceleration
|Δv|/dt ≤ a_max, range limits never crossed, endless pan takes the short way across ±180°, tilt at
±90° stays finite, zoom stays within the lens range, and reported positions sit on the step grid.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from camgen.config.ptz_program import (
    Keyframe,
    KeyframeProgram,
    PtzPreset,
    ScanProgram,
    TourProgram,
    TourStop,
)
from camgen.motion.pose import R_world_from_cam
from camgen.motion.programs import Position, build_controller
from camgen.motion.ptz import (
    AxisLimits,
    HeadLimits,
    HeadPose,
    braking_speed,
    simulate_head,
    step_axis,
    wrap_deg,
)
from tests.stress import stress_settings

EPS = 1e-9


def head(endless: bool, pan_speed=240.0, pan_accel=400.0, tilt_range=(-90.0, 20.0), step=0.0, zoom_max=30.0):
    zoom_rate = math.log(zoom_max) / 4.0
    return HeadLimits(
        pan=AxisLimits(pan_speed, pan_accel, low=-170.0, high=170.0, endless=endless, step=step, angular=True),
        tilt=AxisLimits(150.0, 300.0, low=tilt_range[0], high=tilt_range[1], step=step),
        zoom=AxisLimits(zoom_rate, zoom_rate / 0.2, low=0.0, high=math.log(zoom_max)),
    )


def check_limits(track, limits: HeadLimits, dt: float) -> None:
    for position, velocity, axis in (
        (track.pan_unwrapped_deg, track.pan_deg_s, limits.pan),
        (track.tilt_deg, track.tilt_deg_s, limits.tilt),
        (np.log(track.zoom_x), track.log_zoom_per_s, limits.zoom),
    ):
        assert np.all(np.isfinite(position)) and np.all(np.isfinite(velocity))
        assert np.max(np.abs(velocity)) <= axis.speed_max * (1 + EPS) + EPS
        assert np.max(np.abs(np.diff(velocity))) <= axis.accel_max * dt * (1 + 1e-6) + EPS
        # the position integrates the velocity (no jumps)
        np.testing.assert_allclose(np.diff(position), velocity[1:] * dt, atol=1e-9)
        if not axis.endless:
            assert position.min() >= axis.low - 1e-9 and position.max() <= axis.high + 1e-9


positions = st.tuples(st.floats(-179.0, 179.0), st.floats(-90.0, 20.0), st.floats(1.0, 30.0)).map(
    lambda t: PtzPreset(name="p", pan_deg=t[0], tilt_deg=t[1], zoom_x=t[2])
)


@st.composite
def programs(draw):
    kind = draw(st.sampled_from(["tour", "scan", "keyframes"]))
    if kind == "tour":
        stops = draw(st.lists(positions, min_size=1, max_size=4))
        presets = [p.model_copy(update={"name": f"p{i}"}) for i, p in enumerate(stops)]
        dwell = draw(st.floats(0.0, 0.5))
        speed = draw(st.one_of(st.none(), st.floats(5.0, 300.0)))
        program = TourProgram(
            type="tour", stops=[TourStop(preset=p.name, dwell_s=dwell) for p in presets], speed_deg_s=speed
        )
        return program, presets
    if kind == "scan":
        a, b = draw(st.floats(-170.0, 170.0)), draw(st.floats(-170.0, 170.0))
        program = ScanProgram(
            type="scan",
            pan_range_deg=(a, b),
            tilt_deg=draw(st.floats(-90.0, 20.0)),
            zoom_x=draw(st.floats(1.0, 30.0)),
            speed_deg_s=draw(st.floats(5.0, 400.0)),
            dwell_s=draw(st.floats(0.0, 0.3)),
        )
        return program, []
    count = draw(st.integers(1, 5))
    times = np.cumsum(draw(st.lists(st.floats(0.05, 1.0), min_size=count, max_size=count)))
    keys = [
        Keyframe(time_s=float(t), pan_deg=p.pan_deg, tilt_deg=p.tilt_deg, zoom_x=p.zoom_x)
        for t, p in zip(times, draw(st.lists(positions, min_size=count, max_size=count)), strict=True)
    ]
    return KeyframeProgram(type="keyframes", keys=keys), []


@stress_settings(60)
@given(programs(), st.booleans(), positions, st.floats(20.0, 400.0), st.floats(50.0, 1000.0))
def test_limits_hold_for_random_programs(program_presets, endless, start, pan_speed, pan_accel):
    program, presets = program_presets
    limits = head(endless, pan_speed=pan_speed, pan_accel=pan_accel)
    pan = start.pan_deg if endless else float(np.clip(start.pan_deg, -170, 170))
    home = Position(pan, start.tilt_deg, start.zoom_x)
    controller = build_controller(program, home, presets, endless_pan=endless)
    fps = 100.0  # one control step per sample: the samples are the servo loop itself
    track = simulate_head(controller, limits, HeadPose(pan, start.tilt_deg, start.zoom_x), 300, fps, steps_per_frame=1)
    check_limits(track, limits, 1.0 / fps)
    assert np.all((track.zoom_x >= 1.0 - 1e-12) & (track.zoom_x <= 30.0 * (1 + 1e-12)))
    if endless:
        assert np.all((track.pan_deg >= -180.0) & (track.pan_deg < 180.0))


@stress_settings(20)
@given(programs(), st.integers(2, 8))
def test_frame_samples_respect_the_limits_too(program_presets, steps):
    """Frame samples average the servo steps: finite differences obey v_max and a_max as well."""
    program, presets = program_presets
    limits = head(True)
    controller = build_controller(program, Position(0.0, 0.0, 1.0), presets, endless_pan=True)
    fps = 25.0
    track = simulate_head(controller, limits, HeadPose(0.0, 0.0, 1.0), 100, fps, steps_per_frame=steps)
    velocity = np.diff(track.pan_unwrapped_deg) * fps
    assert np.max(np.abs(velocity)) <= limits.pan.speed_max * (1 + 1e-9)
    assert np.max(np.abs(np.diff(velocity))) * fps <= limits.pan.accel_max * (1 + 1e-6)


@pytest.mark.parametrize(
    ("start", "goal", "way"), [(170.0, -170.0, +20.0), (-175.0, 160.0, -25.0), (179.0, -179.0, 2.0)]
)
def test_endless_pan_takes_the_short_way_across_180(start, goal, way):
    limits = head(True)
    presets = [PtzPreset(name="goal", pan_deg=goal)]
    program = TourProgram(type="tour", stops=[TourStop(preset="goal", dwell_s=10.0)], loop=False)
    controller = build_controller(program, Position(start, 0.0, 1.0), presets, endless_pan=True)
    track = simulate_head(controller, limits, HeadPose(start, 0.0, 1.0), 200, 100.0, steps_per_frame=1)
    travelled = track.pan_unwrapped_deg - start
    assert travelled[-1] == pytest.approx(way, abs=1e-6)
    assert np.all(np.sign(travelled[travelled != 0]) == np.sign(way))  # never the long way
    assert abs(float(wrap_deg(track.pan_deg[-1] - goal))) < 1e-6


def test_a_limited_pan_goes_round_the_long_way_and_never_crosses_its_limits():
    limits = head(False)  # range [−170°, 170°]
    presets = [PtzPreset(name="goal", pan_deg=-165.0)]
    program = TourProgram(type="tour", stops=[TourStop(preset="goal", dwell_s=10.0)], loop=False)
    controller = build_controller(program, Position(165.0, 0.0, 1.0), presets, endless_pan=False)
    track = simulate_head(controller, limits, HeadPose(165.0, 0.0, 1.0), 400, 100.0, steps_per_frame=1)
    check_limits(track, limits, 0.01)
    assert track.pan_unwrapped_deg[-1] == pytest.approx(-165.0, abs=1e-6)


def test_a_goal_beyond_a_limit_stops_at_the_limit_without_crossing():
    axis = AxisLimits(100.0, 200.0, low=-90.0, high=20.0)
    position, velocity, dt = -80.0, 0.0, 0.01
    trace = []
    for _ in range(300):
        position, velocity = step_axis(position, velocity, 60.0, axis, dt)
        trace.append(position)
    assert max(trace) <= 20.0 + 1e-12
    assert trace[-1] == pytest.approx(20.0, abs=1e-9)


@pytest.mark.parametrize("tilt", [-90.0, 90.0, -89.999, 89.9999])
def test_tilt_at_the_poles_stays_finite(tilt):
    limits = head(True, tilt_range=(-90.0, 90.0))
    presets = [PtzPreset(name="pole", pan_deg=120.0, tilt_deg=tilt, zoom_x=4.0)]
    program = TourProgram(type="tour", stops=[TourStop(preset="pole", dwell_s=0.2)])
    controller = build_controller(program, Position(0.0, 0.0, 1.0), presets, endless_pan=True)
    track = simulate_head(controller, limits, HeadPose(0.0, 0.0, 1.0), 400, 100.0, steps_per_frame=1)
    check_limits(track, limits, 0.01)
    assert track.tilt_deg[-1] == pytest.approx(tilt, abs=1e-6)
    R = R_world_from_cam(30.0, -10.0, 0.0, float(track.pan_deg[-1]), float(track.tilt_deg[-1]))
    assert np.all(np.isfinite(R)) and np.allclose(R @ R.T, np.eye(3), atol=1e-12)


def test_reported_positions_sit_on_the_step_grid():
    limits = head(True, step=0.05)
    presets = [PtzPreset(name="a", pan_deg=33.333, tilt_deg=-12.345)]
    program = TourProgram(type="tour", stops=[TourStop(preset="a", dwell_s=1.0)])
    controller = build_controller(program, Position(0.0, 0.0, 1.0), presets, endless_pan=True)
    track = simulate_head(controller, limits, HeadPose(0.0, 0.0, 1.0), 60, 25.0)
    for values in (track.pan_deg, track.tilt_deg):
        np.testing.assert_allclose(values / 0.05, np.round(values / 0.05), atol=1e-9)
    assert abs(track.pan_deg[-1] - 33.35) < 1e-9  # nearest step to 33.333


@stress_settings(100)
@given(st.floats(1e-6, 1e4), st.floats(1.0, 1e4), st.floats(1e-3, 0.05))
def test_braking_speed_stops_exactly_within_the_distance(distance, accel, dt):
    """The closed form equals the distance covered by braking at a·dt per step from that speed."""
    v = braking_speed(distance, accel, dt)
    covered, speed = 0.0, v
    while speed > 1e-15:
        covered += speed * dt
        speed -= accel * dt
    assert covered == pytest.approx(distance, rel=1e-9, abs=1e-12)
    assert v <= math.sqrt(2 * accel * distance) + accel * dt  # the continuous curve, plus one step


def test_a_still_goal_is_reached_without_overshoot_in_the_trapezoid_time():
    """From rest to a still goal: accelerate, cruise, brake; time ≈ d/v + v/a (continuous trapezoid)."""
    axis = AxisLimits(100.0, 200.0)
    position, velocity, dt = 0.0, 0.0, 0.001
    steps = 0
    while not (abs(position - 90.0) < 1e-9 and velocity == 0.0) and steps < 5000:
        position, velocity = step_axis(position, velocity, 90.0, axis, dt)
        assert position <= 90.0 + 1e-9
        steps += 1
    assert steps * dt == pytest.approx(90.0 / 100.0 + 100.0 / 200.0, abs=0.01)


@pytest.mark.parametrize(
    ("endless", "pan_range", "ends"),
    [
        (True, (-170.0, 170.0), (-170.0, 170.0)),
        (False, (-170.0, 170.0), (-170.0, 170.0)),
        (True, (150.0, -150.0), (150.0, 210.0)),
    ],
)
def test_a_scan_sweeps_to_both_ends_and_back(endless, pan_range, ends):
    """Endless: counter-clockwise from the first angle to the second (340° or 60° here); limited:
    between the angles as given, never across the range's ends."""
    limits = head(endless)
    program = ScanProgram(type="scan", pan_range_deg=pan_range, tilt_deg=-10.0, speed_deg_s=100.0, dwell_s=0.2)
    controller = build_controller(program, Position(0.0, 0.0, 1.0), [], endless_pan=endless)
    track = simulate_head(controller, limits, HeadPose(0.0, 0.0, 1.0), 1500, 100.0, steps_per_frame=1)
    check_limits(track, limits, 0.01)
    pan = track.pan_unwrapped_deg
    first = int(np.argmax(np.isclose(pan, ends[0], atol=1e-6)))
    assert np.isclose(pan[first], ends[0], atol=1e-6)
    swept = pan[first:]
    assert swept.max() == pytest.approx(ends[1], abs=1e-6) and swept.min() == pytest.approx(ends[0], abs=1e-6)
    back = int(np.argmax(np.isclose(swept, ends[1], atol=1e-6)))
    assert np.all(np.diff(swept[: back + 1]) >= -1e-12)  # out in one direction …
    assert np.isclose(swept[back:], ends[0], atol=1e-6).any()  # … and back again


def test_keyframes_on_a_limited_head_never_cross_its_ends():
    """170° → −170° is 20° the short way, but a head limited to [−170°, 170°] must turn 340° back."""
    limits = head(False)
    keys = [Keyframe(time_s=0.0, pan_deg=170.0), Keyframe(time_s=10.0, pan_deg=-170.0)]
    controller = build_controller(
        KeyframeProgram(type="keyframes", keys=keys), Position(170.0, 0.0, 1.0), [], endless_pan=False
    )
    track = simulate_head(controller, limits, HeadPose(170.0, 0.0, 1.0), 1100, 100.0, steps_per_frame=1)
    check_limits(track, limits, 0.01)
    assert np.all(np.diff(track.pan_unwrapped_deg) <= 1e-12)
    assert track.pan_unwrapped_deg[-1] == pytest.approx(-170.0, abs=1e-6)
