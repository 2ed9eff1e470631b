"""camgen.sim.head: a PTZ head under ONVIF commands, against closed forms of its trapezoidal motion."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from camgen.config import load_profile, load_scene
from camgen.errors import ConfigError
from camgen.motion.ptz import AxisLimits, HeadLimits
from camgen.plan.ptz import ZOOM_RAMP_S, head_limits
from camgen.sim import AbsoluteMove, CommandError, ContinuousMove, GotoPreset, RelativeMove, SetPreset, Stop
from camgen.sim.head import CommandedHead
from tests.conftest import write

PAN_SPEED, PAN_ACCEL = 100.0, 200.0  # deg/s, deg/s²
TILT_SPEED, TILT_ACCEL = 60.0, 150.0
LATENCY_S = 0.1
DT_S = 0.01  # the servo period simulate_head uses at 10 fps (10 control steps a frame)


def _head(latency_s: float = LATENCY_S) -> CommandedHead:
    limits = HeadLimits(
        pan=AxisLimits(PAN_SPEED, PAN_ACCEL, low=-170.0, high=170.0, angular=True),
        tilt=AxisLimits(TILT_SPEED, TILT_ACCEL, low=-90.0, high=10.0),
        zoom=AxisLimits(1.15, 5.75, low=0.0, high=math.log(10.0)),
    )
    return CommandedHead(limits, 0.0, -12.0, 1.5, latency_s, {"gate": (30.0, -20.0, 2.0)})


def _run(head: CommandedHead, start_s: float, duration_s: float) -> tuple[list[float], list[str]]:
    """Advance control step by control step; the pan rate after each."""
    rates, events = [], []
    for k in range(round(duration_s / DT_S)):
        events += head.advance(start_s + k * DT_S, 1, DT_S)
        rates.append(head.pan.velocity)
    return rates, events


def test_continuous_move_waits_for_the_latency_then_accelerates_to_the_max_speed():
    head = _head()
    head.command(ContinuousMove(pan=1.0), 0.0, "test")
    assert head.status(0.0).pan_tilt == "MOVING"  # given, not yet acting: a controller must not give it again
    rates, events = _run(head, 0.0, 1.0)
    latency_steps = round(LATENCY_S / DT_S)
    assert rates[:latency_steps] == [0.0] * latency_steps
    # Then +a·dt each servo step (2 deg/s) until the max speed, reached after v/a = 0.5 s.
    ramp = rates[latency_steps : latency_steps + 50]
    assert ramp == pytest.approx([PAN_ACCEL * DT_S * (k + 1) for k in range(50)])
    assert rates[latency_steps + 50 :] == pytest.approx([PAN_SPEED] * (len(rates) - latency_steps - 50))
    # Position: ½·a·t² over the ramp (discrete sum), then v·t.
    expected_deg = sum(PAN_ACCEL * DT_S * (k + 1) * DT_S for k in range(50)) + PAN_SPEED * 0.4
    assert head.pan.position == pytest.approx(expected_deg)
    assert events == []


def test_half_velocity_caps_the_speed_at_half_the_max():
    head = _head(latency_s=0.0)
    head.command(ContinuousMove(pan=-0.5, tilt=0.25), 0.0, "test")
    _run(head, 0.0, 1.0)
    assert head.pan.velocity == pytest.approx(-0.5 * PAN_SPEED)
    assert head.tilt.velocity == pytest.approx(0.25 * TILT_SPEED)


def test_stop_brakes_at_the_head_deceleration_and_then_reports_idle():
    head = _head(latency_s=0.0)
    head.command(ContinuousMove(pan=1.0), 0.0, "test")
    _run(head, 0.0, 0.6)
    assert head.pan.velocity == pytest.approx(PAN_SPEED)
    head.command(Stop(), 0.6, "test")
    rates, _ = _run(head, 0.6, 0.6)
    assert rates[:50] == pytest.approx([PAN_SPEED - PAN_ACCEL * DT_S * (k + 1) for k in range(50)])
    status = head.status(1.2)
    assert status.pan_tilt == status.zoom == "IDLE" and status.pan_deg_s == 0.0


def test_absolute_move_arrives_and_get_status_says_idle():
    head = _head()
    head.command(AbsoluteMove(pan_deg=40.0, tilt_deg=-30.0, zoom_x=3.0), 0.0, "test")
    _run(head, 0.0, 0.5)
    assert head.status(0.5).pan_tilt == "MOVING"
    _run(head, 0.5, 2.0)
    status = head.status(2.5)
    assert (status.pan_tilt, status.zoom) == ("IDLE", "IDLE")
    assert status.pan_deg == pytest.approx(40.0, abs=1e-3)
    assert status.tilt_deg == pytest.approx(-30.0, abs=1e-3)
    assert status.zoom_x == pytest.approx(3.0, rel=1e-3)


def test_goals_outside_the_range_are_clamped_and_reported():
    head = _head(latency_s=0.0)
    # Tilt 50° is above the 10° stop; pan 400° is 40° one turn down, inside the range (not a clamp).
    head.command(AbsoluteMove(pan_deg=400.0, tilt_deg=50.0, zoom_x=40.0), 0.0, "test")
    _, events = _run(head, 0.0, 3.0)
    assert events == [
        "tilt: AbsoluteMove to 50° is outside the range [-90°, 10°]; clamped to 10°",
        "zoom: AbsoluteMove to 40× is outside the range [1×, 10×]; clamped to 10×",
    ]
    status = head.status(3.0)
    assert status.pan_deg == pytest.approx(40.0, abs=1e-3) and status.tilt_deg == pytest.approx(10.0, abs=1e-3)
    # A relative move past the tilt stop (a pan bearing is taken at its turn inside the range instead:
    # +200° from 40° is 240° = −120°, where a real head goes the short way).
    head.command(RelativeMove(pan_deg=200.0, tilt_deg=-120.0), 3.0, "test")
    _, events = _run(head, 3.0, 4.0)
    assert events == ["tilt: RelativeMove to -110° is outside the range [-90°, 10°]; clamped to -90°"]
    status = head.status(7.0)
    assert status.pan_deg == pytest.approx(-120.0, abs=1e-3) and status.tilt_deg == pytest.approx(-90.0, abs=1e-3)


def test_get_status_reports_a_clamp_until_the_next_command_acts():
    head = _head(latency_s=LATENCY_S)
    head.command(AbsoluteMove(pan_deg=20.0, tilt_deg=50.0, zoom_x=40.0), 0.0, "test")
    assert head.status(0.0).clamp is None and head.status(0.0).error is None  # given, not acting yet
    _run(head, 0.0, 3.0)
    status = head.status(3.0)
    assert status.pan_tilt == status.zoom == "IDLE"  # arrived where it could: a real head stops short
    assert status.tilt_deg == pytest.approx(10.0, abs=1e-3) and status.zoom_x == pytest.approx(10.0, rel=1e-3)
    clamp = status.clamp
    assert clamp.command == "AbsoluteMove"
    assert (clamp.requested_pan_deg, clamp.clamped_pan_deg) == (None, None)  # 20° lies inside the range
    assert (clamp.requested_tilt_deg, clamp.clamped_tilt_deg) == (50.0, 10.0)
    assert clamp.requested_zoom_x == pytest.approx(40.0) and clamp.clamped_zoom_x == pytest.approx(10.0)
    assert status.error == (
        "tilt: AbsoluteMove to 50° is outside the range [-90°, 10°]; clamped to 10°; "
        "zoom: AbsoluteMove to 40× is outside the range [1×, 10×]; clamped to 10×"
    )
    # A relative move's request is the goal it adds up to; SetPreset leaves the clamp reported.
    head.command(RelativeMove(tilt_deg=-120.0), 3.0, "test")
    head.command(SetPreset("low"), 3.0, "test")
    _run(head, 3.0, 4.0)
    clamp = head.status(7.0).clamp
    assert clamp.command == "RelativeMove" and (clamp.requested_tilt_deg, clamp.clamped_tilt_deg) == (-110.0, -90.0)
    assert clamp.requested_zoom_x is None
    # The next move inside the range clears it once it acts.
    head.command(AbsoluteMove(tilt_deg=-30.0), 7.0, "test")
    assert head.status(7.0).clamp == clamp
    _run(head, 7.0, 0.2)
    assert head.status(7.2).clamp is None and head.status(7.2).error is None


def test_continuous_move_stops_at_a_range_end_and_says_so():
    head = _head(latency_s=0.0)
    head.command(ContinuousMove(tilt=1.0), 0.0, "test")
    _, events = _run(head, 0.0, 1.5)
    assert events == ["tilt: ContinuousMove stopped at the range end 10°"]
    assert head.tilt.position == pytest.approx(10.0) and head.status(1.5).pan_tilt == "IDLE"


def test_continuous_move_timeout_brakes_the_head():
    head = _head(latency_s=0.0)
    head.command(ContinuousMove(pan=1.0, timeout_s=0.3), 0.0, "test")
    rates, _ = _run(head, 0.0, 1.0)
    assert max(rates) == pytest.approx(PAN_ACCEL * 0.3, rel=0.05)
    assert head.status(1.0).pan_tilt == "IDLE"


def test_presets_store_and_recall_positions():
    head = _head(latency_s=0.0)
    head.command(GotoPreset("gate"), 0.0, "test")
    _run(head, 0.0, 2.0)
    assert head.status(2.0).pan_deg == pytest.approx(30.0, abs=1e-3)
    head.command(RelativeMove(pan_deg=-10.0), 2.0, "test")
    _run(head, 2.0, 1.0)
    head.command(SetPreset("door"), 3.0, "test")
    head.command(GotoPreset("gate"), 3.0, "test")
    _run(head, 3.0, 1.0)
    head.command(GotoPreset("door"), 4.0, "test")
    _run(head, 4.0, 1.0)
    assert head.status(5.0).pan_deg == pytest.approx(20.0, abs=1e-3)


@pytest.mark.parametrize(
    ("command", "message"),
    [
        (ContinuousMove(pan=1.5), r"pan must lie in ONVIF's normalised space \[-1, 1\].*got 1.5"),
        (ContinuousMove(zoom=math.nan), "zoom must be a finite number, got nan"),
        (AbsoluteMove(pan_deg=math.inf), "pan_deg must be a finite number"),
        (AbsoluteMove(pan_deg=10.0, speed=0.0), r"speed must lie in ONVIF's generic speed space \(0, 1\]"),
        (RelativeMove(zoom_ratio=0.0), "zoom_ratio must be > 0"),
        (GotoPreset("nowhere"), r"no preset 'nowhere' \(presets: gate\); store it with SetPreset"),
    ],
)
def test_malformed_commands_are_refused_and_the_head_carries_on(command, message):
    head = _head(latency_s=0.0)
    with pytest.raises(CommandError, match=message):
        head.command(command, 0.0, "dome")
    _run(head, 0.0, 0.1)
    assert head.status(0.1).pan_tilt == "IDLE" and head.pan.position == 0.0


def test_command_latency_is_a_validated_profile_key(tmp_path):
    base = (
        "sensor: {width_px: 64, height_px: 48, pixel_pitch_um: 3, full_well_e: 10000, conversion_gain_dn_per_e: 0.4}\n"
    )
    base += "lens: {focal_length_range_mm: [4, 40], f_number: 1.6}\n"
    assert load_profile(write(tmp_path, "default.yaml", base + "ptz: {}\n")).profile.ptz.command_latency_s == 0.1
    path = write(tmp_path, "bad.yaml", base + "ptz:\n  command_latency_s: -0.05\n")
    with pytest.raises(ConfigError, match=r"bad.yaml:4:3: ptz.command_latency_s must be ≥ 0, got -0.05; IP PTZ"):
        load_profile(path)


@pytest.mark.parametrize("command", [AbsoluteMove(zoom_x=30.0), ContinuousMove(zoom=1.0)])
def test_a_wide_to_tele_zoom_takes_the_profiles_datasheet_time(command):
    """ptz_follow's dome (ptz_2mp_30x, 4.5–135 mm: 30×) zooms from the wide to the tele end in
    `ptz.zoom_wide_to_tele_s`, plus the motor's ramp up to its rate and down from it."""
    loaded = load_scene(Path(__file__).parents[2] / "scenes" / "ptz_follow.yaml")
    camera = loaded.scene.cameras[0]
    profile = loaded.profiles[camera.name].profile
    head = CommandedHead(head_limits(camera, profile), 0.0, -12.0, 1.0, latency_s=0.0)
    head.command(command, 0.0, "test")
    sweep_s = profile.ptz.zoom_wide_to_tele_s
    _run(head, 0.0, sweep_s - 0.1)
    assert head.status(sweep_s - 0.1).zoom == "MOVING" and head.status(sweep_s - 0.1).zoom_x < 29.0
    _run(head, sweep_s - 0.1, ZOOM_RAMP_S + 0.1 + 2 * DT_S)
    status = head.status(sweep_s + ZOOM_RAMP_S + 2 * DT_S)
    assert status.zoom_x == pytest.approx(30.0, rel=1e-3) and status.zoom == "IDLE"


