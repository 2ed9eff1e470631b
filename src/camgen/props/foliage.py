"""Crowns and bushes made of leaves: a closed envelope (the crown's lumps) filled with small two-sided leaf
cards, clumped, with gaps through which the sky and the background show and sunlight dapples the ground.

The model, per plant (its frame: z up):

- **Leaf area.** Solved from the gap fraction: each tree draws a gap fraction p from `CROWN_GAP_FRACTION`
  (inside the measured crown porosity, below) and takes the mean leaf area density u for which Beer–Lambert
  (randomly placed, spherically oriented leaves: G = ½, Ross 1981, "The radiation regime and architecture
  of plant stands"; Campbell & Norman 1998, "An Introduction to Environmental Biophysics", §15), averaged
  over lines through the envelope along z, x and y (`line_envelopes`, `LINE_WEIGHTS`), clumps included,
  lets p through (`leaf_area_for_gap_m2`); the leaf area is u times the envelope's volume. Its leaf area
  index, LAI = A / P with P the envelope's area seen from above (`Envelope.projected_area_m2`), comes to
  4.5–7.5 for these crowns, within the 3–8 of broadleaf canopies (Asner, Scurlock & Hicke 2003, "Global
  synthesis of leaf area index observations", Global Ecol. Biogeogr. 12: 191). Bushes draw their LAI
  instead (`BUSH_LEAF_AREA_INDEX`) and hide their inside behind a dark core.
- **Where the leaves are.** Twigs are thrown uniformly into the envelope's volume (the union of its
  closed lumps, resolved on vertical columns of `COLUMN_CELL_FRACTION` of the crown's width), kept with a
  probability that a smooth random field of wavelengths 0.15–0.4 of the crown's width sets
  (`ClumpField`, `CLUMP_THRESHOLD`): leaves gather in clumps with empty gaps between them, as on real
  branches (a clumping index Ω < 1, Nilson 1971, Agric. Meteorol. 8: 25), so that a given gap fraction
  takes 1.5–1.7 times the leaves of a random (Poisson) canopy (measured: Ω ≈ 0.6–0.7). Each twig holds
  `LEAVES_PER_TWIG` leaves fanned about it, and they flutter in the wind as one (`PropPart.flutter_groups`,
  `camgen.props.sway`), so that each leaf keeps its shape.
- **Leaves.** Kites of length l and width 0.6·l (area 0.3·l²), each a leaf or a small cluster of leaves:
  `LEAF_CARD_AREA_M2` each, made larger when a big crown would need more than `MAX_LEAF_CARDS` (the
  triangle budget: 4 triangles a card). Normals uniform on the sphere, twig by twig, jittered leaf by
  leaf (a spherical leaf angle distribution). Each card has two sides, two triangles each, wound
  opposite ways (the renderer culls back faces), so it is seen and casts a shadow from either side.
- **Shading normals.** Each side's normal is its face normal bent towards the envelope's outward
  normal at the leaf by `OUTWARD_NORMAL_WEIGHT`: a crown at 10–40 m then reads as a volume lit on its
  sunward side, not as confetti of randomly lit cards (the common practice for foliage cards in real-time
  rendering), while the shadow maps still cut the light into flecks inside the crown and on the ground.
- **Colour.** The canopy's albedo (`camgen.props.types.LEAF_RGB`) times a smooth field (±30 %, lighter at
  the top) and a ±12 % draw per leaf; the 850 nm reflectance varies by a tenth of that.

Crown porosity, measured (`CROWN_POROSITY_RANGE`): the fraction of the sky seen through the crowns of
mature urban trees in leaf is 0.11–0.27 (lime 0.11, oak 0.17, sycamore 0.18, horse chestnut 0.19, birch
0.24, Scots pine 0.27: Wilkinson 1992, "Modelling light attenuation by urban trees", PhD thesis,
Manchester Metropolitan University, as tabulated by Tregenza & Sharples, "Daylight algorithms", 1.44);
solar transmissivity through single urban crowns in full leaf 0.088–0.275 (Konarska et al. 2014,
"Transmissivity of solar radiation through crowns of single urban trees", Theor. Appl. Climatol. 117:
363). Beer–Lambert along a path through a single crown: Zhang et al. 2023, "Estimating the leaf area
index of urban individual trees based on actual path length", Build. Environ. 245: 110811.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from camgen.props.shapes import PropPart, smooth_noise

CROWN_POROSITY_RANGE = (0.11, 0.27)
"""Measured fraction of the sky seen through mature urban crowns in leaf (module docstring)."""
CROWN_GAP_FRACTION = (0.15, 0.24)
"""The gap fraction, along lines in the three axes' directions, a tree's leaf area is solved for, drawn per
tree: inside the measured range (`CROWN_POROSITY_RANGE`), with room for lines in other directions."""
CROWN_LEAF_AREA_INDEX_RANGE = (3.0, 8.0)
"""The span of broadleaf canopies' LAI (Asner, Scurlock & Hicke 2003) that the solved LAI must lie in (tested)."""
BUSH_LEAF_AREA_INDEX = (3.0, 5.0)
"""Shrubs and hedges, over their projected area (chosen, as a tree's); their dense inside is a dark core
(`camgen.props.types.BUSH_CORE_SCALE`)."""
LEAF_PROJECTION_G = 0.5
"""Mean projection of a unit leaf area on a plane normal to a direction, leaves oriented uniformly on the sphere."""
LEAF_CARD_AREA_M2 = 0.012
"""A tree's leaf card: a kite 0.2 m long (a large leaf, or a few lime leaves together: 2–7 px at 10–40 m
for a 2 MP camera of 60° field)."""
BUSH_LEAF_CARD_AREA_M2 = 0.003
"""A bush's: 0.10 m long (privet, laurel, box clusters)."""
BUSH_LARGEST_CARD_M2 = 0.012
"""A long hedge's cards grow to a tree's at most (0.2 m), then carry less leaf area than its LAI asks."""
MAX_LEAF_CARDS = 5000
"""Cards per plant at most (20 000 triangles, 40 000 vertices); a bigger crown gets bigger cards, the same
leaf area. The cost is the sway's: each frame bends every vertex of a swaying plant (`camgen.props.sway`)."""
LEAF_ASPECT = 0.6
"""A card's width over its length."""
LEAVES_PER_TWIG = 4
TWIG_SPREAD_RAD = math.radians(35.0)
"""How far each leaf's normal tilts from its twig's, at most."""
CLUMP_WAVES = 9
CLUMP_WAVELENGTH_FRACTION = (0.15, 0.4)
"""Wavelengths of the clumping field's waves over the envelope's width (`ClumpField`): clumps the size of
branches, 0.6–1.6 m in a 4 m crown; a fixed size would leave whole columns of a small crown empty."""
CLUMP_THRESHOLD = (-1.0, 0.2)
"""A twig is kept with probability clip((n − a)/(b − a), 0, 1) of the unit-variance clumping field n: none
where n < a (a gap), all where n > b (a clump); `leafy_volume(..., clumped=False)` keeps every twig."""
OUTWARD_NORMAL_WEIGHT = 1.0
"""Weight of the envelope's outward normal against the card's own in a leaf's shading normal."""
COLUMN_CELL_FRACTION = 1.0 / 100.0
"""Column width over the envelope's larger horizontal extent, for the volume's resolution."""
DENSITY_STEPS = 16
"""Points per column at which `leaf_area_for_gap_m2` integrates a leaf density."""
COLOUR_VARIATION = 0.3
LEAF_SHADE_JITTER = 0.12


