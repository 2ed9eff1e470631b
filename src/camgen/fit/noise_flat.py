"""Estimators on the flat frames of a sensor noise fit, after EMVA 1288 release 4.0 (as cited in `camgen.fit.noise`).

Per channel: the photon transfer curve and its saturation point (`_photon_transfer`,
`_saturation_index`); the system gain K, the saturation capacity, the clip level and the responsivity
(`_flat_figures`); the dead pixels (`_dead_pixels`); PRNU1288 and its pixel, row and column parts (§8;
`_prnu`); the linearity error (`_linearity`); and the sensitivity threshold, maximum SNR, dynamic range
and quantum efficiency (`_sensitivity`). The methods are described in `camgen.fit.noise.fit_noise`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from camgen.fit.noise_dark import _DarkFigures
from camgen.fit.noise_groups import _Context, _Darks
from camgen.fit.noise_result import PhotonTransferCurve
from camgen.fit.noise_spatial import (
    DEAD_MEDIAN_BLOCK_PX,
    HIGHPASS_PIXEL_VARIANCE_GAIN,
    SHADING_POLYNOMIAL_ORDER,
    Spectrogram,
    _block_median,
    _filled,
    _shading_surface,
    _spatial_variances,
    _spectrogram,
    highpass_filtered,
)
from camgen.fit.noise_stack import FrameGroup
from camgen.fit.noise_statistics import Estimate, _estimate, _masked_means, _plane, _sigma_estimate

GAIN_FIT_LIMIT = 0.7
"""The system gain is fitted from the lowest point up to this fraction of saturation (EMVA 1288 4.0)."""
LINEARITY_RANGE = (0.05, 0.95)
"""Fraction of saturation over which the linearity error is evaluated (EMVA 1288 4.0, as `emva1288`)."""
MID_SIGNAL_RANGE = (0.3, 0.7)
"""Flats for PRNU and dead pixels lie in this fraction of saturation (EMVA 1288 asks for 50 %)."""
SATURATION_DROP_SIGMA = 3.0
"""The variance peak is the saturation point only if a brighter flat's variance lies below it by more than
this many standard uncertainties of the difference (see `_saturation_index`)."""
SATURATION_DROP_FRACTION = 0.1
"""The variance peak is the saturation point only if a brighter flat's variance lies below it by more than
this fraction of the peak as well (see `_saturation_index`)."""
DEAD_RESPONSE_FRACTION = 0.5
"""A pixel is dead when its response is below this fraction of the local median response."""
PLATEAU_VARIANCE_FRACTION = 0.05
"""A flat beyond the saturation point whose temporal variance has fallen below this fraction of the
peak has (almost) every pixel clipped in every frame: its mean is the clip level."""


def _mid_signal_flat(mean_above: np.ndarray, full_scale_dn: float, frames: np.ndarray) -> tuple[int, bool]:
    """The flat for PRNU and dead pixels: within 30–70 % of `full_scale_dn` (saturation, or the largest
    mean when the flats do not reach it) the one with the most frames (nearest 50 % among equals); else the
    one nearest 50 %. Returns its index and whether it lay in range."""
    level = mean_above / full_scale_dn
    inside = np.flatnonzero((level >= MID_SIGNAL_RANGE[0]) & (level <= MID_SIGNAL_RANGE[1]))
    if inside.size:
        best = min(inside, key=lambda i: (-frames[i], abs(level[i] - 0.5)))
        return int(best), True
    return int(np.nanargmin(np.abs(level - 0.5))), False


@dataclass(frozen=True)
class _PhotonTransfer:
    """One channel's photon transfer points per region, ordered by the whole-image signal."""

    order: np.ndarray
    """Flat indices in signal order."""
    mean_above: np.ndarray
    """(F, R) μ_y − μ_y.dark, DN, in signal order."""
    variance_above: np.ndarray
    """(F, R) σ²_y − σ²_y.dark, DN², in signal order."""
    mean: np.ndarray
    """(F, R) μ_y, DN."""
    variance: np.ndarray
    """(F, R) σ²_y, DN²."""
    saturation: int | None
    """Index (in signal order) of the variance peak; None when the flats do not reach saturation."""

    @property
    def full_scale(self) -> int:
        """Index of the level the fit ranges are fractions of: saturation, else the largest mean."""
        return len(self.order) - 1 if self.saturation is None else self.saturation

    @property
    def full_scale_dn(self) -> float:
        """μ_y − μ_y.dark at `full_scale` (whole channel), DN."""
        return float(self.mean_above[self.full_scale, 0])


