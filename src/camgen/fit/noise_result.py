"""What a sensor noise fit returns, in the terms of EMVA 1288 release 4.0 (as cited in `camgen.fit.noise`).

The figures of each CFA channel and of all combined (`ChannelNoise`), the photon transfer curves and
dark histograms that the report draws, and `NoiseFit`, which holds them with the defect maps and
warnings and writes the figures as a partial camera profile (`NoiseFit.profile_fragment`) and as table
rows (`NoiseFit.summary_rows`). `camgen.fit.noise.fit_noise` makes one; `camgen.fit.noise_report`
draws it.
"""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass

import numpy as np

from camgen.config.profile import Noise, Sensor
from camgen.fit.lens import rounded
from camgen.fit.noise_spatial import (
    HIGHPASS_LINE_VARIANCE_GAIN,
    HIGHPASS_PIXEL_VARIANCE_GAIN,
    SHADING_POLYNOMIAL_ORDER,
    Spectrogram,
)
from camgen.fit.noise_statistics import Estimate


@dataclass(frozen=True)
class ChannelNoise:
    """The fitted figures of one CFA channel (or of all channels combined).

    Figures in electrons are None without a system gain; figures that the frames cannot give (no
    flats, one exposure time, one temperature) are None as well.
    """

    channel: str
    """"R", "Gr", "Gb", "B", "mono", or "combined"."""
    pixels: int
    black_level_dn: Estimate
    """Dark signal extrapolated to zero exposure, DN."""
    temporal_dark_noise_dn: Estimate
    """σ_y.dark at zero exposure (read and quantisation noise), DN."""
    read_noise_dn: Estimate
    """σ_read·K = sqrt(σ²_y.dark − 1/12), DN."""
    read_noise_e: Estimate | None
    dsnu_dn: Estimate
    """Pixel part of the dark offset non-uniformity, DN."""
    row_fpn_dn: Estimate
    column_fpn_dn: Estimate
    dsnu1288_dn: Estimate
    """EMVA's DSNU1288: the total spatial σ of the averaged dark image, temporal part removed, DN."""
    dsnu_e: Estimate | None
    row_fpn_e: Estimate | None
    column_fpn_e: Estimate | None
    dsnu1288_e: Estimate | None
    dark_current_dn_per_s: Estimate | None
    """Mean dark signal rate at the reference temperature, DN/s."""
    dark_current_e_per_s: Estimate | None
    dark_current_from_variance_e_per_s: Estimate | None
    """EMVA's second dark current estimate: the slope of σ²_y.dark against t divided by K², e⁻/s (it
    counts the dark electrons by their shot noise; the two agree for a sensor without dark-signal drift)."""
    dark_current_doubling_c: Estimate | None
    gain_dn_per_e: Estimate | None
    """System gain K, DN/e⁻."""
    prnu_pct: Estimate | None
    """EMVA's PRNU1288: sqrt(s²_y.50 − s²_y.dark)/(μ_y.50 − μ_y.dark), %, every spatial part together."""
    prnu_pixel_pct: Estimate | None
    """The pixel (white) part of PRNU1288, %: what the profile's ``prnu_pct`` means."""
    prnu_row_pct: Estimate | None
    prnu_column_pct: Estimate | None
    prnu_stack: str | None
    """Label and frame count of the flat PRNU comes from."""
    prnu_level: str | None
    """Its signal, as a fraction of saturation (or of the largest mean without saturation)."""
    saturation_dn: Estimate | None
    """μ_y.sat: mean raw signal at the variance peak, DN (dark level included); None when the flats do not
    reach saturation (`_saturation_index`)."""
    saturation_capacity_e: Estimate | None
    """EMVA's μ_e.sat = (μ_y.sat − μ_y.dark)/K, e⁻."""
    full_well_e: Estimate | None
    """The clip level the profile's `full_well_e` means (see `full_well_source`), e⁻."""
    full_well_source: str | None
    """"plateau" (mean of flats beyond saturation), "ADC" (the ADC clips first: (2^bits − 1 − black)/K),
    or "variance peak" (μ_e.sat, a few shot-noise σ below the clip level); None without saturation."""
    hot_pixel_fraction: Estimate
    hot_pixel_dark_current_e_per_s: Estimate | None
    """Median dark current of the hot pixels at the reference temperature, e⁻/s: their total rate (the
    slope of their dark signal) with ≥ 2 dark exposure times; with one, only their excess over the channel
    median (see `fit_noise`, *Hot pixels*)."""
    dead_pixel_fraction: Estimate | None
    linearity_error_pct: Estimate | None
    sensitivity_threshold_e: Estimate | None
    """μ_e.min = sqrt(σ²_y.dark/K² + 1/4) + 1/2: the signal, e⁻, at which the SNR is 1."""
    snr_max: Estimate | None
    """SNR_max = sqrt(μ_e.sat) (ratio)."""
    dynamic_range: Estimate | None
    """DR = μ_p.sat/μ_p.min (ratio); without photon counts μ_e.sat/μ_e.min, the same ratio with η cancelled."""
    responsivity_dn_per_photon: Estimate | None
    """R: slope of μ_y − μ_y.dark against μ_p through the origin, DN per photon (needs photon counts)."""
    quantum_efficiency_pct: Estimate | None
    """η = R/K, % (needs photon counts; at the wavelength of the light)."""
    saturation_photons: Estimate | None
    """μ_p.sat: photons per pixel at the saturation point."""
    sensitivity_threshold_photons: Estimate | None
    """μ_p.min = μ_e.min/η: the absolute sensitivity threshold, photons per pixel."""


