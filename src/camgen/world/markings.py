"""Painted road markings as worn paint geometry: pure functions of a marking's configuration
(`camgen.config.markings`) and a seed.

A marking is a set of painted rectangles (`PaintRect`): a line's dashes along its polyline, a row of bays'
lines, a crosswalk's bars. Each rectangle is laid out as a grid of cells (`WEAR_CELL_M` × `WEAR_ROW_M`),
and the cells where the paint has worn off are left out: wear is a share `wear` of each rectangle's
cells, chosen where a seeded value-noise field of the world position (patches 0.1–0.4 m across, as tyres
and weather wear them) is lowest, the cells nearer a rectangle's edges more readily (frayed edges), so
that lines are not CAD strips and the asphalt shows through. The remaining cells of each row merge into
one quad per run, flat, facing up, `PAINT_LIFT_M` over the surface the marking lies on.

Paint reflectance (linear RGB, `PAINT_RGB`) and 850 nm reflectance (`PAINT_NIR_REFLECTANCE`) per colour,
with a small seeded variation (dirt) per vertex.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from camgen.config.markings import BaysMarking, CrossingMarking, LineMarking

PAINT_LIFT_M = 0.003
"""Height of the paint over the surface it lies on, m: hot thermoplastic road marking is laid 1–3 mm thick
(0.040–0.125 in; sprayed 1.0–2.5 mm), thin paint a fraction of a millimetre. It also keeps the paint in
front of the surface in the depth test: with the renderer's float32 depth and 0.05 m near plane, depth
steps are about 1.2e-6·d² m at distance d, and a camera h metres up sees the paint's lift as h_lift·d/h of
depth along its ray, so 3 mm clears the steps by more than 2× out to d = 3 mm / (2 · 1.2e-6 · h) (210 m for
a camera 6 m up), beyond where a 0.1 m line is a pixel wide."""

WEAR_CELL_M = 0.02
"""Length of the wear grid's cells along a painted rectangle, m: the raggedness of a worn edge (a pixel spans
2 cm about 10–20 m from a 1080p camera of 60–90° field of view)."""
WEAR_ROW_M = 0.01
"""Width of the wear grid's rows across a rectangle, m: half a cell, since the steps of a worn long edge show
most (a 4K camera at 8 mm resolves 2.5 mm 10 m away)."""

PAINT_RGB = {"white": (0.50, 0.50, 0.48), "yellow": (0.45, 0.30, 0.04)}
"""Diffuse reflectance of road paint in daylight, linear RGB. EN 1436 classes the luminance factor β of dry
markings in steps of 0.10: a white class B4 marking has β ≥ 0.50, a yellow class B2 one β ≥ 0.30 (as a
supplier's EN 1436 specification of white and yellow sprayed thermoplastic states them; the standard's
table itself was not read). Edge lines measured on 965 km of Michigan highways reflected around 28 % or
60 % (two modes; Johnson, Kluge & Ervin 1995, UMTRI-95-42). White here: β = Y = 0.50, class B4's minimum;
yellow: Y = 0.31, B2's, with the chromaticity of a traffic yellow (R > G ≫ B). As Lambertian surfaces their
luminance coefficients under diffuse light Qd = 1000·ρ/π are 159 and 99 mcd m⁻² lx⁻¹, above EN 1436's
classes Q3 (white on asphalt, ≥ 130) and Q1 (yellow, ≥ 80). Retroreflection (RL: R2 ≥ 100 … R5 ≥ 300
mcd m⁻² lx⁻¹ for white) is not modelled: the paint is diffuse."""

PAINT_NIR_REFLECTANCE = {"white": 0.50, "yellow": 0.45}
"""Reflectance at 850 nm (the IR night mode, `camgen.render.nir`) of a marking in service, as `PAINT_RGB` is.
Estimates: no measured 850 nm reflectance of road-marking paint was found. Rutile TiO₂, the white of road
paint, scatters strongly through the near infrared and absorbs almost nothing there (Levinson, Berdahl &
Akbari 2005, "Solar spectral optical properties of pigments — Part II: survey of common colorants", Sol.
Energy Mater. Sol. Cells 89: 351–389), so white paint reflects about as much at 850 nm as in the visible;
a yellow pigment absorbs the blue and reflects the red and the near infrared alike. The dirt and tyre
rubber that take a marking in service from clean paint's 0.8–0.9 down to `PAINT_RGB`'s 0.50 are carbon,
which absorbs the near infrared as much as the visible. So a marking in service reflects at 850 nm what it
reflects in its red channel (`camgen.world.night.default_nir_reflectance`'s rule): 0.50 white, 0.45
yellow. (Clean paint's 0.80 / 0.70 beside a worn marking's visible 0.50 had the IR image show markings
brighter against the road than the day image, with nothing to support it.)"""

PAINT_ROUGHNESS = 0.7
"""glTF roughness of road paint: a matte binder with glass beads pressed in."""

DIRT_VARIATION = 0.08
"""Half the spread of a marking's reflectance about its colour (dirt, tyre rubber): ±8 %."""

EDGE_WEAR_BIAS = 0.07
"""How much better a cell holds for each cell it lies inside its rectangle's edge (up to
`EDGE_WEAR_DEPTH_CELLS`), in units of the noise's range: paint frays from its edges, and a worn patch seldom
takes a line's whole width."""
EDGE_WEAR_DEPTH_CELLS = 5
"""Cells in from the edge beyond which a cell holds no better."""

RUN_END_JITTER_CELLS = 0.4
"""How far a worn end of a run of paint moves along its row, at most, in cells (ragged worn edges)."""

WATER_N = 1.333
"""Refractive index of water."""
WATER_EXTERNAL_DIFFUSE_REFLECTANCE = 0.066
"""Reflectance of a water surface for diffuse light from above (Fresnel averaged over the hemisphere)."""


@dataclass(frozen=True)
class PaintRect:
    """A painted rectangle on the ground: centre (x, y), unit axis of its length, its length and width, m."""

    centre_m: tuple[float, float]
    axis: tuple[float, float]
    length_m: float
    width_m: float

    def corners_m(self) -> np.ndarray:
        """(4, 2) corners, counter-clockwise seen from above."""
        c, u = np.asarray(self.centre_m), np.asarray(self.axis)
        v = np.array([-u[1], u[0]])
        a, b = self.length_m / 2, self.width_m / 2
        return np.array([c - a * u - b * v, c + a * u - b * v, c + a * u + b * v, c - a * u + b * v])


@dataclass(frozen=True)
class PaintMesh:
    """A marking's worn paint, flat and facing up, in world coordinates."""

    vertices_m: np.ndarray
    """(V, 3) float32."""
    faces: np.ndarray
    """(F, 3) int32, counter-clockwise seen from above."""
    colours: np.ndarray
    """(V, 3) float32 linear reflectance."""
    nir_reflectance: np.ndarray
    """(V,) float32 reflectance at 850 nm."""
    painted_area_m2: float
    """Area of the paint left, m²."""
    design_area_m2: float
    """Area of the marking's rectangles as designed (no wear)."""


def _rect(start: np.ndarray, end: np.ndarray, width_m: float) -> PaintRect:
    d = end - start
    length = float(np.hypot(*d))
    return PaintRect(tuple((start + end) / 2), tuple(d / length), length, width_m)


def line_rects(along_m, width_m: float, dash_m: float | None = None, gap_m: float | None = None) -> list[PaintRect]:
    """The painted rectangles of a line `width_m` wide along the polyline `along_m` ((N, 2), m): one per
    segment when solid; when dashed, dashes `dash_m` long every `dash_m + gap_m` of arc length from the
    first point (the pattern runs on around bends; a dash over a bend is one rectangle per segment, and the
    last dash is cut at the polyline's end)."""
    points = np.asarray(along_m, dtype=np.float64)
    lengths = np.hypot(*np.diff(points, axis=0).T)
    if dash_m is None:
        return [_rect(a, b, width_m) for a, b in itertools.pairwise(points)]
    starts_s = np.concatenate([[0.0], np.cumsum(lengths)])
    total = starts_s[-1]
    rects = []
    period = dash_m + gap_m
    for k in range(math.floor(total / period) + 1):
        s0, s1 = k * period, min(k * period + dash_m, total)
        if s1 - s0 < 1e-9:
            continue
        for i, length in enumerate(lengths):
            lo, hi = max(s0, starts_s[i]), min(s1, starts_s[i + 1])
            if hi - lo > 1e-9:
                direction = (points[i + 1] - points[i]) / length
                a = points[i] + (lo - starts_s[i]) * direction
                rects.append(_rect(a, a + (hi - lo) * direction, width_m))
    return rects


def bay_rects(
    first_centre_m,
    heading_deg: float,
    count: int,
    width_m: float,
    length_m: float,
    line_width_m: float,
    layout: str = "perpendicular",
    closed: bool = False,
) -> list[PaintRect]:
    """The lines of a row of `count` bays `width_m` × `length_m` (across × along a parked car), the first
    centred at `first_centre_m`, their length along `heading_deg`.

    Perpendicular: bays side by side, the k-th centred k·width_m to the left (+90°) of the first; a line
    `length_m` long along each of the count + 1 bay sides, centred on the side; closed: a line across the
    row's front end (its centre on the bays' front edge), the side lines then stopping at its near edge.
    Parallel: bays nose to tail, the k-th k·length_m ahead; a line `width_m` long across each of the
    count + 1 bay ends; closed: a line along the row's left side, the end lines stopping at it."""
    h = math.radians(heading_deg)
    u = np.array([math.cos(h), math.sin(h)])  # along a parked car
    v = np.array([-u[1], u[0]])  # to its left
    c0 = np.asarray(first_centre_m, dtype=np.float64)
    if layout == "perpendicular":
        step, across, along, side_len, side_axis = v, width_m, length_m, length_m, u
    else:
        step, across, along, side_len, side_axis = u, length_m, width_m, width_m, v
    # The "sides" are the lines between neighbours (along side_axis); the closing line runs along the row
    # at the far end of side_axis.
    trim = line_width_m / 2 if closed else 0.0
    rects = []
    for k in range(count + 1):
        centre = c0 + (k - 0.5) * across * step - trim / 2 * side_axis
        rects.append(PaintRect(tuple(centre), tuple(side_axis), side_len - trim, line_width_m))
    if closed:
        row_centre = c0 + (count - 1) / 2 * across * step + along / 2 * side_axis
        row_length = count * across + line_width_m
        rects.append(PaintRect(tuple(row_centre), tuple(step), row_length, line_width_m))
    return rects


def crossing_rects(from_m, to_m, width_m: float, stripe_m: float, gap_m: float) -> list[PaintRect]:
    """The bars of a zebra crosswalk between the kerbs `from_m` and `to_m` (the walkers' line across the
    road, span L): n = ⌊(L + gap_m) / (stripe_m + gap_m)⌋ bars `stripe_m` wide across the road and
    `width_m` long along the traffic, `stripe_m + gap_m` apart, the pattern centred between the kerbs."""
    a, b = np.asarray(from_m, dtype=np.float64), np.asarray(to_m, dtype=np.float64)
    span = float(np.hypot(*(b - a)))
    across = (b - a) / span
    along = np.array([-across[1], across[0]])
    n = math.floor((span + gap_m) / (stripe_m + gap_m) + 1e-9)
    used = n * stripe_m + (n - 1) * gap_m
    first = (span - used) / 2 + stripe_m / 2
    return [
        PaintRect(tuple(a + (first + k * (stripe_m + gap_m)) * across), tuple(along), width_m, stripe_m)
        for k in range(n)
    ]


def marking_rects(marking: LineMarking | BaysMarking | CrossingMarking) -> list[PaintRect]:
    """The painted rectangles of a marking of `camgen.config.markings`."""
    if isinstance(marking, LineMarking):
        return line_rects(marking.along_m, marking.width_m, marking.dash_m, marking.gap_m)
    if isinstance(marking, BaysMarking):
        width, length = marking.bay_size_m
        return bay_rects(
            marking.first_centre_m,
            marking.heading_deg,
            marking.count,
            width,
            length,
            marking.line_width_m,
            marking.layout,
            marking.closed,
        )
    if isinstance(marking, CrossingMarking):
        return crossing_rects(marking.from_m, marking.to_m, marking.width_m, marking.stripe_m, marking.gap_m)
    raise TypeError(f"unknown marking {type(marking).__name__}")


def _hash_uniform(ix: np.ndarray, iy: np.ndarray, seed: int) -> np.ndarray:
    """A uniform number in [0, 1) for each integer lattice point and seed (SplitMix64's finaliser)."""
    with np.errstate(over="ignore"):
        h = (
            ix.astype(np.uint64) * np.uint64(0x9E3779B97F4A7C15)
            ^ iy.astype(np.uint64) * np.uint64(0xC2B2AE3D27D4EB4F)
            ^ np.uint64(seed & 0xFFFFFFFFFFFFFFFF) * np.uint64(0x165667B19E3779F9)
        )
        h ^= h >> np.uint64(30)
        h *= np.uint64(0xBF58476D1CE4E5B9)
        h ^= h >> np.uint64(27)
        h *= np.uint64(0x94D049BB133111EB)
        h ^= h >> np.uint64(31)
    return (h >> np.uint64(11)).astype(np.float64) / float(1 << 53)


def value_noise(xy_m: np.ndarray, scale_m: float, seed: int) -> np.ndarray:
    """Value noise in [0, 1) at points (N, 2), m: seeded values on a lattice `scale_m` apart, blended with
    a smoothstep; the same seed gives the same field everywhere."""
    p = np.asarray(xy_m, dtype=np.float64) / scale_m
    i = np.floor(p)
    f = p - i
    w = f * f * (3 - 2 * f)
    ix, iy = i[:, 0].astype(np.int64), i[:, 1].astype(np.int64)
    v00, v10 = _hash_uniform(ix, iy, seed), _hash_uniform(ix + 1, iy, seed)
    v01, v11 = _hash_uniform(ix, iy + 1, seed), _hash_uniform(ix + 1, iy + 1, seed)
    bottom = v00 + (v10 - v00) * w[:, 0]
    top = v01 + (v11 - v01) * w[:, 0]
    return bottom + (top - bottom) * w[:, 1]


def wear_score(xy_m: np.ndarray, seed: int) -> np.ndarray:
    """How well the paint at each point (N, 2) holds, in [0, 1): octaves of value noise 0.4, 0.12 and
    0.04 m across; the lowest scores wear first."""
    return (
        0.6 * value_noise(xy_m, 0.4, seed)
        + 0.3 * value_noise(xy_m, 0.12, seed + 1)
        + 0.1 * value_noise(xy_m, 0.04, seed + 2)
    )


def paint_mesh(
    rects: list[PaintRect],
    colour: str,
    *,
    height_m: float,
    wear: float,
    seed: int,
    cell_m: float = WEAR_CELL_M,
    row_m: float = WEAR_ROW_M,
) -> PaintMesh:
    """The worn paint of `rects` at `height_m` (the surface's height plus `PAINT_LIFT_M`): each rectangle's
    grid of cells (rows about `row_m` wide across it, columns about `cell_m` long along it), a share `wear`
    of each rectangle's cells left out where `wear_score` plus `EDGE_WEAR_BIAS` per cell in from the edge
    is lowest, and each row's runs of kept cells as one quad."""
    grids = []
    for rect in rects:
        rows = max(1, round(rect.width_m / row_m))
        cols = max(1, math.ceil(rect.length_m / cell_m))
        su = (np.arange(cols) + 0.5) / cols * rect.length_m - rect.length_m / 2
        sv = (np.arange(rows) + 0.5) / rows * rect.width_m - rect.width_m / 2
        u, c = np.asarray(rect.axis), np.asarray(rect.centre_m)
        v = np.array([-u[1], u[0]])
        centres = c + su[None, :, None] * u + sv[:, None, None] * v  # (rows, cols, 2)
        row, col = np.arange(rows), np.arange(cols)
        inward = np.minimum.outer(np.minimum(row, rows - 1 - row), np.minimum(col, cols - 1 - col))
        grids.append((rect, rows, cols, centres, np.minimum(inward, EDGE_WEAR_DEPTH_CELLS)))
    scores = np.concatenate([wear_score(g[3].reshape(-1, 2), seed) + EDGE_WEAR_BIAS * g[4].ravel() for g in grids])
    sizes = [g[1] * g[2] for g in grids]
    kept_all = np.ones(len(scores), dtype=bool)
    start = 0
    for n in sizes:  # each rectangle loses its share: a thin line as much as a wide bar
        if wear > 0:
            kept_all[start + np.argsort(scores[start : start + n], kind="stable")[: round(wear * n)]] = False
        start += n
    quads = []
    offset = 0
    for (rect, rows, cols, _, _), n in zip(grids, sizes, strict=True):
        kept = kept_all[offset : offset + n].reshape(rows, cols)
        offset += n
        padded = np.pad(kept.astype(np.int8), ((0, 0), (1, 1)))
        steps = np.diff(padded, axis=1)
        row_of_start, start = np.nonzero(steps == 1)
        _, stop = np.nonzero(steps == -1)  # row-major: each row's stops pair with its starts in order
        u, c = np.asarray(rect.axis), np.asarray(rect.centre_m)
        v = np.array([-u[1], u[0]])
        # A worn end of a run moves by up to ±0.4 of a cell (seeded by where it lies), so that the worn edges
        # are ragged rather than steps on the grid; a run's end at the rectangle's own end stays put.
        cell_u = rect.length_m / cols
        u0 = start * cell_u - rect.length_m / 2
        u1 = stop * cell_u - rect.length_m / 2
        v_mid = (row_of_start + 0.5) / rows * rect.width_m - rect.width_m / 2
        for ends, index, keep in ((u0, start, 0), (u1, stop, cols)):
            at = c + ends[:, None] * u + v_mid[:, None] * v
            shift = RUN_END_JITTER_CELLS * cell_u * (2.0 * value_noise(at, cell_m, seed + 4) - 1.0)
            ends += np.where(index == keep, 0.0, shift)
        v0 = row_of_start / rows * rect.width_m - rect.width_m / 2
        v1 = (row_of_start + 1) / rows * rect.width_m - rect.width_m / 2
        corners = np.stack(
            [c + a[:, None] * u + b[:, None] * v for a, b in ((u0, v0), (u1, v0), (u1, v1), (u0, v1))], axis=1
        )
        quads.append(corners)
    corners = np.concatenate(quads) if quads else np.zeros((0, 4, 2))
    xy = corners.reshape(-1, 2)
    vertices = np.column_stack([xy, np.full(len(xy), height_m)]).astype(np.float32)
    base = np.arange(len(corners), dtype=np.int32)[:, None] * 4
    faces = np.concatenate([base + np.array([0, 1, 2]), base + np.array([0, 2, 3])]).astype(np.int32)
    dirt = 1.0 + DIRT_VARIATION * (2.0 * value_noise(xy, 0.25, seed + 3) - 1.0) if len(xy) else np.zeros(0)
    colours = (np.asarray(PAINT_RGB[colour])[None, :] * dirt[:, None]).astype(np.float32)
    nir = (PAINT_NIR_REFLECTANCE[colour] * dirt).astype(np.float32)
    return PaintMesh(
        vertices_m=vertices,
        faces=faces,
        colours=colours,
        nir_reflectance=nir,
        painted_area_m2=_quads_area_m2(corners),
        design_area_m2=float(sum(r.length_m * r.width_m for r in rects)),
    )


def _quads_area_m2(corners: np.ndarray) -> float:
    """Total area of quads (Q, 4, 2), each ½ |d₀₂ × d₁₃| of its diagonals."""
    d02, d13 = corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1]
    return float(np.sum(d02[:, 0] * d13[:, 1] - d02[:, 1] * d13[:, 0]) / 2)


