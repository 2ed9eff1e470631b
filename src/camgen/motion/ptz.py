"""PTZ head kinematics: pan, tilt and zoom axes under speed, acceleration, range and step limits.

Each axis is a double integrator driven in discrete time with control period dt (a servo loop): per
step its velocity changes by at most a·dt (|Δv| ≤ a_max·dt), stays within ±v_max, and the position
advances by v·dt. Towards a goal the axis accelerates, cruises and brakes — a trapezoidal velocity
profile — using the *discrete* braking curve (`braking_speed`), so it lands on a still goal without
overshoot and never crosses a range limit: at every step it can still stop before the limit, and that
stays true after one step of full braking, so no later step can be forced past it.

Units: pan and tilt in degrees, zoom as ln(zoom_x) (a zoom motor sweeps magnification at a roughly
constant rate in log scale: equal time for 1×→2× and 10×→20×). An endless pan axis keeps an
unwrapped position inside and takes the short way to a goal; `HeadTrack` reports it wrapped to
[−180°, 180°). Mechanical step resolution is applied to the reported positions only (the motor's
commanded profile is continuous; the head stops on the nearest step).

The head frame (`camgen.motion.pose`): pan turns counter-clockwise about the mount's up axis, tilt
raises the optical axis; tilt = ±90° looks straight down/up and every formula here stays finite there.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

CONTROL_PERIOD_MAX_S = 0.01
"""Longest servo-loop period, s: frames are split into this many control steps or more."""


@dataclass(frozen=True)
class AxisLimits:
    """What one axis can do. Units: deg, deg/s, deg/s² for pan and tilt; ln(zoom) for zoom."""

    speed_max: float
    accel_max: float
    low: float = -math.inf
    high: float = math.inf
    endless: bool = False
    """Continuous rotation (slip ring): no range, goals are reached the short way round."""
    step: float = 0.0
    """Mechanical resolution of the reported position (0 = continuous)."""
    angular: bool = False
    """Positions are angles in degrees: a goal outside the range is first taken at the turn (±360°)
    that lies in it, nearest the position (a pan range of [−90°, 270°] reaches a bearing of −170° as
    190°); a goal inside the range is taken as given."""

    def __post_init__(self) -> None:
        if not (self.speed_max > 0 and self.accel_max > 0):
            raise ValueError(f"speed_max and accel_max must be > 0, got {self.speed_max}, {self.accel_max}")
        if not self.endless and not self.low < self.high:
            raise ValueError(f"low must be < high, got [{self.low}, {self.high}]")


def wrap_deg(angle_deg):
    """Angle(s) wrapped to [−180°, 180°)."""
    return (np.asarray(angle_deg, dtype=np.float64) + 180.0) % 360.0 - 180.0


def braking_speed(distance: float, accel: float, dt: float) -> float:
    """Largest speed from which a discrete-time axis stops within `distance`.

    With control period dt and deceleration a per step, a speed v = (n + θ)·a·dt runs the steps
    v, v − a·dt, …, v − n·a·dt (all positive) and covers dt·[(n + 1)·v − a·dt·n(n + 1)/2]. Solving
    for v at a given distance D gives n = ⌈(√(1 + 8·D/(a·dt²)) − 3)/2⌉ and
    v = (D/dt + a·dt·n(n + 1)/2)/(n + 1): the continuous curve √(2·a·D) corrected for sampling.
    """
    if distance <= 0.0:
        return 0.0
    if math.isinf(distance):
        return math.inf
    quantum = accel * dt  # velocity change per step
    steps = distance / dt / quantum  # D / (a·dt²)
    n = max(0, math.ceil((math.sqrt(1.0 + 8.0 * steps) - 3.0) / 2.0))
    return (distance / dt + quantum * n * (n + 1) / 2.0) / (n + 1)


def axis_error(goal: float, position: float, limits: AxisLimits) -> float:
    """Signed distance to the goal: the short way round on an endless axis, else to the goal
    clamped into the range (a goal beyond a limit is approached up to the limit)."""
    if limits.endless:
        return float(wrap_deg(goal - position))
    if limits.angular and not limits.low <= goal <= limits.high:
        turns = [goal + 360.0 * k for k in (-2, -1, 1, 2) if limits.low <= goal + 360.0 * k <= limits.high]
        if turns:
            goal = min(turns, key=lambda g: abs(g - position))
    return min(max(goal, limits.low), limits.high) - position


def step_axis(
    position: float,
    velocity: float,
    goal: float,
    limits: AxisLimits,
    dt: float,
    *,
    goal_velocity: float = 0.0,
    speed_cap: float | None = None,
) -> tuple[float, float]:
    """One control step towards `goal` (moving at `goal_velocity`); returns (position, velocity).

    The commanded velocity is goal_velocity + sign(e)·braking_speed(|e|), limited to ±min(v_max,
    speed_cap), to what still stops before each range limit, and to velocity ± a_max·dt. A speed cap
    below the current speed is reached by braking at a_max, never by a jump.
    """
    accel = limits.accel_max
    speed = limits.speed_max if speed_cap is None else min(limits.speed_max, speed_cap)
    error = axis_error(goal, position, limits)
    wanted = goal_velocity + math.copysign(braking_speed(abs(error), accel, dt), error)
    wanted = min(max(wanted, -speed), speed)
    if not limits.endless:
        wanted = min(wanted, braking_speed(limits.high - position, accel, dt))
        wanted = max(wanted, -braking_speed(position - limits.low, accel, dt))
    new_velocity = min(max(wanted, velocity - accel * dt), velocity + accel * dt)
    return position + new_velocity * dt, new_velocity


@dataclass(frozen=True)
class HeadLimits:
    pan: AxisLimits
    tilt: AxisLimits
    zoom: AxisLimits
    """In ln(zoom_x): low 0 (wide end), high ln(zoom_max_x)."""


@dataclass(frozen=True)
class HeadPose:
    """Where the head is now (pan unwrapped on an endless axis) and how fast it moves."""

    pan_deg: float
    tilt_deg: float
    zoom_x: float
    pan_deg_s: float = 0.0
    tilt_deg_s: float = 0.0
    log_zoom_per_s: float = 0.0


@dataclass(frozen=True)
class Command:
    """What a program asks of the head at one control step."""

    pan_deg: float
    tilt_deg: float
    zoom_x: float
    pan_deg_s: float = 0.0
    """Velocity of a moving goal (feed-forward), deg/s."""
    tilt_deg_s: float = 0.0
    log_zoom_per_s: float = 0.0
    pan_speed_cap_deg_s: float | None = None
    """Slower than the head's maximum for this move (a program's speed), deg/s."""
    tilt_speed_cap_deg_s: float | None = None
    mode: str = "hold"
    """What the program is doing, for the per-frame metadata (hold, move, dwell, scan, follow, …)."""
    target: str | None = None
    """The actor being followed, if any."""


Controller = Callable[[float, HeadPose], Command]
"""program(time_s, pose) → Command; may keep state between calls (called in time order)."""


def step_head(pose: HeadPose, command: Command, limits: HeadLimits, dt: float) -> HeadPose:
    """One control step of all three axes."""
    pan, pan_v = step_axis(
        pose.pan_deg,
        pose.pan_deg_s,
        command.pan_deg,
        limits.pan,
        dt,
        goal_velocity=command.pan_deg_s,
        speed_cap=command.pan_speed_cap_deg_s,
    )
    tilt, tilt_v = step_axis(
        pose.tilt_deg,
        pose.tilt_deg_s,
        command.tilt_deg,
        limits.tilt,
        dt,
        goal_velocity=command.tilt_deg_s,
        speed_cap=command.tilt_speed_cap_deg_s,
    )
    log_zoom, zoom_v = step_axis(
        math.log(pose.zoom_x),
        pose.log_zoom_per_s,
        math.log(command.zoom_x),
        limits.zoom,
        dt,
        goal_velocity=command.log_zoom_per_s,
    )
    # Float rounding on the last braking step may leave a limit behind by ~1e-15: that is not a move.
    log_zoom = min(max(log_zoom, limits.zoom.low), limits.zoom.high)
    return HeadPose(pan, tilt, math.exp(log_zoom), pan_v, tilt_v, zoom_v)


@dataclass(frozen=True)
class HeadTrack:
    """A head's motion sampled at frame times (each array (F,))."""

    time_s: np.ndarray
    pan_deg: np.ndarray
    """Wrapped to [−180°, 180°) on an endless axis; quantised to the pan step."""
    tilt_deg: np.ndarray
    zoom_x: np.ndarray
    pan_unwrapped_deg: np.ndarray
    """Continuous (not wrapped, not quantised): the motor's profile."""
    pan_deg_s: np.ndarray
    tilt_deg_s: np.ndarray
    log_zoom_per_s: np.ndarray
    modes: tuple[str, ...]
    targets: tuple[str | None, ...]


