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
  and pixel parts by the standard's equations (`_spatial_variances`): the pixel part is the white
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

References
----------
.. [1] EMVA Standard 1288, "Standard for Characterization of Image Sensors and Cameras", release 4.0
   Linear, European Machine Vision Association, 2021. Section numbers and equations below refer to it.
.. [2] P. J. Rousseeuw, C. Croux, "Alternatives to the median absolute deviation", JASA 88(424),
   pp. 1273–1283, 1993 (MAD, scaled by 1.4826 to estimate a normal σ).
.. [3] B. P. Welford, "Note on a method for calculating corrected sums of squares and products",
   Technometrics 4(3), pp. 419–420, 1962 (shifted sums for a stable one-pass variance).
.. [4] EMVA 1288 reference implementation, `emva1288` 1.0.2 (release 4.0), https://github.com/EMVA1288/emva1288
   (``process/results.py``: the same spatial variances, responsivity, η, μ_p.min and DR).
"""

from __future__ import annotations

import math
import operator
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np

from camgen.config.profile import Noise, Sensor
from camgen.errors import ConfigError
from camgen.fit.lens import rounded
from camgen.sensor.cfa import CFA_NAMES

QUANTISATION_DN2 = 1.0 / 12.0
"""Variance of the ADC's rounding, DN² (EMVA 1288 eq. 6)."""
DARK_VARIANCE_FLOOR_DN2 = 0.24
"""Below this temporal dark variance, DN², quantisation dominates and σ_y.dark is an upper limit:
EMVA 1288 then sets σ²_y.dark to 0.24 DN² (as the `emva1288` reference implementation does)."""
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
DOUBLING_MIN_SIGNIFICANCE = 2.0
"""The doubling temperature ln 2/b is reported only when the slope b of ln I against T exceeds this many
standard uncertainties (see `_dark_current`)."""
DEAD_RESPONSE_FRACTION = 0.5
"""A pixel is dead when its response is below this fraction of the local median response."""
DEAD_MEDIAN_BLOCK_PX = 16
"""Side of the blocks (channel pixels) whose median is the local response for dead pixels."""
PLATEAU_VARIANCE_FRACTION = 0.05
"""A flat beyond the saturation point whose temporal variance has fallen below this fraction of the
peak has (almost) every pixel clipped in every frame: its mean is the clip level."""
SATURATED_DARK_FRACTION = 0.01
"""A dark group with more than this fraction of pixels at the ADC maximum saw light."""
MAD_TO_SIGMA = 1.4826
"""σ of a normal distribution per median absolute deviation [2]_."""
HOT_PIXEL_MIN_EXCESS_SIGMA = 1.0
"""A hot pixel's extra dark signal at the longest dark exposure must reach this many temporal dark
σ of one frame: a smaller excess never shows above one frame's noise, so modelling it changes nothing."""
SHADING_GRID_BLOCKS = 64
"""The illumination surface is fitted to block means of at most this many blocks along a side."""
SHADING_CORRECTIONS = ("none", "highpass", "polynomial")
"""How the PRNU flat is corrected for uneven illumination (see `fit_noise`): not at all (EMVA's PRNU1288),
the standard's high-pass filter, or a quadratic illumination surface divided out."""
SHADING_POLYNOMIAL_ORDER = 2
"""Total degree of the illumination surface of ``shading_correction="polynomial"``."""
HIGHPASS_BOX_PX = (7, 11)
"""Box filters of the low-pass image that EMVA 1288 4.0's correction for uneven illumination subtracts
(followed by a 3 × 3 binomial filter; mirrored edges)."""
PLANCK_J_S = 6.62607015e-34
SPEED_OF_LIGHT_M_PER_S = 299_792_458.0
CHANNEL_ORDER = ("R", "Gr", "Gb", "B")
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


@dataclass(frozen=True)
class Estimate:
    """A measured figure and its 1σ standard uncertainty, in the same unit (NaN: not known)."""

    value: float
    uncertainty: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "value", float(self.value))
        object.__setattr__(self, "uncertainty", float(self.uncertainty))


