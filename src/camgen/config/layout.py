"""Candidates for `camgen layout`: where cameras may go (poles, walls), how they may be aimed, which
profiles may be used, and how the objective weighs regions and hand-off overlap."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from camgen.config.base import Model, Why, invalid
from camgen.config.scene import Name
from camgen.config.world import Point3


class CandidateMount(Model):
    """A place a camera may be fixed, with the headings and pitches it may be aimed at."""

    name: Name
    kind: Literal["pole", "wall"] = "pole"
    position_m: Point3
    yaw_deg_range: tuple[float, float] = (-180.0, 180.0)
    """[min, max] heading, counter-clockwise from +X seen from above, degrees (a wall: the half-plane
    it faces)."""
    pitch_deg_range: tuple[Annotated[float, Field(ge=-90, le=90)], Annotated[float, Field(ge=-90, le=90)]] = (
        -45.0,
        -5.0,
    )
    """[min, max] elevation of the optical axis, degrees; negative looks down."""

    @model_validator(mode="after")
    def _check(self) -> CandidateMount:
        for key in ("yaw_deg_range", "pitch_deg_range"):
            low, high = getattr(self, key)
            if low > high:
                raise invalid(key, f"must be ordered [min, max] with min ≤ max, got [{low:g}, {high:g}]; swap them")
        if self.position_m[2] <= 0:
            raise invalid("position_m", f"must be above the ground (z > 0), got z = {self.position_m[2]:g} m")
        return self


class LayoutCandidates(Model):
    """Everything `camgen layout` may choose from, and its objective's weights."""

    mounts: Annotated[list[CandidateMount], Field(min_length=1)]
    profiles: Annotated[list[Annotated[str, Field(min_length=1)]], Field(min_length=1)]
    """Profile names or paths (relative to this file) a camera may be."""
    yaw_step_deg: Annotated[float, Field(gt=0, le=360)] = 15.0
    """Spacing of the headings tried within each mount's range, degrees."""
    pitch_step_deg: Annotated[float, Field(gt=0, le=180)] = 10.0
    focal_length_steps: Annotated[
        int,
        Field(ge=1, le=12),
        Why("1 tries the wide end only; each step multiplies the options a zoom profile adds, so at most 12"),
    ] = 1
    """Focal lengths a varifocal or zoom profile is tried at: this many, spaced evenly in log from its wide
    to its tele end (1: the wide end only). A PTZ profile is placed with its head at pan 0, tilt 0 and that
    zoom; a fixed lens has one."""
    region_weights: dict[str, Annotated[float, Field(ge=0)]] = {}
    """Weight of each region's area in the objective (by region name; 1 for a region not listed)."""
    handoff_weight: Annotated[float, Field(ge=0, le=10)] = 0.0
    """Weight of region area seen at its required class by two or more cameras (hand-off overlap), relative
    to area seen by one: 0 ignores overlap (and keeps the greedy's guarantee)."""

    @model_validator(mode="after")
    def _check(self) -> LayoutCandidates:
        seen: dict[str, int] = {}
        for i, mount in enumerate(self.mounts):
            if mount.name in seen:
                raise invalid(
                    f"mounts[{i}].name",
                    f"must be unique, got {mount.name!r} again (first at mounts[{seen[mount.name]}])",
                )
            seen[mount.name] = i
        return self
