"""Painted road markings (`environment.markings`): lines, rows of parking bays and zebra crossings, laid on
a level surface of the scene; `camgen.world.markings` turns them into worn paint geometry.

Dimensions default to published practice, each cited where it is set: line widths and dash patterns of the
US MUTCD (FHWA, Manual on Uniform Traffic Control Devices, 2009 edition, §3A.06, §3B.16, §3B.18) and the UK
Traffic Signs Manual (DfT, chapter 5 "Road Markings", 2003, table 4-1), the perpendicular bays of UK car
parks (IStructE, "Design recommendations for multi-storey and underground car parks", 4th ed. 2011:
2.4 × 4.8 m). The parallel bay's 2.0 × 6.0 m is an estimate (`PARALLEL_BAY_M`).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from camgen.config.base import Model, Why, invalid
from camgen.config.world import Point2

HEADING = Annotated[float, Field(ge=-360, le=360), Why("a direction, −360° to 360°")]
MarkingName = Annotated[str, Field(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.-]+$")]

LINE_WIDTH_M = 0.1
"""A normal line, m: MUTCD §3A.06's normal line is 4 to 6 in (0.10–0.15 m; FHWA, "Research – Pavement
Markings", ch. 3 "Pavement marking width"); the UK's centre line to diagram 1008 and its lane lines are
100 mm (150 mm on roads 10 m or more wide: Traffic Signs Manual ch. 5, 2003, table 4-1 and para 4.3)."""
BAY_LINE_WIDTH_M = 0.1
"""Parking-bay lines, m: AS/NZS 2890.1:2004 asks unbroken lines 80–100 mm wide; US stall lines are commonly
4 in (0.10 m). No UK figure for off-street bay lines was found; 0.1 matches the UK's 100 mm road lines."""
PERPENDICULAR_BAY_M = (2.4, 4.8)
"""(width, length) of a perpendicular (or echelon) parking bay, m: the standard bay of IStructE's car-park
recommendations from the 1st (1976; 2.3 m wide for long stays to 2.5 for short) to the 4th (2011) edition,
and what UK contractors still mark. Its successor, IStructE's "Car park design" (announced 2022), raises the
bay to about 2.6 × 5.0 m for today's larger cars."""
PARALLEL_BAY_M = (2.0, 6.0)
"""(width, length) of a parallel (kerbside) parking bay, m. An estimate: no published UK length for a
kerbside bay was found (Manual for Streets, DfT 2007, ch. 8 gives guidance on parking-space sizes, but its
figure could not be checked; UK designers report none nationally, with 1.8 m the usual minimum width and
6.1 m an older handbook's length). 6 m holds a 4.5–5 m car with room to manoeuvre in; 2.0 m a 1.8 m wide one."""
CROSSING_WIDTH_M = 3.0
"""Width of a crosswalk along the traffic, m: MUTCD §3B.18 asks at least 6 ft (1.83 m); 3 m (10 ft) is an
estimate of common practice, not a figure of the MUTCD."""
CROSSING_STRIPE_M = 0.6
"""Width of a crosswalk's bar, m: MUTCD §3B.18, longitudinal bars 12–24 in (0.30–0.61 m) wide."""
CROSSING_GAP_M = 0.6
"""Gap between a crosswalk's bars, m: MUTCD §3B.18, 12–60 in (0.30–1.52 m)."""
CROSSING_GAP_MAX_STRIPES = 2.5
"""MUTCD 2009 §3B.18 guidance: the gap between the bars should not exceed 2.5 times their width (quoted
from the 2009 text; not found in the copies searched, where the 12–24 in bars and 12–60 in gaps were)."""
WEAR = 0.15
"""Share of a marking's paint worn away by default (edges and patches, `camgen.world.markings`)."""