def _saturation_index(variance_above: np.ndarray) -> int | None:
    """The saturation point: the variance peak, provided the flats go beyond it.

    A peak is only known to be one when a brighter flat's variance has clearly fallen: below the peak by
    more than `SATURATION_DROP_SIGMA` standard uncertainties of the difference (the tile scatter of both
    points, so a chance dip of a still rising curve has probability < 0.2 %) and by more than
    `SATURATION_DROP_FRACTION` of the peak (beyond the few-per-cent systematic scatter of a photon transfer
    point: flicker, RTS, a tile σ from 16 tiles). Clipping takes the variance far lower, towards zero on
    the plateau. Without such a flat the brightest flats are still below saturation, and the peak (then
    simply the brightest flat, or a noise spike below it) would put saturation, the full well and every
    range measured against them far too low.

    Parameters
    ----------
    variance_above : (F, R) float
        σ²_y − σ²_y.dark of each flat in signal order, whole channel then its tiles, DN².

    Returns
    -------
    int or None
        Index of the peak, or None when no flat beyond it has clearly fallen.
    """
    whole = variance_above[:, 0]
    peak = int(np.nanargmax(whole))
    u_peak = _estimate(variance_above[peak]).uncertainty
    for i in range(peak + 1, len(whole)):
        drop = whole[peak] - whole[i]
        u = math.hypot(u_peak, _estimate(variance_above[i]).uncertainty)
        if drop > SATURATION_DROP_SIGMA * u and drop > SATURATION_DROP_FRACTION * whole[peak]:
            return peak
    return None


def _photon_transfer(
    flats: list[FrameGroup], flat_mean: np.ndarray, flat_variance: np.ndarray, darks: _Darks, flat_sets, c: int
) -> _PhotonTransfer:
    """μ_y − μ_y.dark and σ²_y − σ²_y.dark of every flat for channel `c` (EMVA 1288 4.0)."""
    dark_mean = np.empty_like(flat_mean[:, c])
    dark_variance = np.empty_like(dark_mean)
    for f, flat in enumerate(flats):
        mean, variance = darks.at(flat_sets[f], flat.exposure_time_s)
        dark_mean[f], dark_variance[f] = mean[c], variance[c]
    mean_above = flat_mean[:, c] - dark_mean
    variance_above = flat_variance[:, c] - dark_variance
    order = np.argsort(mean_above[:, 0], kind="stable")
    variance_sorted = variance_above[order]
    return _PhotonTransfer(
        order=order,
        mean_above=mean_above[order],
        variance_above=variance_sorted,
        mean=flat_mean[order, c],
        variance=flat_variance[order, c],
        saturation=_saturation_index(variance_sorted),
    )


def _dead_pixels(response_dn: np.ndarray, hot: np.ndarray) -> np.ndarray:
    """Pixels whose response (flat − dark) is below `DEAD_RESPONSE_FRACTION` of their block's median."""
    local = _block_median(np.where(hot, np.nan, response_dn), DEAD_MEDIAN_BLOCK_PX)
    return response_dn < DEAD_RESPONSE_FRACTION * local


@dataclass(frozen=True)
class _Prnu:
    total_pct: Estimate
    pixel_pct: Estimate
    row_pct: Estimate
    column_pct: Estimate
    stack: str
    level: str
    spectrogram: Spectrogram


@dataclass(frozen=True, eq=False)
class _FlatFigures:
    gain_dn_per_e: Estimate | None
    gain_dn_per_e_regions: np.ndarray | None
    """(R,) K of the whole channel and of each tile."""
    saturation_dn: Estimate | None
    """None (as the next four) when the flats do not reach saturation."""
    saturation_above_dark_dn: Estimate | None
    saturation_above_dark_dn_regions: np.ndarray | None
    """(R,) μ_y.sat − μ_y.dark of the whole channel and of each tile, DN."""
    full_well_dn: Estimate | None
    """Clip level above black, DN."""
    full_well_source: str | None
    responsivity_dn_per_photon_regions: np.ndarray | None
    """(R,) R of the whole channel and each tile; None without photon counts."""
    saturation_photons: float | None
    """μ_p of the saturation point; None without saturation or its photon count."""
    prnu: _Prnu
    linearity_error_pct: Estimate | None
    curve: PhotonTransferCurve


