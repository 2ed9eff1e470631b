"""A PTZ head driven by commands (`camgen.sim.commands`) instead of a program.

The axes are `camgen.motion.ptz`'s: each control step runs `step_axis` (speed, acceleration, range
and the discrete braking curve), so a commanded head accelerates, cruises and brakes exactly as a
programmed one does. What a command adds:

- latency: a command takes effect `command_latency_s` (the profile's `ptz.command_latency_s`) after it
  is given; commands given together take effect in the order given;
- ContinuousMove: each axis runs towards its range end in the velocity's direction (an endless pan
  towards a goal `CARROT_DEG` ahead) with its speed capped at |v| of the fastest; it stops at a range
  end (reported) and brakes when the move's timeout ends;
- AbsoluteMove, RelativeMove, GotoPreset: each axis goes to its goal at `speed` of the fastest; a goal
  outside the range is clamped to it as a real head does, and the clamp is reported (in the step's
  events, and in GetStatus's `clamp` until the next command acts);
- Stop: the axes brake at their deceleration (a speed cap of 0), then rest.

An axis at rest is not stepped, so a head that is never commanded stays exactly where it started.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from camgen.motion.programs import ARRIVED_DEG, ARRIVED_DEG_S, ARRIVED_LOG_ZOOM, CARROT_DEG
from camgen.motion.ptz import AxisLimits, HeadLimits, quantize, step_axis, wrap_deg
from camgen.sim.commands import (
    AbsoluteMove,
    Clamp,
    Command,
    CommandError,
    ContinuousMove,
    GotoPreset,
    PtzStatus,
    RelativeMove,
    SetPreset,
    Stop,
)

RANGE_END_TOLERANCE = 1e-9
"""An axis this close to a range end, at rest, has reached it (deg, or ln zoom)."""


@dataclass
class _Axis:
    """One axis: where it is, how fast it moves, and what it was told (rest, goal or velocity)."""

    name: str
    limits: AxisLimits
    position: float
    velocity: float = 0.0
    mode: str = "rest"
    """rest (not stepped), stop (braking to rest), goal (to `goal`) or velocity (towards `direction`)."""
    goal: float = 0.0
    direction: float = 0.0
    speed_cap: float = math.inf
    until_s: float = math.inf
    """A ContinuousMove's timeout: when the axis starts braking, s."""
    arrived: float = ARRIVED_DEG
    arrived_speed: float = ARRIVED_DEG_S

    def step(self, dt: float, time_s: float, events: list[str]) -> None:
        if self.mode == "rest":
            return
        if self.mode == "velocity" and time_s >= self.until_s - 1e-9:
            self.mode = "stop"
        if self.mode == "stop":
            self.position, self.velocity = step_axis(
                self.position, self.velocity, self.position, self.limits, dt, speed_cap=0.0
            )
            if self.velocity == 0.0:
                self.mode = "rest"
            return
        limits = self.limits
        if self.mode == "velocity":
            if limits.endless:
                goal = self.position + math.copysign(CARROT_DEG, self.direction)
            else:
                goal = limits.high if self.direction > 0 else limits.low
        else:
            goal = self.goal
        self.position, self.velocity = step_axis(
            self.position, self.velocity, goal, limits, dt, speed_cap=self.speed_cap
        )
        if not limits.endless:
            # Float rounding on the last braking step may leave a limit behind by ~1e-15: that is not a move.
            self.position = min(max(self.position, limits.low), limits.high)
        if self.mode == "velocity" and not limits.endless and self.velocity == 0.0:
            end = limits.high if self.direction > 0 else limits.low
            if abs(self.position - end) <= RANGE_END_TOLERANCE:
                events.append(f"{self.name}: ContinuousMove stopped at the range end {_shown(self.name, end)}")
                self.mode = "rest"
        elif self.mode == "goal" and abs(self.velocity) <= self.arrived_speed:
            error = float(wrap_deg(self.goal - self.position)) if limits.endless else self.goal - self.position
            if abs(error) <= self.arrived:
                self.velocity, self.mode = 0.0, "rest"

    @property
    def moving(self) -> bool:
        return self.mode != "rest"