class _Paint(Model):
    name: MarkingName | None = None
    """The instance's name; null: `<type>_<index>` (its place in `environment.markings`)."""
    colour: Literal["white", "yellow"] = "white"
    """White, or yellow (a US centre line, a UK waiting restriction); reflectances in `camgen.world.markings`."""
    surface_height_m: Annotated[
        float, Field(ge=-100, le=100), Why("the surface a marking lies on is within 100 m of z = 0")
    ] = 0.0
    """Height of the level surface the paint lies on, m: 0 for the ground, a road plane's own z when the road
    is laid over it (0.011); the paint is drawn `camgen.world.markings.PAINT_LIFT_M` above it."""
    wear: Annotated[float, Field(ge=0, le=0.9), Why("at most 90 % of a marking can be worn away (0: new paint)")] = WEAR
    """Share of the paint's area worn away, along its edges and in patches (0: new paint)."""
    seed: Annotated[int, Field(ge=0)] | None = None
    """Draws the wear; null derives one from the scene's seed and the marking's place in the list."""


class LineMarking(_Paint):
    """A solid or dashed line along a polyline: a centre, lane or edge line, a stop or give-way line."""

    type: Literal["line"]
    along_m: Annotated[list[Point2], Field(min_length=2)]
    """[[x, y], …] of the line's middle on the ground, m, at least two points."""
    width_m: Annotated[
        float,
        Field(ge=0.05, le=1.0),
        Why("road lines are 0.05–1 m wide (MUTCD: normal 0.10–0.15, stop lines 0.30–0.61)"),
    ] = LINE_WIDTH_M
    """Width, m (`LINE_WIDTH_M`; a stop line 0.3–0.6: MUTCD §3B.16, 12–24 in; a UK centre line 0.1 or 0.15)."""
    dash_m: Annotated[float, Field(gt=0, le=100), Why("a dash is at most 100 m long")] | None = None
    """A dash's length, m (MUTCD §3A.06's broken line: 10 ft, 3.05 m; the UK's diagram 1008 centre line, 40 mph or
    less: 2 m, and 1008.1 above 40 mph: 3 m); null with gap_m: a solid line."""
    gap_m: Annotated[float, Field(gt=0, le=100), Why("a gap is at most 100 m long")] | None = None
    """The gap between dashes, m (MUTCD §3A.06: 30 ft, 9.14 m; diagrams 1008 and 1008.1: 4 and 6 m); the pattern runs
    on around the polyline's bends."""

    @model_validator(mode="after")
    def _check(self) -> LineMarking:
        if (self.dash_m is None) != (self.gap_m is None):
            given, missing = ("dash_m", "gap_m") if self.gap_m is None else ("gap_m", "dash_m")
            raise invalid(given, f"needs {missing} as well (a dashed line has both; a solid one neither)")
        for i, (a, b) in enumerate(zip(self.along_m, self.along_m[1:], strict=False)):
            if (a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 < 1e-6:
                raise invalid(
                    f"along_m[{i + 1}]",
                    f"repeats the point before it, {list(a)}; a line's points must be at least 1 mm apart",
                )
        return self


class BaysMarking(_Paint):
    """A row of parking bays: the lines between them (and around the row's ends), each bay a rectangle."""

    type: Literal["bays"]
    first_centre_m: Point2
    """[x, y] of the first bay's middle, m."""
    heading_deg: HEADING = 0.0
    """Direction of the bays' length (the way a car parked in one faces), degrees counter-clockwise from +X."""
    count: Annotated[int, Field(ge=1, le=200), Why("a row holds 1–200 bays")]
    """Number of bays in the row. Perpendicular bays follow one another to the left of `heading_deg`
    (+90°), parallel ones along it."""
    layout: Literal["perpendicular", "parallel"] = "perpendicular"
    """perpendicular: bays side by side (a car park's row); parallel: nose to tail along a kerb."""
    width_m: Annotated[float, Field(ge=1.5, le=6), Why("a bay is 1.5–6 m wide (a car is 1.5–2.1 m wide)")] | None = None
    """A bay's width across a parked car, m; null: 2.4 perpendicular, 2.0 parallel (`PERPENDICULAR_BAY_M`,
    `PARALLEL_BAY_M`). US stalls are commonly 9 ft (2.74 m)."""
    length_m: Annotated[float, Field(ge=3, le=25), Why("a bay is 3–25 m long (a car to a coach)")] | None = None
    """A bay's length along a parked car, m; null: 4.8 perpendicular, 6.0 parallel. US stalls: 18 ft (5.49 m)."""
    line_width_m: Annotated[float, Field(ge=0.05, le=0.3), Why("bay lines are 0.05–0.3 m wide")] = BAY_LINE_WIDTH_M
    """Width of the bay lines, m (`BAY_LINE_WIDTH_M`)."""
    closed: bool = False
    """Perpendicular: also a line across the bays' front end (the `heading_deg` end); parallel: also the long
    line on the row's left side (+90° from `heading_deg`, the traffic side when that is the kerb's right).
    false: the lines between bays only (and at the row's two ends)."""

    @property
    def bay_size_m(self) -> tuple[float, float]:
        """(width, length) of a bay, m, the defaults filled in."""
        width, length = PERPENDICULAR_BAY_M if self.layout == "perpendicular" else PARALLEL_BAY_M
        return (self.width_m or width, self.length_m or length)

    @model_validator(mode="after")
    def _check(self) -> BaysMarking:
        width = self.bay_size_m[0]
        if self.line_width_m >= width / 5:
            raise invalid(
                "line_width_m",
                f"is {self.line_width_m:g} m, too wide for {width:g} m wide bays (the lines take at most a fifth of "
                "a bay's width); make it 0.1",
            )
        return self


class CrossingMarking(_Paint):
    """A zebra (continental) crosswalk: bars along the traffic, repeated across the road (MUTCD §3B.18)."""

    type: Literal["crossing"]
    from_m: Point2
    """[x, y] where the walkers' line across the road starts, at one kerb, m."""
    to_m: Point2
    """[x, y] where it ends, at the other kerb, m: the crossing spans the road's width between the two."""
    width_m: Annotated[
        float, Field(ge=1.8, le=10), Why("a crosswalk is 1.8–10 m wide along the traffic (MUTCD: at least 6 ft)")
    ] = CROSSING_WIDTH_M
    """Width along the traffic (each bar's length), m (`CROSSING_WIDTH_M`)."""
    stripe_m: Annotated[
        float, Field(ge=0.2, le=1.0), Why("crossing bars are 0.2–1 m wide (MUTCD: 12–24 in, 0.30–0.61 m)")
    ] = CROSSING_STRIPE_M
    """Each bar's width across the road, m (`CROSSING_STRIPE_M`)."""
    gap_m: Annotated[
        float, Field(ge=0.2, le=1.6), Why("gaps between crossing bars are 0.2–1.6 m (MUTCD: 12–60 in)")
    ] = CROSSING_GAP_M
    """The gap between bars, m (`CROSSING_GAP_M`); the bars are centred between the kerbs."""

    @model_validator(mode="after")
    def _check(self) -> CrossingMarking:
        if self.gap_m > CROSSING_GAP_MAX_STRIPES * self.stripe_m + 1e-9:
            raise invalid(
                "gap_m",
                f"is {self.gap_m:g} m, over {CROSSING_GAP_MAX_STRIPES:g} × stripe_m ({self.stripe_m:g} m; MUTCD "
                f"§3B.18); make it at most {CROSSING_GAP_MAX_STRIPES * self.stripe_m:g}",
            )
        span_m = ((self.to_m[0] - self.from_m[0]) ** 2 + (self.to_m[1] - self.from_m[1]) ** 2) ** 0.5
        if span_m < self.stripe_m:
            raise invalid(
                "to_m",
                f"is {span_m:.3g} m from from_m, narrower than one bar ({self.stripe_m:g} m); from_m and to_m are "
                "the crossing's two kerbs",
            )
        return self


Marking = Annotated[LineMarking | BaysMarking | CrossingMarking, Field(discriminator="type")]


def marking_names(markings: list) -> list[str]:
    """Each marking's instance name: its own, or `<type>_<index>`."""
    return [marking.name or f"{marking.type}_{i}" for i, marking in enumerate(markings)]


__all__ = [
    "BaysMarking",
    "CrossingMarking",
    "LineMarking",
    "Marking",
    "marking_names",
]
