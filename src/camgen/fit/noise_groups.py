"""Frame groups of a sensor noise fit, checked and sorted, after EMVA 1288 release 4.0 (as cited in `camgen.fit.noise`).

What the fit relies on is checked first (`_check_input`: each failure a `ConfigError` naming the
group); dark groups are clustered by temperature and the reference temperature chosen
(`_dark_sets`, `_reference`); each group is reduced to its spatial mean and temporal variance over the
good pixels of every channel and tile, less its frame-mean variance (`_group_statistics`, `_Darks`);
and `_Context` holds what the per-channel estimators of `camgen.fit.noise_dark` and
`camgen.fit.noise_flat` share.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from camgen.errors import ConfigError
from camgen.fit.noise_spatial import SHADING_CORRECTIONS
from camgen.fit.noise_stack import FrameGroup
from camgen.fit.noise_statistics import Estimate, Region, _line_fit, _masked_means, _plane
from camgen.sensor.cfa import CFA_NAMES

SATURATED_DARK_FRACTION = 0.01
"""A dark group with more than this fraction of pixels at the ADC maximum saw light."""


def _at_exposure(times_s: np.ndarray, values: np.ndarray, exposure_time_s: float) -> np.ndarray:
    """Dark values at `exposure_time_s`: the groups taken at that time if any (EMVA's pairing of a dark
    with each bright measurement), else the least-squares line through all of them (linear in t)."""
    times_s = np.asarray(times_s, np.float64)
    same = np.isclose(times_s, exposure_time_s, rtol=1e-6, atol=1e-12)
    if same.any():
        return values[same].mean(axis=0)
    slope, intercept = _line_fit(times_s, values)
    return intercept + slope * exposure_time_s


def _check_input(
    groups: Sequence[FrameGroup],
    cfa: str,
    bit_depth: int,
    gain_dn_per_e: float | None,
    tiles: int,
    shading_correction: str,
) -> tuple[list, list]:
    """Dark and flat groups after checking what the fit relies on (ConfigError naming the group)."""
    if cfa not in CFA_NAMES:
        raise ConfigError(f"cfa must be one of {', '.join(CFA_NAMES)}, got {cfa!r}")
    if shading_correction not in SHADING_CORRECTIONS:
        raise ConfigError(
            f"shading_correction (--shading-correction) must be one of {', '.join(SHADING_CORRECTIONS)}, "
            f"got {shading_correction!r}"
        )
    if not 1 <= int(bit_depth) <= 32:
        raise ConfigError(f"bit_depth must be 1–32 bits, got {bit_depth}")
    if gain_dn_per_e is not None and not (math.isfinite(gain_dn_per_e) and gain_dn_per_e > 0):
        raise ConfigError(f"gain_dn_per_e (--gain-dn-per-e) must be a system gain > 0 DN/e⁻, got {gain_dn_per_e}")
    if not isinstance(tiles, int | np.integer) or tiles < 2:
        raise ConfigError(f"tiles must be a whole number ≥ 2 (the uncertainties need ≥ 2 × 2 tiles), got {tiles}")
    white = 2**bit_depth - 1
    for group in groups:
        if group.kind not in ("dark", "flat"):
            raise ConfigError(f"{group.label}: kind must be 'dark' or 'flat', got {group.kind!r}")
        if not (math.isfinite(group.exposure_time_s) and group.exposure_time_s >= 0):
            raise ConfigError(
                f"{group.label}: exposure_time_s must be a finite time ≥ 0 s, got {group.exposure_time_s}"
            )
        photons = group.photons_per_pixel
        if photons is not None and not (math.isfinite(photons) and photons >= 0):
            raise ConfigError(f"{group.label}: photons_per_pixel must be a finite count ≥ 0, got {photons}")
    darks = [g for g in groups if g.kind == "dark"]
    flats = [g for g in groups if g.kind == "flat"]
    if not darks:
        given = ", ".join(g.label for g in groups) or "none"
        raise ConfigError(
            f"no dark group (groups given: {given}); the fit needs dark frames (lens capped) at one or more "
            "exposure times: pass a folder of them with --dark DIR"
        )
    shape = darks[0].stats.shape_px
    for group in groups:
        if group.stats.shape_px != shape:
            raise ConfigError(
                f"{group.label}: frames of {group.stats.shape_px[1]}×{group.stats.shape_px[0]} px differ from "
                f"{darks[0].label}'s {shape[1]}×{shape[0]} px; use one sensor mode for every group"
            )
        if group.stats.count < 2:
            raise ConfigError(
                f"{group.label}: {group.stats.count} frame(s); a temporal variance needs at least 2 frames at "
                "each setting — add frames or remove the group"
            )
        if group.stats.maximum_dn > white:
            raise ConfigError(
                f"{group.label}: values reach {group.stats.maximum_dn:g} DN, above the {white} DN of a "
                f"{bit_depth}-bit ADC; give the right bit depth (--bit-depth)"
            )
    # The smallest channel plane (a Bayer phase has ⌊H/2⌋ × ⌊W/2⌋ sites or one more) must hold tiles × tiles
    # tiles of ≥ 3 × 3 px: EMVA's split into pixel, row and column variances needs 3 rows and 3 columns.
    step = 1 if cfa == "mono" else 2
    plane = (shape[0] // step, shape[1] // step)
    minimum = 3 * tiles
    if min(plane) < minimum:
        raise ConfigError(
            f"{darks[0].label}: frames of {shape[1]}×{shape[0]} px give {cfa} channel planes of "
            f"{plane[1]}×{plane[0]} px; the fit needs at least {minimum}×{minimum} px per channel plane "
            f"({tiles}×{tiles} tiles of 3×3 px for the uncertainties), frames of at least "
            f"{step * minimum}×{step * minimum} px"
        )
    for group in darks:
        mean = group.stats.mean_dn
        clipped = float(np.mean(mean >= white - 0.5))
        if clipped > SATURATED_DARK_FRACTION or float(np.mean(mean)) > 0.9 * white:
            raise ConfigError(
                f"{group.label}: a saturated dark group ({clipped:.1%} of pixels at the ADC maximum {white} DN, "
                f"mean {float(np.mean(mean)):.0f} DN): these frames saw light or ran far too long — cap the "
                "lens, shorten the exposure, or move them to the flats"
            )
    return darks, flats


@dataclass(frozen=True)
class _DarkSet:
    """Dark groups taken at one temperature."""

    temperature_c: float | None
    groups: tuple[FrameGroup, ...]

    @property
    def exposure_times_s(self) -> np.ndarray:
        return np.array([g.exposure_time_s for g in self.groups])

    @property
    def has_slope(self) -> bool:
        return np.unique(self.exposure_times_s).size >= 2


def _dark_sets(darks: list[FrameGroup], tolerance_c: float) -> list[_DarkSet]:
    """Dark groups clustered by temperature: a new set starts where the sorted temperatures step by
    more than `tolerance_c`; a set's temperature is its groups' mean."""
    known = [g for g in darks if g.temperature_c is not None]
    if not known:
        return [_DarkSet(None, tuple(darks))]
    if len(known) < len(darks):
        missing = ", ".join(g.label for g in darks if g.temperature_c is None)
        raise ConfigError(
            f"{missing}: no temperature, while other dark groups have one; give every dark group its "
            "temperature (frames.csv) or none"
        )
    ordered = sorted(darks, key=lambda g: g.temperature_c)
    clusters = [[ordered[0]]]
    for group in ordered[1:]:
        if group.temperature_c - clusters[-1][-1].temperature_c > tolerance_c:
            clusters.append([])
        clusters[-1].append(group)
    return [_DarkSet(float(np.mean([g.temperature_c for g in c])), tuple(c)) for c in clusters]


def _reference(sets: list[_DarkSet]) -> tuple[float | None, _DarkSet]:
    """The reference temperature (median of the temperatures whose sets give a dark current, else of
    all) and the primary set (the one nearest it, the colder on a tie)."""
    if sets[0].temperature_c is None:
        return None, sets[0]
    candidates = [s for s in sets if s.has_slope] or sets
    reference_c = float(np.median([s.temperature_c for s in candidates]))
    primary = min(candidates, key=lambda s: (abs(s.temperature_c - reference_c), s.temperature_c))
    return reference_c, primary


def _set_of(flat: FrameGroup, sets: list[_DarkSet], primary: _DarkSet) -> _DarkSet:
    if flat.temperature_c is None or primary.temperature_c is None:
        return primary
    return min(sets, key=lambda s: abs(s.temperature_c - flat.temperature_c))


def _group_statistics(
    groups: Sequence[FrameGroup],
    channels: tuple[tuple[str, tuple[int, int] | None], ...],
    valid: np.ndarray,
    regions: list[list[Region]],
) -> tuple[np.ndarray, np.ndarray]:
    """Spatial means of each group's mean and temporal variance images over the valid pixels of each
    channel region; the variance less the group's frame-mean variance (EMVA's (μ_A − μ_B) term).

    Returns
    -------
    mean_dn, variance_dn2 : (G, C, R) float64
    """
    shape = (len(groups), len(channels), len(regions[0]))
    means, variances = np.empty(shape), np.empty(shape)
    for g, group in enumerate(groups):
        mean, variance = group.stats.mean_dn, group.stats.temporal_variance_dn2
        for c, (_, phase) in enumerate(channels):
            ok = _plane(valid, phase)
            means[g, c] = _masked_means(_plane(mean, phase), ok, regions[c])
            variances[g, c] = _masked_means(_plane(variance, phase), ok, regions[c])
            variances[g, c] -= group.stats.frame_mean_variance_dn2(phase)
    return means, variances


@dataclass(frozen=True)
class _Darks:
    """Spatial means of every dark group, per channel and region."""

    index: dict[int, int]
    """id(group) → row in `mean_dn` and `variance_dn2`."""
    mean_dn: np.ndarray
    variance_dn2: np.ndarray

    def of(self, dark_set: _DarkSet) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Exposure times (n,), means and variances (n, C, R) of one set."""
        rows = [self.index[id(g)] for g in dark_set.groups]
        return dark_set.exposure_times_s, self.mean_dn[rows], self.variance_dn2[rows]

    def at(self, dark_set: _DarkSet, exposure_time_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Dark mean and temporal variance (C, R) at an exposure time (`_at_exposure`)."""
        times, mean, variance = self.of(dark_set)
        return _at_exposure(times, mean, exposure_time_s), _at_exposure(times, variance, exposure_time_s)


@dataclass(frozen=True, eq=False)
class _Context:
    """Everything the per-channel fit shares: groups, decisions and per-region statistics."""

    channels: tuple[tuple[str, tuple[int, int] | None], ...]
    regions: list[list[Region]]
    white_dn: int
    sets: list[_DarkSet]
    primary: _DarkSet
    reference_c: float | None
    flats: list[FrameGroup]
    flat_sets: list[_DarkSet]
    flat_mean: np.ndarray
    """(F, C, R) spatial means of the flats over good pixels, DN."""
    flat_variance: np.ndarray
    """(F, C, R) temporal variances of the flats over good pixels, DN²."""
    darks: _Darks
    valid: np.ndarray
    hot_map: np.ndarray
    dead_map: np.ndarray
    hot_rates_dn_per_s: list[np.ndarray]
    """Per channel: the hot pixels' dark signal rates (reference set's temperature), DN/s."""
    dsnu_group: FrameGroup
    longest_dark: FrameGroup
    gain_given: Estimate | None
    shading_correction: str

    @property
    def frames(self) -> np.ndarray:
        return np.array([f.stats.count for f in self.flats])

    @property
    def photons(self) -> np.ndarray:
        """(F,) μ_p of each flat, NaN where not known."""
        return np.array([math.nan if f.photons_per_pixel is None else f.photons_per_pixel for f in self.flats])
