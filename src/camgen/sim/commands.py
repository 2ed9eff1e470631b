"""PTZ commands as the ONVIF PTZ service takes them (ONVIF PTZ Service Specification, §5.3 Move
operations, §5.4 Preset operations, §5.3.4 GetStatus).

Positions are in the camera's own units (pan and tilt in degrees relative to the mount, zoom as a
magnification), which is what ONVIF's spherical position spaces carry; velocities are ONVIF's generic
velocity space, normalised to [−1, 1] per axis, where ±1 is the head's fastest (the profile's
`ptz.pan_max_deg_s`, `tilt_max_deg_s`, and a full zoom sweep in `zoom_wide_to_tele_s`). A speed
argument (AbsoluteMove, RelativeMove, GotoPreset) is ONVIF's generic speed space, (0, 1] of the
fastest.

A position beyond the head's range is taken as a real head takes it: clamped to the range, reported
in the step's events and, until the next command acts, in GetStatus (`PtzStatus.clamp` and its
`error` text, ONVIF's PTZStatus Error); a value that is no number, or a velocity or speed outside its
normalised space, is refused with `CommandError` (ONVIF answers ter:InvalidVelocity /
ter:InvalidSpeed), and the head carries on as before.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

MoveStatus = Literal["IDLE", "MOVING"]
"""ONVIF's tt:MoveStatus (a device may also answer UNKNOWN; a simulated head always knows)."""


class CommandError(ValueError):
    """A command the head refuses (ONVIF: a SOAP fault); the simulation keeps running."""


def _finite(where: str, **values: float | None) -> None:
    for name, value in values.items():
        if value is not None and not math.isfinite(value):
            raise CommandError(f"{where}: {name} must be a finite number, got {value!r}")


def _normalised(where: str, low: float, **values: float | None) -> None:
    _finite(where, **values)
    for name, value in values.items():
        if value is not None and not low <= value <= 1.0:
            raise CommandError(
                f"{where}: {name} must lie in ONVIF's normalised space [{low:g}, 1] (1 = the head's fastest), "
                f"got {value:g}; scale the command into it"
            )


@dataclass(frozen=True)
class ContinuousMove:
    """Move at these velocities until stopped (or `timeout_s` after the head starts; None: until the
    next command). Each in [−1, 1] of the axis's fastest; pan > 0 turns counter-clockwise seen from
    above (to the left in the image), tilt > 0 up, zoom > 0 towards tele."""

    pan: float = 0.0
    tilt: float = 0.0
    zoom: float = 0.0
    timeout_s: float | None = None

    def check(self, where: str) -> None:
        _normalised(where, -1.0, pan=self.pan, tilt=self.tilt, zoom=self.zoom)
        _finite(where, timeout_s=self.timeout_s)
        if self.timeout_s is not None and self.timeout_s <= 0:
            raise CommandError(f"{where}: timeout_s must be > 0, got {self.timeout_s:g}; leave it None to move on")


@dataclass(frozen=True)
class AbsoluteMove:
    """Go to a position: pan and tilt in degrees, zoom as a magnification (None keeps that axis where it
    is); `speed` in (0, 1] of the fastest."""

    pan_deg: float | None = None
    tilt_deg: float | None = None
    zoom_x: float | None = None
    speed: float = 1.0

    def check(self, where: str) -> None:
        _finite(where, pan_deg=self.pan_deg, tilt_deg=self.tilt_deg, zoom_x=self.zoom_x)
        _speed(where, self.speed)


@dataclass(frozen=True)
class RelativeMove:
    """Move by a translation from where the head is: degrees of pan and tilt, and a zoom ratio (2 doubles
    the magnification); `speed` in (0, 1] of the fastest."""

    pan_deg: float = 0.0
    tilt_deg: float = 0.0
    zoom_ratio: float = 1.0
    speed: float = 1.0

    def check(self, where: str) -> None:
        _finite(where, pan_deg=self.pan_deg, tilt_deg=self.tilt_deg, zoom_ratio=self.zoom_ratio)
        if self.zoom_ratio <= 0:
            raise CommandError(f"{where}: zoom_ratio must be > 0 (1 keeps the zoom), got {self.zoom_ratio:g}")
        _speed(where, self.speed)


