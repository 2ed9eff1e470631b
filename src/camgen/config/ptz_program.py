"""PTZ programs in a scene: presets, tours, scans, keyframes and follow-target.

A program says where the head should go; `camgen.motion.programs` turns it into commands and
`camgen.motion.ptz` moves the head there under the profile's speed, acceleration, range and step
limits. Angles: pan counter-clockwise about the mount's up axis, tilt up, degrees (DESIGN.md).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from camgen.config.base import Model, invalid
from camgen.config.world import Point2

PositiveFloat = Annotated[float, Field(gt=0)]
NonNegativeFloat = Annotated[float, Field(ge=0)]
Name = Annotated[str, Field(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.-]+$")]
ZoomX = Annotated[float, Field(ge=1)]


class PtzPreset(Model):
    """A named head position (pan, tilt, zoom), as stored in a camera."""

    name: Name
    pan_deg: float = 0.0
    tilt_deg: Annotated[float, Field(ge=-90, le=90)] = 0.0
    zoom_x: ZoomX = 1.0


class HoldProgram(Model):
    """Stay at the camera's starting position (ptz.pan_deg, tilt_deg, zoom_x)."""

    type: Literal["hold"]


class PresetProgram(Model):
    """Go to one preset at `start_s` and stay there."""

    type: Literal["preset"]
    preset: Name
    start_s: NonNegativeFloat = 0.0


class TourStop(Model):
    preset: Name
    dwell_s: NonNegativeFloat = 5.0
    """Time spent at the preset after arriving, s."""


class TourProgram(Model):
    """Visit presets in order, dwelling at each; the dwell starts when the head has arrived."""

    type: Literal["tour"]
    stops: Annotated[list[TourStop], Field(min_length=1)]
    loop: bool = True
    """Start again at the first stop after the last; otherwise stay at the last."""
    start_s: NonNegativeFloat = 0.0
    speed_deg_s: PositiveFloat | None = None
    """Pan and tilt speed of the moves between stops, deg/s; null moves at the head's maximum."""


class ScanProgram(Model):
    """Sweep the pan from one angle to another and back at a steady speed (a patrol).

    On an endless head the sweep turns counter-clockwise (increasing pan) from the first angle to the
    second; equal angles (mod 360°) rotate endlessly. On a limited head it sweeps within the range.
    """

    type: Literal["scan"]
    pan_range_deg: tuple[float, float]
    """[from, to], degrees."""
    tilt_deg: Annotated[float, Field(ge=-90, le=90)] = 0.0
    zoom_x: ZoomX = 1.0
    speed_deg_s: PositiveFloat = 10.0
    """Pan speed of the sweep, deg/s."""
    dwell_s: NonNegativeFloat = 0.0
    """Pause at each end of the sweep, s."""
    start_s: NonNegativeFloat = 0.0


class Keyframe(Model):
    time_s: NonNegativeFloat
    pan_deg: float = 0.0
    tilt_deg: Annotated[float, Field(ge=-90, le=90)] = 0.0
    zoom_x: ZoomX = 1.0


class KeyframeProgram(Model):
    """An explicit path: the head follows the straight line (pan the short way, zoom in log scale)
    between keyframes, as fast as its limits allow; before the first key it moves to it."""

    type: Literal["keyframes"]
    keys: Annotated[list[Keyframe], Field(min_length=1)]

    @model_validator(mode="after")
    def _check(self) -> KeyframeProgram:
        for i in range(1, len(self.keys)):
            if self.keys[i].time_s <= self.keys[i - 1].time_s:
                raise invalid(
                    f"keys[{i}].time_s",
                    f"must be later than keys[{i - 1}].time_s ({self.keys[i - 1].time_s:g} s), "
                    f"got {self.keys[i].time_s:g}; list keyframes in time order",
                )
        return self


Fallback = Annotated[
    HoldProgram | PresetProgram | TourProgram | ScanProgram | KeyframeProgram, Field(discriminator="type")
]


class FollowProgram(Model):
    """Auto-tracking of one actor, as a PTZ camera's built-in tracker does it.

    Until the target is in coverage the `fallback` program runs. The target is acquired when its
    centre is in the image (and inside `acquire_region_m`, when given). While following, the head
    keeps the target inside the central dead zone, moving only as much as needed: it sees the target
    `reaction_lag_s` late and extrapolates that sighting by the target's velocity, and zooms so
    that the target spans `target_height_frac` of the image height. The target is lost when it
    leaves the region, or stays out of the image for `lost_after_s`; the fallback program then
    starts again from its beginning (hand-back), and a later sighting re-acquires it.
    """

    type: Literal["follow"]
    target: Name
    """The actor's name."""
    dead_zone_frac: Annotated[float, Field(gt=0, lt=1)] = 0.3
    """Size of the central dead zone as a fraction of the image width and height."""
    reaction_lag_s: Annotated[float, Field(ge=0, le=5)] = 0.2
    """Delay between the target's motion and the tracker seeing it, s."""
    target_height_frac: Annotated[float, Field(gt=0, le=1)] | None = 0.3
    """Image height the target should span, as a fraction of the frame; null keeps the zoom."""
    speed_deg_s: PositiveFloat | None = None
    """Pan and tilt speed limit while following, deg/s; null: the head's maximum."""
    acquire_region_m: Annotated[list[Point2], Field(min_length=3)] | None = None
    """Ground polygon [[x, y], …] of this camera's coverage, m: the target is followed only inside
    it (hand-over between cameras); null: wherever the camera sees it."""
    lost_after_s: NonNegativeFloat = 1.0
    """How long the target may stay out of the image before the camera gives up, s."""
    fallback: Fallback = HoldProgram(type="hold")
    """What the camera does while it has no target."""


PtzProgram = Annotated[
    HoldProgram | PresetProgram | TourProgram | ScanProgram | KeyframeProgram | FollowProgram,
    Field(discriminator="type"),
]


def program_presets(program) -> list[tuple[str, str]]:
    """(key path below `program`, preset name) for every preset a program refers to."""
    if isinstance(program, PresetProgram):
        return [("preset", program.preset)]
    if isinstance(program, TourProgram):
        return [(f"stops[{i}].preset", stop.preset) for i, stop in enumerate(program.stops)]
    if isinstance(program, FollowProgram):
        return [(f"fallback.{path}", name) for path, name in program_presets(program.fallback)]
    return []
