"""Props of the environment: trees, bushes, benches, bins, bollards, lamp posts, signs and fences, placed one
by one (`environment.props`) or scattered by rules (`environment.scatter`); `camgen.props` builds them and
resolves the rules.

A prop stands on the ground (z = `elevation_m`) at `position_m`, its local x along `heading_deg`
(counter-clockwise from the world's +X). Props are static geometry of the environment: they cast and
receive shadows and take instance ids after the environment's meshes, but they are not annotated.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import Field, model_validator

from camgen.config.base import Model, Why, invalid
from camgen.config.world import Length, Point2

PropType = Literal["tree", "bush", "bench", "bin", "bollard", "lamp_post", "sign", "fence"]

PROP_HEIGHT_RANGE_M: dict[str, tuple[float, float]] = {
    "tree": (5.0, 15.0),
    "bush": (0.5, 2.0),
    "bench": (0.75, 0.9),
    "bin": (0.9, 1.0),
    "bollard": (0.9, 1.0),
    "lamp_post": (4.0, 12.0),
    "sign": (2.4, 3.4),
    "fence": (1.0, 2.0),
}
"""Overall height of each prop type, m (`camgen.props.types` cites each range): street trees 5–15 m,
shrubs and hedges 0.5–2 m, a bench's backrest top 0.75–0.9 m, litter bins and bollards 0.9–1.0 m, lamp
columns 4–12 m (BS EN 40-2), a sign's plate top 2.4–3.4 m (its lower edge 2.1–2.5 m up), fences and
railings 1.0–2.0 m."""

HEADING = Annotated[float, Field(ge=-360, le=360), Why("a direction, −360° to 360°")]
SCATTER_MAX_COUNT = 500
"""Most props one scatter rule places (each is a draw of the renderer)."""
RANDOM_PACKING_FRACTION = 0.5
"""Share of a region that discs of diameter min_gap_m can cover when thrown at random without overlap:
random sequential adsorption jams at 0.547 (Feder 1980, J. Theor. Biol. 87: 237); a little under it
leaves the dart throwing room to finish."""


class Prop(Model):
    """One prop at a given place."""

    type: PropType
    position_m: Point2
    """[x, y] of the prop's foot on the ground, m (a fence's first post; a bench's middle)."""
    elevation_m: Annotated[float, Field(ge=-100, le=100), Why("a prop stands within 100 m of z = 0")] = 0.0
    """Height of the ground under the prop, m (0.15 on a kerb)."""
    heading_deg: HEADING = 0.0
    """Direction of the prop's local +x (a bench faces its local −y; a fence runs along +x; a lamp's
    bracket reaches along +x; a sign's plate faces +x), degrees counter-clockwise from the world's +X."""
    seed: Annotated[int, Field(ge=0)] | None = None
    """Draws the prop's dimensions, shape and colours within its type's cited ranges; null derives one from
    the scene's seed and the prop's place in the list."""
    name: Annotated[str, Field(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.-]+$")] | None = None
    """The instance's name; null: `<type>_<index>`."""
    form: Literal["deciduous", "conifer"] | None = None
    """A tree's form (null: deciduous)."""
    height_m: Annotated[float, Field(gt=0, le=40), Why("props stand at most 40 m tall")] | None = None
    """The prop's overall height, m, within its type's range (`PROP_HEIGHT_RANGE_M`); null: drawn."""
    length_m: Annotated[float, Field(ge=0.5, le=200), Why("a fence or hedge runs 0.5–200 m")] | None = None
    """A fence's or a hedge's (bush's) length along its +x, m; null: drawn (fence 4–10 m, bush 0.8–2.5 m)."""

    @model_validator(mode="after")
    def _check(self) -> Prop:
        _check_options(self.type, self.form, self.height_m, getattr(self, "length_m", None))
        return self


def _check_options(kind: str, form: str | None, height_m: float | None, length_m: float | None) -> None:
    if form is not None and kind != "tree":
        raise invalid("form", f"shapes a tree, but this prop is a {kind!r}; remove form")
    if length_m is not None and kind not in ("fence", "bush"):
        raise invalid("length_m", f"is the length of a fence or a hedge (bush), but this prop is a {kind!r}; remove it")
    if height_m is not None:
        low, high = PROP_HEIGHT_RANGE_M[kind]
        if not low <= height_m <= high:
            raise invalid(
                "height_m",
                f"must lie within a {kind}'s {low:g}–{high:g} m (camgen.props cites the range), got {height_m:g}",
            )


class ScatterRule(Model):
    """Props of one type placed by a rule, deterministically from `seed`: every `spacing_m` along a
    polyline (`along`), or `count` of them at random in a rectangle (`region_m`), no two closer than
    `min_gap_m`."""

    type: PropType
    seed: Annotated[int, Field(ge=0)] = 0
    """Draws the positions (in a region), headings and each prop's own seed."""
    along: list[Point2] | None = None
    """[[x, y], …] a polyline (a kerb, a building's front); props stand every `spacing_m` along it,
    the first at its start."""
    spacing_m: Length | None = None
    """Distance between neighbours along `along`, m."""
    region_m: tuple[Point2, Point2] | None = None
    """[[x0, y0], [x1, y1]] opposite corners of a rectangle on the ground."""
    count: Annotated[int, Field(ge=1, le=SCATTER_MAX_COUNT), Why(f"1–{SCATTER_MAX_COUNT} props per rule")] | None = None
    """How many props to place in `region_m`."""
    min_gap_m: Annotated[float, Field(ge=0, le=1000), Why("a gap of 0–1000 m")] = 0.0
    """Least distance between two props' feet, m."""
    heading_deg: HEADING | None = None
    """Every prop's heading; null: along the polyline's leg (`along`) or drawn at random (`region_m`)."""
    elevation_m: Annotated[float, Field(ge=-100, le=100), Why("a prop stands within 100 m of z = 0")] = 0.0
    form: Literal["deciduous", "conifer"] | None = None
    height_m: Annotated[float, Field(gt=0, le=40), Why("props stand at most 40 m tall")] | None = None
    """Every prop's height, m (null: each drawn from its own seed)."""

    @model_validator(mode="after")
    def _check(self) -> ScatterRule:
        _check_options(self.type, self.form, self.height_m, None)
        if (self.along is None) == (self.region_m is None):
            raise invalid(
                "",
                "needs exactly one of along (a polyline, with spacing_m) or region_m (a rectangle, with count)",
            )
        if self.along is not None:
            if self.count is not None:
                raise invalid("count", "counts props in a region_m; along a polyline give spacing_m instead")
            if self.spacing_m is None:
                raise invalid("spacing_m", "is required with along: the distance between neighbours, m")
            if len(self.along) < 2:
                raise invalid("along", f"must hold at least 2 points [[x, y], …], got {len(self.along)}")
            if self.spacing_m < self.min_gap_m:
                raise invalid(
                    "spacing_m",
                    f"must be ≥ min_gap_m ({self.min_gap_m:g}), got {self.spacing_m:g}; neighbours along the line "
                    "stand spacing_m apart",
                )
            length = sum(math.dist(a, b) for a, b in zip(self.along, self.along[1:], strict=False))
            if length / self.spacing_m + 1 > SCATTER_MAX_COUNT:
                raise invalid(
                    "spacing_m",
                    f"places {math.floor(length / self.spacing_m) + 1} props along {length:g} m, more than "
                    f"{SCATTER_MAX_COUNT}; widen the spacing",
                )
            return self
        if self.spacing_m is not None:
            raise invalid("spacing_m", "spaces props along a polyline; in a region_m give count instead")
        if self.count is None:
            raise invalid("count", "is required with region_m: how many props to place")
        (x0, y0), (x1, y1) = self.region_m
        area = abs(x1 - x0) * abs(y1 - y0)
        if area <= 0:
            raise invalid("region_m", f"must span an area (two opposite corners), got {self.region_m}")
        fits = math.floor(RANDOM_PACKING_FRACTION * area / (math.pi * (self.min_gap_m / 2) ** 2 or 1e-12))
        if self.count > fits:
            raise invalid(
                "count",
                f"is {self.count}, but at most {fits} props {self.min_gap_m:g} m apart fit at random in "
                f"{area:g} m² (half the area in discs of that diameter); lower count or min_gap_m, or enlarge region_m",
            )
        return self


__all__ = ["PROP_HEIGHT_RANGE_M", "Prop", "PropType", "ScatterRule"]