def _flat_figures(ctx: _Context, c: int, black_dn: np.ndarray, warnings: list[str]) -> _FlatFigures:
    """Photon transfer, system gain, saturation and clip level, responsivity, PRNU and linearity of channel `c`."""
    name = ctx.channels[c][0]
    transfer = _photon_transfer(ctx.flats, ctx.flat_mean, ctx.flat_variance, ctx.darks, ctx.flat_sets, c)
    sat = transfer.saturation
    x, y = transfer.mean_above, transfer.variance_above
    fit_points = x[:, 0] > 0
    if sat is not None:
        fit_points &= (x[:, 0] <= GAIN_FIT_LIMIT * x[sat, 0]) & (np.arange(len(x)) <= sat)
    gain = gain_regions = None
    if fit_points.any():
        xs, ys = x[fit_points], y[fit_points]
        gain_regions = np.sum(xs * ys, axis=0) / np.sum(xs * xs, axis=0)
        gain = _estimate(gain_regions)
        if fit_points.sum() < 3:
            warnings.append(f"{name}: the system gain rests on {int(fit_points.sum())} photon transfer point(s)")
        if not gain.value > 0:
            warnings.append(f"{name}: the photon transfer slope is {gain.value:.3g} DN/e⁻; no system gain")
            gain = gain_regions = None
    photons = ctx.photons[transfer.order]
    responsivity = None
    known = fit_points & np.isfinite(photons) & (photons > 0)
    if known.any():
        # EMVA: R is fitted through the origin over the points K is fitted to.
        if known.sum() < fit_points.sum():
            warnings.append(
                f"{name}: {int(fit_points.sum() - known.sum())} of the {int(fit_points.sum())} flats of the gain fit "
                "have no photon count; the responsivity and η rest on the others"
            )
        ps, xs = photons[known], x[known]
        responsivity = np.tensordot(ps, xs, axes=(0, 0)) / float(ps @ ps)
    curve = PhotonTransferCurve(
        channel=name,
        labels=tuple(ctx.flats[i].label for i in transfer.order),
        exposure_time_s=np.array([ctx.flats[i].exposure_time_s for i in transfer.order]),
        mean_above_dark_dn=x[:, 0].copy(),
        variance_above_dark_dn2=y[:, 0].copy(),
        used_in_gain_fit=fit_points,
        saturation_index=sat,
        gain_dn_per_e=None if gain is None else gain.value,
    )
    figures = {
        "saturation_dn": None,
        "saturation_above_dark_dn": None,
        "saturation_above_dark_dn_regions": None,
        "full_well_dn": None,
        "full_well_source": None,
        "saturation_photons": None,
    }
    if sat is not None:
        collapsed = [i for i in range(sat + 1, len(x)) if y[i, 0] < PLATEAU_VARIANCE_FRACTION * y[sat, 0]]
        if collapsed:
            plateau = transfer.mean[max(collapsed, key=lambda i: x[i, 0])]
            if plateau[0] >= ctx.white_dn - 1.0:
                source, full_well = "ADC", _estimate(ctx.white_dn - black_dn)
            else:
                source, full_well = "plateau", _estimate(plateau - black_dn)
        else:
            source, full_well = "variance peak", _estimate(x[sat])
        figures = {
            "saturation_dn": _estimate(transfer.mean[sat]),
            "saturation_above_dark_dn": _estimate(x[sat]),
            "saturation_above_dark_dn_regions": x[sat].copy(),
            "full_well_dn": full_well,
            "full_well_source": source,
            "saturation_photons": float(photons[sat]) if np.isfinite(photons[sat]) else None,
        }
    return _FlatFigures(
        gain_dn_per_e=gain,
        gain_dn_per_e_regions=gain_regions,
        responsivity_dn_per_photon_regions=responsivity,
        prnu=_prnu(ctx, c, transfer, warnings),
        linearity_error_pct=_linearity(ctx, c, transfer, warnings),
        curve=curve,
        **figures,
    )


