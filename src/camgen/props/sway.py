"""Trees and bushes in the wind: the crown bends like a cantilever and sways at the plant's own
frequency, gusts come and go, and leaves flutter faster and less far. Pure functions of time.

The model, per plant (prop frame: z up, foot at the origin, height H):

- **Bending.** A point at height z moves horizontally by ψ(z)·D(t), ψ = (z/H)², the static shape of a
  cantilever under a load near its tip, to first order its first mode (Chopra, "Dynamics of Structures",
  2012, §8.2; de Langre 2008, "Effects of wind on plants", Annu. Rev. Fluid Mech. 40: 141). It drops by
  ∫₀^z ½ ψ′(ζ)² |D|² dζ = (2/3)|D|²·(z/H)³/H so that the stem keeps its length; the foot never moves.
  Normals turn with the surface: n′ ∝ (I − ∇uᵀ) n (first order in the displacement u).
- **Tip motion.** D(t) = L·g(t)²·[(1 + r·sin(2πf t + φ))·ŵ + r·c·sin(2π·1.04 f t + φ′)·ĉ]: a mean
  lean L downwind ŵ, with sway of r·L about it along the wind and c·r·L across it (trees trace
  ellipses; a crown's two principal stiffnesses differ a little, hence 1.04). The drag, and so the lean,
  grows as U² up to `DRAG_REFERENCE_SPEED_M_S` and as U^(2+β) above it, crowns streamlining with
  Vogel's exponent β (Vogel 1989, "Drag and reconfiguration of broad leaves in high winds", J. Exp.
  Bot. 40: 941; de Langre 2008, §4). The phases φ, φ′ are the plant's own, from its seed.
- **Natural frequency f.** Trees: f = k·D_stem/H² (Moore & Maguire 2004, "Natural sway frequencies and
  damping ratios of trees: concepts, review and synthesis of previous studies", Trees 18: 195, found f
  linear in DBH/H² over 602 trees, as a cantilever beam's is); k is chosen so that this package's
  street trees (5–15 m, stems 0.2–0.5 m) span 1.1–0.22 Hz, within the 0.2–1 Hz measured for trees in
  leaf (leaves lower f: Jackson et al. 2019, "An architectural understanding of natural sway
  frequencies in trees", J. R. Soc. Interface 16: 20190116). Bushes: short, thin stems sway faster,
  f = 1.5 Hz·√(1 m / H) (chosen: 2.1 Hz at 0.5 m, 1.1 Hz at 2 m, like a tree's small branches).
- **Gusts.** The wind speed over its mean, g(t) = max(0, 1 + I·n(t − x/U)), where I is the turbulence
  intensity and n a unit-variance sum of `GUST_WAVES` cosines with periods of 3 s (the WMO gust) to a
  minute and amplitudes falling as f^(−1/3) (the −5/3 power spectrum of the inertial range, on
  log-spaced frequencies), drawn from the wind's seed; a gust reaches a plant x metres downwind x/U
  seconds later. The same g scales every plant's lean and flutter.
- **Flutter.** Leaves and twigs (the leafy parts, `camgen.props.types.ORGANIC_PARTS`) move besides by
  a sum of `FLUTTER_WAVES` travelling waves, each a displacement along its own axis with wavelength
  0.6–1.5 m (clumps of leaves move together) and frequency 1.5–4 Hz (leaf and twig motion lies above
  the whole plant's, de Langre 2008, §5; Tadrist et al. 2018, "Foliage motion under wind, from leaf
  flutter to branch buffeting", J. R. Soc. Interface 15: 20180010); their RMS displacement grows
  linearly with the wind speed, 1.7 cm at 4 m/s (chosen: Beaufort 3, 3.4–5.4 m/s, "leaves and small
  twigs in constant motion", WMO-No. 8; Tadrist et al. found leaf flutter to depend weakly on the speed
  and to dominate in light wind, the branches' buffeting to grow strongly and dominate in strong wind,
  as here the flutter's U against the sway's U²), and the normals wobble with it, so the crown's shading
  flickers as a real one does. A part may group its vertices (`PropPart.flutter_groups`: a twig with its
  leaf cards, `camgen.props.foliage`): a group moves as one, by the waves at its vertices' mean rest place,
  its leaves keeping their shape, while its normals still wobble with the waves' slope.

Calibration (chosen, against the Beaufort scale's descriptions, WMO-No. 8): the tip's mean lean is
`LEAN_AT_REFERENCE_FRAC` = 3 % of the height at 10 m/s (Beaufort 5, "small trees in leaf begin to
sway"): 3.4 cm for a 7 m tree at 4 m/s, 21 cm at 10 m/s, 37 cm at 15 m/s (Beaufort 7, "whole trees in
motion"), sway of the same size about it.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from camgen.config.scene import Environment, Wind
from camgen.props import PlacedProp, placed_props
from camgen.props.shapes import frustum
from camgen.props.types import ORGANIC_PARTS, PropModel

WIND_SPAWN_KEY = 0x7769_6E64
"""Spawn key of the gusts' seed derived from the scene's seed (ASCII "wind")."""
SWAY_SPAWN_KEY = 0x7377_6179
"""Spawn key of a plant's sway (phases, flutter waves) derived from its identity seed (ASCII "sway")."""
SWAYING_TYPES = ("tree", "bush")