@dataclass(frozen=True)
class GotoPreset:
    """Go to a stored preset (the scene's `ptz.presets` or one made by SetPreset)."""

    name: str
    speed: float = 1.0

    def check(self, where: str) -> None:
        _speed(where, self.speed)


@dataclass(frozen=True)
class SetPreset:
    """Store the head's current position under `name` (replacing a preset of that name)."""

    name: str

    def check(self, where: str) -> None:
        if not self.name:
            raise CommandError(f"{where}: a preset needs a name, got an empty one")


@dataclass(frozen=True)
class Stop:
    """Stop pan/tilt and/or zoom: each axis brakes at the head's deceleration."""

    pan_tilt: bool = True
    zoom: bool = True

    def check(self, where: str) -> None:
        return None


def _speed(where: str, speed: float) -> None:
    _finite(where, speed=speed)
    if not 0.0 < speed <= 1.0:
        raise CommandError(
            f"{where}: speed must lie in ONVIF's generic speed space (0, 1] (1 = the head's fastest), got {speed:g}"
        )


Command = ContinuousMove | AbsoluteMove | RelativeMove | GotoPreset | SetPreset | Stop
COMMAND_TYPES = (ContinuousMove, AbsoluteMove, RelativeMove, GotoPreset, SetPreset, Stop)


@dataclass(frozen=True)
class Clamp:
    """A move whose goal lay beyond the head's range: what the command asked for and where the head
    went instead, per axis (None: that axis was inside its range, or not moved). A RelativeMove's
    request is the goal it adds up to (position + translation)."""

    command: str
    """AbsoluteMove, RelativeMove or GotoPreset."""
    requested_pan_deg: float | None = None
    requested_tilt_deg: float | None = None
    requested_zoom_x: float | None = None
    clamped_pan_deg: float | None = None
    clamped_tilt_deg: float | None = None
    clamped_zoom_x: float | None = None
    error: str = ""
    """The clamp in words, one sentence an axis ("tilt: AbsoluteMove to 50° is outside the range
    [-90°, 10°]; clamped to 10°"), as the step's events say it."""


@dataclass(frozen=True)
class PtzStatus:
    """GetStatus: where the head is and whether it moves (ONVIF tt:PTZStatus: Position, MoveStatus,
    Error, UtcTime)."""

    pan_deg: float
    """Wrapped to [−180°, 180°) on an endless head; on the head's step grid."""
    tilt_deg: float
    zoom_x: float
    pan_tilt: MoveStatus
    zoom: MoveStatus
    time_s: float
    """Scene time of this status, s (ONVIF's UtcTime)."""
    pan_deg_s: float = 0.0
    tilt_deg_s: float = 0.0
    log_zoom_per_s: float = 0.0
    clamp: Clamp | None = None
    """The clamp of the last move that acted (None: it was inside the range, or none acted yet). It
    stays until the next command other than SetPreset acts, so a controller that polls after the
    head has stopped short still learns why; a command given but not yet acting leaves it."""

    @property
    def error(self) -> str | None:
        """ONVIF's PTZStatus Error, "a current PTZ error condition" (ONVIF PTZ Service
        Specification, GetStatus; onvif.xsd tt:PTZStatus): the clamp in words, or None."""
        return self.clamp.error if self.clamp is not None else None


def velocity_action(action, where: str) -> ContinuousMove:
    """A gymnasium action ``(pan, tilt, zoom)`` as a ContinuousMove, checked (`CommandError` names the
    problem: not three numbers, not finite, outside [−1, 1])."""
    try:
        values = [float(v) for v in np.asarray(action, dtype=np.float64).reshape(-1)]
    except (TypeError, ValueError):
        raise CommandError(f"{where}: the action must be three numbers (pan, tilt, zoom), got {action!r}") from None
    if len(values) != 3:
        raise CommandError(f"{where}: the action must be three numbers (pan, tilt, zoom), got {len(values)}: {values}")
    move = ContinuousMove(pan=values[0], tilt=values[1], zoom=values[2])
    move.check(where)
    return move