def _full_scale_name(transfer: _PhotonTransfer) -> str:
    return "saturation" if transfer.saturation is not None else "the largest mean (no saturation)"


def _prnu(ctx: _Context, c: int, transfer: _PhotonTransfer, warnings: list[str]) -> _Prnu:
    """PRNU1288 of channel `c` and its pixel, row and column parts, % (EMVA 1288 4.0; see `fit_noise`)."""
    name, phase = ctx.channels[c]
    full_scale = transfer.full_scale_dn
    position, in_range = _mid_signal_flat(transfer.mean_above[:, 0], full_scale, ctx.frames[transfer.order])
    f = int(transfer.order[position])
    flat, dark_set = ctx.flats[f], ctx.flat_sets[f]
    level = transfer.mean_above[position, 0] / full_scale
    if not in_range:
        warnings.append(
            f"{name}: no flat lies within 30–70 % of {_full_scale_name(transfer)}; PRNU and dead pixels use "
            f"{flat.label} at {level:.0%}"
        )
    ok = _plane(ctx.valid, phase)
    regions = ctx.regions[c]
    same = [g for g in dark_set.groups if math.isclose(g.exposure_time_s, flat.exposure_time_s, rel_tol=1e-6)]
    dark_group = max(same, key=lambda g: g.stats.count) if same else ctx.dsnu_group
    light = _filled(_plane(flat.stats.mean_dn, phase), ok)
    dark = _filled(_plane(dark_group.stats.mean_dn, phase), ok)
    light_variance = _plane(flat.stats.temporal_variance_dn2, phase)
    dark_temporal = ctx.darks.variance_dn2[ctx.darks.index[id(dark_group)], c]
    dark_level = ctx.darks.at(dark_set, flat.exposure_time_s)[0][c]
    if ctx.shading_correction == "polynomial":
        surface = _shading_surface(light - dark_level[0], ok, SHADING_POLYNOMIAL_ORDER)
        if surface is None:
            warnings.append(f"{name}: the illumination of {flat.label} could not be fitted; PRNU keeps its shading")
        else:
            # The signal, and its temporal noise with it, as under uniform light.
            light = dark_level[0] + (light - dark_level[0]) / surface
            light_variance = light_variance / surface**2
    light_temporal = _masked_means(light_variance, ok, regions) - flat.stats.frame_mean_variance_dn2(phase)
    signal = _masked_means(light, ok, regions) - dark_level
    if ctx.shading_correction == "highpass":
        light, dark = highpass_filtered(light), highpass_filtered(dark)
        light_temporal = light_temporal * HIGHPASS_PIXEL_VARIANCE_GAIN
        dark_temporal = dark_temporal * HIGHPASS_PIXEL_VARIANCE_GAIN
    parts = _spatial_variances(light, light_temporal / flat.stats.count, regions) - _spatial_variances(
        dark, dark_temporal / dark_group.stats.count, regions
    )
    total, pixel, row, column = (_sigma_estimate(e) for e in parts.scaled(1e4 / signal**2).estimates())
    stack = f"{flat.label} ({flat.stats.count} frames)"
    spectrogram = _spectrogram(
        name,
        "PRNU",
        light - dark,
        100.0 / signal[0],
        total.value,
        100.0 * math.sqrt(max(float(light_temporal[0]), 0.0)) / signal[0],
    )
    return _Prnu(total, pixel, row, column, stack, f"{level:.0%} of {_full_scale_name(transfer)}", spectrogram)