@dataclass(frozen=True)
class Envelope:
    """The volume of a union of closed surfaces, on vertical columns: for each column (x, y) the z
    intervals inside at least one surface. Pure geometry; `leafy_volume` throws its twigs into it."""

    cell_m: float
    origin_m: np.ndarray
    """(2,) the corner of the column grid: column (i, j) is centred on origin + (i + ½, j + ½)·cell."""
    grid_rows: np.ndarray
    """(I, J) each grid column's row in the arrays below, −1 where the column is empty."""
    columns_xy_m: np.ndarray
    """(C, 2) centres of the columns with some volume."""
    low_m: np.ndarray
    """(C, K) lower ends of each column's intervals in each surface, NaN where none (K: the most any has)."""
    high_m: np.ndarray
    """(C, K) upper ends."""

    @property
    def width_m(self) -> float:
        """The larger horizontal extent of the columns, m."""
        return float(np.ptp(self.columns_xy_m, axis=0).max()) + self.cell_m

    @property
    def projected_area_m2(self) -> float:
        """The area of the envelope's shadow from straight above, m²."""
        return len(self.columns_xy_m) * self.cell_m**2

    def count_inside(self, column: np.ndarray, z_m: np.ndarray) -> np.ndarray:
        """(N,) how many of the surfaces hold the point at height `z_m` (N,) of column index `column` (N,)."""
        low, high = self.low_m[column], self.high_m[column]
        return np.sum((z_m[:, None] >= low) & (z_m[:, None] < high), axis=1)

    def contains(self, points_m: np.ndarray) -> np.ndarray:
        """(N,) whether each point (N, 3) lies inside the union (to the columns' width)."""
        ij = np.floor((points_m[:, :2] - self.origin_m) / self.cell_m).astype(int)
        inside_grid = np.all((ij >= 0) & (ij < self.grid_rows.shape), axis=1)
        rows = np.full(len(points_m), -1)
        rows[inside_grid] = self.grid_rows[ij[inside_grid, 0], ij[inside_grid, 1]]
        result = np.zeros(len(points_m), dtype=bool)
        found = rows >= 0
        result[found] = self.count_inside(rows[found], points_m[found, 2]) > 0
        return result

    def column_lengths_m(self) -> np.ndarray:
        """(C,) each column's length inside the union (overlapping intervals counted once), m."""
        order = np.argsort(np.nan_to_num(self.low_m, nan=np.inf), axis=1)
        low = np.take_along_axis(self.low_m, order, axis=1)
        high = np.take_along_axis(self.high_m, order, axis=1)
        total = np.zeros(len(low))
        end = np.full(len(low), -np.inf)
        for k in range(low.shape[1]):
            a, b = low[:, k], high[:, k]
            present = ~np.isnan(a)
            total += np.where(present & (b > end), b - np.maximum(a, end), 0.0)
            end = np.where(present, np.maximum(end, b), end)
        return total

    def volume_m3(self) -> float:
        """The union's volume, m³ (overlaps counted once)."""
        return float(self.column_lengths_m().sum()) * self.cell_m**2