TREE_FREQUENCY_COEFF_M_S = 110.0
"""k of f = k·D_stem/H² for trees (module docstring), m/s."""
BUSH_FREQUENCY_HZ = 1.5
"""A 1 m bush's sway frequency; f ∝ 1/√H."""
DRAG_REFERENCE_SPEED_M_S = 10.0
"""Below this speed the drag grows as U², above it as U^(2 + VOGEL_EXPONENT)."""
VOGEL_EXPONENT = -0.7
"""Vogel's exponent β of leafy crowns streamlining in strong wind (de Langre 2008: −0.5 to −1.2)."""
LEAN_AT_REFERENCE_FRAC = 0.03
"""The tip's mean lean over the plant's height at `DRAG_REFERENCE_SPEED_M_S`."""
SWAY_TO_LEAN = 1.0
"""Along-wind sway amplitude over the mean lean."""
CROSS_WIND_FRAC = 0.6
"""Cross-wind sway amplitude over the along-wind one."""
CROSS_FREQUENCY_RATIO = 1.04
"""Cross-wind sway frequency over the along-wind one (a crown's two principal stiffnesses)."""
FLUTTER_RMS_M_PER_M_S = 0.006 / math.sqrt(2.0)
"""Leaf flutter's RMS displacement per m/s of wind speed, m: 1.7 cm at 4 m/s."""
FLUTTER_WAVES = 6
FLUTTER_FREQUENCY_HZ = (1.5, 4.0)
FLUTTER_WAVELENGTH_M = (0.6, 1.5)
TRUNK_BAND_M = 0.5
"""A swaying trunk's side is cut into bands no taller than this (`bendable`), so that it curves."""
GUST_WAVES = 8
GUST_PERIOD_S = (3.0, 60.0)
GUST_BOUND_STEP_S = 0.1
"""Grid on which `Gusts.factor_max` looks for a sequence's strongest gust."""