def _axes_moved(command: Command) -> tuple[bool, bool]:
    """Whether a command moves (or stops) pan/tilt, and the zoom."""
    if isinstance(command, SetPreset):
        return False, False
    if isinstance(command, Stop):
        return command.pan_tilt, command.zoom
    if isinstance(command, ContinuousMove):
        return True, command.zoom != 0.0
    if isinstance(command, AbsoluteMove):
        return command.pan_deg is not None or command.tilt_deg is not None, command.zoom_x is not None
    if isinstance(command, RelativeMove):
        return command.pan_deg != 0.0 or command.tilt_deg != 0.0, command.zoom_ratio != 1.0
    return True, True


def _shown(axis: str, value: float) -> str:
    return f"{math.exp(value):.4g}×" if axis == "zoom" else f"{value:g}°"


@dataclass
class CommandedHead:
    """A head at `pan_deg`, `tilt_deg`, `zoom_x` (at rest), with `limits`, commands taking effect
    `latency_s` after they are given, and named presets (pan_deg, tilt_deg, zoom_x)."""

    limits: HeadLimits
    pan_deg: float
    tilt_deg: float
    zoom_x: float
    latency_s: float
    presets: dict[str, tuple[float, float, float]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.pan = _Axis("pan", self.limits.pan, self.pan_deg)
        self.tilt = _Axis("tilt", self.limits.tilt, self.tilt_deg)
        self.zoom = _Axis(
            "zoom", self.limits.zoom, math.log(self.zoom_x), arrived=ARRIVED_LOG_ZOOM, arrived_speed=ARRIVED_LOG_ZOOM
        )
        self._home_zoom_x = self.zoom_x
        self._pending: list[tuple[float, Command]] = []
        self.moved = False
        """Whether any axis has moved: until then the status reports the start exactly."""
        self._now_s = 0.0
        self._clamp: Clamp | None = None
        """The clamp of the last command that acted (GetStatus reports it)."""

    # --- commands --------------------------------------------------------------------------------

    def command(self, command: Command, time_s: float, where: str) -> None:
        """Accept `command` given at `time_s`; it acts `latency_s` later. Refuses a malformed one."""
        command.check(where)
        if isinstance(command, GotoPreset) and command.name not in self.presets:
            names = ", ".join(sorted(self.presets)) or "none stored"
            raise CommandError(f"{where}: no preset {command.name!r} (presets: {names}); store it with SetPreset")
        self._pending.append((time_s + self.latency_s, command))
        if isinstance(command, SetPreset):  # stored at once, so a GotoPreset after it in the same step finds it
            self.presets.setdefault(command.name, (math.nan, math.nan, math.nan))

    def _apply(self, command: Command, events: list[str]) -> None:
        axes = (self.pan, self.tilt, self.zoom)
        if not isinstance(command, SetPreset):
            self._clamp = None
        if isinstance(command, Stop):
            for axis in (self.pan, self.tilt) if command.pan_tilt else ():
                axis.mode = "stop" if axis.moving else "rest"
            if command.zoom:
                self.zoom.mode = "stop" if self.zoom.moving else "rest"
        elif isinstance(command, ContinuousMove):
            for axis, v in zip(axes, (command.pan, command.tilt, command.zoom), strict=True):
                if v == 0.0:
                    axis.mode = "stop" if axis.moving else "rest"
                    continue
                axis.mode, axis.direction = "velocity", v
                axis.speed_cap = abs(v) * axis.limits.speed_max
                axis.until_s = math.inf if command.timeout_s is None else self._now_s + command.timeout_s
        elif isinstance(command, SetPreset):
            self.presets[command.name] = (self.status(self._now_s).pan_deg, self.tilt.position, self._zoom_x())
        else:
            if isinstance(command, AbsoluteMove):
                goals = (
                    command.pan_deg,
                    command.tilt_deg,
                    None if command.zoom_x is None else math.log(command.zoom_x) if command.zoom_x > 0 else -math.inf,
                )
            elif isinstance(command, RelativeMove):
                goals = (
                    self.pan.position + command.pan_deg,
                    self.tilt.position + command.tilt_deg,
                    self.zoom.position + math.log(command.zoom_ratio),
                )
            else:  # GotoPreset
                pan, tilt, zoom_x = self.presets[command.name]
                goals = (pan, tilt, math.log(zoom_x))
            name = type(command).__name__
            requested: dict[str, float] = {}
            clamped: dict[str, float] = {}
            messages: list[str] = []
            for axis, goal in zip(axes, goals, strict=True):
                if goal is None:
                    continue
                axis.goal, message = self._clamped(axis, goal, name)
                axis.mode, axis.speed_cap = "goal", command.speed * axis.limits.speed_max
                if message:
                    messages.append(message)
                    to_value = math.exp if axis.name == "zoom" else float
                    requested[axis.name], clamped[axis.name] = to_value(goal), to_value(axis.goal)
            if messages:
                events.extend(messages)
                self._clamp = Clamp(
                    name,
                    requested_pan_deg=requested.get("pan"),
                    requested_tilt_deg=requested.get("tilt"),
                    requested_zoom_x=requested.get("zoom"),
                    clamped_pan_deg=clamped.get("pan"),
                    clamped_tilt_deg=clamped.get("tilt"),
                    clamped_zoom_x=clamped.get("zoom"),
                    error="; ".join(messages),
                )

    def _clamped(self, axis: _Axis, goal: float, name: str) -> tuple[float, str]:
        """The goal a real head takes: an endless pan anywhere, a limited angle at the turn (±360°) in
        its range, else the range end nearest the goal; with what to report of a clamp ("" if none)."""
        limits = axis.limits
        if limits.endless:
            return goal, ""
        if limits.angular and not limits.low <= goal <= limits.high:
            turns = [goal + 360.0 * k for k in (-2, -1, 1, 2) if limits.low <= goal + 360.0 * k <= limits.high]
            if turns:
                return min(turns, key=lambda g: abs(g - axis.position)), ""
        clamped = min(max(goal, limits.low), limits.high)
        if clamped == goal:
            return goal, ""
        asked = f"{math.exp(goal):.4g}×" if axis.name == "zoom" and math.isfinite(goal) else _shown(axis.name, goal)
        return clamped, (
            f"{axis.name}: {name} to {asked} is outside the range "
            f"[{_shown(axis.name, limits.low)}, {_shown(axis.name, limits.high)}]; clamped to "
            f"{_shown(axis.name, clamped)}"
        )

    # --- time ---------------------------------------------------------------------------------------

    def advance(self, start_s: float, steps: int, dt: float) -> list[str]:
        """Run `steps` control steps of `dt` from `start_s`, applying the commands whose time has come
        at the start of each; returns what happened that a controller must hear of (clamps, range ends)."""
        events: list[str] = []
        for k in range(steps):
            self._now_s = start_s + k * dt
            due = [c for t, c in self._pending if t <= self._now_s + 1e-9]
            if due:
                self._pending = [(t, c) for t, c in self._pending if t > self._now_s + 1e-9]
                for command in due:
                    self._apply(command, events)
            for axis in (self.pan, self.tilt, self.zoom):
                if axis.moving:
                    self.moved = True
                axis.step(dt, self._now_s, events)
        self._now_s = start_s + steps * dt
        return events

    def _zoom_x(self) -> float:
        return math.exp(self.zoom.position) if self.moved else self._home_zoom_x

    def status(self, time_s: float) -> PtzStatus:
        """GetStatus at `time_s`: the reported position (pan wrapped on an endless head, on the step
        grid), IDLE or MOVING (a command given but not yet acting counts as moving) and the clamp of
        the last command that acted."""
        pending = [_axes_moved(command) for _, command in self._pending]
        pending_pan_tilt = any(pan_tilt for pan_tilt, _ in pending)
        pending_zoom = any(zoom for _, zoom in pending)
        pan = self.pan.position
        tilt = self.tilt.position
        if self.moved:
            pan = float(quantize(wrap_deg(pan) if self.limits.pan.endless else pan, self.limits.pan.step))
            tilt = float(quantize(tilt, self.limits.tilt.step))
        return PtzStatus(
            pan_deg=pan,
            tilt_deg=tilt,
            zoom_x=self._zoom_x(),
            pan_tilt="MOVING" if self.pan.moving or self.tilt.moving or pending_pan_tilt else "IDLE",
            zoom="MOVING" if self.zoom.moving or pending_zoom else "IDLE",
            time_s=time_s,
            pan_deg_s=self.pan.velocity,
            tilt_deg_s=self.tilt.velocity,
            log_zoom_per_s=self.zoom.velocity,
            clamp=self._clamp,
        )