def _linearity(ctx: _Context, c: int, transfer: _PhotonTransfer, warnings: list[str]) -> Estimate | None:
    """Linearity error of channel `c`, % (EMVA 1288 4.0; see `fit_noise`).

    LE = (max δ − min δ)/2 of the relative deviations δ_i = (y_i − (a·u_i + b))/(a·u_i + b)·100 % from the
    line fitted to y = μ_y − μ_y.dark against u with weights 1/y, over 5–95 % of μ_y.sat − μ_y.dark (up to
    the largest mean when the flats do not reach saturation); u is the photon count μ_p where every one of
    those flats has one (as EMVA), else the exposure time t (proportional to μ_p under constant
    irradiance). The `emva1288` reference implementation's LE_min and LE_max are min δ and max δ over the
    same points, so LE = (LE_max − LE_min)/2. u(LE) =
    sqrt(u(δ_max)² + u(δ_min)²)/2, u(δ_i) the temporal noise of point i's spatial mean relative to the fit.
    """
    x = transfer.mean_above[:, 0]
    full_scale = transfer.full_scale_dn
    top = LINEARITY_RANGE[1] if transfer.saturation is not None else 1.0
    times = np.array([ctx.flats[i].exposure_time_s for i in transfer.order])
    inside = (x >= LINEARITY_RANGE[0] * full_scale) & (x <= top * full_scale)
    photons = ctx.photons[transfer.order][inside]
    u = photons if np.all(np.isfinite(photons)) else times[inside]
    if np.unique(u).size < 3:
        if len(ctx.flats) >= 3:
            warnings.append(
                f"{ctx.channels[c][0]}: fewer than 3 exposure times (or photon counts) within "
                f"{LINEARITY_RANGE[0]:.0%}–{top:.0%} of {_full_scale_name(transfer)}; no linearity error"
            )
        return None
    y = x[inside]
    offset, slope = np.polynomial.polynomial.polyfit(u, y, 1, w=1.0 / y)
    fitted = offset + slope * u
    deviation = 100 * (y - fitted) / fitted
    frames = ctx.frames[transfer.order][inside]
    pixels = np.count_nonzero(_plane(ctx.valid, ctx.channels[c][1]))
    noise_dn = np.sqrt(np.maximum(transfer.variance[inside][:, 0], 0.0) / (pixels * frames))
    u_deviation = 100 * noise_dn / fitted
    high, low = int(np.argmax(deviation)), int(np.argmin(deviation))
    return Estimate((deviation[high] - deviation[low]) / 2, math.hypot(u_deviation[high], u_deviation[low]) / 2)


def _sensitivity(dark: _DarkFigures, flat: _FlatFigures | None, gain: Estimate | None) -> dict[str, Estimate | None]:
    """μ_e.min, SNR_max, DR and, with photon counts, R, η, μ_p.sat and μ_p.min of one channel (see
    `fit_noise`, *Sensitivity*): the ChannelNoise fields of those names. Each is computed on the whole
    channel and on each tile (K, σ²_y.dark, μ_y.sat and R of the tile) for its uncertainty."""
    names = (
        "sensitivity_threshold_e",
        "snr_max",
        "dynamic_range",
        "responsivity_dn_per_photon",
        "quantum_efficiency_pct",
        "saturation_photons",
        "sensitivity_threshold_photons",
    )
    out: dict[str, Estimate | None] = dict.fromkeys(names)
    if gain is None:
        return out
    measured = flat is not None and flat.gain_dn_per_e_regions is not None
    gain_regions = flat.gain_dn_per_e_regions if measured else np.full(dark.variance_0_dn2.shape, gain.value)
    threshold_e = np.sqrt(dark.variance_0_dn2 / gain_regions**2 + 0.25) + 0.5
    out["sensitivity_threshold_e"] = _estimate(threshold_e)
    if flat is None:
        return out
    saturation_e = None
    if flat.saturation_above_dark_dn_regions is not None:
        saturation_e = flat.saturation_above_dark_dn_regions / gain_regions
        out["snr_max"] = _estimate(np.sqrt(np.maximum(saturation_e, 0.0)))
    responsivity = flat.responsivity_dn_per_photon_regions
    if responsivity is None:
        if saturation_e is not None:
            out["dynamic_range"] = _estimate(saturation_e / threshold_e)
        return out
    efficiency = responsivity / gain_regions
    threshold_photons = threshold_e / efficiency
    out["responsivity_dn_per_photon"] = _estimate(responsivity)
    out["quantum_efficiency_pct"] = _estimate(100 * efficiency)
    out["sensitivity_threshold_photons"] = _estimate(threshold_photons)
    if flat.saturation_photons is not None:
        out["saturation_photons"] = Estimate(flat.saturation_photons, math.nan)
        out["dynamic_range"] = _estimate(flat.saturation_photons / threshold_photons)
    elif saturation_e is not None:
        out["dynamic_range"] = _estimate(saturation_e / threshold_e)
    return out