@dataclass(frozen=True, eq=False)
class PhotonTransferCurve:
    """One channel's photon transfer points (EMVA 1288 4.0), in the order of the flat groups' signal."""

    channel: str
    labels: tuple[str, ...]
    exposure_time_s: np.ndarray
    """(n,) float64, s."""
    mean_above_dark_dn: np.ndarray
    """(n,) float64: μ_y − μ_y.dark, DN."""
    variance_above_dark_dn2: np.ndarray
    """(n,) float64: σ²_y − σ²_y.dark, DN²."""
    used_in_gain_fit: np.ndarray
    """(n,) bool: the points the system gain was fitted to."""
    saturation_index: int | None
    """Index of the variance peak (the saturation point); None when the flats do not reach saturation."""
    gain_dn_per_e: float | None
    """Slope of the fitted line through the origin, DN/e⁻."""


@dataclass(frozen=True, eq=False)
class DarkHistogram:
    """Histogram of one channel's averaged dark image and the Gaussian the fit predicts for it."""

    channel: str
    label: str
    """The dark group it shows (the longest exposure of the reference temperature)."""
    bin_edges_dn: np.ndarray
    """(n + 1,) float64, DN; fine bins (σ/4) within ±8σ of the mean, logarithmic beyond."""
    counts: np.ndarray
    """(n,) int64: pixels per bin."""
    mean_dn: float
    sigma_dn: float
    """sqrt(s²_y.dark + σ²_y.dark/L): spatial non-uniformity plus the temporal noise left in the average."""