def test_a_head_response_key_out_of_bounds_is_located_and_explained(tmp_path):
    base = (
        "sensor: {width_px: 64, height_px: 48, pixel_pitch_um: 3, full_well_e: 10000, conversion_gain_dn_per_e: 0.4}\n"
    )
    base += "lens: {focal_length_range_mm: [4, 40], f_number: 1.6}\n"
    defaults = load_profile(write(tmp_path, "default.yaml", base + "ptz: {}\n")).profile.ptz
    assert (defaults.autofocus_time_s, defaults.zoom_wide_to_tele_s) == (0.5, 3.5)
    path = write(tmp_path, "slow_focus.yaml", base + "ptz:\n  pan_max_deg_s: 90\n  autofocus_time_s: 30\n")
    with pytest.raises(
        ConfigError, match=r"slow_focus.yaml:5:3: ptz.autofocus_time_s must be ≤ 10, got 30; contrast-detection"
    ):
        load_profile(path)
    path = write(tmp_path, "no_zoom_time.yaml", base + "ptz:\n  zoom_wide_to_tele_s: 0\n")
    with pytest.raises(ConfigError, match=r"no_zoom_time.yaml:4:3: ptz.zoom_wide_to_tele_s must be > 0, got 0; a zoom"):
        load_profile(path)