def marking_seed(scene_seed: int, index: int) -> int:
    """The wear seed of the `index`-th marking whose own is left out: drawn from the scene's seed."""
    return int(np.random.SeedSequence([scene_seed, 0x4D41524B, index]).generate_state(1)[0])


def marking_paint(marking: LineMarking | BaysMarking | CrossingMarking, *, scene_seed: int, index: int) -> PaintMesh:
    """The worn paint of the `index`-th marking of a scene whose seed is `scene_seed`."""
    seed = marking.seed if marking.seed is not None else marking_seed(scene_seed, index)
    return paint_mesh(
        marking_rects(marking),
        marking.colour,
        height_m=marking.surface_height_m + PAINT_LIFT_M,
        wear=marking.wear,
        seed=seed,
    )


def wet_reflectance(reflectance):
    """Diffuse reflectance of a surface of dry reflectance A under a water film (Ångström 1925, "The
    albedo of various surfaces of ground", Geogr. Ann. 7: 323–342; Lekner & Dorf 1988, Appl. Opt. 27:
    1278–1280): light entering the film (1 − r_e) is reflected by the surface, and of what returns to the
    water's surface a share r_i = 1 − (1 − r_e)/n² is reflected back down again, so
    A_wet = (1 − r_e)(1 − r_i)·A / (1 − r_i·A). With n = 1.333 and r_e = 0.066: r_i = 0.474, asphalt
    (A = 0.1) keeps 0.52 of its reflectance, white paint (0.5) 0.64: bright paint darkens less when wet.
    Any shape."""
    a = np.asarray(reflectance, dtype=np.float64)
    r_e = WATER_EXTERNAL_DIFFUSE_REFLECTANCE
    r_i = 1.0 - (1.0 - r_e) / WATER_N**2
    return (1.0 - r_e) * (1.0 - r_i) * a / (1.0 - r_i * a)
