"""Auto-exposure and PTZ at their limits: from any state and any light, the next state is finite and
inside the limits the profile allows.

Auto-exposure: exposure time 1 µs–10 s, gain 0–72 dB, speeds anything > 0 (the schema has no upper
bound, so "instant" cameras with 10⁶ EV/s are valid), metered levels from black (≤ 0) to clipped.
PTZ: ranges, speeds and accelerations the `ptz` schema accepts, starts and goals at and beyond the
range limits, goal velocities beyond the head's speed, zoom pinned at wide and tele.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import example, given
from hypothesis import strategies as st

from camgen.motion.ptz import AxisLimits, Command, HeadLimits, HeadPose, step_head
from camgen.sensor.auto_exposure import ExposureLimits, ExposureSetting, next_exposure, split_exposure
from camgen.sensor.exposure import gain_linear
from tests.stress import stress_settings

TOLERANCE = 1e-9


@st.composite
def exposure_limits(draw):
    a, b = draw(st.floats(1e-6, 10.0)), draw(st.floats(1e-6, 10.0))
    return ExposureLimits(min(a, b), max(a, b), draw(st.floats(0.0, 72.0)))


@stress_settings(200)
@given(
    limits=exposure_limits(),
    time_s=st.floats(1e-6, 10.0),
    gain_db=st.floats(0.0, 72.0),
    metered=st.one_of(st.sampled_from([0.0, -0.01, 1.0, 1e-300]), st.floats(-0.1, 1.0)),
    target=st.floats(0.0, 1.0, exclude_min=True, exclude_max=True),
    speed_up=st.floats(1e-3, 1e7),
    speed_down=st.floats(1e-3, 1e7),
    fps=st.floats(0.1, 240.0),
)
@example(  # found: 2.0 ** step overflowed (OverflowError) for a fast camera on a black frame
    limits=ExposureLimits(1e-5, 1 / 30, 30.0),
    time_s=0.01,
    gain_db=0.0,
    metered=0.0,
    target=0.18,
    speed_up=1e5,
    speed_down=8.0,
    fps=25.0,
)
def test_next_exposure_stays_finite_and_within_limits(
    limits, time_s, gain_db, metered, target, speed_up, speed_down, fps
):
    """The next exposure time lies in [min, max] and its gain in [0, max] dB; the exposure product
    moves towards the target (up for a frame darker than it, down for a brighter one), by at most the
    speed limit in EV (2^(speed·Δt)) unless the current product lies outside the limits and is
    clipped back in."""
    current = ExposureSetting(time_s, gain_db)
    dt = 1.0 / fps
    following = next_exposure(
        current,
        metered,
        target_frac=target,
        speed_up_ev_per_s=speed_up,
        speed_down_ev_per_s=speed_down,
        frame_interval_s=dt,
        limits=limits,
    )
    assert math.isfinite(following.exposure_time_s) and math.isfinite(following.gain_db)
    assert (
        limits.exposure_time_min_s * (1 - TOLERANCE)
        <= following.exposure_time_s
        <= limits.exposure_time_max_s * (1 + TOLERANCE)
    )
    assert -TOLERANCE <= following.gain_db <= limits.gain_max_db + TOLERANCE
    before, after = current.product_s, following.product_s
    inside = limits.product_min_s <= before <= limits.product_max_s
    if inside:
        step_ev = math.log2(after / before)
        assert -speed_down * dt - 1e-9 <= step_ev <= speed_up * dt + 1e-9
        if metered < target:
            assert after >= before * (1 - TOLERANCE)
        elif metered > target:
            assert after <= before * (1 + TOLERANCE)


@stress_settings(100)
@given(limits=exposure_limits(), product_s=st.floats(0.0, 1e6))
def test_split_exposure_spends_time_before_gain(limits, product_s):
    """The product is clipped to [t_min, t_max·G_max] and split as a camera does: time up to its
    maximum, then gain; time × gain reproduces the clipped product (1e-9 relative)."""
    setting = split_exposure(product_s, limits)
    clipped = min(max(product_s, limits.product_min_s), limits.product_max_s)
    assert math.isclose(setting.exposure_time_s * gain_linear(setting.gain_db), clipped, rel_tol=1e-9)
    if setting.gain_db > 1e-12:
        assert setting.exposure_time_s == limits.exposure_time_max_s


@st.composite
def heads(draw):
    """Head limits as `camgen.plan.ptz.head_limits` builds them from a schema `ptz` and lens."""
    pan_low = draw(st.floats(-360.0, 359.0))
    pan_high = draw(st.floats(pan_low + 1e-3, pan_low + 360.0))
    endless = draw(st.booleans())
    tilt_low = draw(st.floats(-90.0, 89.0))
    tilt_high = draw(st.floats(tilt_low + 1e-3, 90.0))
    speed = st.floats(1e-2, 1e4)
    accel = st.floats(1e-2, 1e5)
    zoom_max_x = draw(st.floats(1.0, 100.0))
    log_zoom = math.log(zoom_max_x)
    zoom_rate = log_zoom / draw(st.floats(0.05, 60.0)) if log_zoom > 0 else 1.0
    return HeadLimits(
        pan=AxisLimits(
            draw(speed),
            draw(accel),
            low=-180.0 if endless else pan_low,
            high=180.0 if endless else pan_high,
            endless=endless,
            step=draw(st.floats(0.0, 1.0)),
            angular=True,
        ),
        tilt=AxisLimits(draw(speed), draw(accel), low=tilt_low, high=tilt_high, step=draw(st.floats(0.0, 1.0))),
        zoom=AxisLimits(zoom_rate, zoom_rate / 0.2, low=0.0, high=max(log_zoom, 1e-12)),
    )


@stress_settings(60)
@given(
    limits=heads(),
    start=st.tuples(st.sampled_from([0.0, 1.0]), st.sampled_from([0.0, 1.0]), st.sampled_from([0.0, 1.0])),
    goal=st.tuples(st.floats(-1e4, 1e4), st.floats(-1e4, 1e4), st.floats(1e-3, 1e3)),
    goal_velocity=st.tuples(st.floats(-1e5, 1e5), st.floats(-1e5, 1e5), st.floats(-1e3, 1e3)),
    fps=st.floats(1.0, 240.0),
)
def test_ptz_head_started_at_its_limits_stays_within_them(limits, start, goal, goal_velocity, fps):
    """From rest at any corner of the pan/tilt/zoom ranges, chasing goals far beyond them with goal
    velocities beyond the head's speed, 200 control steps keep every state finite, every speed within
    v_max, every change of speed within a_max·dt, the range limits held and the zoom within
    [1, zoom_max]."""

    def corner(axis, which):
        return axis.high if which else axis.low

    pan0 = 0.0 if limits.pan.endless else corner(limits.pan, start[0])
    pose = HeadPose(pan0, corner(limits.tilt, start[1]), math.exp(corner(limits.zoom, start[2])))
    command = Command(
        goal[0],
        goal[1],
        goal[2],
        pan_deg_s=goal_velocity[0],
        tilt_deg_s=goal_velocity[1],
        log_zoom_per_s=goal_velocity[2],
    )
    dt = 1.0 / fps / math.ceil(1.0 / fps / 0.01)
    for _ in range(200):
        after = step_head(pose, command, limits, dt)
        values = np.array(
            [after.pan_deg, after.tilt_deg, after.zoom_x, after.pan_deg_s, after.tilt_deg_s, after.log_zoom_per_s]
        )
        assert np.isfinite(values).all()
        for axis, v0, v1, position in (
            (limits.pan, pose.pan_deg_s, after.pan_deg_s, after.pan_deg),
            (limits.tilt, pose.tilt_deg_s, after.tilt_deg_s, after.tilt_deg),
            (limits.zoom, pose.log_zoom_per_s, after.log_zoom_per_s, math.log(after.zoom_x)),
        ):
            assert abs(v1) <= axis.speed_max * (1 + 1e-9) + 1e-12
            assert abs(v1 - v0) <= axis.accel_max * dt * (1 + 1e-9) + 1e-12
            if not axis.endless:
                span = axis.high - axis.low
                assert axis.low - 1e-9 * (1 + span) <= position <= axis.high + 1e-9 * (1 + span)
        pose = after