@dataclass(frozen=True)
class Gusts:
    """The wind's speed through time, relative to its mean (module docstring, "Gusts")."""

    speed_m_s: float
    direction: np.ndarray
    """(2,) unit world vector the wind blows towards."""
    turbulence_intensity: float
    frequencies_hz: np.ndarray
    amplitudes: np.ndarray
    """Of the unit-variance sum: Σ a²/2 = 1."""
    phases_rad: np.ndarray

    def factor(self, time_s, along_m: float = 0.0) -> np.ndarray:
        """g(t) = max(0, 1 + I·n(t − x/U)): the wind speed over its mean at `time_s` (scalar or array, s)
        at a place `along_m` downwind of the origin."""
        t = np.asarray(time_s, dtype=np.float64) - along_m / self.speed_m_s
        n = np.cos(2 * math.pi * self.frequencies_hz * t[..., None] + self.phases_rad) @ self.amplitudes
        return np.maximum(0.0, 1.0 + self.turbulence_intensity * n)

    def factor_max(self, duration_s: float | None = None, along_m: float = 0.0) -> float:
        """An upper bound of `factor` at any time and place, or, given `duration_s`, over the times
        0…duration_s at `along_m`: its largest value on a grid of GUST_BOUND_STEP_S plus how far it can
        rise between two grid points (|dn/dt| ≤ Σ|a|·2πf)."""
        anywhere = 1.0 + self.turbulence_intensity * float(np.abs(self.amplitudes).sum())
        if duration_s is None:
            return anywhere
        step = GUST_BOUND_STEP_S
        sampled = float(self.factor(np.arange(0.0, duration_s + step, step), along_m).max())
        rise = (
            self.turbulence_intensity * float(np.abs(self.amplitudes) @ (2 * math.pi * self.frequencies_hz)) * step / 2
        )
        return min(anywhere, sampled + rise)


def wind_gusts(wind: Wind | None, *, scene_seed: int) -> Gusts | None:
    """The gusts of `wind` (its seed, or one derived from the scene's); None when calm."""
    if wind is None or wind.speed_m_s == 0:
        return None
    seed = (
        wind.seed
        if wind.seed is not None
        else int(np.random.SeedSequence(scene_seed, spawn_key=(WIND_SPAWN_KEY,)).generate_state(1)[0])
    )
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    low, high = 1.0 / GUST_PERIOD_S[1], 1.0 / GUST_PERIOD_S[0]
    # Log-spaced bands, one frequency drawn in each; −5/3 spectrum on a log axis: amplitude ∝ f^(−1/3).
    edges = np.geomspace(low, high, GUST_WAVES + 1)
    frequencies = np.exp(rng.uniform(np.log(edges[:-1]), np.log(edges[1:])))
    amplitudes = frequencies ** (-1.0 / 3.0)
    amplitudes *= math.sqrt(2.0 / float(np.sum(amplitudes**2)))
    phases = rng.uniform(0.0, 2 * math.pi, GUST_WAVES)
    angle = math.radians(wind.direction_deg)
    return Gusts(
        float(wind.speed_m_s),
        np.array([math.cos(angle), math.sin(angle)]),
        float(wind.turbulence_intensity),
        frequencies,
        amplitudes,
        phases,
    )


def drag_factor(speed_m_s: float) -> float:
    """Drag at `speed_m_s` over drag at `DRAG_REFERENCE_SPEED_M_S`: U² below it, U^(2+β) above."""
    ratio = speed_m_s / DRAG_REFERENCE_SPEED_M_S
    return ratio**2 if ratio <= 1.0 else ratio ** (2.0 + VOGEL_EXPONENT)


def natural_frequency_hz(model: PropModel) -> float:
    """A tree's or bush's first sway frequency (module docstring), Hz."""
    height_m = model.height_m
    if model.type == "tree":
        return TREE_FREQUENCY_COEFF_M_S * model.dims["trunk_diameter_m"] / height_m**2
    if model.type == "bush":
        return BUSH_FREQUENCY_HZ / math.sqrt(height_m)
    raise ValueError(f"a {model.type} does not sway; only {SWAYING_TYPES} do")


