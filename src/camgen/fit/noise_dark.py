"""Estimators on the dark frames of a sensor noise fit, after EMVA 1288 release 4.0 (as cited in `camgen.fit.noise`).

Per-pixel dark signal lines and the hot pixels they show (`_find_hot_pixels`); per channel the black
level, the temporal dark noise and the read noise (eq. 6), DSNU1288 and its pixel, row and column
parts (§8; `_dark_figures`); the dark current from the mean and from the variance, and its doubling
temperature (`_dark_current`); and the histogram of the averaged dark image (`_dark_histogram`). The
methods are described in `camgen.fit.noise.fit_noise`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from camgen.errors import ConfigError
from camgen.fit.noise_groups import _Context, _DarkSet
from camgen.fit.noise_result import DarkHistogram
from camgen.fit.noise_spatial import Spectrogram, _filled, _spatial_variances, _spectrogram
from camgen.fit.noise_stack import FrameGroup
from camgen.fit.noise_statistics import (
    Estimate,
    _estimate,
    _line_fit,
    _plane,
    _robust_sigma,
    _sigma_estimate,
)

QUANTISATION_DN2 = 1.0 / 12.0
"""Variance of the ADC's rounding, DN² (EMVA 1288 eq. 6)."""
DARK_VARIANCE_FLOOR_DN2 = 0.24
"""Below this temporal dark variance, DN², quantisation dominates and σ_y.dark is an upper limit:
EMVA 1288 then sets σ²_y.dark to 0.24 DN² (as the `emva1288` reference implementation does)."""
DOUBLING_MIN_SIGNIFICANCE = 2.0
"""The doubling temperature ln 2/b is reported only when the slope b of ln I against T exceeds this many
standard uncertainties (see `_dark_current`)."""
HOT_PIXEL_MIN_EXCESS_SIGMA = 1.0
"""A hot pixel's extra dark signal at the longest dark exposure must reach this many temporal dark
σ of one frame: a smaller excess never shows above one frame's noise, so modelling it changes nothing."""


def _pixel_dark_fit(dark_set: _DarkSet) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel least-squares line of the averaged dark signal against exposure time.

    Returns
    -------
    intercept_dn, slope_dn_per_s : (H, W) float64
        The slope is 0 when the set has one exposure time (the intercept is then the mean).
    """
    times = dark_set.exposure_times_s
    dt = times - times.mean()
    sxx = float(dt @ dt)
    total = np.zeros(dark_set.groups[0].stats.shape_px)
    weighted = np.zeros_like(total)
    for group, d in zip(dark_set.groups, dt, strict=True):
        mean = group.stats.mean_dn
        total += mean
        if sxx > 0:
            weighted += d * mean
    total /= len(times)
    slope = weighted / sxx if sxx > 0 else weighted
    return total - slope * times.mean(), slope


def _hot_pixels(rate: np.ndarray, min_excess_dn_per_s: float, threshold_sigma: float) -> tuple[np.ndarray, float]:
    """Pixels whose dark signal rate stands out: above median + k·σ_MAD and by at least
    `min_excess_dn_per_s`. Returns the mask and the median rate."""
    median, sigma = _robust_sigma(rate)
    excess = rate - median
    return (excess > threshold_sigma * sigma) & (excess >= min_excess_dn_per_s), median


def _find_hot_pixels(
    primary: _DarkSet, slope_dn_per_s: np.ndarray, channels, threshold_sigma: float, warnings: list[str]
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Hot-pixel map (H, W) and, per channel, the hot pixels' dark signal rates, DN/s (see `fit_noise`)."""
    times = primary.exposure_times_s
    longest = primary.groups[int(np.argmax(times))]
    hot_map = np.zeros(longest.stats.shape_px, bool)
    if primary.has_slope:
        rate = slope_dn_per_s
    elif times.max() > 0:
        rate = longest.stats.mean_dn / times.max()
        warnings.append(
            "one dark exposure time: hot pixels are found from (mean − median)/t, and their dark current "
            "(hot_pixel_dark_current_e_per_s) is only the excess over the channel median, not the total rate "
            "the profile means: the normal dark current, which one exposure time cannot tell from the black "
            "level, is missing from it; add that, or take darks at ≥ 2 exposure times"
        )
    else:
        warnings.append("the dark frames have zero exposure time: hot pixels cannot be found")
        return hot_map, [np.zeros(0) for _ in channels]
    variance = longest.stats.temporal_variance_dn2
    rates = []
    for _, phase in channels:
        rate_c = _plane(rate, phase)
        noise_dn = math.sqrt(float(np.median(_plane(variance, phase))))
        hot_c, median_c = _hot_pixels(rate_c, HOT_PIXEL_MIN_EXCESS_SIGMA * noise_dn / times.max(), threshold_sigma)
        _plane(hot_map, phase)[...] = hot_c
        rates.append(rate_c[hot_c] - (0.0 if primary.has_slope else median_c))
    return hot_map, rates