LINE_AXES = ((0, 1, 2), (1, 2, 0), (2, 0, 1))
"""Cyclic orders of the world's axes: an envelope built on points reordered so (z along the last) runs its
columns along world z, x and y (`line_envelopes`)."""
LINE_WEIGHTS = (2.0, 1.0, 1.0)
"""Weights of the lines along z, x and y in a tree's gap fraction (over their areas): the vertical twice, as
the measurements look up through crowns or along the sun's steep rays, the horizontal as cameras see them."""


def line_envelopes(surfaces: list[tuple[np.ndarray, np.ndarray]]) -> list[tuple[Envelope, tuple[int, int, int]]]:
    """The `Envelope` of closed surfaces (vertices (V, 3), faces (F, 3)) three times, its columns along world
    z, x and y, each with its axis order (`LINE_AXES`)."""
    return [(envelope_of([(np.asarray(v)[:, list(axes)], f) for v, f in surfaces]), axes) for axes in LINE_AXES]


def leaf_area_for_gap_m2(
    envelopes: list[tuple[Envelope, tuple[int, int, int]]],
    gap_fraction: float,
    density=None,
    g: float = LEAF_PROJECTION_G,
) -> float:
    """The leaf area, m², spread through a volume, uniformly or in proportion to `density` (a function of world
    points (N, 3) → (N,) ≥ 0: the clumps' `ClumpField.keep_probability`), that lets `gap_fraction` of the
    lines along the envelopes' columns through (one envelope, vertical lines; `line_envelopes`' three, lines
    along the three axes, each set weighed by its area, as lines at random cross a body in proportion to its
    area seen along them). Beer–Lambert (`beer_lambert_gap`): a column's optical path is G·u·ℓ, ℓ = ∫ρ ds /
    mean(ρ) (its length inside when uniform), by the midpoint rule on `DENSITY_STEPS` points; u, the mean leaf
    area density, solves the weighted mean over columns of exp(−G·u·ℓ) = `gap_fraction` by bisection; the leaf
    area is u times the volume."""
    lengths, weights, integrals, covered = [], [], 0.0, 0.0
    for envelope, axes in envelopes:
        length = envelope.column_lengths_m()
        if density is not None:
            low = np.nanmin(envelope.low_m, axis=1)
            step = (np.nanmax(envelope.high_m, axis=1) - low) / DENSITY_STEPS
            rows = np.repeat(np.arange(len(low)), DENSITY_STEPS)
            z = (low[:, None] + (np.arange(DENSITY_STEPS) + 0.5) * step[:, None]).ravel()
            inside = envelope.count_inside(rows, z) > 0
            world = np.empty((int(inside.sum()), 3))
            world[:, list(axes)] = np.column_stack([envelope.columns_xy_m[rows[inside]], z[inside]])
            weight = np.zeros(len(z))
            weight[inside] = density(world)
            length = weight.reshape(-1, DENSITY_STEPS).sum(axis=1) * step
            integrals += float(length.sum()) * envelope.cell_m**2
            covered += float((inside.reshape(-1, DENSITY_STEPS).sum(axis=1) * step).sum()) * envelope.cell_m**2
        lengths.append(length)
        weights.append(np.full(len(length), LINE_WEIGHTS[LINE_AXES.index(axes)] * envelope.cell_m**2))
    length, weight = np.concatenate(lengths), np.concatenate(weights)
    if density is not None:
        length = length / (integrals / covered)
    weight /= weight.sum()

    def gap(u: float) -> float:
        return float(weight @ beer_lambert_gap(length, u, g))

    low, high = 0.0, 1.0
    while gap(high) > gap_fraction:
        high *= 2.0
    for _ in range(40):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if gap(middle) > gap_fraction else (low, middle)
    return 0.5 * (low + high) * envelopes[0][0].volume_m3()