@dataclass(frozen=True)
class PropSway:
    """One plant's motion in the wind, in its own frame (module docstring)."""

    height_m: float
    natural_frequency_hz: float
    lean_m: float
    """The tip's mean lean in the mean wind, m."""
    phase_rad: float
    cross_phase_rad: float
    downwind: np.ndarray
    """(3,) unit, horizontal, in the prop's frame."""
    along_m: float
    """How far downwind of the world origin the plant's foot stands (when gusts reach it), m."""
    gusts: Gusts
    leafy: np.ndarray
    """(V,) bool: the vertices of leafy parts, which flutter."""
    flutter_m: np.ndarray
    """(W,) amplitude of each flutter wave in the mean wind, m."""
    flutter_axes: np.ndarray
    """(W, 3) unit direction each wave displaces along."""
    flutter_wave_vectors_rad_m: np.ndarray
    """(W, 3)."""
    flutter_frequencies_hz: np.ndarray
    flutter_phases_rad: np.ndarray
    flutter_groups: np.ndarray | None = None
    """(V,) int, per vertex: the group (a twig with its leaves) whose leafy vertices' mean rest place sets
    their phase in each wave, so that a group moves as one (its leaves keep their shape, and the sines are
    taken once a group); None: each leafy vertex by its own rest place."""
    _rest: _RestTerms | None = dataclasses.field(default=None, init=False, repr=False, compare=False)
    """The time-independent terms of `deformed` for the last rest vertices and normals it was given."""

    def tip_displacement_m(self, time_s) -> np.ndarray:
        """(…, 3) horizontal displacement D of the top (z = H) at `time_s` (scalar or array, s)."""
        t = np.asarray(time_s, dtype=np.float64)
        return self._tip_displacement_m(t, self.gusts.factor(t, self.along_m))

    def _tip_displacement_m(self, t: np.ndarray, gust_factor: np.ndarray) -> np.ndarray:
        """`tip_displacement_m` at `t` (…) s, given the gusts' `factor` (…) there."""
        g2 = gust_factor**2
        f = self.natural_frequency_hz
        along = self.lean_m * g2 * (1.0 + SWAY_TO_LEAN * np.sin(2 * math.pi * f * t + self.phase_rad))
        across = (
            self.lean_m
            * g2
            * SWAY_TO_LEAN
            * CROSS_WIND_FRAC
            * np.sin(2 * math.pi * CROSS_FREQUENCY_RATIO * f * t + self.cross_phase_rad)
        )
        crosswind = np.array([-self.downwind[1], self.downwind[0], 0.0])
        return along[..., None] * self.downwind + across[..., None] * crosswind

    def deformed(self, vertices_m: np.ndarray, normals: np.ndarray, time_s: float) -> tuple[np.ndarray, np.ndarray]:
        """The plant's vertices (V, 3) and unit normals (V, 3) at rest, bent and fluttering at `time_s`.

        What does not change with time (`_RestTerms`) is kept for the last rest vertices and normals given,
        so that a plant bent to one time after another computes it once."""
        rest = self._rest_terms(vertices_m, normals)
        t = np.asarray(time_s, dtype=np.float64)
        g = self.gusts.factor(t, self.along_m)
        D = self._tip_displacement_m(t, g)
        moved = vertices_m + rest.s_squared * D
        moved[:, 2] -= (2.0 / 3.0) * float(D @ D) * rest.s_cubed / self.height_m
        turned = normals.copy()
        turned[:, 2] -= rest.tilt_per_m * (normals @ D)
        if rest.leafy_rows is not None:
            theta = (
                rest.leafy_wave_phases_rad + rest.flutter_angular_frequencies_rad_s * time_s + self.flutter_phases_rad
            )
            amplitude = float(g) * self.flutter_m
            shift = (amplitude * np.sin(theta)) @ self.flutter_axes
            slope = amplitude * np.cos(theta)
            if rest.leafy_groups is not None:  # (G, …) per group, to each of its vertices
                shift, slope = shift[rest.leafy_groups], slope[rest.leafy_groups]
            moved[rest.leafy_rows] += shift
            tilt = slope * rest.leafy_normals_along_axes
            turned[rest.leafy_rows] -= tilt @ self.flutter_wave_vectors_rad_m
        turned /= np.linalg.norm(turned, axis=1, keepdims=True)
        return moved, turned

    def _rest_terms(self, vertices_m: np.ndarray, normals: np.ndarray) -> _RestTerms:
        """The time-independent terms of `deformed` for these rest vertices and normals: the kept ones when
        they are the same arrays bit for bit (compared by content, so that arrays changed in place or new
        arrays with other values get their own), else new ones, kept in their place."""
        kept = self._rest
        if kept is not None and kept.describes(vertices_m, normals):
            return kept
        kept = _RestTerms.of(self, vertices_m, normals)
        object.__setattr__(self, "_rest", kept)
        return kept

    def speed_max_m_s(self, duration_s: float | None = None) -> float:
        """An upper bound of any vertex's speed, m/s, at any time or over 0…`duration_s`: the tip's sway and
        the flutter at their fastest in the strongest gust (the gusts' own change, periods of 3 s and
        more, adds little and is left out)."""
        g = self.gusts.factor_max(duration_s, self.along_m)
        omega = 2 * math.pi * self.natural_frequency_hz
        tip = self.lean_m * g**2 * SWAY_TO_LEAN * omega * math.hypot(1.0, CROSS_WIND_FRAC * CROSS_FREQUENCY_RATIO)
        flutter = g * float(self.flutter_m @ (2 * math.pi * self.flutter_frequencies_hz)) if self.leafy.any() else 0.0
        return tip + flutter

    def moved_bound_m(self, time_a_s: float, time_b_s: float, height_frac_max: float) -> float:
        """An upper bound, m, on how far any vertex whose height fraction s = max(z/H, 0) at rest is at most
        `height_frac_max` lies at `time_a_s` from where it lies at `time_b_s` (`deformed`, in the prop's frame),
        with a margin far above the rounding of both. Its bend moves by s²·ΔD and drops by (2/3)·(s³/H)·Δ|D|²; a
        leafy vertex besides by Σ_w a_w·|g_a·sin θ_a − g_b·sin θ_b| ≤ Σ_w a_w·(|g_a − g_b| + g_b·min(2, ω_w·|t_a −
        t_b|)) (θ_a − θ_b = ω_w·(t_a − t_b); each wave moves along a unit axis)."""
        t = np.array([time_a_s, time_b_s], dtype=np.float64)
        g = self.gusts.factor(t, self.along_m)
        D = self._tip_displacement_m(t, g)
        squared = D @ D.T
        s = height_frac_max
        bend = s**2 * float(np.linalg.norm(D[0] - D[1])) + (2.0 / 3.0) * s**3 / self.height_m * abs(
            float(squared[0, 0] - squared[1, 1])
        )
        flutter = 0.0
        if self.leafy.any():
            phase_rad = np.minimum(2.0, 2 * math.pi * self.flutter_frequencies_hz * abs(time_a_s - time_b_s))
            flutter = float(self.flutter_m @ (abs(float(g[0] - g[1])) + float(g[1]) * phase_rad))
        return (bend + flutter) * (1.0 + 1e-9) + 1e-9

    def reach_m(self) -> float:
        """An upper bound of any vertex's displacement from rest, at any time, m."""
        g2 = self.gusts.factor_max() ** 2
        tip = self.lean_m * g2 * math.hypot(1.0 + SWAY_TO_LEAN, SWAY_TO_LEAN * CROSS_WIND_FRAC)
        flutter = self.gusts.factor_max() * float(self.flutter_m.sum()) if self.leafy.any() else 0.0
        return tip + (2.0 / 3.0) * tip**2 / self.height_m + flutter