def _dsnu_group(primary: _DarkSet, exposure_time_s: float | None) -> FrameGroup:
    """The dark group for the spatial non-uniformity: the largest stack of the reference set (the
    shortest exposure among equals), or the largest at `exposure_time_s`."""
    if exposure_time_s is None:
        return min(primary.groups, key=lambda g: (-g.stats.count, g.exposure_time_s))
    matching = [g for g in primary.groups if math.isclose(g.exposure_time_s, exposure_time_s, rel_tol=1e-6)]
    if not matching:
        available = ", ".join(f"{t:g}" for t in sorted(set(primary.exposure_times_s)))
        raise ConfigError(
            f"dsnu_exposure_time_s {exposure_time_s:g} s: no dark group at that time at the reference "
            f"temperature (available: {available} s)"
        )
    return max(matching, key=lambda g: g.stats.count)


@dataclass(frozen=True, eq=False)
class _DarkFigures:
    black_level_dn: Estimate
    temporal_dark_noise_dn: Estimate
    read_noise_dn: Estimate
    dsnu_dn: Estimate
    row_fpn_dn: Estimate
    column_fpn_dn: Estimate
    dsnu1288_dn: Estimate
    spatial_variance_dn2: float
    """s²_y.dark of the DSNU group (whole channel), DN²."""
    black_dn: np.ndarray
    """(R,) black level of the whole channel and of each tile, DN."""
    variance_0_dn2: np.ndarray
    """(R,) σ²_y.dark(t → 0) of the whole channel and of each tile (EMVA's floor applied), DN²."""
    variance_slope_dn2_per_s: Estimate | None
    """Slope of σ²_y.dark against t at the reference set's temperature, DN²/s; None with one exposure time."""
    spectrogram: Spectrogram


def _dark_figures(ctx: _Context, c: int, name: str, warnings: list[str]) -> _DarkFigures:
    """Black level, temporal dark noise and the spatial dark non-uniformity of channel `c`, DN."""
    times, mean, variance = ctx.darks.of(ctx.primary)
    _, black = _line_fit(times, mean[:, c])
    variance_slope, variance_0 = _line_fit(times, variance[:, c])
    if variance_0[0] < DARK_VARIANCE_FLOOR_DN2:
        warnings.append(
            f"{name}: σ²_y.dark = {variance_0[0]:.3g} DN² is below the {DARK_VARIANCE_FLOOR_DN2} DN² at which "
            "quantisation dominates; the read noise is an upper limit (EMVA 1288)"
        )
        variance_0 = np.maximum(variance_0, DARK_VARIANCE_FLOOR_DN2)

    # Spatial non-uniformity of the largest stack: hot pixels replaced by the channel median.
    phase = ctx.channels[c][1]
    group = ctx.dsnu_group
    image = _filled(_plane(group.stats.mean_dn, phase), ~_plane(ctx.hot_map, phase))
    temporal = ctx.darks.variance_dn2[ctx.darks.index[id(group)], c]
    parts = _spatial_variances(image, temporal / group.stats.count, ctx.regions[c])
    total, pixel, row, column = parts.estimates()
    height, width = image.shape
    black_u = math.sqrt(
        _estimate(black).uncertainty ** 2 + max(row.value, 0.0) / height + max(column.value, 0.0) / width
    )
    dsnu1288 = _sigma_estimate(total)
    return _DarkFigures(
        black_level_dn=Estimate(black[0], black_u),
        temporal_dark_noise_dn=_sigma_estimate(_estimate(variance_0)),
        read_noise_dn=_sigma_estimate(_estimate(variance_0 - QUANTISATION_DN2)),
        dsnu_dn=_sigma_estimate(pixel),
        row_fpn_dn=_sigma_estimate(row),
        column_fpn_dn=_sigma_estimate(column),
        dsnu1288_dn=dsnu1288,
        spatial_variance_dn2=float(parts.tiles[0, 0]),
        black_dn=black,
        variance_0_dn2=variance_0,
        variance_slope_dn2_per_s=_estimate(variance_slope) if ctx.primary.has_slope else None,
        spectrogram=_spectrogram(name, "DSNU", image, 1.0, dsnu1288.value, math.sqrt(max(float(temporal[0]), 0.0))),
    )


