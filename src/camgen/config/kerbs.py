"""Kerbs (`environment.kerbs`): precast concrete kerbs along polylines at the road's edge, with a real profile
(a half-battered HB2 by default) and joints between their units; `camgen.world.kerbs` sweeps the profile into
a mesh. Dimensions default to BS EN 1340 / BS 7263-1, each cited where it is set.
"""

from __future__ import annotations

import itertools
import math
from typing import Annotated, Literal

from pydantic import Field, model_validator

from camgen.config.base import Model, Why, invalid
from camgen.config.world import Point2

KerbName = Annotated[str, Field(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.-]+$")]
Fraction = Annotated[float, Field(ge=0, le=1)]

HB2_WIDTH_M = 0.125
"""Width of a half-battered kerb HB2, m (BS EN 1340's UK national annex and BS 7263-1: 125 × 255 mm; the HB2
road kerb UK highway authorities specify, e.g. Lincolnshire County Council's "Development road specification",
section 6)."""
UPSTAND_M = 0.125
"""Height of a road kerb's top over the road's channel, m: an estimate of UK practice, which lays a road kerb
with an upstand of 100–125 mm and drops it to 25–50 mm at crossings (no one specification read for camgen)."""
BATTER_SETBACK_M = 0.05
"""How far the batter leans back from the foot of the batter to the top, m."""
BATTER_RISE_M = 0.1
"""Height of the battered part of the road face, m. With `BATTER_SETBACK_M`: an estimate of BS 7263's HB
profile after manufacturers' drawings (the standard's figure was not read for camgen): the road face's top
100 mm slope back 50 mm, leaving a 75 mm top."""
ARRIS_RADIUS_M = 0.015
"""Radius of the rounded arris between the batter and the top, m (an estimate: cast kerbs round their
exposed arrises by 10–20 mm)."""
UNIT_LENGTH_M = 0.914
"""Length of one precast kerb unit, m: BS 7263-1's and BS EN 1340's UK national annex's 914 mm (3 ft) kerb."""
JOINT_M = 0.003
"""Width of the open joint between two units, m: "joints generally open, 2–3 mm" (NBS specification Q10 for
precast kerbs to BS EN 1340)."""

MAX_TURN_DEG = 135.0
"""The sharpest turn a kerb's polyline may take at a point: a mitred corner sharper than this would reach far
behind the kerb (its mitre is 1/cos(turn/2) of the width); real kerbs turn such corners on a radius."""


class Kerb(Model):
    """A line of precast concrete kerb units along a polyline, the road on one side: its profile swept along
    the polyline, concrete-textured, an open joint every `unit_length_m`."""

    name: KerbName | None = None
    """The instance's name; null: `kerb_<index>` (its place in `environment.kerbs`)."""
    along_m: Annotated[list[Point2], Field(min_length=2)]
    """[[x, y], …] of the foot of the kerb's road face on the road, m, at least two points."""
    road_side: Literal["left", "right"] = "right"
    """Which side of `along_m` (walking from its first point) the road lies on; the footway is on the other."""
    road_height_m: Annotated[
        float, Field(ge=-100, le=100), Why("the road a kerb stands on is within 100 m of z = 0")
    ] = 0.0
    """Height of the road surface the kerb stands on, m (0 for the ground, a road plane's own z)."""
    width_m: Annotated[float, Field(ge=0.05, le=0.5), Why("kerbs are 0.05–0.5 m wide (BS EN 1340's HB2: 0.125 m)")] = (
        HB2_WIDTH_M
    )
    """Width of the kerb across its top and batter, m (HB2: 0.125)."""
    upstand_m: Annotated[
        float, Field(gt=0, le=0.4), Why("a kerb stands 0–0.4 m over the road (UK road kerbs: 0.10–0.125 m)")
    ] = UPSTAND_M
    """Height of the kerb's top over the road, m (0.125; a dropped kerb at a crossing 0.025–0.05)."""
    batter_setback_m: Annotated[float, Field(ge=0, le=0.4), Why("a batter leans back 0–0.4 m (HB2: 0.05 m)")] = (
        BATTER_SETBACK_M
    )
    """How far the top of the road face leans back, m (0 with `batter_rise_m` 0: a square kerb)."""
    batter_rise_m: Annotated[float, Field(ge=0, le=0.4), Why("a batter rises 0–0.4 m (HB2: 0.1 m)")] = BATTER_RISE_M
    """Height of the battered part of the road face, m."""
    arris_radius_m: Annotated[float, Field(ge=0, le=0.05), Why("a kerb's arris is rounded to a radius of 0–50 mm")] = (
        ARRIS_RADIUS_M
    )
    """Radius of the arris between the road face's batter and the top, m."""
    unit_length_m: Annotated[float, Field(ge=0.1, le=5), Why("kerb units are 0.1–5 m long (BS 7263: 0.914 m)")] = (
        UNIT_LENGTH_M
    )
    """Length of one kerb unit, m: an open joint between units every this far along the kerb."""
    joint_m: Annotated[
        float, Field(ge=0, le=0.02), Why("open joints between kerb units are 0–20 mm (specified 2–3 mm)")
    ] = JOINT_M
    """Width of the joint between units, m."""
    color_rgb: tuple[Fraction, Fraction, Fraction] | None = None
    """Mean linear reflectance; null: weathered concrete's (`camgen.world.textures.TYPICAL_ALBEDO_RGB`)."""
    seed: Annotated[int, Field(ge=0)] = 0
    """Draws the concrete's grain and each unit's tint."""

    @model_validator(mode="after")
    def _check(self) -> Kerb:
        points = self.along_m
        for i, (a, b) in enumerate(itertools.pairwise(points)):
            if (a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 < 1e-6:
                raise invalid(
                    f"along_m[{i + 1}]",
                    f"repeats the point before it, {list(a)}; a kerb's points must be at least 1 mm apart",
                )
        for i in range(1, len(points) - 1):
            (ax, ay), (bx, by), (cx, cy) = points[i - 1], points[i], points[i + 1]
            turn = math.atan2(cy - by, cx - bx) - math.atan2(by - ay, bx - ax)
            turn_deg = abs(math.degrees(math.remainder(turn, 2 * math.pi)))
            if turn_deg > MAX_TURN_DEG:
                raise invalid(
                    f"along_m[{i}]",
                    f"turns the kerb by {turn_deg:.0f}°, sharper than {MAX_TURN_DEG:g}°; round the corner with more "
                    "points (a kerb turns a corner on a radius)",
                )
        if self.batter_rise_m > self.upstand_m:
            raise invalid(
                "batter_rise_m",
                f"is {self.batter_rise_m:g} m, above the kerb's upstand_m ({self.upstand_m:g} m); make it at most "
                f"{self.upstand_m:g}",
            )
        if (self.batter_setback_m > 0) != (self.batter_rise_m > 0):
            given = "batter_setback_m" if self.batter_setback_m > 0 else "batter_rise_m"
            raise invalid(given, "needs the other of batter_setback_m and batter_rise_m above 0 too (0 and 0: square)")
        # The arris's rounding runs tan(turn/2)·radius down the face it leaves (the batter, or the whole road face
        # of a square kerb): past that face's foot the profile would dip below the road or bulge into it.
        battered = self.batter_rise_m > 0
        face_m = math.hypot(self.batter_setback_m, self.batter_rise_m) if battered else self.upstand_m
        turn_rad = math.atan2(self.batter_rise_m, self.batter_setback_m) if battered else math.pi / 2
        tangent_m = self.arris_radius_m * math.tan(turn_rad / 2)
        if tangent_m > face_m + 1e-12:
            face = "batter" if battered else "road face (upstand_m)"
            raise invalid(
                "arris_radius_m",
                f"is {self.arris_radius_m:g} m, whose rounding takes {1000 * tangent_m:.1f} mm of a "
                f"{1000 * face_m:.1f} mm {face}; make it at most {face_m / math.tan(turn_rad / 2):.4g} m",
            )
        if self.batter_setback_m + self.arris_radius_m >= self.width_m:
            raise invalid(
                "batter_setback_m",
                f"is {self.batter_setback_m:g} m, which with arris_radius_m ({self.arris_radius_m:g} m) leaves no top "
                f"on a {self.width_m:g} m wide kerb; make it under {self.width_m - self.arris_radius_m:g}",
            )
        return self


def kerb_names(kerbs: list[Kerb]) -> list[str]:
    """Each kerb's instance name: its own, or `kerb_<index>`."""
    return [kerb.name or f"kerb_{i}" for i, kerb in enumerate(kerbs)]


__all__ = ["Kerb", "kerb_names"]
