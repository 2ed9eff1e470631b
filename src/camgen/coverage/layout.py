"""Choose where to put cameras: mounts, orientations and profiles that maximise the weighted area of the
regions of interest seen at their required DORI class, under a camera budget.

Objective. Over the cells c of the regions (cell area a_c, region weight w_c, required class r_c) and a
set S of cameras, each camera s seeing cell c at class k_s(c) (through the lens, occlusion included)::

    F(S) = Σ_c w_c a_c · [#{s ∈ S : k_s(c) ≥ r_c} ≥ 1]  +  λ · Σ_c w_c a_c · [#{s ∈ S : k_s(c) ≥ r_c} ≥ 2]

The first term is weighted maximum coverage; the second (λ = `handoff_weight`) rewards overlap for
hand-off between cameras, i.e. penalises region area that only one camera sees.

Search. Every candidate mount is tried at headings and pitches on a grid over its ranges (`yaw_step_deg`,
`pitch_step_deg`) with every candidate profile; a varifocal or zoom lens at `focal_length_steps` focal
lengths spaced evenly in log from its wide to its tele end (the wide end alone by default; a PTZ profile
is set up with its head at pan 0, tilt 0 and that zoom, so the mount aims it). These options form a
finite ground set.
Greedy selection adds the option of largest marginal gain until the budget is spent; then a swap local
search replaces one chosen option by any other while that raises F.

Guarantee. With λ = 0, F is monotone submodular (a weighted coverage function), and the greedy under a
cardinality budget reaches at least (1 − 1/e) ≈ 63 % of the best layout *from the same option set*
(Nemhauser, Wolsey & Fisher, "An analysis of approximations for maximizing submodular set functions — I",
Math. Programming 14, 1978). The local search only raises F, so the bound still holds after it. The report
also gives the data-dependent bound OPT ≤ F(S) + Σ of the k largest marginal gains over S (from
submodularity; Minoux 1978, Leskovec et al. 2007), usually far tighter. What breaks the guarantee: the
orientation search is a grid, so the optimum over continuous headings and pitches may be higher than
the option set's (no bound holds for it); and with λ > 0 the overlap term is not submodular (a second
camera's gain grows with the first's coverage), so neither bound holds.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from camgen.config.layout import LayoutCandidates
from camgen.config.profile import Profile
from camgen.config.scene import Mount, Region
from camgen.coverage.density import densities, in_image
from camgen.coverage.dori import class_index, class_name, dori_class
from camgen.coverage.grid import Grid
from camgen.coverage.occlusion import Occluder, inside_solids, sight_blocked
from camgen.coverage.views import view_at
from camgen.errors import ConfigError, Problem

LOCAL_SEARCH_ROUNDS_MAX = 50


@dataclass(frozen=True)
class Option:
    """One camera the search may place: a mount, an orientation and a profile."""

    mount: str
    position_m: tuple[float, float, float]
    yaw_deg: float
    pitch_deg: float
    profile: str
    focal_length_mm: float | None = None
    """Where a varifocal or zoom lens is set, mm; None: a fixed lens (or the wide end)."""


@dataclass(frozen=True)
class RegionCells:
    """The cells the objective counts: positions (N, 3) m, their weight w·a (N,) and required class (N,)."""

    points_m: np.ndarray
    weight_m2: np.ndarray
    required: np.ndarray
    regions: tuple[Region, ...] = ()
    membership: np.ndarray | None = None
    """(N, regions) bool: the cell lies in the region."""


@dataclass(frozen=True)
class LayoutResult:
    chosen: tuple[int, ...]
    objective_m2: float
    greedy_objective_m2: float
    upper_bound_m2: float | None
    """Data-dependent bound on the best layout of the option set (λ = 0 only)."""
    guarantee: str
    baseline: tuple[int, ...]
    baseline_objective_m2: float
    total_weight_m2: float
    options: tuple[Option, ...]


def region_cells(
    regions: Sequence[Region], masks: Sequence[np.ndarray], grid: Grid, weights: Mapping[str, float], occluders
) -> RegionCells:
    """The region cells outside solids; a cell in several regions counts for the strictest."""
    points = grid.points_m()
    site = ~inside_solids(points, occluders)
    required = np.zeros(len(points), np.int8)
    weight = np.zeros(len(points))
    for region, mask in zip(regions, masks, strict=True):
        cells = mask.ravel() & site
        required[cells] = np.maximum(required[cells], class_index(region.required_class))
        weight[cells] = np.maximum(weight[cells], weights.get(region.name, 1.0) * grid.cell_area_m2)
    keep = required > 0
    membership = np.stack([mask.ravel() & site for mask in masks], 1) if masks else np.zeros((len(points), 0), bool)
    return RegionCells(points[keep], weight[keep], required[keep], tuple(regions), membership[keep])


def _angles(low: float, high: float, step: float) -> np.ndarray:
    count = max(1, math.floor((high - low) / step + 1e-9) + 1)
    return low + step * np.arange(count) if high > low else np.array([low])


def focal_lengths_mm(profile: Profile, steps: int) -> list[float | None]:
    """The focal lengths a candidate profile is tried at: None for a fixed lens, else `steps` spaced evenly
    in log from the wide to the tele end (equal ratios: equal steps in field of view and in px/m)."""
    low, high = profile.lens.focal_length_min_mm, profile.lens.focal_length_max_mm
    if high <= low:
        return [None]
    return [float(f) for f in np.geomspace(low, high, steps)] if steps > 1 else [float(low)]


def enumerate_options(
    candidates: LayoutCandidates, profiles: Mapping[str, Profile] | None = None
) -> tuple[Option, ...]:
    """Every (mount, heading, pitch, profile, focal length) the search may choose; without `profiles`, every
    lens at its wide end."""
    focal = {
        name: focal_lengths_mm(profiles[name], candidates.focal_length_steps) if profiles else [None]
        for name in candidates.profiles
    }
    return tuple(
        Option(m.name, tuple(m.position_m), float(yaw), float(pitch), profile, focal_length_mm)
        for m in candidates.mounts
        for yaw in _angles(*m.yaw_deg_range, candidates.yaw_step_deg)
        for pitch in _angles(*m.pitch_deg_range, candidates.pitch_step_deg)
        for profile in candidates.profiles
        for focal_length_mm in focal[profile]
    )


def option_classes(
    options: Sequence[Option],
    points_m: np.ndarray,
    profiles: Mapping[str, Profile],
    occluders: Sequence[Occluder],
    plane_height_m: float = 0.0,
) -> np.ndarray:
    """(options, points) int8: the DORI class index (`camgen.coverage.dori`) each option sees each point at,
    unhidden; 0 where it does not see it."""
    blocked_at: dict[tuple, np.ndarray] = {}
    classes = np.zeros((len(options), len(points_m)), dtype=np.int8)
    for i, option in enumerate(options):
        if option.position_m not in blocked_at:
            blocked_at[option.position_m] = sight_blocked(np.array(option.position_m), points_m, occluders)
        profile = profiles[option.profile]
        mount = Mount(position_m=option.position_m, yaw_deg=option.yaw_deg, pitch_deg=option.pitch_deg)
        focal_length_mm = option.focal_length_mm or profile.lens.focal_length_min_mm
        view = view_at(option.mount, profile, mount, focal_length_mm)
        uv, dens = densities(points_m, plane_height_m, view)
        seen = in_image(uv, view.width_px, view.height_px) & ~blocked_at[option.position_m]
        classes[i] = np.where(seen, dori_class(dens.person_px_m), 0)
    return classes


def option_meets(
    options: Sequence[Option],
    cells: RegionCells,
    profiles: Mapping[str, Profile],
    occluders: Sequence[Occluder],
    plane_height_m: float = 0.0,
) -> np.ndarray:
    """(options, cells) bool: the option sees the cell, unhidden, at its required class or better."""
    return option_classes(options, cells.points_m, profiles, occluders, plane_height_m) >= cells.required


def unreachable_regions(best_class: np.ndarray, cells: RegionCells) -> list[Problem]:
    """A located problem for each region whose required class no option reaches on any of its cells
    (`best_class` (cells,): the best class any option sees each cell at)."""
    problems = []
    for r, region in enumerate(cells.regions):
        member = cells.membership[:, r]
        if not member.any():
            continue
        best = int(best_class[member].max())
        if best >= class_index(region.required_class):
            continue
        problems.append(
            Problem(
                ("regions", r, "required_class"),
                f"is {region.required_class!r}, which no candidate camera (mount, heading, pitch and profile) reaches "
                f"on any point of region {region.name!r}: the best is {class_name(best)!r}; lower the required "
                "class, or add mounts nearer the region or a profile with a longer lens",
            )
        )
    return problems


def objective_m2(meets: np.ndarray, chosen: Sequence[int], weight_m2: np.ndarray, handoff_weight: float) -> float:
    count = meets[list(chosen)].sum(axis=0) if len(chosen) else np.zeros(meets.shape[1], int)
    return float(weight_m2 @ (count >= 1) + handoff_weight * (weight_m2 @ (count >= 2)))


def _gains(meets: np.ndarray, count: np.ndarray, weight_m2: np.ndarray, handoff_weight: float) -> np.ndarray:
    """Marginal gain of adding each option to a set whose per-cell counts are `count`."""
    return meets @ (weight_m2 * (count == 0)) + handoff_weight * (meets @ (weight_m2 * (count == 1)))


def greedy(meets: np.ndarray, budget: int, weight_m2: np.ndarray, handoff_weight: float) -> list[int]:
    chosen: list[int] = []
    count = np.zeros(meets.shape[1], int)
    for _ in range(min(budget, len(meets))):
        gains = _gains(meets, count, weight_m2, handoff_weight)
        gains[chosen] = -np.inf
        best = int(np.argmax(gains))
        chosen.append(best)
        count += meets[best]
    return chosen


def swap_search(meets: np.ndarray, chosen: list[int], weight_m2: np.ndarray, handoff_weight: float) -> list[int]:
    """Replace one chosen option by another while the objective rises (best swap each round)."""
    chosen = list(chosen)
    current = objective_m2(meets, chosen, weight_m2, handoff_weight)
    for _ in range(LOCAL_SEARCH_ROUNDS_MAX):
        best_value, best_swap = current, None
        for position in range(len(chosen)):
            rest = chosen[:position] + chosen[position + 1 :]
            count = meets[rest].sum(axis=0) if rest else np.zeros(meets.shape[1], int)
            values = objective_m2(meets, rest, weight_m2, handoff_weight) + _gains(
                meets, count, weight_m2, handoff_weight
            )
            values[chosen] = -np.inf
            j = int(np.argmax(values))
            if values[j] > best_value + 1e-9:
                best_value, best_swap = float(values[j]), (position, j)
        if best_swap is None:
            break
        chosen[best_swap[0]] = best_swap[1]
        current = best_value
    return chosen


def evenly_spaced(
    options: Sequence[Option], candidates: LayoutCandidates, budget: int, aim_m: np.ndarray | None = None
) -> list[int]:
    """The naive baseline, as a 2-D planning tool would set it up: `budget` mounts spread evenly through the
    candidate list, each turned towards `aim_m` (the regions' weighted centroid; its heading brought into the
    mount's range, the middle of the range without an aim) at the middle of its pitch range, with the first
    profile at its wide end."""
    mounts = candidates.mounts
    first = candidates.profiles[0]
    wide = min((o.focal_length_mm for o in options if o.profile == first and o.focal_length_mm), default=None)
    picks = [mounts[int(i) % len(mounts)] for i in np.linspace(0, len(mounts) - 1, budget).round()] if budget else []
    chosen = []
    for mount in picks:
        yaw, pitch = np.mean(mount.yaw_deg_range), np.mean(mount.pitch_deg_range)
        if aim_m is not None:
            towards = np.degrees(np.arctan2(aim_m[1] - mount.position_m[1], aim_m[0] - mount.position_m[0]))
            low, high = mount.yaw_deg_range
            towards = (towards - low) % 360 + low  # the same heading, ≥ the range's start
            if towards > high:  # outside the range: its nearer end
                towards = high if towards - high < (low + 360) - towards else low
            yaw = towards
        scores = [
            (_angle_deg(o.yaw_deg - yaw) + abs(o.pitch_deg - pitch), i)
            for i, o in enumerate(options)
            if o.mount == mount.name and o.profile == first and o.focal_length_mm == wide and i not in chosen
        ]
        if scores:
            chosen.append(min(scores)[1])
    return chosen


def _angle_deg(difference_deg: float) -> float:
    """|difference| wrapped to [0, 180], degrees."""
    return abs((difference_deg + 180.0) % 360.0 - 180.0)


def optimise_layout(
    candidates: LayoutCandidates,
    cells: RegionCells,
    profiles: Mapping[str, Profile],
    occluders: Sequence[Occluder],
    budget: int,
) -> LayoutResult:
    """Greedy selection and swap local search over the candidates' options (see the module docstring).
    Raises ConfigError for a region whose required class no option reaches on any of its cells (key paths
    from the scene, to be located by the caller)."""
    options = enumerate_options(candidates, profiles)
    classes = option_classes(options, cells.points_m, profiles, occluders)
    if cells.membership is not None and (problems := unreachable_regions(classes.max(axis=0, initial=0), cells)):
        raise ConfigError(problems)
    meets = classes >= cells.required
    w, lam = cells.weight_m2, candidates.handoff_weight
    first = greedy(meets, budget, w, lam)
    chosen = swap_search(meets, first, w, lam)
    value = objective_m2(meets, chosen, w, lam)
    bound = None
    if lam == 0:
        count = meets[chosen].sum(axis=0)
        gains = np.sort(_gains(meets, count, w, 0.0))[::-1]
        bound = value + float(gains[:budget].sum())
        guarantee = (
            "λ = 0: the objective is monotone submodular; the greedy reaches ≥ (1 − 1/e) of the best layout from "
            "this option set (Nemhauser, Wolsey & Fisher 1978), and the swaps only raise it; not guaranteed "
            "against headings and pitches between the grid's"
        )
    else:
        guarantee = (
            "none: with handoff_weight > 0 the overlap term is not submodular, so the (1 − 1/e) guarantee and the "
            "bound do not hold"
        )
    aim = (cells.weight_m2 @ cells.points_m) / cells.weight_m2.sum() if cells.weight_m2.sum() > 0 else None
    baseline = evenly_spaced(options, candidates, budget, aim)
    return LayoutResult(
        chosen=tuple(chosen),
        objective_m2=value,
        greedy_objective_m2=objective_m2(meets, first, w, lam),
        upper_bound_m2=bound,
        guarantee=guarantee,
        baseline=tuple(baseline),
        baseline_objective_m2=objective_m2(meets, baseline, w, lam),
        total_weight_m2=float(w.sum()),
        options=options,
    )