def control_steps_per_frame(frame_interval_s: float) -> int:
    return max(1, math.ceil(frame_interval_s / CONTROL_PERIOD_MAX_S - 1e-9))


def quantize(values: np.ndarray, step: float) -> np.ndarray:
    return values if step <= 0 else np.round(values / step) * step


def simulate_head(
    program: Controller,
    limits: HeadLimits,
    start: HeadPose,
    frame_count: int,
    fps: float,
    *,
    steps_per_frame: int | None = None,
) -> HeadTrack:
    """Run `program` on the head from `start` (at rest, time 0) and sample every frame time k/fps.

    The program is asked for a command at every control step (period 1/(fps·steps_per_frame)); the
    frame's state is the head's at the frame time.
    """
    steps = steps_per_frame or control_steps_per_frame(1.0 / fps)
    dt = 1.0 / (fps * steps)
    pose = start
    rows: list[tuple[float, ...]] = []
    modes: list[str] = []
    targets: list[str | None] = []
    command = program(0.0, pose)
    for frame in range(frame_count):
        rows.append((pose.pan_deg, pose.tilt_deg, pose.zoom_x, pose.pan_deg_s, pose.tilt_deg_s, pose.log_zoom_per_s))
        modes.append(command.mode)
        targets.append(command.target)
        for k in range(steps):
            time_s = (frame * steps + k) / (fps * steps)
            command = program(time_s, pose)
            pose = step_head(pose, command, limits, dt)
    table = np.array(rows, dtype=np.float64).reshape(-1, 6)
    pan = table[:, 0]
    reported_pan = wrap_deg(pan) if limits.pan.endless else pan
    return HeadTrack(
        time_s=np.arange(frame_count) / fps,
        pan_deg=quantize(reported_pan, limits.pan.step),
        tilt_deg=quantize(table[:, 1], limits.tilt.step),
        zoom_x=table[:, 2],
        pan_unwrapped_deg=pan,
        pan_deg_s=table[:, 3],
        tilt_deg_s=table[:, 4],
        log_zoom_per_s=table[:, 5],
        modes=tuple(modes),
        targets=tuple(targets),
    )


def bearing_deg(points_m: np.ndarray, mount_position_m: Sequence[float], R_world_from_mount: np.ndarray):
    """Pan and tilt (degrees) that point the head's optical axis at world point(s) (..., 3).

    Pan = atan2(y, x) and tilt = atan2(z, √(x² + y²)) in the mount frame (x forward, y left, z up).
    Straight above or below the mount the pan is 0 (any pan looks there): finite, never NaN.
    """
    d = (np.asarray(points_m, dtype=np.float64) - np.asarray(mount_position_m, dtype=np.float64)) @ R_world_from_mount
    horizontal = np.hypot(d[..., 0], d[..., 1])
    return np.degrees(np.arctan2(d[..., 1], d[..., 0])), np.degrees(np.arctan2(d[..., 2], horizontal))