@dataclass(frozen=True)
class _RestTerms:
    """What `PropSway.deformed` computes from the rest vertices and normals alone, each array by the same
    operations as the whole expression it stands in, so that the deformation comes out bit for bit the same."""

    vertices_m: np.ndarray
    """(V, 3) a read-only copy of the rest vertices these terms are of."""
    normals: np.ndarray
    """(V, 3) a read-only copy of the rest normals."""
    s_squared: np.ndarray
    """(V, 1) s², s = max(z/H, 0)."""
    s_cubed: np.ndarray
    """(V,) s³."""
    tilt_per_m: np.ndarray
    """(V,) 2s/H, 1/m: how much a normal's z changes per metre of its (n·D)."""
    leafy_rows: slice | np.ndarray | None
    """The leafy vertices (a slice where they are one run), None where none is."""
    leafy_wave_phases_rad: np.ndarray | None
    """(L, W) each leafy vertex's phase in each flutter wave at rest, k·x, rad; (G, W) each flutter group's, at
    the mean of its vertices' rest places, where the sway has `flutter_groups`."""
    flutter_angular_frequencies_rad_s: np.ndarray
    """(W,) 2πf of the flutter waves, rad/s."""
    leafy_groups: np.ndarray | None
    """(L,) each leafy vertex's row in `leafy_wave_phases_rad` (its flutter group's), None without groups."""
    leafy_normals_along_axes: np.ndarray | None
    """(L, W) each leafy vertex's rest normal along each wave's axis."""

    @classmethod
    def of(cls, sway: PropSway, vertices_m: np.ndarray, normals: np.ndarray) -> _RestTerms:
        s = np.clip(vertices_m[:, 2] / sway.height_m, 0.0, None)
        leafy_rows, phases, along_axes, groups = None, None, None, None
        if sway.leafy.any():
            rows = np.flatnonzero(sway.leafy)
            leafy_rows = slice(int(rows[0]), int(rows[-1]) + 1) if rows[-1] - rows[0] + 1 == len(rows) else rows
            places = vertices_m[sway.leafy]
            if sway.flutter_groups is not None:
                places, groups = group_centres_m(places, sway.flutter_groups[sway.leafy])
            phases = places @ sway.flutter_wave_vectors_rad_m.T
            along_axes = normals[sway.leafy] @ sway.flutter_axes.T
        return cls(
            vertices_m=_read_only_copy(vertices_m),
            normals=_read_only_copy(normals),
            s_squared=(s**2)[:, None],
            s_cubed=s**3,
            tilt_per_m=2.0 * s / sway.height_m,
            leafy_rows=leafy_rows,
            leafy_wave_phases_rad=phases,
            flutter_angular_frequencies_rad_s=2 * math.pi * sway.flutter_frequencies_hz,
            leafy_normals_along_axes=along_axes,
            leafy_groups=groups,
        )

    def describes(self, vertices_m: np.ndarray, normals: np.ndarray) -> bool:
        """Whether these are the terms of `vertices_m` and `normals`: the same dtype, shape and bytes (not just
        equal values: −0.0 and 0.0 differ)."""
        return _same_bits(self.vertices_m, vertices_m) and _same_bits(self.normals, normals)