@dataclass(frozen=True, eq=False)
class NoiseFit:
    """What `fit_noise` found: per-channel and combined figures, defect maps, curves and warnings."""

    cfa: str
    bit_depth: int
    shape_px: tuple[int, int]
    channels: tuple[ChannelNoise, ...]
    combined: ChannelNoise
    """Channel figures combined (inverse-variance weighted means, pixel fractions pooled; see `_combine`);
    for a mono sensor, its one channel."""
    hot_pixel_fraction: Estimate
    hot_pixel_dark_current_e_per_s: Estimate | None
    dead_pixel_fraction: Estimate | None
    hot_pixel_map: np.ndarray
    """(H, W) bool."""
    dead_pixel_map: np.ndarray
    """(H, W) bool."""
    dark_current_doubling_c: Estimate | None
    dark_current_reference_c: float | None
    """Temperature the dark currents hold at (the median measured temperature), °C; None if unknown."""
    linearity_error_pct: Estimate | None
    photon_transfer: tuple[PhotonTransferCurve, ...]
    dark_histograms: tuple[DarkHistogram, ...]
    spectrograms: tuple[Spectrogram, ...]
    """DSNU then PRNU spectrograms of each channel (PRNU only with flats)."""
    shading_correction: str
    """One of `SHADING_CORRECTIONS`: how the PRNU flat was corrected for uneven illumination."""
    dsnu_stack: str
    """Label and frame count of the dark group DSNU1288 comes from."""
    warnings: tuple[str, ...]

    @property
    def notes(self) -> tuple[str, ...]:
        """Where the spatial figures come from and whether illumination shading was corrected, as lines."""
        notes = [f"DSNU1288 from {self.dsnu_stack}"]
        levels: dict[str, list[str]] = {}
        for c in self.channels:
            if c.prnu_stack is not None:
                suffix = f" ({c.channel})" if len(self.channels) > 1 else ""
                levels.setdefault(c.prnu_stack, []).append(f"{c.prnu_level}{suffix}")
        if levels:
            sources = [f"{stack} at {', '.join(where)}" for stack, where in levels.items()]
            notes.append(f"PRNU1288 from {'; '.join(sources)}")
            notes.append(
                {
                    "none": "illumination shading not corrected (EMVA 1288 PRNU1288, as the emva1288 reference "
                    "implementation): a non-uniform light adds to PRNU1288; shading_correction "
                    "(--shading-correction) highpass or polynomial removes it",
                    "highpass": "illumination shading removed by EMVA 1288 4.0's high-pass filter (7×7, 11×11 box "
                    f"and 3×3 binomial low-pass subtracted): it keeps {HIGHPASS_PIXEL_VARIANCE_GAIN:.1%} of a white "
                    f"non-uniformity's variance and {HIGHPASS_LINE_VARIANCE_GAIN:.1%} of a row or column pattern's",
                    "polynomial": f"illumination shading removed by dividing a degree-{SHADING_POLYNOMIAL_ORDER} "
                    "illumination surface out of the flat",
                }[self.shading_correction]
            )
        return tuple(notes)

    def profile_fragment(self) -> dict:
        """The measured figures as a partial camera profile: nested dicts of plain Python numbers.

        Values are rounded to two significant digits of their uncertainty (`camgen.fit.lens.rounded`).
        Only figures the frames gave are present, and only values the profile accepts: the bounds of
        `camgen.config.profile.Sensor` and `Noise` (a doubling temperature > 0, a dark current ≥ 0, a bit
        depth of 8–16, ...), a black level below the white level, and a hot-pixel fraction only with a
        dark current > 0 (the profile needs both; the fraction is left out when that current is not
        known). A figure outside them is left out, so the profile keeps its own value, and `fit_noise`
        says so in `warnings`. ``noise.prnu_pct`` is PRNU1288's pixel part, the white per-pixel gain
        spread the sensor model draws (row and column patterns, which it does not model, and a smooth
        illumination shading fall mostly into the other parts). ``sensor.temperature_c`` is the reference
        temperature, so the profile's dark current at its operating temperature is the one measured. The
        system gain is written whenever one was used (measured, or given), since the figures in electrons
        depend on it.
        """
        return self._fragment()[0]

    def _fragment(self) -> tuple[dict, list[str]]:
        """`profile_fragment`, and a warning for each figure it leaves out because the profile would refuse it."""
        c = self.combined
        refused: list[str] = []

        def measured(estimate: Estimate | None) -> float | None:
            if estimate is None or not math.isfinite(estimate.value):
                return None
            return rounded(estimate.value, estimate.uncertainty)

        def refuse(key: str, value: float, requirement: str) -> None:
            refused.append(
                f"{key} = {value:g} is not written to the profile, which requires {requirement}; it keeps its own value"
            )

        def put(target: dict, model: type[Sensor | Noise], key: str, value: float | None) -> bool:
            if value is None:
                return False
            violated = _schema_violation(model, key, value)
            if violated is not None:
                refuse(f"{'sensor.noise' if model is Noise else 'sensor'}.{key}", value, violated)
                return False
            target[key] = value
            return True

        sensor: dict = {}
        put(sensor, Sensor, "bit_depth", int(self.bit_depth))
        black = measured(c.black_level_dn)
        white = 2**self.bit_depth - 1
        if black is not None and black >= white:
            refuse("sensor.black_level_dn", black, f"< the white level {white} DN")
        else:
            put(sensor, Sensor, "black_level_dn", black)
        put(sensor, Sensor, "conversion_gain_dn_per_e", measured(c.gain_dn_per_e))
        put(sensor, Sensor, "full_well_e", measured(c.full_well_e))
        reference_c = None if self.dark_current_reference_c is None else rounded(self.dark_current_reference_c, 0.01)
        put(sensor, Sensor, "temperature_c", reference_c)
        noise: dict = {}
        put(noise, Noise, "read_noise_e", measured(c.read_noise_e))
        put(noise, Noise, "prnu_pct", measured(c.prnu_pixel_pct))
        put(noise, Noise, "dsnu_e", measured(c.dsnu_e))
        put(noise, Noise, "row_fpn_e", measured(c.row_fpn_e))
        put(noise, Noise, "column_fpn_e", measured(c.column_fpn_e))
        if put(noise, Noise, "dark_current_e_per_s", measured(c.dark_current_e_per_s)):
            put(noise, Noise, "dark_current_reference_c", reference_c)
        put(noise, Noise, "dark_current_doubling_c", measured(self.dark_current_doubling_c))
        fraction = measured(self.hot_pixel_fraction)
        hot_current = measured(self.hot_pixel_dark_current_e_per_s)
        if fraction == 0:
            put(noise, Noise, "hot_pixel_fraction", fraction)
        elif hot_current is not None and hot_current <= 0:
            refuse("sensor.noise.hot_pixel_dark_current_e_per_s", hot_current, "> 0 with hot pixels")
            refused[-1] += " (hot_pixel_fraction is left out with it)"
        elif put(noise, Noise, "hot_pixel_dark_current_e_per_s", hot_current):
            put(noise, Noise, "hot_pixel_fraction", fraction)
        put(noise, Noise, "dead_pixel_fraction", measured(self.dead_pixel_fraction))
        if noise:
            sensor["noise"] = noise
        return {"sensor": sensor}, refused

    def summary_rows(self) -> list[tuple[str, float, float, str]]:
        """(name, value, 1σ uncertainty, unit) of the combined figures, for a table; NaN: no uncertainty.

        The figures that depend on the colour (responsivity, η, μ_p.sat, μ_p.min) are listed per channel
        for a colour sensor."""
        c = self.combined
        at = f" at {self.dark_current_reference_c:g} °C" if self.dark_current_reference_c is not None else ""

        def decibels(ratio: Estimate | None) -> Estimate | None:
            if ratio is None or not ratio.value > 0:
                return None
            return Estimate(20 * math.log10(ratio.value), 20 / math.log(10) * ratio.uncertainty / ratio.value)

        rows = [
            ("black level", c.black_level_dn, "DN"),
            ("temporal dark noise σ_y.dark (t → 0)", c.temporal_dark_noise_dn, "DN"),
            ("read noise", c.read_noise_dn, "DN"),
            ("read noise", c.read_noise_e, "e⁻"),
            ("system gain K", c.gain_dn_per_e, "DN/e⁻"),
            ("DSNU1288 (total)", c.dsnu1288_e, "e⁻"),
            ("DSNU1288 pixel", c.dsnu_e, "e⁻"),
            ("DSNU1288 row", c.row_fpn_e, "e⁻"),
            ("DSNU1288 column", c.column_fpn_e, "e⁻"),
            ("DSNU1288 (total)", c.dsnu1288_dn if c.dsnu1288_e is None else None, "DN"),
            ("DSNU1288 pixel", c.dsnu_dn if c.dsnu_e is None else None, "DN"),
            ("DSNU1288 row", c.row_fpn_dn if c.row_fpn_e is None else None, "DN"),
            ("DSNU1288 column", c.column_fpn_dn if c.column_fpn_e is None else None, "DN"),
            ("PRNU1288 (total)", c.prnu_pct, "%"),
            ("PRNU1288 pixel", c.prnu_pixel_pct, "%"),
            ("PRNU1288 row", c.prnu_row_pct, "%"),
            ("PRNU1288 column", c.prnu_column_pct, "%"),
            ("dark current" + at, c.dark_current_e_per_s, "e⁻/s"),
            ("dark current" + at, c.dark_current_dn_per_s if c.dark_current_e_per_s is None else None, "DN/s"),
            ("dark current from variance" + at, c.dark_current_from_variance_e_per_s, "e⁻/s"),
            ("dark current doubling", self.dark_current_doubling_c, "°C"),
            ("saturation μ_y.sat", c.saturation_dn, "DN"),
            ("saturation capacity μ_e.sat", c.saturation_capacity_e, "e⁻"),
            (f"full well ({c.full_well_source})", c.full_well_e, "e⁻"),
            ("sensitivity threshold μ_e.min", c.sensitivity_threshold_e, "e⁻"),
            ("maximum SNR", decibels(c.snr_max), "dB"),
            ("dynamic range DR", c.dynamic_range, "ratio"),
            ("dynamic range DR", decibels(c.dynamic_range), "dB"),
        ]
        colour = [(f" ({r.channel})", r) for r in self.channels] if len(self.channels) > 1 else [("", c)]
        for suffix, r in colour:
            rows += [
                ("responsivity R" + suffix, r.responsivity_dn_per_photon, "DN/p"),
                ("quantum efficiency η" + suffix, r.quantum_efficiency_pct, "%"),
                ("saturation capacity μ_p.sat" + suffix, r.saturation_photons, "p"),
                ("sensitivity threshold μ_p.min" + suffix, r.sensitivity_threshold_photons, "p"),
            ]
        rows += [
            ("linearity error", self.linearity_error_pct, "%"),
            ("hot pixels", self.hot_pixel_fraction, "fraction"),
            ("hot-pixel dark current" + at, self.hot_pixel_dark_current_e_per_s, "e⁻/s"),
            ("dead pixels", self.dead_pixel_fraction, "fraction"),
        ]
        return [(name, e.value, e.uncertainty, unit) for name, e, unit in rows if e is not None]


_BOUNDS = (("gt", operator.gt, ">"), ("ge", operator.ge, "≥"), ("lt", operator.lt, "<"), ("le", operator.le, "≤"))


def _schema_violation(model: type[Sensor | Noise], key: str, value: float) -> str | None:
    """The bound of the profile field `model.key` (its pydantic constraints) that `value` breaks, as
    text ("> 0"); None when it keeps them all."""
    for constraint in model.model_fields[key].metadata:
        for name, holds, symbol in _BOUNDS:
            limit = getattr(constraint, name, None)
            if limit is not None and not holds(value, limit):
                return f"{symbol} {limit:g}"
    return None
