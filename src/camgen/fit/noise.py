"""Sensor noise from stacks of raw dark and flat frames, after EMVA 1288 release 4.0 [1]_.

Frames taken at one setting (kind, exposure time, temperature, light) form a group; `StackStatistics`
reduces each group to a per-pixel mean and temporal variance while the frames stream past (a 4K stack
is never held in memory). `fit_noise` turns the groups into the figures of EMVA 1288 4.0 and of
camgen's sensor model (DESIGN.md "Sensor model"; `camgen.config.profile.Noise`):

    e  = Poisson(η·Φ·(1 + PRNU)) + Poisson(D(T)·t) + DSNU + row FPN + column FPN + N(0, σ_read²)
    DN = clip(round(K·min(e, full_well) + black), 0, 2^bits − 1)

Every mean and variance image is split by CFA phase (site (y, x) has the colour ``cfa[2·(y%2) + x%2]``,
`camgen.sensor.cfa`) and each channel (R, Gr, Gb, B, or mono) is analysed as an image of its own:

- **Dark groups** give the black level (the averaged dark signal extrapolated to t = 0), the temporal
  dark noise σ²_y.dark(t → 0) and from it the read noise (EMVA eq. 6, quantisation 1/12 DN² removed),
  the dark current (slope of the dark mean against exposure time; EMVA's second estimate, the slope of
  the dark variance, as well) and its doubling temperature (ln I against T, when the temperatures
  resolve a rise), and the hot pixels.
- **Spatial non-uniformity** (EMVA 4.0 §8) comes from the *largest* stacks: DSNU1288 from the dark
  group with the most frames, PRNU1288 from the flat with the most frames near half saturation (and
  the largest dark stack at its exposure time). The spatial variance of an L-frame mean is corrected
  for the temporal noise left in it, s²_y = s²_y.measured − σ²_y.stack/L, and split into column, row
  and pixel parts by the standard's equations (`camgen.fit.noise_spatial`): the pixel part is the white
  non-uniformity, the row and column parts the non-white one. The horizontal and vertical
  spectrograms (EMVA 4.0 §8.6) of both images are kept for the report.
- **Illumination shading** is not corrected by default, as EMVA's PRNU1288 and the `emva1288`
  reference implementation do not: PRNU1288 then includes any non-uniformity of the light. On request
  (`shading_correction`) either the standard's high-pass filter for uneven illumination (7 × 7 and
  11 × 11 box filters and a 3 × 3 binomial filter, subtracted) or a quadratic illumination surface
  divided out of the flat removes it.
- **Flat groups** give the photon transfer curve (σ²_y − σ²_y.dark against μ_y − μ_y.dark), whose
  slope through the origin up to 70 % of saturation is the system gain K; the saturation point (the
  variance peak, when brighter flats show the variance falling beyond it) and the clip level (the
  plateau beyond it); the linearity error LE = (max δ − min δ)/2; and the dead pixels.
- **Photon counts** μ_p of the flats, when given (`FrameGroup.photons_per_pixel`; `photons_per_pixel`
  converts an irradiance), give the responsivity R (slope of μ_y − μ_y.dark against μ_p), the quantum
  efficiency η = R/K, μ_p.sat, the absolute sensitivity threshold μ_p.min and the dynamic range
  DR = μ_p.sat/μ_p.min.

Uncertainties are 1σ standard uncertainties. Figures computed from images are computed again on
independent parts of each channel image (4 × 4 tiles; horizontal bands for row noise, vertical bands
for column noise) and take the standard error of those part estimates, std/√n. This measures the
scatter of a figure about the *population* value a profile holds (the sensor model's σ), including
the sampling of the realised fixed pattern. Fitted figures (intercepts, slopes, the system gain) are
fitted on each part as well. Products and ratios are propagated to first order assuming independent
factors; a photon count's own calibration uncertainty is not known here and not included.

The system gain's uncertainty is not taken from the residuals of its fit: the scatter of a photon
transfer point grows with its variance (σ(σ²_y) ≈ σ²_y·sqrt(2/(P(L − 1))) for P pixels, L frames),
so the residuals of an unweighted fit, most of them at low signal, understate the uncertainty of a
slope that the highest points fix. Over 20 simulated sensors the residual-based σ was half the actual
scatter of K; the tile-based σ matched it.

Where each part lives (the estimators are described in `fit_noise`'s notes):

- `camgen.fit.noise_stack`: the frames of one setting streamed into statistics (`StackStatistics`,
  `FrameGroup`);
- `camgen.fit.noise_groups`: input checks, dark groups by temperature, the groups' means and variances
  per channel and tile;
- `camgen.fit.noise_statistics`: `Estimate`, CFA channels, tiles and small statistics;
- `camgen.fit.noise_spatial`: spatial variances and spectrograms (§8), illumination shading;
- `camgen.fit.noise_dark`, `camgen.fit.noise_flat`: the per-channel estimators on the darks and flats;
- `camgen.fit.noise_result`: what the fit returns (`NoiseFit`, `ChannelNoise`), as a profile and a table;
- `camgen.fit.noise_report`: the report PNG.

This module holds `fit_noise`, which runs them and combines the channels, and `photons_per_pixel`.

References
----------
.. [1] EMVA Standard 1288, "Standard for Characterization of Image Sensors and Cameras", release 4.0
   Linear, European Machine Vision Association, 2021. Section numbers and equations below refer to it.
.. [2] EMVA 1288 reference implementation, `emva1288` 1.0.2 (release 4.0), https://github.com/EMVA1288/emva1288
   (``process/results.py``: the same spatial variances, responsivity, η, μ_p.min and DR).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from camgen.fit.noise_dark import (
    _dark_current,
    _dark_figures,
    _dark_histogram,
    _dsnu_group,
    _find_hot_pixels,
    _pixel_dark_fit,
)
from camgen.fit.noise_flat import _dead_pixels, _flat_figures, _mid_signal_flat, _photon_transfer, _sensitivity
from camgen.fit.noise_groups import (
    _check_input,
    _Context,
    _dark_sets,
    _Darks,
    _group_statistics,
    _reference,
    _set_of,
)
from camgen.fit.noise_result import ChannelNoise, DarkHistogram, NoiseFit, PhotonTransferCurve
from camgen.fit.noise_spatial import Spectrogram
from camgen.fit.noise_stack import FrameGroup
from camgen.fit.noise_statistics import (
    Estimate,
    _median_estimate,
    _per_gain,
    _plane,
    _regions,
    _weighted_mean,
    channel_phases,
)

PLANCK_J_S = 6.62607015e-34
SPEED_OF_LIGHT_M_PER_S = 299_792_458.0
SHARED_ROW_COLUMN_FIELDS = frozenset(
    {"black_level_dn", "row_fpn_dn", "row_fpn_e", "column_fpn_dn", "column_fpn_e", "prnu_row_pct", "prnu_column_pct"}
)
"""Figures whose error comes largely from the realised row and column offsets, which Bayer phases share."""
SATURATION_FIELDS = frozenset({"saturation_dn", "saturation_capacity_e", "full_well_e", "snr_max", "dynamic_range"})
"""Figures a channel lacks when the flats do not reach its saturation; combined over the channels that have them."""
COLOUR_FIELDS = frozenset(
    {"responsivity_dn_per_photon", "quantum_efficiency_pct", "saturation_photons", "sensitivity_threshold_photons"}
)
"""Figures that differ by colour filter: a colour sensor has them per channel only (none combined)."""


def photons_per_pixel(
    irradiance_w_per_m2: float, exposure_time_s: float, wavelength_nm: float, pixel_area_um2: float
) -> float:
    """Mean photons reaching one pixel in one exposure (EMVA 1288 4.0):

        μ_p = A·E·t_exp·λ/(h·c)

    Parameters
    ----------
    irradiance_w_per_m2 : float
        E on the sensor surface, W/m².
    exposure_time_s : float
        t_exp, s.
    wavelength_nm : float
        λ of the (monochromatic) light, nm.
    pixel_area_um2 : float
        A, the pixel's area (pitch_x · pitch_y), µm².

    Returns
    -------
    float
        μ_p, photons per pixel.
    """
    energy_j = irradiance_w_per_m2 * pixel_area_um2 * 1e-12 * exposure_time_s
    return energy_j * wavelength_nm * 1e-9 / (PLANCK_J_S * SPEED_OF_LIGHT_M_PER_S)


def fit_noise(
    groups: Sequence[FrameGroup],
    *,
    cfa: str,
    bit_depth: int,
    gain_dn_per_e: float | None = None,
    hot_pixel_threshold_sigma: float = 8.0,
    temperature_tolerance_c: float = 0.5,
    shading_correction: str = "none",
    dsnu_exposure_time_s: float | None = None,
    tiles: int = 4,
) -> NoiseFit:
    """Fit the sensor noise model to dark and flat frame groups (EMVA 1288 4.0 methods).

    Parameters
    ----------
    groups : sequence of FrameGroup
        At least one dark group; every group ≥ 2 frames, all of one shape (H, W) px.
    cfa : {"RGGB", "BGGR", "GRBG", "GBRG", "mono"}
        The mosaic; each Bayer phase is analysed as its own channel.
    bit_depth : int
        ADC bits; the white level is 2^bits − 1 DN.
    gain_dn_per_e : float, optional
        System gain K, DN/e⁻, used when there are no flats (the flats' K wins when both are given).
    hot_pixel_threshold_sigma : float
        A pixel is hot when its dark signal rate exceeds the channel median by this many robust σ
        (1.4826·MAD) — and by at least one frame's temporal dark σ at the longest exposure
        (`HOT_PIXEL_MIN_EXCESS_SIGMA`). 8σ: a normal tail beyond 8σ has probability 6·10⁻¹⁶, so not one
        false hot pixel is expected even on a 100 MP sensor, with margin for the heavier-than-normal
        tails of real read noise (RTS); 5σ would already flag ~2 normal pixels of an 8 MP sensor.
    temperature_tolerance_c : float
        Dark groups whose sorted temperatures step by no more than this, °C, form one temperature set.
    shading_correction : {"none", "highpass", "polynomial"}
        Correction of the PRNU flat for uneven illumination. "none" (default) keeps it as it is: EMVA's
        PRNU1288, as the `emva1288` reference implementation computes it, which includes any non-uniformity
        of the light. "highpass": EMVA 1288 4.0's correction for uneven illumination (`highpass_filtered`)
        on the flat and on its dark image. "polynomial": a degree-2 illumination surface fitted to the
        flat and divided out (removes only the light's smooth shape).
    dsnu_exposure_time_s : float, optional
        Exposure time, s, of the dark group the spatial dark non-uniformity is measured on; default the
        group with the most frames at the reference temperature (the shortest exposure among equals).
    tiles : int
        Each channel image is cut into tiles × tiles parts (≥ 2) for the uncertainties.

    Returns
    -------
    NoiseFit

    Raises
    ------
    ConfigError
        No dark group; a group of < 2 frames; a saturated dark group; groups of different shapes;
        frames whose channel planes (a Bayer phase: half the frame a side) are under 3·tiles px a side;
        values above the white level; mixed known and unknown temperatures; a photon count < 0. Each
        names the group. Also a gain_dn_per_e ≤ 0, tiles < 2, or an unknown shading_correction.

    Notes
    -----
    Methods, per channel:

    - *Hot pixels*: with ≥ 2 dark exposure times, each pixel's dark signal rate is the slope of its
      averaged dark signal against t (reference temperature); with one, (mean − channel median)/t.
      Offsets (DSNU, FPN) cancel in a slope, so the rate's spread is temporal noise only. Hot pixels
      are left out of every spatial mean and variance (replaced by the channel median in the dark image
      the DSNU decomposition uses). Fraction = count/pixels (uncertainty √count/pixels); dark current =
      the hot pixels' median rate ÷ K, scaled to the reference temperature with the fitted doubling:
      with ≥ 2 exposure times the total rate the profile's ``hot_pixel_dark_current_e_per_s`` means;
      with one, only the excess over the channel median (a warning says so), since the normal dark
      current cannot then be told from the black level — it is never known in that case.
    - *Black level and read noise*: μ_y.dark(t) and σ²_y.dark(t) (spatial means over good pixels,
      frame-mean variance removed) are fitted with lines in t at the reference temperature; the
      intercepts are the black level and σ²_y.dark(0), so dark-current shot noise (∝ t) drops out.
      σ_read = sqrt(σ²_y.dark(0) − 1/12)/K; below 0.24 DN² EMVA's floor applies (an upper limit, with
      a warning).
    - *Dark non-uniformity* (EMVA 4.0 §8): `_variance_parts` on the averaged dark image of the largest
      dark stack (the most frames; L = 50 leaves 1/50 of the temporal variance to subtract, a 2-frame
      pair half of it, and with it half of any temporal row noise, which the correction σ²/(L·N) does
      not cover); DSNU1288 = sqrt(s²_y.dark)/K, and its pixel, row and column parts likewise. The row
      and column parts take their uncertainty from horizontal and vertical bands; DSNU1288's and the
      black level's add those of the row and column offsets (tiles in one band share them).
    - *Dark current*: slope of μ_y.dark(t) ÷ K, from the hot-pixel-free mean; EMVA's estimate from
      the variance, the slope of σ²_y.dark(t) ÷ K², beside it. With ≥ 2
      temperatures each with ≥ 2 exposure times: ln I(T) = a + b·T by least squares, doubling = ln 2/b,
      I at the reference temperature (the median measured temperature) = exp(a + b·T_ref) — provided
      b > 0 by 2 u(b) (`DOUBLING_MIN_SIGNIFICANCE`); otherwise no doubling (a warning; the profile
      keeps its own), I = the mean of the temperatures' rates, and no temperature scaling.
    - *Photon transfer*: each flat's μ_y − μ_y.dark and σ²_y − σ²_y.dark, the dark values from
      dark groups at the same exposure time (and temperature set) when there are any, else from their
      lines in t. The saturation point is the variance peak, if a brighter flat's variance has clearly
      fallen below it (`_saturation_index`); K is the least-squares slope through the origin over the
      points up to 70 % of μ_sat (unweighted, as EMVA and `emva1288`); u(K) from the same fit on each
      tile (see the module docstring). μ_e.sat = (μ_y.sat − μ_y.dark)/K. The profile's full well is
      the clip level: the mean of the flat deepest beyond saturation when its variance has collapsed
      (< 5 % of the peak) and the ADC does not clip first, (μ_plateau − black)/K (dark electrons are
      clipped with the rest); else μ_e.sat, with a warning. When the flats do not reach saturation
      there is no saturation, μ_e.sat or full well (a warning asks for brighter flats), K is fitted to
      every point, and the ranges below are fractions of the largest measured μ_y − μ_y.dark instead.
    - *Dead pixels*: in the mid-signal flat (30–70 % of saturation), response = mean − per-pixel dark
      line at its exposure time; dead where below 50 % of the median of its 16 × 16 block.
    - *PRNU* (EMVA 4.0 §8): the mid-signal flat (30–70 % of saturation; the largest stack there,
      nearest 50 % among equals) and the largest dark group at its exposure time (else the DSNU group),
      hot and dead pixels set to the median, corrected for uneven illumination if asked
      (`shading_correction`); `_variance_parts` of each, PRNU1288 = sqrt(s²_y.50 − s²_y.dark)/(μ_y.50 −
      μ_y.dark)·100 %, and its pixel, row and column parts from the parts' differences.
    - *Sensitivity* (EMVA 4.0): μ_e.min = sqrt(σ²_y.dark/K² + 1/4) + 1/2, the signal at which
      SNR = η·μ_p/sqrt(σ²_y.dark/K² + η·μ_p) is 1 (`emva1288` uses the approximation σ_y.dark/K + 1/2,
      smaller by 1.5 % for σ_y.dark/K = 2.6 e⁻, by 0.45 % for 5 e⁻); SNR_max = sqrt(μ_e.sat). With photon
      counts on the flats, the responsivity R is the slope through the origin of μ_y − μ_y.dark against
      μ_p over the points K is fitted to, η = R/K, μ_p.sat the photon count of the saturation point,
      μ_p.min = μ_e.min/η and DR = μ_p.sat/μ_p.min; without, DR = μ_e.sat/μ_e.min (the same ratio for a
      linear sensor; η cancels).
    - *Linearity* (EMVA 1288 4.0): with flats at ≥ 3 exposure times within 5–95 % of μ_sat (5–100 %
      of the largest mean without saturation) and constant irradiance, μ_y − μ_y.dark = a·t + b is
      fitted minimising relative deviations (weights 1/y, as `emva1288`); from the relative deviations
      δ = (y − fit)/fit·100 %, LE = (max δ − min δ)/2, i.e. (LE_max − LE_min)/2 of `emva1288`
      (`_linearity`); its uncertainty from the temporal noise of the two extreme points' means.
    """
    darks, flats = _check_input(groups, cfa, bit_depth, gain_dn_per_e, tiles, shading_correction)
    shape = darks[0].stats.shape_px
    channels = channel_phases(cfa)
    warnings: list[str] = []
    sets = _dark_sets(darks, temperature_tolerance_c)
    reference_c, primary = _reference(sets)
    flat_sets = [_set_of(f, sets, primary) for f in flats]
    warnings += _temperature_warnings(reference_c, flats, flat_sets, temperature_tolerance_c)
    regions = [_regions(_plane(np.empty(shape, bool), phase).shape, tiles) for _, phase in channels]
    intercept_dn, slope_dn_per_s = _pixel_dark_fit(primary)
    hot_map, hot_rates = _find_hot_pixels(primary, slope_dn_per_s, channels, hot_pixel_threshold_sigma, warnings)

    def dark_statistics(valid: np.ndarray) -> _Darks:
        mean, variance = _group_statistics(darks, channels, valid, regions)
        return _Darks({id(g): i for i, g in enumerate(darks)}, mean, variance)

    # Photon transfer without the hot pixels finds the mid-signal flat for the dead pixels; then both
    # are left out of every statistic.
    dark_stats = dark_statistics(~hot_map)
    flat_mean, flat_variance = _group_statistics(flats, channels, ~hot_map, regions)
    dead_map = np.zeros(shape, bool)
    for c, (_, phase) in enumerate(channels if flats else ()):
        transfer = _photon_transfer(flats, flat_mean, flat_variance, dark_stats, flat_sets, c)
        frames = np.array([flats[i].stats.count for i in transfer.order])
        flat = flats[transfer.order[_mid_signal_flat(transfer.mean_above[:, 0], transfer.full_scale_dn, frames)[0]]]
        response = flat.stats.mean_dn - (intercept_dn + slope_dn_per_s * flat.exposure_time_s)
        _plane(dead_map, phase)[...] = _dead_pixels(_plane(response, phase), _plane(hot_map, phase))
    valid = ~(hot_map | dead_map)
    if dead_map.any():
        dark_stats = dark_statistics(valid)
        flat_mean, flat_variance = _group_statistics(flats, channels, valid, regions)
    times = primary.exposure_times_s
    context = _Context(
        channels=channels,
        regions=regions,
        white_dn=2**bit_depth - 1,
        sets=sets,
        primary=primary,
        reference_c=reference_c,
        flats=flats,
        flat_sets=flat_sets,
        flat_mean=flat_mean,
        flat_variance=flat_variance,
        darks=dark_stats,
        valid=valid,
        hot_map=hot_map,
        dead_map=dead_map,
        hot_rates_dn_per_s=hot_rates,
        dsnu_group=_dsnu_group(primary, dsnu_exposure_time_s),
        longest_dark=primary.groups[int(np.argmax(times))],
        gain_given=None if gain_dn_per_e is None else Estimate(gain_dn_per_e, 0.0),
        shading_correction=shading_correction,
    )
    fits = [_fit_channel(context, c, warnings) for c in range(len(channels))]
    results = [f.noise for f in fits]
    warnings += _summary_warnings(context, results)
    combined = _combine(results, [f.hot_rates_e for f in fits if f.hot_rates_e is not None])
    fit = NoiseFit(
        cfa=cfa,
        bit_depth=int(bit_depth),
        shape_px=shape,
        channels=tuple(results),
        combined=combined,
        hot_pixel_fraction=combined.hot_pixel_fraction,
        hot_pixel_dark_current_e_per_s=combined.hot_pixel_dark_current_e_per_s,
        dead_pixel_fraction=combined.dead_pixel_fraction,
        hot_pixel_map=hot_map,
        dead_pixel_map=dead_map,
        dark_current_doubling_c=combined.dark_current_doubling_c,
        dark_current_reference_c=reference_c,
        linearity_error_pct=combined.linearity_error_pct,
        photon_transfer=tuple(f.curve for f in fits if f.curve is not None),
        dark_histograms=tuple(f.histogram for f in fits),
        spectrograms=tuple(spectrogram for f in fits for spectrogram in f.spectrograms),
        shading_correction=shading_correction,
        dsnu_stack=f"{context.dsnu_group.label} ({context.dsnu_group.stats.count} frames)",
        warnings=(),
    )
    return replace(fit, warnings=tuple(dict.fromkeys(warnings + fit._fragment()[1])))


def _temperature_warnings(reference_c, flats, flat_sets, tolerance_c) -> list[str]:
    warnings = []
    if reference_c is None:
        warnings.append(
            "the dark frames record no temperature: the dark current holds at the (unknown) temperature they "
            "were taken at; set sensor.temperature_c and noise.dark_current_reference_c to it"
        )
    far: dict[float, list[str]] = {}
    for flat, dark_set in zip(flats, flat_sets, strict=True):
        if (
            flat.temperature_c is not None
            and dark_set.temperature_c is not None
            and abs(flat.temperature_c - dark_set.temperature_c) > tolerance_c
        ):
            far.setdefault(dark_set.temperature_c, []).append(f"{flat.label} ({flat.temperature_c:g} °C)")
    for temperature_c, labels in far.items():
        warnings.append(
            f"{len(labels)} flat group(s) have no dark frames at their temperature; their dark level is taken "
            f"from the darks at {temperature_c:g} °C: {', '.join(labels[:3])}{', …' if len(labels) > 3 else ''}"
        )
    return warnings


@dataclass(frozen=True, eq=False)
class _ChannelFit:
    noise: ChannelNoise
    curve: PhotonTransferCurve | None
    histogram: DarkHistogram
    spectrograms: tuple[Spectrogram, ...]
    hot_rates_e: tuple[np.ndarray, float] | None
    """The hot pixels' dark currents at the reference temperature, e⁻/s, and their relative scale
    uncertainty (gain and temperature scaling)."""


def _per_gain_squared(estimate: Estimate | None, gain: Estimate | None, factor: Estimate) -> Estimate | None:
    """A variance rate, DN²/s, in electrons per second: estimate/K² × factor, first-order uncertainty."""
    if estimate is None or gain is None:
        return None
    scale = factor.value / gain.value**2
    value = estimate.value * scale
    uncertainty = math.sqrt(
        (estimate.uncertainty * scale) ** 2
        + (value * 2 * gain.uncertainty / gain.value) ** 2
        + (value * factor.uncertainty / factor.value) ** 2
    )
    return Estimate(value, uncertainty)


def _fit_channel(ctx: _Context, c: int, warnings: list[str]) -> _ChannelFit:
    """Every figure of channel `c`."""
    name, phase = ctx.channels[c]
    dark = _dark_figures(ctx, c, name, warnings)
    rate_dn, doubling, to_reference = _dark_current(ctx, c, warnings)
    flat = None
    gain = ctx.gain_given
    if ctx.flats:
        flat = _flat_figures(ctx, c, dark.black_dn, warnings)
        if flat.gain_dn_per_e is not None:
            if gain is not None:
                warnings.append(
                    f"{name}: the flats give K = {flat.gain_dn_per_e.value:.4g} ± "
                    f"{flat.gain_dn_per_e.uncertainty:.2g} DN/e⁻, used instead of the given {gain.value:.4g} DN/e⁻"
                )
            gain = flat.gain_dn_per_e
    hot = _plane(ctx.hot_map, phase)
    pixels = hot.size
    hot_count = int(np.count_nonzero(hot))
    hot_rates_e = hot_current = None
    if gain is not None and hot_count:
        rates_e = ctx.hot_rates_dn_per_s[c] / gain.value * to_reference.value
        relative = math.hypot(gain.uncertainty / gain.value, to_reference.uncertainty / to_reference.value)
        hot_rates_e = (rates_e, relative)
        hot_current = _median_estimate(rates_e, relative)
    dead_fraction = None
    if ctx.flats:
        dead_count = int(np.count_nonzero(_plane(ctx.dead_map, phase)))
        dead_fraction = Estimate(dead_count / pixels, math.sqrt(dead_count) / pixels)
    prnu = None if flat is None else flat.prnu
    noise = ChannelNoise(
        channel=name,
        pixels=pixels,
        black_level_dn=dark.black_level_dn,
        temporal_dark_noise_dn=dark.temporal_dark_noise_dn,
        read_noise_dn=dark.read_noise_dn,
        read_noise_e=_per_gain(dark.read_noise_dn, gain),
        dsnu_dn=dark.dsnu_dn,
        row_fpn_dn=dark.row_fpn_dn,
        column_fpn_dn=dark.column_fpn_dn,
        dsnu1288_dn=dark.dsnu1288_dn,
        dsnu_e=_per_gain(dark.dsnu_dn, gain),
        row_fpn_e=_per_gain(dark.row_fpn_dn, gain),
        column_fpn_e=_per_gain(dark.column_fpn_dn, gain),
        dsnu1288_e=_per_gain(dark.dsnu1288_dn, gain),
        dark_current_dn_per_s=rate_dn,
        dark_current_e_per_s=_per_gain(rate_dn, gain),
        dark_current_from_variance_e_per_s=_per_gain_squared(dark.variance_slope_dn2_per_s, gain, to_reference),
        dark_current_doubling_c=doubling,
        gain_dn_per_e=gain,
        prnu_pct=None if prnu is None else prnu.total_pct,
        prnu_pixel_pct=None if prnu is None else prnu.pixel_pct,
        prnu_row_pct=None if prnu is None else prnu.row_pct,
        prnu_column_pct=None if prnu is None else prnu.column_pct,
        prnu_stack=None if prnu is None else prnu.stack,
        prnu_level=None if prnu is None else prnu.level,
        saturation_dn=None if flat is None else flat.saturation_dn,
        saturation_capacity_e=None if flat is None else _per_gain(flat.saturation_above_dark_dn, gain),
        full_well_e=None if flat is None else _per_gain(flat.full_well_dn, gain),
        full_well_source=None if flat is None else flat.full_well_source,
        hot_pixel_fraction=Estimate(hot_count / pixels, math.sqrt(hot_count) / pixels),
        hot_pixel_dark_current_e_per_s=hot_current,
        dead_pixel_fraction=dead_fraction,
        linearity_error_pct=None if flat is None else flat.linearity_error_pct,
        **_sensitivity(dark, flat, gain),
    )
    image = _plane(ctx.longest_dark.stats.mean_dn, phase)
    histogram = _dark_histogram(ctx, c, image, dark.spatial_variance_dn2)
    spectrograms = (dark.spectrogram,) if prnu is None else (dark.spectrogram, prnu.spectrogram)
    return _ChannelFit(noise, None if flat is None else flat.curve, histogram, spectrograms, hot_rates_e)


def _summary_warnings(ctx: _Context, results: list[ChannelNoise]) -> list[str]:
    warnings = []
    if not (ctx.flats and any(r.gain_dn_per_e is not None for r in results)):
        why = "no flats" if not ctx.flats else "the flats give no system gain"
        if ctx.gain_given is not None:
            warnings.append(f"{why}: K taken from gain_dn_per_e (--gain-dn-per-e) = {ctx.gain_given.value:g} DN/e⁻")
        else:
            warnings.append(
                f"{why} and no gain_dn_per_e (--gain-dn-per-e): figures in electrons are not reported, only those in DN"
            )
    if not ctx.primary.has_slope:
        warnings.append(
            "the dark frames have one exposure time at the reference temperature: no dark current, and the "
            "read noise includes the dark-current shot noise of that exposure"
        )
    elif len([s for s in ctx.sets if s.has_slope]) < 2:
        warnings.append(
            "dark frames at one temperature: the dark current's doubling temperature is not measured (the "
            "profile keeps its own)"
        )
    unsaturated = [r.channel for r in results if ctx.flats and r.saturation_dn is None]
    if unsaturated:
        which = "" if len(unsaturated) == len(results) else f"{', '.join(unsaturated)}: "
        others = "" if len(unsaturated) == len(results) else " (the combined ones come from the other channels)"
        warnings.append(
            f"{which}the flats do not reach saturation: no full well, saturation or μ_e.sat{others}; add brighter "
            "flats, up to 1.5× the saturating exposure (no flat beyond the photon-transfer variance peak has a "
            "clearly lower variance). Meanwhile the system gain is fitted to every point, PRNU and dead pixels use "
            "a flat at 30–70 % of the largest measured mean (the one with the most frames, then the nearest to "
            "50 %), and the linearity error covers 5–100 % of that mean"
        )
    sources = {r.full_well_source for r in results} - {None}
    if "variance peak" in sources:
        warnings.append(
            "no flat lies well beyond saturation: full_well_e is EMVA's μ_e.sat at the variance peak, a few "
            "shot-noise σ below the clip level the profile means; add flats at 1.5× the saturating exposure"
        )
    if "ADC" in sources:
        warnings.append(
            "the ADC clips before the pixels fill: full_well_e is the ADC's limit (2^bits − 1 − black)/K, which "
            "the simulation treats alike"
        )
    return warnings


def _combine(results: list[ChannelNoise], hot_rates_e: list[tuple[np.ndarray, float]]) -> ChannelNoise:
    """Channel figures combined (`NoiseFit.combined`): inverse-variance weighted means (saturation, μ_e.sat
    and full well over the channels that reach saturation); pixel fractions pooled (count over all
    pixels); the hot pixels' dark current the median of all of them; the linearity error that of the
    worst channel.

    The four Bayer phases are two pairs that share their rows (R, Gr and Gb, B) and two that share their
    columns, so the channels' row and column offsets, and the black level they shift, are two independent
    samples rather than four: those combined uncertainties are multiplied by √2.
    """
    if len(results) == 1:
        return results[0]
    pixels = sum(r.pixels for r in results)

    def weighted(field: str) -> Estimate | None:
        if field in COLOUR_FIELDS:
            return None
        values = [getattr(r, field) for r in results]
        if field in SATURATION_FIELDS:
            # One pixel design under every filter: the channels that reach saturation give it.
            values = [v for v in values if v is not None]
        if not values or any(v is None for v in values):
            return None
        finite = [v for v in values if math.isfinite(v.value)]
        if not finite:
            return None
        mean = _weighted_mean(finite)
        if field in SHARED_ROW_COLUMN_FIELDS:
            return Estimate(mean.value, math.sqrt(2) * mean.uncertainty)
        return mean

    def pooled(field: str) -> Estimate | None:
        values = [getattr(r, field) for r in results]
        if any(v is None for v in values):
            return None
        count = sum(round(v.value * r.pixels) for v, r in zip(values, results, strict=True))
        return Estimate(count / pixels, math.sqrt(count) / pixels)

    hot_current = None
    known = all(r.hot_pixel_dark_current_e_per_s is not None or not r.hot_pixel_fraction.value for r in results)
    if hot_rates_e and known:
        # The channels' gains are independent: their relative errors average down.
        relative = math.sqrt(sum(rel**2 for _, rel in hot_rates_e)) / len(hot_rates_e)
        hot_current = _median_estimate(np.concatenate([rates for rates, _ in hot_rates_e]), relative)
    linearity = [r.linearity_error_pct for r in results]
    sources = {r.full_well_source for r in results} - {None}
    special = ("channel", "pixels", "full_well_source", "hot_pixel_fraction", "dead_pixel_fraction")
    special += ("hot_pixel_dark_current_e_per_s", "linearity_error_pct", "prnu_stack", "prnu_level")
    stacks = list(dict.fromkeys(r.prnu_stack for r in results if r.prnu_stack is not None))
    return ChannelNoise(
        channel="combined",
        pixels=pixels,
        prnu_stack=" and ".join(stacks) if stacks else None,
        prnu_level=None,
        full_well_source=None if not sources else sources.pop() if len(sources) == 1 else "mixed",
        hot_pixel_fraction=pooled("hot_pixel_fraction"),
        dead_pixel_fraction=pooled("dead_pixel_fraction"),
        hot_pixel_dark_current_e_per_s=hot_current,
        linearity_error_pct=None if None in linearity else max(linearity, key=lambda e: e.value),
        **{name: weighted(name) for name in ChannelNoise.__dataclass_fields__ if name not in special},
    )