def group_centres_m(points_m: np.ndarray, groups: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mean (G, 3) of the points (N, 3) of each group present in `groups` (N,), and each point's row there (N,)."""
    _, row = np.unique(groups, return_inverse=True)
    counts = np.bincount(row)
    centres = np.column_stack([np.bincount(row, weights=points_m[:, k]) / counts for k in range(3)])
    return centres, row


def _read_only_copy(array: np.ndarray) -> np.ndarray:
    copy = np.array(array, copy=True, order="C")
    copy.flags.writeable = False
    return copy


def _same_bits(kept: np.ndarray, array: np.ndarray) -> bool:
    """Whether `array` has `kept`'s dtype, shape and bytes (`kept` C-contiguous)."""
    if not isinstance(array, np.ndarray) or array.dtype != kept.dtype or array.shape != kept.shape:
        return False
    if kept.dtype.itemsize != 8:
        return kept.tobytes() == array.tobytes()
    return bool(np.array_equal(kept.view(np.uint64), np.ascontiguousarray(array).view(np.uint64)))


def bendable(model: PropModel) -> PropModel:
    """`model` with its trunk's side cut into bands of at most `TRUNK_BAND_M` (the same surface, more
    rings), so that a bent trunk curves as (z/H)² instead of tilting straight between its foot and its top
    ring. A prop without a trunk comes back as it is."""
    if not any(part.name == "trunk" for part in model.parts):
        return model
    parts = []
    for part in model.parts:
        if part.name != "trunk":
            parts.append(part)
            continue
        z = part.vertices_m[:, 2]
        z0, z1 = float(z.min()), float(z.max())
        radius = np.linalg.norm(part.vertices_m[:, :2], axis=1)
        r0, r1 = float(radius[z == z0].max()), float(radius[z == z1].max())
        bands = max(1, math.ceil((z1 - z0) / TRUNK_BAND_M))
        rgb, nir = part.colours_rgb[0], float(part.nir_reflectance[0])
        parts.append(frustum("trunk", r0, r1, z0, z1, rgb, nir, bands=bands))
    return dataclasses.replace(model, parts=parts)


def prop_sway(model: PropModel, T_world_from_prop: np.ndarray, gusts: Gusts | None) -> PropSway | None:
    """How the tree or bush `model`, standing at `T_world_from_prop` (4, 4), moves in the wind of `gusts`;
    None for a prop that does not sway or in calm air. Its phases and flutter come from its seed."""
    if gusts is None or model.type not in SWAYING_TYPES:
        return None
    rng = np.random.default_rng(np.random.SeedSequence(model.seed, spawn_key=(SWAY_SPAWN_KEY,)))
    phase, cross_phase = rng.uniform(0.0, 2 * math.pi, 2)
    R = np.asarray(T_world_from_prop, dtype=np.float64)[:3, :3]
    downwind_world = np.array([*gusts.direction, 0.0])
    downwind = R.T @ downwind_world
    downwind[2] = 0.0
    downwind /= np.linalg.norm(downwind)
    along_m = float(np.asarray(T_world_from_prop)[:2, 3] @ gusts.direction)
    leafy = np.concatenate([np.full(len(p.vertices_m), p.name.startswith(ORGANIC_PARTS)) for p in model.parts])
    flutter_groups, first = [], 0
    for part in model.parts:  # each part's groups numbered after the last part's; a vertex alone its own group
        own = np.arange(len(part.vertices_m)) if part.flutter_groups is None else part.flutter_groups
        flutter_groups.append(first + own)
        first += int(own.max()) + 1 if len(own) else 0
    grouped = any(p.flutter_groups is not None for p in model.parts)
    axes = rng.normal(size=(FLUTTER_WAVES, 3)) * (1.0, 1.0, 0.5)  # leaves and twigs move more sideways
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    directions = rng.normal(size=(FLUTTER_WAVES, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    wavelengths_m = rng.uniform(*FLUTTER_WAVELENGTH_M, FLUTTER_WAVES)
    flutter_rms_m = FLUTTER_RMS_M_PER_M_S * gusts.speed_m_s
    # W waves of amplitude a: RMS a·√(W/2).
    flutter_m = np.full(FLUTTER_WAVES, flutter_rms_m * math.sqrt(2.0 / FLUTTER_WAVES))
    return PropSway(
        height_m=float(model.height_m),
        natural_frequency_hz=natural_frequency_hz(model),
        lean_m=LEAN_AT_REFERENCE_FRAC * float(model.height_m) * drag_factor(gusts.speed_m_s),
        phase_rad=float(phase),
        cross_phase_rad=float(cross_phase),
        downwind=downwind,
        along_m=along_m,
        gusts=gusts,
        leafy=leafy,
        flutter_m=flutter_m,
        flutter_axes=axes,
        flutter_wave_vectors_rad_m=directions * (2 * math.pi / wavelengths_m)[:, None],
        flutter_frequencies_hz=rng.uniform(*FLUTTER_FREQUENCY_HZ, FLUTTER_WAVES),
        flutter_phases_rad=rng.uniform(0.0, 2 * math.pi, FLUTTER_WAVES),
        flutter_groups=np.concatenate(flutter_groups) if grouped else None,
    )


def swaying_props(environment: Environment, *, scene_seed: int) -> list[tuple[PlacedProp, PropSway]]:
    """Every placed prop of `environment` that sways in its wind, with its sway; empty when calm."""
    gusts = wind_gusts(environment.wind, scene_seed=scene_seed)
    if gusts is None:
        return []
    placed = [
        (prop, prop_sway(prop.model, prop.T_world_from_prop, gusts))
        for prop in placed_props(environment, scene_seed=scene_seed)
    ]
    return [(prop, sway) for prop, sway in placed if sway is not None]