def _dark_current(ctx: _Context, c: int, warnings: list[str]) -> tuple[Estimate | None, Estimate | None, Estimate]:
    """Channel `c`'s dark signal rate at the reference temperature (DN/s), its doubling temperature
    (°C), and the factor (with uncertainty) from the reference set's temperature to the reference.

    The doubling temperature needs a temperature dependence the darks resolve: b > 0 and b >
    `DOUBLING_MIN_SIGNIFICANCE`·u(b). Below that, u(d)/d = u(b)/b exceeds 50 % and b = 0 (no dependence,
    d = ∞) lies inside b's 2σ interval, so ln 2/b is noise (or, for b ≤ 0, not a doubling at all): the
    doubling is None (the profile keeps its own), the rate is the mean of the temperatures' rates, and
    nothing is scaled.
    """
    usable = [s for s in ctx.sets if s.has_slope]
    unity = Estimate(1.0, 0.0)
    if len(usable) < 2:
        if not ctx.primary.has_slope:
            return None, None, unity
        times, mean, _ = ctx.darks.of(ctx.primary)
        return _estimate(_line_fit(times, mean[:, c])[0]), None, unity
    slopes = np.array([_line_fit(*ctx.darks.of(s)[:2])[0][c] for s in usable])
    temperatures = np.array([s.temperature_c for s in usable])
    with np.errstate(invalid="ignore", divide="ignore"):
        b, a = _line_fit(temperatures, np.log(np.where(slopes > 0, slopes, np.nan)))
    slope = _estimate(b)
    if not (slope.value > 0 and slope.value > DOUBLING_MIN_SIGNIFICANCE * slope.uncertainty):
        found = (
            f"the slope of ln I against T is {slope.value:.3g} ± {slope.uncertainty:.2g} /°C, not > 0 by "
            f"{DOUBLING_MIN_SIGNIFICANCE:g}σ"
            if math.isfinite(slope.value)
            else "a dark current ≤ 0 at some temperature"
        )
        warnings.append(
            f"{ctx.channels[c][0]}: the dark current's temperature dependence was not measurable ({found}): no "
            "doubling temperature (the profile keeps its own); the dark current is the mean over "
            f"{temperatures.min():g}–{temperatures.max():g} °C, not scaled to another temperature"
        )
        return _estimate(slopes.mean(axis=0)), None, unity
    with np.errstate(invalid="ignore", divide="ignore"):
        rate = _estimate(np.exp(a + b * ctx.reference_c))
        doubling = _estimate(math.log(2) / b)
    delta = ctx.reference_c - ctx.primary.temperature_c
    if delta == 0 or not math.isfinite(doubling.value):
        return rate, doubling, unity
    factor = 2 ** (delta / doubling.value)
    return (
        rate,
        doubling,
        Estimate(factor, factor * math.log(2) * abs(delta) * doubling.uncertainty / doubling.value**2),
    )


def _dark_histogram(ctx: _Context, c: int, image: np.ndarray, spatial_dn2: float) -> DarkHistogram:
    """Histogram of channel `c`'s averaged dark image at the longest exposure, and the predicted Gaussian.

    Bins are σ/4 wide within ±8σ of the mean (a whole number of 1/L DN steps when the frames are integers,
    so the averaged values do not alias), then 32 logarithmic bins out to the extreme values (hot pixels).
    """
    group = ctx.longest_dark
    row = ctx.darks.index[id(group)]
    frames = group.stats.count
    mean = float(ctx.darks.mean_dn[row, c, 0])
    sigma = math.sqrt(max(spatial_dn2, 0.0) + max(ctx.darks.variance_dn2[row, c, 0], 0.0) / frames)
    sigma = max(sigma, 1.0 / frames)
    step, start = sigma / 4, mean - 8 * sigma
    if group.stats.integer_frames:
        step = max(1, round(step * frames)) / frames
        start = (math.floor(start * frames) - 0.5) / frames
    edges = np.arange(start, mean + 8 * sigma + step, step)
    low, high = float(image.min()), float(image.max())
    if high >= edges[-1]:
        edges = np.concatenate([edges, edges[-1] + np.geomspace(step, high - edges[-1] + step, 33)])
    if low < edges[0]:
        edges = np.concatenate([edges[0] - np.geomspace(edges[0] - low + step, step, 33), edges])
    counts, _ = np.histogram(image, edges)
    return DarkHistogram(ctx.channels[c][0], group.label, edges, counts, mean, sigma)