class StackStatistics:
    """Per-pixel mean and temporal variance of frames taken at one setting, accumulated frame by frame.

    Shifted sums [3]_: each frame is stored as d = frame − s, with s the first frame (float32), and
    Σd, Σd² are kept in float64, so memory is 20 bytes per pixel whatever the number of frames; for
    integer frames the sums are exact. Each frame's mean per Bayer phase is kept too (EMVA's frame-mean
    correction, see `frame_mean_variance_dn2`).

    Parameters
    ----------
    shape_px : (int, int)
        (H, W) of the frames, px.
    """

    def __init__(self, shape_px: tuple[int, int]):
        height, width = (int(n) for n in shape_px)
        if height < 1 or width < 1:
            raise ConfigError(f"a frame stack needs a shape of at least 1×1 px, got {shape_px}")
        self.shape_px = (height, width)
        self.count = 0
        self.integer_frames = True
        self.maximum_dn = -math.inf
        self._shift = np.zeros(self.shape_px, np.float32)
        self._sum = np.zeros(self.shape_px, np.float64)
        self._sum_sq = np.zeros(self.shape_px, np.float64)
        self._phase_means: list[np.ndarray] = []

    def add(self, frame_dn: np.ndarray) -> None:
        """Add one frame.

        Parameters
        ----------
        frame_dn : (H, W) uint16, other integer, or float array
            Raw values, DN.

        Raises
        ------
        ConfigError
            For a frame of another shape, or one with NaN or infinite values.
        """
        frame = np.asarray(frame_dn)
        if frame.shape != self.shape_px:
            raise ConfigError(
                f"a frame of shape {frame.shape} cannot join a stack of {self.shape_px[0]}×{self.shape_px[1]} "
                "(H×W) frames; keep one sensor mode per folder"
            )
        if frame.dtype.kind == "f":
            if not np.isfinite(frame).all():
                raise ConfigError("a frame holds NaN or infinite values; raw frames must be finite numbers")
            self.integer_frames = self.integer_frames and bool(np.all(frame == np.round(frame)))
        elif frame.dtype.kind not in "ui":
            raise ConfigError(f"frames must be integer or float arrays, got dtype {frame.dtype}")
        if self.count == 0:
            self._shift[...] = frame
        deviation = frame.astype(np.float64)
        deviation -= self._shift
        self._sum += deviation
        deviation *= deviation
        self._sum_sq += deviation
        self.count += 1
        self.maximum_dn = max(self.maximum_dn, float(frame.max()))
        self._phase_means.append(
            np.array([[np.mean(frame[py::2, px::2], dtype=np.float64) for px in (0, 1)] for py in (0, 1)])
        )

    @property
    def mean_dn(self) -> np.ndarray:
        """(H, W) float64: per-pixel mean over the stack, DN."""
        if self.count == 0:
            raise ConfigError("a frame stack without frames has no mean; add frames first")
        return self._shift + self._sum / self.count

    @property
    def temporal_variance_dn2(self) -> np.ndarray:
        """(H, W) float64: per-pixel variance over the stack (ddof = 1), DN².

        With 2 frames A, B this is (A − B)²/2, whose spatial mean is EMVA's frame-difference estimate
        σ²_y = ⟨(y_A − y_B)²⟩/2 before the frame-mean correction; more frames generalise it.
        """
        if self.count < 2:
            raise ConfigError(f"a temporal variance needs at least 2 frames, the stack has {self.count}")
        variance = self._sum_sq - self._sum * self._sum / self.count
        variance /= self.count - 1
        return np.maximum(variance, 0.0, out=variance)

    @property
    def frame_means_dn(self) -> np.ndarray:
        """(count, 2, 2) float64: each frame's spatial mean per Bayer phase (y mod 2, x mod 2), DN."""
        return np.array(self._phase_means).reshape(self.count, 2, 2)

    def frame_mean_variance_dn2(self, phase: tuple[int, int] | None) -> float:
        """Variance (ddof = 1) over the frames of their spatial mean, DN², for one Bayer phase or (None)
        all sites.

        A global offset that changes from frame to frame (black-level drift, light flicker) adds this to
        every pixel's temporal variance; EMVA's σ²_y = ⟨(y_A − y_B − (μ_A − μ_B))²⟩/2 subtracts it
        ((μ_A − μ_B)²/2 for two frames).
        """
        if self.count < 2:
            return 0.0
        means = self.frame_means_dn
        if phase is None:
            height, width = self.shape_px
            counts = np.array(
                [[((height - py + 1) // 2) * ((width - px + 1) // 2) for px in (0, 1)] for py in (0, 1)], float
            )
            series = np.tensordot(means, counts, axes=([1, 2], [0, 1])) / counts.sum()
        else:
            series = means[:, phase[0], phase[1]]
        return float(np.var(series, ddof=1))


@dataclass(frozen=True)
class FrameGroup:
    """Frames of one kind taken at one exposure time and temperature, reduced to their statistics."""

    kind: Literal["dark", "flat"]
    exposure_time_s: float
    temperature_c: float | None
    """Sensor temperature, °C; None when the frames do not record it."""
    stats: StackStatistics
    label: str
    """Names the group in messages and the report (folder, sub-folder or file range)."""
    photons_per_pixel: float | None = None
    """μ_p: mean number of photons reaching a pixel during one exposure of a flat (`photons_per_pixel`
    converts an irradiance); None when not known. Flats with it give the quantum efficiency."""


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
class Spectrogram:
    """Horizontal and vertical spectrograms of one channel (EMVA 1288 4.0 §8.6), as `emva1288` draws them.

    Each row (column) of the mean-free image is Fourier transformed, |FFT|²/N averaged over the rows
    (columns); the mean over all N frequencies is then the image's spatial variance (Parseval), so a flat
    spectrogram is white non-uniformity and peaks or a rise towards low frequencies the non-white part.
    Values are the square root of that power, at 0 … 0.5 cycles per pixel.
    """

    channel: str
    kind: Literal["DSNU", "PRNU"]
    """"DSNU": the averaged dark image, DN; "PRNU": flat minus dark, % of its mean."""
    unit: str
    horizontal_frequency_per_px: np.ndarray
    """(N//2 + 1,) float64, cycles per pixel along a row."""
    horizontal: np.ndarray
    """(N//2 + 1,) float64: sqrt of the mean power of the rows' spectra, `unit`."""
    vertical_frequency_per_px: np.ndarray
    vertical: np.ndarray
    nonuniformity: float
    """DSNU1288 (DN) or PRNU1288 (%): the level a white non-uniformity of that σ would have."""
    temporal: float
    """σ_y.stack of the stack (DN, or % of the signal): the white level of one frame's temporal noise."""


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


# --- channels, regions and small statistics ---------------------------------------------------------


def channel_phases(cfa: str) -> tuple[tuple[str, tuple[int, int] | None], ...]:
    """The channels of a CFA and the Bayer phase (y mod 2, x mod 2) each samples.

    Parameters
    ----------
    cfa : {"RGGB", "BGGR", "GRBG", "GBRG", "mono"}

    Returns
    -------
    tuple of (name, phase)
        ``(("mono", None),)`` for a mono sensor; otherwise R, Gr, Gb, B in that order, Gr being the green
        that shares its rows with red. Example: "GRBG" → R (0, 1), Gr (0, 0), Gb (1, 1), B (1, 0).
    """
    if cfa == "mono":
        return (("mono", None),)
    phases = {}
    for index, colour in enumerate(cfa):
        py, px = divmod(index, 2)
        if colour == "G":
            colour = "Gr" if cfa[2 * py + 1 - px] == "R" else "Gb"
        phases[colour] = (py, px)
    return tuple((name, phases[name]) for name in CHANNEL_ORDER)


def _plane(image: np.ndarray, phase: tuple[int, int] | None) -> np.ndarray:
    """The sites of one Bayer phase as an image (a view), or the whole image for mono."""
    return image if phase is None else image[phase[0] :: 2, phase[1] :: 2]


Region = tuple[slice, slice]


def _grid_regions(height: int, width: int, rows: int, columns: int) -> list[Region]:
    """`rows` × `columns` rectangles tiling an image, row-major."""
    y = np.linspace(0, height, rows + 1).round().astype(int)
    x = np.linspace(0, width, columns + 1).round().astype(int)
    return [(slice(y[i], y[i + 1]), slice(x[j], x[j + 1])) for i in range(rows) for j in range(columns)]


def _regions(shape: tuple[int, int], tiles: int) -> list[Region]:
    """The whole image, then its tiles × tiles tiles (at least 3 px a side: `_check_input`)."""
    height, width = shape
    return [(slice(0, height), slice(0, width)), *_grid_regions(height, width, tiles, tiles)]


def _estimate(values: np.ndarray) -> Estimate:
    """The whole-image value (entry 0) and the standard error of the part estimates (the rest)."""
    values = np.asarray(values, np.float64)
    parts = values[1:][np.isfinite(values[1:])]
    uncertainty = float(np.std(parts, ddof=1) / math.sqrt(parts.size)) if parts.size >= 2 else math.nan
    return Estimate(values[0], uncertainty)


def _sigma_estimate(variance: Estimate) -> Estimate:
    """σ = sqrt(s²) from a variance estimate: u(σ) = u(s²)/(2σ), at most sqrt(u(s²)) (the σ at which
    first-order propagation breaks down); σ = 0 for a variance that came out negative."""
    sigma = math.sqrt(max(variance.value, 0.0))
    u = variance.uncertainty
    if not math.isfinite(u):
        return Estimate(sigma, math.nan)
    cap = math.sqrt(max(u, 0.0))
    return Estimate(sigma, min(u / (2 * sigma), cap) if sigma > 0 else cap)


def _per_gain(estimate: Estimate | None, gain: Estimate | None) -> Estimate | None:
    """A figure in DN converted to electrons, estimate/K, with first-order propagation of both relative
    uncertainties (u/|v|)² = (u_x/x)² + (u_K/K)²."""
    if estimate is None or gain is None:
        return None
    value = estimate.value / gain.value
    if estimate.value == 0:
        return Estimate(0.0, estimate.uncertainty / gain.value)
    relative = math.hypot(estimate.uncertainty / estimate.value, gain.uncertainty / gain.value)
    return Estimate(value, abs(value) * relative)


def _masked_means(image: np.ndarray, valid: np.ndarray, regions: list[Region]) -> np.ndarray:
    """(R,) mean of the valid pixels of each region (NaN where a region has none)."""
    out = np.empty(len(regions))
    for r, (ys, xs) in enumerate(regions):
        mask = valid[ys, xs]
        n = np.count_nonzero(mask)
        out[r] = np.sum(image[ys, xs], where=mask) / n if n else math.nan
    return out


def _masked_variances(image: np.ndarray, valid: np.ndarray, regions: list[Region]) -> np.ndarray:
    """(R,) variance (ddof = 1) of the valid pixels of each region."""
    out = np.empty(len(regions))
    for r, (ys, xs) in enumerate(regions):
        values = image[ys, xs][valid[ys, xs]]
        out[r] = np.var(values, ddof=1) if values.size > 1 else math.nan
    return out


def _line_fit(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ordinary least-squares line y = a + b·x through (x_i, y_i), for every column of `y`.

    Parameters
    ----------
    x : (n,) float
    y : (n, ...) float

    Returns
    -------
    slope, intercept : (...) float64
        With a single distinct x the slope is 0 and the intercept the mean of y.
    """
    x = np.asarray(x, np.float64)
    y = np.asarray(y, np.float64)
    dx = x - x.mean()
    sxx = float(dx @ dx)
    y_mean = y.mean(axis=0)
    if sxx == 0:
        return np.zeros_like(y_mean), y_mean
    slope = np.tensordot(dx, y - y_mean, axes=(0, 0)) / sxx
    return slope, y_mean - slope * x.mean()


def _at_exposure(times_s: np.ndarray, values: np.ndarray, exposure_time_s: float) -> np.ndarray:
    """Dark values at `exposure_time_s`: the groups taken at that time if any (EMVA's pairing of a dark
    with each bright measurement), else the least-squares line through all of them (linear in t)."""
    times_s = np.asarray(times_s, np.float64)
    same = np.isclose(times_s, exposure_time_s, rtol=1e-6, atol=1e-12)
    if same.any():
        return values[same].mean(axis=0)
    slope, intercept = _line_fit(times_s, values)
    return intercept + slope * exposure_time_s


def _robust_sigma(values: np.ndarray) -> tuple[float, float]:
    """Median and MAD-based σ (1.4826·MAD) [2]_."""
    median = float(np.median(values))
    return median, MAD_TO_SIGMA * float(np.median(np.abs(values - median)))


def _median_estimate(values: np.ndarray, relative_scale_uncertainty: float) -> Estimate:
    """Median and its standard error, 1.2533·σ/√n (σ robust; NaN for one value), combined with a
    relative uncertainty of a scale factor applied to every value."""
    median, spread = _robust_sigma(values)
    u = 1.2533 * spread / math.sqrt(values.size) if values.size >= 2 else math.nan
    return Estimate(median, math.hypot(u, median * relative_scale_uncertainty))


def _weighted_mean(estimates: Sequence[Estimate]) -> Estimate:
    """Inverse-variance weighted mean; the plain mean (uncertainty sqrt(Σu²)/n) when some uncertainty
    is zero or unknown."""
    values = np.array([e.value for e in estimates])
    u = np.array([e.uncertainty for e in estimates])
    if np.all(np.isfinite(u)) and np.all(u > 0):
        weights = 1.0 / u**2
        return Estimate(float(weights @ values / weights.sum()), float(1.0 / math.sqrt(weights.sum())))
    return Estimate(float(values.mean()), float(math.sqrt(np.sum(u**2)) / len(u)))


# --- input checks and grouping ---------------------------------------------------------------------


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


# --- per-pixel work ---------------------------------------------------------------------------------


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


def _block_median(image: np.ndarray, block: int) -> np.ndarray:
    """Each pixel's local median: the median of its `block` × `block` block, repeated over the block."""
    height, width = image.shape
    hb, wb = -(-height // block), -(-width // block)
    padded = np.full((hb * block, wb * block), np.nan)
    padded[:height, :width] = image
    medians = np.nanmedian(padded.reshape(hb, block, wb, block), axis=(1, 3))
    return np.repeat(np.repeat(medians, block, axis=0), block, axis=1)[:height, :width]


def _shading_surface(signal: np.ndarray, valid: np.ndarray, order: int) -> np.ndarray | None:
    """Relative illumination: a 2-D polynomial of total degree `order` fitted by least squares to block
    means of `signal` (valid pixels only), normalised to mean 1 over the valid pixels. None when the
    signal is not positive."""
    height, width = signal.shape
    block = max(1, -(-max(height, width) // SHADING_GRID_BLOCKS))
    hb, wb = -(-height // block), -(-width // block)
    sums = np.zeros((hb * block, wb * block))
    counts = np.zeros_like(sums)
    sums[:height, :width] = np.where(valid, signal, 0.0)
    counts[:height, :width] = valid
    sums = sums.reshape(hb, block, wb, block).sum(axis=(1, 3))
    counts = counts.reshape(hb, block, wb, block).sum(axis=(1, 3))
    yc = (np.arange(hb) * block + (block - 1) / 2) / max(height - 1, 1) * 2 - 1
    xc = (np.arange(wb) * block + (block - 1) / 2) / max(width - 1, 1) * 2 - 1
    powers = [(i, j) for i in range(order + 1) for j in range(order + 1 - i)]
    ok = counts > 0
    if np.count_nonzero(ok) < len(powers):
        return None
    yy, xx = np.meshgrid(yc, xc, indexing="ij")
    design = np.stack([xx[ok] ** i * yy[ok] ** j for i, j in powers], axis=1)
    weight = np.sqrt(counts[ok])
    coefficients = np.linalg.lstsq(design * weight[:, None], sums[ok] / counts[ok] * weight, rcond=None)[0]
    y = np.arange(height) / max(height - 1, 1) * 2 - 1
    x = np.arange(width) / max(width - 1, 1) * 2 - 1
    surface = sum(c * np.outer(y**j, x**i) for c, (i, j) in zip(coefficients, powers, strict=True))
    level = float(np.mean(surface[valid]))
    if not level > 0 or np.any(surface <= 0):
        return None
    return surface / level


def _lowpass_kernel_1d() -> np.ndarray:
    """The standard's low-pass filter for uneven illumination along one axis: a 3-tap binomial
    [1, 2, 1]/4 convolved with boxes of `HIGHPASS_BOX_PX` (19 taps; the 2-D filter is its outer product)."""
    kernel = np.array([0.25, 0.5, 0.25])
    for size in HIGHPASS_BOX_PX:
        kernel = np.convolve(kernel, np.full(size, 1.0 / size))
    return kernel


def _highpass_variance_gains() -> tuple[float, float]:
    """Fractions of a white non-uniformity's variance, and of a white row (or column) pattern's, that
    the high-pass filter y − R⊛y keeps: Σ(δ − R)² for the 2-D and the 1-D kernel (away from the edges)."""
    low = _lowpass_kernel_1d()
    unit = np.zeros_like(low)
    unit[low.size // 2] = 1.0
    pixel = float(np.sum((np.outer(unit, unit) - np.outer(low, low)) ** 2))
    return pixel, float(np.sum((unit - low) ** 2))


HIGHPASS_PIXEL_VARIANCE_GAIN, HIGHPASS_LINE_VARIANCE_GAIN = _highpass_variance_gains()
"""0.988 and 0.889: what the standard's high-pass filter keeps of a white pixel, and of a row or column,
non-uniformity's variance. The temporal noise, white too, keeps the pixel fraction."""


def highpass_filtered(image: np.ndarray) -> np.ndarray:
    """EMVA 1288 4.0's correction for uneven illumination: the image less its low-pass version, which
    is the image smoothed by 7 × 7 and 11 × 11 box filters and a 3 × 3 binomial filter (edges mirrored).

    Parameters
    ----------
    image : (M, N) float array
        One channel's averaged image, DN.

    Returns
    -------
    (M, N) float64
        y − R⊛y, DN (mean ≈ 0): variations slower than about 20 px are gone, white non-uniformity keeps
        `HIGHPASS_PIXEL_VARIANCE_GAIN` of its variance.
    """
    from scipy.ndimage import convolve, uniform_filter

    image = np.asarray(image, np.float64)
    low = image
    for size in HIGHPASS_BOX_PX:
        low = uniform_filter(low, size=size, mode="reflect")
    binomial = np.outer([0.25, 0.5, 0.25], [0.25, 0.5, 0.25])
    return image - convolve(low, binomial, mode="reflect")


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


def _variance_parts(image: np.ndarray, residual_dn2: float) -> np.ndarray:
    """Spatial variances of an averaged image, [total, pixel, row, column], DN² (EMVA 1288 4.0 §8).

    With M rows, N columns and σ²_y.stack/L the temporal variance left in an L-frame mean
    (`residual_dn2`), as the standard and `emva1288` compute them:

        s²_y     = var(image, ddof = 1) − σ²_y.stack/L
        s²_y.cav = var(column means) − σ²_y.stack/(L·M)       s²_y.rav = var(row means) − σ²_y.stack/(L·N)
        s²_y.pixel = M·N/(M·N − M − N)·(s²_y − s²_y.cav − s²_y.rav)
        s²_y.col = s²_y.cav − s²_y.pixel/M                      s²_y.row = s²_y.rav − s²_y.pixel/N

    (the variances of the row and column means with ddof = 0). s²_y is EMVA's s²_y.dark (DSNU1288) or
    s²_y.50 (PRNU1288); the pixel part is the white non-uniformity, the row and column parts the
    non-white one. NaN for fewer than 3 rows or columns (M·N − M − N ≤ 0 has no split).
    """
    rows, columns = image.shape
    if rows < 3 or columns < 3:
        return np.full(4, math.nan)
    total = float(np.var(image, ddof=1)) - residual_dn2
    column_average = float(np.var(image.mean(axis=0))) - residual_dn2 / rows
    row_average = float(np.var(image.mean(axis=1))) - residual_dn2 / columns
    pixel = rows * columns / (rows * columns - rows - columns) * (total - column_average - row_average)
    return np.array([total, pixel, row_average - pixel / columns, column_average - pixel / rows])


@dataclass(frozen=True)
class _SpatialVariances:
    """`_variance_parts` of a channel image: of the whole image and each tile, and the row (column) part
    of each horizontal (vertical) band, where the tiles would share their row and column offsets."""

    tiles: np.ndarray
    """(R, 4) [total, pixel, row, column] of the whole channel (row 0) and of each tile."""
    row_bands: np.ndarray
    """(B,) the row part of each horizontal band."""
    column_bands: np.ndarray
    """(B,) the column part of each vertical band."""

    def __sub__(self, other: _SpatialVariances) -> _SpatialVariances:
        return _SpatialVariances(
            self.tiles - other.tiles, self.row_bands - other.row_bands, self.column_bands - other.column_bands
        )

    def scaled(self, per_region: np.ndarray) -> _SpatialVariances:
        """Each tile multiplied by its factor (R,), the bands by the whole image's (entry 0)."""
        return _SpatialVariances(
            self.tiles * per_region[:, None], self.row_bands * per_region[0], self.column_bands * per_region[0]
        )

    def estimates(self) -> tuple[Estimate, Estimate, Estimate, Estimate]:
        """Total, pixel, row and column variances with their uncertainties: the pixel part's from the
        tiles, the row (column) part's from the horizontal (vertical) bands. Tiles in one band share its
        row offsets, so their scatter misses most of the row and column parts' sampling error in the
        total: its uncertainty adds the three."""
        pixel = _estimate(self.tiles[:, 1])
        row = _estimate(np.concatenate([[self.tiles[0, 2]], self.row_bands]))
        column = _estimate(np.concatenate([[self.tiles[0, 3]], self.column_bands]))
        total = Estimate(self.tiles[0, 0], math.sqrt(pixel.uncertainty**2 + row.uncertainty**2 + column.uncertainty**2))
        return total, pixel, row, column


def _spatial_variances(image: np.ndarray, residual_dn2: np.ndarray, regions: list[Region]) -> _SpatialVariances:
    """`_SpatialVariances` of a channel image; `residual_dn2` (R,) is σ²_y.stack/L over each region."""
    height, width = image.shape
    tiles = np.array([_variance_parts(image[ys, xs], residual_dn2[r]) for r, (ys, xs) in enumerate(regions)])
    row_bands = _grid_regions(height, width, max(2, min(16, height // 8)), 1)
    column_bands = _grid_regions(height, width, 1, max(2, min(16, width // 8)))
    return _SpatialVariances(
        tiles,
        np.array([_variance_parts(image[band], residual_dn2[0])[2] for band in row_bands]),
        np.array([_variance_parts(image[band], residual_dn2[0])[3] for band in column_bands]),
    )


def _spectrum(image: np.ndarray, axis: int) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies (cycles per pixel) and sqrt of the mean power of the mean-free image's spectra along
    `axis` (1: each row, horizontal; 0: each column, vertical), normalised by the length (Parseval)."""
    length = image.shape[axis]
    spectra = np.fft.rfft(image - image.mean(), axis=axis)
    power = np.mean(np.abs(spectra) ** 2, axis=1 - axis) / length
    return np.fft.rfftfreq(length), np.sqrt(power)


def _spectrogram(channel: str, kind: str, image: np.ndarray, scale: float, nonuniformity: float, temporal: float):
    """A `Spectrogram` of `image` multiplied by `scale` (1 for DN, 100/signal for %)."""
    horizontal_frequency, horizontal = _spectrum(image, 1)
    vertical_frequency, vertical = _spectrum(image, 0)
    return Spectrogram(
        channel=channel,
        kind=kind,
        unit="DN" if kind == "DSNU" else "%",
        horizontal_frequency_per_px=horizontal_frequency,
        horizontal=horizontal * scale,
        vertical_frequency_per_px=vertical_frequency,
        vertical=vertical * scale,
        nonuniformity=nonuniformity,
        temporal=temporal,
    )


def _filled(image: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """A copy of a channel image with its invalid (hot, dead) pixels set to the median of the valid ones
    of their `DEAD_MEDIAN_BLOCK_PX` block (the local level, which a shaded flat needs), so that they add
    next to nothing to the spatial variances."""
    out = np.array(image, np.float64)
    if not valid.all():
        local = _block_median(np.where(valid, out, np.nan), DEAD_MEDIAN_BLOCK_PX)
        out[~valid] = np.where(np.isfinite(local), local, np.median(out[valid]))[~valid]
    return out


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


# --- the fit ----------------------------------------------------------------------------------------


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

    def photon_transfer(self, c: int) -> _PhotonTransfer:
        return _photon_transfer(self.flats, self.flat_mean, self.flat_variance, self.darks, self.flat_sets, c)


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


def _dead_pixels(response_dn: np.ndarray, hot: np.ndarray) -> np.ndarray:
    """Pixels whose response (flat − dark) is below `DEAD_RESPONSE_FRACTION` of their block's median."""
    local = _block_median(np.where(hot, np.nan, response_dn), DEAD_MEDIAN_BLOCK_PX)
    return response_dn < DEAD_RESPONSE_FRACTION * local


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
class _ChannelFit:
    noise: ChannelNoise
    curve: PhotonTransferCurve | None
    histogram: DarkHistogram
    spectrograms: tuple[Spectrogram, ...]
    hot_rates_e: tuple[np.ndarray, float] | None
    """The hot pixels' dark currents at the reference temperature, e⁻/s, and their relative scale
    uncertainty (gain and temperature scaling)."""


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
    transfer = ctx.photon_transfer(c)
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