def _vertical_hits(vertices: np.ndarray, faces: np.ndarray, origin: np.ndarray, cell: float, shape: tuple[int, int]):
    """Where the vertical lines through the column centres origin + (i + ½, j + ½)·cell cross the triangles:
    (column flat index (H,), z (H,)). Each triangle is tested against the columns in its xy bounding box."""
    corners = vertices[faces]  # (F, 3, 3)
    lo = np.floor((corners[:, :, :2].min(axis=1) - origin) / cell - 0.5).astype(int) + 1
    hi = np.floor((corners[:, :, :2].max(axis=1) - origin) / cell - 0.5).astype(int)
    lo = np.maximum(lo, 0)
    hi = np.minimum(hi, np.array(shape) - 1)
    nx, ny = np.maximum(hi[:, 0] - lo[:, 0] + 1, 0), np.maximum(hi[:, 1] - lo[:, 1] + 1, 0)
    counts = nx * ny
    tri = np.repeat(np.arange(len(faces)), counts)
    if len(tri) == 0:
        return np.zeros(0, dtype=int), np.zeros(0)
    local = np.arange(len(tri)) - np.repeat(np.cumsum(counts) - counts, counts)
    ix = lo[tri, 0] + local % nx[tri]
    iy = lo[tri, 1] + local // nx[tri]
    px = origin[0] + (ix + 0.5) * cell
    py = origin[1] + (iy + 0.5) * cell
    a, b, c = corners[tri, 0], corners[tri, 1], corners[tri, 2]
    d = (b[:, 1] - c[:, 1]) * (a[:, 0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (a[:, 1] - c[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        u = ((b[:, 1] - c[:, 1]) * (px - c[:, 0]) + (c[:, 0] - b[:, 0]) * (py - c[:, 1])) / d
        v = ((c[:, 1] - a[:, 1]) * (px - c[:, 0]) + (a[:, 0] - c[:, 0]) * (py - c[:, 1])) / d
        w = 1.0 - u - v
        z = u * a[:, 2] + v * b[:, 2] + w * c[:, 2]
    hit = (d != 0) & (u >= 0) & (v >= 0) & (w >= 0)
    return (ix * shape[1] + iy)[hit], z[hit]


def envelope_of(surfaces: list[tuple[np.ndarray, np.ndarray]], cell_fraction: float = COLUMN_CELL_FRACTION) -> Envelope:
    """The `Envelope` of closed surfaces given as (vertices (V, 3), faces (F, 3)), on columns of
    `cell_fraction` × the union's larger horizontal extent."""
    points = np.concatenate([v for v, _ in surfaces])
    origin = points[:, :2].min(axis=0)
    extent = points[:, :2].max(axis=0) - origin
    cell = float(extent.max() * cell_fraction)
    shape = (math.ceil(extent[0] / cell) + 1, math.ceil(extent[1] / cell) + 1)
    per_surface = []
    for vertices, faces in surfaces:
        column, z = _vertical_hits(np.asarray(vertices, float), np.asarray(faces), origin, cell, shape)
        order = np.lexsort((z, column))
        column, z = column[order], z[order]
        # a line through a shared edge or corner meets each of its triangles there: one crossing
        keep = np.ones(len(z), dtype=bool)
        keep[1:] = (column[1:] != column[:-1]) | (np.abs(z[1:] - z[:-1]) > 1e-9)
        column, z = column[keep], z[keep]
        starts = np.flatnonzero(np.r_[True, column[1:] != column[:-1]])
        counts = np.diff(np.r_[starts, len(column)])
        even = np.repeat(counts % 2 == 0, counts)  # a grazing line (an odd count) is left out
        column, z = column[even], z[even]
        per_surface.append((column[0::2], z[0::2], z[1::2]))
    columns = np.unique(np.concatenate([c for c, _, _ in per_surface]))
    rows = np.searchsorted(columns, np.concatenate([c for c, _, _ in per_surface]))
    lows = np.concatenate([lo for _, lo, _ in per_surface])
    highs = np.concatenate([hi for _, _, hi in per_surface])
    order = np.argsort(rows, kind="stable")
    rows, lows, highs = rows[order], lows[order], highs[order]
    starts = np.flatnonzero(np.r_[True, rows[1:] != rows[:-1]])
    rank = np.arange(len(rows)) - np.repeat(starts, np.diff(np.r_[starts, len(rows)]))
    depth = int(rank.max()) + 1
    low = np.full((len(columns), depth), np.nan)
    high = np.full((len(columns), depth), np.nan)
    low[rows, rank], high[rows, rank] = lows, highs
    ix, iy = columns // shape[1], columns % shape[1]
    xy = origin + (np.column_stack([ix, iy]) + 0.5) * cell
    grid = np.full(shape, -1)
    grid[ix, iy] = np.arange(len(columns))
    return Envelope(cell, origin, grid, xy, low, high)


def points_in(envelope: Envelope, count: int, *, rng: np.random.Generator) -> np.ndarray:
    """(count, 3) points uniform in the envelope's volume (to its columns' width): a column by the summed
    length of its intervals, an interval by its length, a height uniform in it, kept with probability 1/m
    where m surfaces overlap there; x, y uniform across the column."""
    lengths = np.nan_to_num(envelope.high_m - envelope.low_m)
    weights = lengths.ravel() / lengths.sum()
    kept: list[np.ndarray] = []
    total = 0
    while total < count:
        n = int((count - total) * 1.6) + 16
        pick = rng.choice(len(weights), size=n, p=weights)
        column, slot = np.divmod(pick, lengths.shape[1])
        z = envelope.low_m[column, slot] + rng.random(n) * lengths[column, slot]
        keep = rng.random(n) * envelope.count_inside(column, z) < 1.0
        xy = envelope.columns_xy_m[column] + (rng.random((n, 2)) - 0.5) * envelope.cell_m
        batch = np.column_stack([xy, z])[keep]
        kept.append(batch)
        total += len(batch)
    return np.concatenate(kept)[:count]


@dataclass(frozen=True)
class ClumpField:
    """A smooth random field of unit variance over space: a sum of `CLUMP_WAVES` plane waves of random
    direction and phase, wavelengths `CLUMP_WAVELENGTH_FRACTION` of the crown's width, amplitudes ∝
    wavelength (larger clumps dominate), normalised by its expected standard deviation (so that it is one
    function of position, whatever points it is asked at)."""

    wave_vectors_rad_m: np.ndarray
    """(W, 3)."""
    phases_rad: np.ndarray
    amplitudes: np.ndarray
    """Σ a²/2 = 1."""

    @classmethod
    def draw(cls, rng: np.random.Generator, width_m: float) -> ClumpField:
        directions = _unit(rng.normal(size=(CLUMP_WAVES, 3)))
        wavelengths = rng.uniform(*CLUMP_WAVELENGTH_FRACTION, CLUMP_WAVES) * width_m
        amplitudes = wavelengths / math.sqrt(float(np.sum(wavelengths**2)) / 2.0)
        return cls(
            directions * (2 * math.pi / wavelengths)[:, None], rng.uniform(0, 2 * math.pi, CLUMP_WAVES), amplitudes
        )

    def __call__(self, points_m: np.ndarray) -> np.ndarray:
        return np.cos(points_m @ self.wave_vectors_rad_m.T + self.phases_rad) @ self.amplitudes

    def keep_probability(self, points_m: np.ndarray) -> np.ndarray:
        """clip((n − a)/(b − a), 0, 1), (a, b) = `CLUMP_THRESHOLD`."""
        a, b = CLUMP_THRESHOLD
        return np.clip((self(points_m) - a) / (b - a), 0.0, 1.0)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _frames(normals: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors (N, 3) each, perpendicular to each other and to `normals`, turned at random about them."""
    helper = np.where(np.abs(normals[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    e1 = _unit(np.cross(normals, helper))
    e2 = np.cross(normals, e1)
    angle = rng.uniform(0.0, 2 * math.pi, len(normals))[:, None]
    return np.cos(angle) * e1 + np.sin(angle) * e2, -np.sin(angle) * e1 + np.cos(angle) * e2


def leaf_cards(
    bases_m: np.ndarray, normals: np.ndarray, along: np.ndarray, length_m: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Kite-shaped cards, two-sided: each leaf from its base (N, 3) along the unit `along` (N, 3), in the plane
    normal to `normals` (N, 3); length `length_m`, width `LEAF_ASPECT`·length, widest at 0.4 of the length.

    Returns (vertices (8N, 3): the front side's 4 corners then the back side's, face normals (8N, 3), faces
    (4N, 3): 2 triangles a side, the front counter-clockwise seen from its normal, the back the other way)."""
    n = len(bases_m)
    across = np.cross(normals, along)
    tip = bases_m + along * length_m
    middle = bases_m + along * (0.4 * length_m)
    half = 0.5 * LEAF_ASPECT * length_m
    corners = np.stack([bases_m, middle - across * half, tip, middle + across * half], axis=1)  # (N, 4, 3)
    vertices = np.concatenate([corners, corners], axis=1).reshape(-1, 3)
    face_normals = np.concatenate([np.repeat(normals[:, None], 4, 1), np.repeat(-normals[:, None], 4, 1)], axis=1)
    # (right − base) × (tip − base) = ½·width·length·n: the front's triangles turn counter-clockwise about n
    card = np.array([[0, 1, 2], [0, 2, 3], [4, 6, 5], [4, 7, 6]])
    faces = ((np.arange(n) * 8)[:, None, None] + card).reshape(-1, 3)
    return vertices, face_normals.reshape(-1, 3), faces


def card_count_and_area(leaf_area_m2: float, card_area_m2: float, *, largest_m2: float = math.inf) -> tuple[int, float]:
    """How many cards carry `leaf_area_m2` and each one's area, m²: `card_area_m2` each, unless that needs more
    than `MAX_LEAF_CARDS`: then that many, larger, up to `largest_m2` (beyond it they carry less leaf area);
    counts round up to whole twigs of `LEAVES_PER_TWIG`."""
    count = max(LEAVES_PER_TWIG, math.ceil(leaf_area_m2 / card_area_m2))
    count = math.ceil(min(count, MAX_LEAF_CARDS) / LEAVES_PER_TWIG) * LEAVES_PER_TWIG
    return count, min(leaf_area_m2 / count, largest_m2)


def leafy_volume(
    name: str,
    envelope: Envelope,
    leaf_area_m2: float | None = None,
    *,
    gap_fraction: float | None = None,
    gap_envelopes: list[tuple[Envelope, tuple[int, int, int]]] | None = None,
    card_area_m2: float,
    centre_m,
    radii_m,
    rgb,
    nir: float,
    rng: np.random.Generator,
    clumped: bool = True,
    exclude=None,
    largest_card_m2: float = math.inf,
) -> PropPart:
    """The leaves of a crown or bush as one part: `leaf_area_m2` (one-sided) of two-sided cards on twigs thrown
    into `envelope` (module docstring), clumped unless `clumped` is False; or, given `gap_fraction` instead, the
    leaf area that lets that fraction of the lines along the columns of `gap_envelopes` (default: `envelope`'s,
    vertical) through, clumps and all (`leaf_area_for_gap_m2`).

    centre_m, radii_m : (3,) the ellipsoid whose gradient gives the outward normal the shading normals lean to.
    exclude : a function of points (N, 3) → bool (N,) marking places no twig goes (a bush's core), or None.
    largest_card_m2 : past `MAX_LEAF_CARDS` cards grow to carry the leaf area, up to this; beyond it they carry
        less (a long hedge, whose core hides its inside anyway)."""
    if (leaf_area_m2 is None) == (gap_fraction is None):
        raise ValueError("leafy_volume takes a leaf_area_m2 or a gap_fraction, one of them")
    clumps = ClumpField.draw(rng, envelope.width_m)
    if gap_fraction is not None:
        lines = [(envelope, LINE_AXES[0])] if gap_envelopes is None else gap_envelopes
        leaf_area_m2 = leaf_area_for_gap_m2(lines, gap_fraction, clumps.keep_probability if clumped else None)
    count, card_area = card_count_and_area(leaf_area_m2, card_area_m2, largest_m2=largest_card_m2)
    length = math.sqrt(card_area / (0.5 * LEAF_ASPECT))
    twigs_needed = count // LEAVES_PER_TWIG
    twigs = np.zeros((0, 3))
    while len(twigs) < twigs_needed:
        candidates = points_in(envelope, max(4 * twigs_needed, 64), rng=rng)
        keep = np.ones(len(candidates), dtype=bool)
        if exclude is not None:
            keep &= ~exclude(candidates)
        if clumped:
            keep &= rng.random(len(candidates)) < clumps.keep_probability(candidates)
        twigs = np.concatenate([twigs, candidates[keep]])
    twigs = twigs[:twigs_needed]
    twig_normals = _unit(rng.normal(size=(len(twigs), 3)))
    twig_along, _ = _frames(twig_normals, rng)
    k = LEAVES_PER_TWIG
    # fan the leaves about the twig's normal, each tilted a little out of its plane
    fan = (np.arange(k) * (2 * math.pi / k))[None, :] + rng.uniform(-0.4, 0.4, (len(twigs), k))
    cross_dir = np.cross(twig_normals, twig_along)
    along = np.cos(fan)[..., None] * twig_along[:, None] + np.sin(fan)[..., None] * cross_dir[:, None]
    tilt = rng.uniform(-TWIG_SPREAD_RAD, TWIG_SPREAD_RAD, (len(twigs), k))[..., None]
    normals = np.cos(tilt) * twig_normals[:, None] - np.sin(tilt) * along  # turned about the leaf's width
    along = np.cos(tilt) * along + np.sin(tilt) * twig_normals[:, None]
    bases = twigs[:, None] + along * (0.15 * length)
    bases, normals, along = bases.reshape(-1, 3), _unit(normals.reshape(-1, 3)), _unit(along.reshape(-1, 3))
    vertices, face_normals, faces = leaf_cards(bases, normals, along, length)
    centre, radii = np.asarray(centre_m, float), np.asarray(radii_m, float)
    outward = _unit((vertices - centre) / radii**2)
    shading = _unit(face_normals + OUTWARD_NORMAL_WEIGHT * outward)
    height = np.clip((vertices[:, 2] - centre[2]) / radii[2], -1.0, 1.0)
    field = np.clip(smooth_noise(twigs, rng=rng, scale=0.5) / 2.5, -1.0, 1.0)
    shade = 1.0 + COLOUR_VARIATION * np.repeat(field, 8 * k) + 0.15 * height
    shade *= np.repeat(rng.uniform(1 - LEAF_SHADE_JITTER, 1 + LEAF_SHADE_JITTER, len(bases)), 8)
    colours = np.clip(np.asarray(rgb, float) * shade[:, None], 0.0, 1.0)
    nirs = np.clip(nir * (1.0 + 0.1 * (shade - 1.0)), 0.0, 1.0)
    twig_of_vertex = np.repeat(np.arange(len(twigs)), 8 * k)  # a twig's leaves flutter together
    return PropPart(name, vertices, shading, faces.astype(np.int64), colours, nirs, flutter_groups=twig_of_vertex)


def leaf_area_m2(part: PropPart) -> float:
    """One-sided leaf area of a part of two-sided cards: half its triangles' area, m²."""
    corners = part.vertices_m[part.faces]
    return 0.25 * float(
        np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1).sum()
    )


def beer_lambert_gap(path_m: np.ndarray, leaf_area_density_m2_m3: float, g: float = LEAF_PROJECTION_G) -> np.ndarray:
    """exp(−G·LAD·ℓ): the chance a line crosses `path_m` (…) of a random canopy of leaf area density
    `leaf_area_density_m2_m3` without meeting a leaf (Monsi & Saeki 1953)."""
    return np.exp(-g * leaf_area_density_m2_m3 * np.asarray(path_m, dtype=np.float64))
