"""Fit a profile's noise to a camera's ordinary 8-bit output: the noise level function, matched.

For a camera whose raw frames are not available, the noise of its processed output is still visible:
the *noise level function* (NLF), the noise variance of the 8-bit output against its mean intensity,
per channel (Liu et al. 2006). `fit_match` measures it on the reference, then adjusts the profile's
noise parameters until camgen's own output, processed by the profile's ISP and measured by the *same*
estimator, shows the same NLF.

Estimating the NLF (`nlf_from_frames`)
--------------------------------------
*Temporal* (a static camera, several frames of one view). For each pixel and channel the variance is
the mean square successive difference (von Neumann 1941)

    s² = Σ_t (x_{t+1} − x_t)² / (2n),     n successive pairs,

which a slow drift of δ codes per frame biases by only δ²/2 (a global step between two frames, from a
light or exposure change, is caught and that pair left out). Pixels are binned by their temporal mean.
A moving object gives a pixel a huge s²: pixels where the 16 × 16-px box mean of the luma changed by
more than `MOTION_THRESHOLD_CODES` between two frames are rejected first (the box mean averages the
noise away, so this test hardly depends on a pixel's own noise), and within each bin the remaining
variances are sigma-clipped: s²/σ² is close to χ²_ν/ν with the Satterthwaite degrees of freedom
ν = 2n²/(3n − 1) of overlapping differences, so pixels above the 99.9 % point of that distribution
(around the bin's level) are dropped, and the mean of those kept is divided by the known mean of a
χ² truncated at that point,

    E[X | X ≤ u]/E[X] = F_{ν+2}(uν) / F_ν(uν)          (X ~ χ²_ν/ν, F the χ² CDF),

iterated to a fixed point. This runs for each 2 × 2 phase of the pixel grid apart, the phases then
weighted by their counts: demosaicing interpolates a colour from 1, 2 or 4 sites by CFA phase, so the
noise of one bin is a mixture (up to 4:1 without denoise), and a χ² cut on the mixture rejects the
noisier phase by an amount that depends on ν (green of a bilinear camera measured −44 % at 48 frames
against 32). A mean, not a median: 8-bit samples make s² discrete (often 0 when σ is below a code),
and a median of discrete values has no usable correction, whereas the mean of the differences is
unbiased for any distribution of noise that is independent from frame to frame and the cut removes
about 0.1 % of the genuine samples (a correction of a fraction of a percent, so the χ² approximation
there costs nothing measurable).
Noise correlated between successive frames by ρ₁ (temporal noise reduction in the camera, a codec's
inter-frame prediction) gives E[s²] = σ²(1 − ρ₁), biased low; the plain per-pixel temporal variance of
the same static pixels is accumulated as well, and their ratio (`NoiseLevelFunction.difference_to_plain_ratio`)
below `TEMPORAL_CORRELATION_RATIO_MIN` earns `fit_match` a warning.

*Spatial* (images, or a moving camera). Each channel is cut into 8 × 8 blocks; a plane fitted to a
block by least squares is removed and the residual variance (61 degrees of freedom) is that block's
sample. Per intensity bin, the level starts as the mean of the lower half of the block variances
divided by the mean of the lower half of χ²_61/61 (the lower envelope of Liu et al. 2006/2008), then
blocks above its 99 % point are rejected as texture or edges and the level is re-estimated with the
truncation correction above, to a fixed point. Noise that the ISP has correlated between neighbours
(demosaicing, denoise, sharpening, a codec) shows a smaller residual inside a block and spreads wider
than χ²_61, so on processed output the spatial level lies below the pixel variance (0.55–0.95 of the
temporal one for `profiles/bullet_4mp_2p8mm.yaml`); the fit is unaffected, as camgen's side is measured
the same way.

In both, a pixel (block) whose samples touch 0 or 255 is left out, and a bin where more than
`CLIPPED_BIN_FRAC_MAX` of the samples that pass as noise touch them is not reported: there, leaving
them out would select the samples whose noise happened to stay inside, which biases the level low.

Fitting (`fit_match`)
---------------------
Camgen's side is a simulation whose *content* is the reference's own: the temporal-mean frame (spatial:
the first frame with each 8 × 8 block replaced by its fitted plane, which removes the noise) is
downscaled to at most `simulation_max_px` pixels (INTER_AREA keeps its histogram, so the adaptive
contrast stretch sees what the camera saw) and inverted through the profile's output range, tone curve
and CCM to linear camera RGB. Per CFA site the sensor collects electrons ∝ that RGB × the colour of the
light × the QE of the site's colour (with fixed white-balance gains: ∝ RGB / gains), scaled so that
auto-exposure has converged (the metered mean at `exposure.auto.target_level_frac`, as
`CameraPipeline.converge_exposure` does) or, for a manual profile, so that the output range spans the
raw range; a colour the camera clipped after white balance is put beyond the clip (`_site_levels`).
`SensorModel.capture` and `CameraIsp.process` (the stages the plan would keep) run frame by frame with
one seed, without the fixed patterns when the content is a temporal mean (it already shows them), then
through the reference's codec when one is given, and the same estimator with the same bins measures
the NLF.

The parameters, in log space relative to the start:

- ``sensor.full_well_e``, with ``sensor.conversion_gain_dn_per_e`` scaled by its inverse so that the
  raw DN of the content stay the same (only the electrons per output code, the shot-noise scale, move);
- ``sensor.noise.read_noise_e``;
- optionally ``isp.denoise_strength`` (``fit_denoise``), in [0, 1]; then the NLF of the frames averaged
  over 2 × 2 pixels joins the objective, as denoise trades against the full well in the NLF but also
  correlates the noise of neighbours;
- with grey-world white balance, the light's R/G and B/G: the output hides the light's colour, but the
  balance gains, and with them the noise of R and B against G, follow it (a warm light gives a noisier
  blue channel). A nuisance parameter of the scene, reported as `MatchFit.light_rgb`, not in the profile.

A first guess takes the start's misfit as if shot noise ruled (output variance ∝ 1/full well, and R, B
against G ∝ G/R, G/B of the light); `scipy.optimize.least_squares` (trust region, soft-L1 loss) then
minimises log(NLF_camgen / NLF_reference) over the channel-bins both measure, with forward differences
of 2 % steps. Every evaluation reuses one seed (common random numbers), so the objective is
deterministic and smooth at that scale. 35–55 simulations of 64 frames.

Limits: the analog gain the reference was taken at is invisible in its output, so the fit assumes
`gain_db` (default the profile's exposure gain, 0 dB for daylight), and a fitted full well is the
*effective* electrons per output range at that gain. Without `codec`, a codec's effect on the
reference's noise (its rounding through YUV adds, its quantisation removes) is folded into the fitted
parameters: an H.264 stream at crf 0 in 4:4:4 measured +9–16 % variance over its PNG frames, a nearly
constant 0.2 code² that no sensor parameter mimics. Read noise is determined only as far as it shows
against shot noise in the darkest bins (`MatchFit.uncertainties`; a warning when one is unconstrained).
With a contrast stretch, the content is undone through it as if its low limit were black, and nothing
in the output says otherwise (the stretch sends the scene's darkest point to its output low either way):
a scene whose darkest point is not black adds that point's shot noise, a constant variance in the
output that read noise gives as well. The NLF is then matched with the wrong parameters (darkest point
at 30 % of the peak: NLF within 4.4 %, full well −56 %, read noise ×5.4), so a fit whose read noise
makes most of the variance at its darkest compared bin warns that read noise and full well are not
separable from that footage: include true black (a shadow, a dark object) in the view. The contrast
stretch's output range is taken from where the output piles up at its extremes and its percentiles are
only bounded (`estimate_tone`); the tone curve stays the base profile's: in a single camera's output its
shape is confounded with the scene's own distribution of intensities. A colour cast strong enough to
clip one channel at the stretch's top shifts the simulated stretch by a few percent, which the full well
takes up. The spatial method, on a few images, gives a rough fit (bins scatter by ±10 %): prefer frames
of a static view.

References
----------
C. Liu, W. T. Freeman, R. Szeliski and S. B. Kang, "Noise estimation from a single image", CVPR 2006;
C. Liu, R. Szeliski, S. B. Kang, C. L. Zitnick and W. T. Freeman, "Automatic estimation and removal of
noise from a single image", IEEE TPAMI 30(2), 299–314 (2008).
J. von Neumann, "Distribution of the ratio of the mean square successive difference to the variance",
Ann. Math. Statist. 12(4), 367–395 (1941).
F. E. Satterthwaite, "An approximate distribution of estimates of variance components", Biometrics
Bulletin 2(6), 110–114 (1946).
"""

from __future__ import annotations

import math
import tempfile
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Literal

import av
import cv2
import numpy as np
from scipy import optimize, special

from camgen.config.profile import Codec, Isp, Profile
from camgen.errors import ConfigError
from camgen.io.video import VideoWriter, decoded_rgb8
from camgen.isp.pipeline import CameraIsp
from camgen.isp.tone import tone_curve
from camgen.plan.compile import isp_steps
from camgen.sensor.auto_exposure import metering_window
from camgen.sensor.capture import NOISE_TERMS, SensorModel
from camgen.sensor.cfa import cfa_site_values, mosaic
from camgen.sensor.characteristics import saturation_e
from camgen.sensor.exposure import gain_linear


class ReferenceContentError(ConfigError):
    """The reference cannot be fitted because of what it shows (no frames, no noise, too few unclipped
    samples): the caller, who knows its files, names them."""


DEFAULT_BINS = 32
"""Intensity bins over 0…256 (8 codes each)."""
MIN_COUNT = MappingProxyType({"temporal": 200, "spatial": 24})
"""Default fewest samples (pixels; blocks) a bin needs for its variance."""
MOTION_BOX_PX = 16
"""Side of the box mean of the luma that the motion test compares between frames, px."""
MOTION_THRESHOLD_CODES = 3.0
"""A change of the box-mean luma above this between two frames marks motion, 8-bit codes (noise of
σ = 10 codes moves a 16 × 16 box mean by 0.9 codes rms)."""
STATIC_FRACTION_MIN = 0.5
"""`method="auto"` takes the temporal method only if at least this fraction of the pixels is static."""
TEMPORAL_FRAMES_MIN = 8
"""`method="auto"` takes the temporal method from this many frames of one size."""
BLOCK_PX = 8
"""Side of the blocks of the spatial method, px."""
SPATIAL_FRAMES_MAX = 64
"""The spatial method reads blocks from at most this many frames."""
TEMPORAL_REJECTION = MappingProxyType({"start_fraction": 0.9, "clip_quantile": 0.999})
"""The temporal level starts from the lowest 90 % of the pixel variances (a trimmed mean); a pixel is an
outlier above the 99.9 % point of χ²_ν/ν times the level. Each 2 × 2 phase of the pixel grid is
estimated on its own (`_temporal_nlf`)."""
SPATIAL_REJECTION = MappingProxyType({"start_fraction": 0.5, "clip_quantile": 0.99})
"""The spatial level starts from the lowest half of the block variances (the lower envelope); a block
is texture above the 99 % point of χ²_61/61 times the level (every block holds every CFA phase)."""
CLIPPED_BIN_FRAC_MAX = 0.05
"""A bin is reported only if at most this fraction of its noise-like samples touches 0 or 255."""
CLIP_FLOOR_CODE2 = 1.0
"""The rejection threshold is never below this, 8-bit codes²: a pixel or block that varies by less is
not an outlier, and very clean output (s² mostly 0) would otherwise reject all but the zeros."""
PILE_UP_MIN_FRAC = 2e-4
"""A clip at an output extreme must hold at least this fraction of the samples …"""
PILE_UP_RATIO = 2.0
"""… and this many times the count of the next code inwards …"""
PILE_UP_OUTSIDE_FRAC = 5e-3
"""… with at most this fraction of the samples beyond it (sharpening overshoots past a clip)."""
CLIP_KNEE = 0.98
"""Content within this fraction of the white-balance clip counts as clipped (`_site_levels`)."""
CLIP_OVERSHOOT = 1.25
"""Clipped content is placed this far beyond the clip, well beyond its noise."""
TEMPORAL_NOISE_TERMS = frozenset({"shot", "dark_current", "read", "blooming"})
"""The sensor model's terms that vary from frame to frame (or act on the signal in a frame)."""
SIGNIFICANT_DIGITS = 4
"""Fitted values are rounded to this many significant digits."""
SIMULATION_FRAMES = 64
"""Frames the simulation runs for the temporal method."""
SIMULATION_FRAMES_SPATIAL = 16
"""Frames the simulation runs for the spatial method (their blocks are pooled)."""
READ_NOISE_BOUNDS_E = (0.01, 500.0)
"""Range of the fitted read noise, e⁻."""
LIGHT_RATIO_MAX = 4.0
"""The fitted light's R/G and B/G lie within [1/4, 4]."""
DENOISE_START_MIN = 0.2
"""`fit_denoise` starts the strength at least here."""
WORST_BIN_WARNING = 0.1
"""A fit whose NLF misses a bin by more than this fraction gets a warning."""
FULL_WELL_SCALE_BOUNDS = (1 / 50, 50.0)
"""Range of the fitted full well relative to the start."""
FIT_COST_TOLERANCE = 1e-2
"""Relative decrease of the cost below which the fit stops."""
FIT_STEP_TOLERANCE = 1e-3
"""Relative step of the parameters below which the fit stops (a looser one stopped a fit whose trust
region had shrunk on the objective's jitter while the cost still fell by 4 % a step)."""
TEMPORAL_CORRELATION_RATIO_MIN = 0.85
"""A temporal reference whose successive-difference variance falls below this fraction of its plain
temporal variance gets a warning (noise correlated between frames). For frame-independent noise both
estimate σ² with ≥ 1000 degrees of freedom even at the fewest data the estimate accepts (200 pixels of
8 frames), so their ratio scatters by ≤ 6 % there (0.998 measured on 8 frames of 320 × 240 px): 0.85 is
2.5σ below 1 in the worst case and far more in practice, while noise correlated by ρ₁ = 0.6 between
frames gives 0.57 on 8 frames and 0.42 on 64. A drift of δ codes per frame over T frames lifts the plain
variance by δ²(T² − 1)/12 (0.85 code² at 0.1 code per frame over 32 frames), which lowers the ratio too."""
UNCONSTRAINED_SIGMA = 0.5
"""A fitted value whose 1σ uncertainty exceeds this fraction of it (denoise strength: this much in
absolute terms) is reported as unconstrained by the reference."""
PEDESTAL_READ_SHARE = 0.5
"""With a contrast stretch, a fit whose read noise makes more than this share of the variance at the
darkest compared bin gets a warning: that constant term is what a stretch low limit above black (a
scene without black) produces as well (module docstring)."""
DIFF_STEP = 0.02
"""Finite-difference step of the fit, in log parameter units (2 %; denoise strength: 0.02): far above
the jitter that 8-bit rounding gives the objective."""


@dataclass(frozen=True)
class NoiseLevelFunction:
    """Noise variance of 8-bit output against its mean intensity, per channel R, G, B.

    Attributes
    ----------
    bin_edges : (B + 1,) float64
        Intensity bins, 8-bit codes; a sample of mean m falls in bin b when edges[b] ≤ m < edges[b + 1].
    mean : (3, B) float64
        Mean intensity of the samples used in each bin, codes; NaN where the variance is NaN.
    variance : (3, B) float64
        Noise variance, codes²; NaN where a bin has fewer samples than the estimator's `min_count`, or
        too many of them clip (module docstring).
    count : (3, B) int64
        Samples (temporal: pixels; spatial: 8 × 8 blocks) behind each variance, or the candidates of a
        bin with too few.
    method : {"temporal", "spatial"}
    frames : int
        Frames the estimate read.
    static_fraction : float
        Temporal: fraction of the pixels free of motion; spatial: NaN.
    difference_to_plain_ratio : float
        Temporal: Σ s² (successive differences) / Σ plain temporal variance over the static, unclipped
        pixels; 1 for noise independent from frame to frame, 1 − ρ₁ for noise whose successive frames
        correlate by ρ₁ (temporal noise reduction, a codec), where the NLF is biased low by that factor.
        NaN for the spatial method, or when a pair of frames was left out (a light step lifts the plain
        variance).
    """

    bin_edges: np.ndarray
    mean: np.ndarray
    variance: np.ndarray
    count: np.ndarray
    method: Literal["temporal", "spatial"]
    frames: int
    static_fraction: float = math.nan
    difference_to_plain_ratio: float = math.nan

    @property
    def usable(self) -> np.ndarray:
        """(3, B) bool: channel-bins with a finite variance."""
        return np.isfinite(self.variance)

    @property
    def bin_centres(self) -> np.ndarray:
        """(B,) float64, codes."""
        return 0.5 * (self.bin_edges[:-1] + self.bin_edges[1:])


def _check_frame(index: int, frame: object) -> np.ndarray:
    if not isinstance(frame, np.ndarray):
        raise ConfigError(f"reference frame {index} is a {type(frame).__name__}, not an (H, W, 3) uint8 image array")
    if frame.dtype != np.uint8:
        raise ConfigError(
            f"reference frame {index} holds {frame.dtype} samples; `fit match` reads a camera's 8-bit output as "
            "(H, W, 3) uint8 RGB (raw or 16-bit frames belong to `camgen fit noise`)"
        )
    if frame.ndim != 3 or frame.shape[2] != 3:
        raise ConfigError(
            f"reference frame {index} has shape {frame.shape}; expected (H, W, 3) RGB (a grey image can be "
            "repeated into three channels; a single frame must still be passed as a list of frames)"
        )
    if min(frame.shape[:2]) < MOTION_BOX_PX:
        raise ConfigError(
            f"reference frame {index} is {frame.shape[1]}×{frame.shape[0]} px; the noise estimate needs at "
            f"least {MOTION_BOX_PX}×{MOTION_BOX_PX} px"
        )
    return frame


def _block_statistics(frame: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per 8 × 8 block and channel: mean, plane slopes (x, y), residual variance, and whether a sample
    is 0 or 255. Each (N, 3); the blocks cover the frame's top-left multiple of 8 px.

    The plane a + b·x + c·y over centred coordinates x, y ∈ {−3.5 … 3.5}: the three basis functions are
    orthogonal on the block, so b = Σx·v / Σx², c = Σy·v / Σy² and RSS = Σ(v − m)² − b²Σx² − c²Σy².
    """
    rows, cols = frame.shape[0] // BLOCK_PX, frame.shape[1] // BLOCK_PX
    blocks = (
        frame[: rows * BLOCK_PX, : cols * BLOCK_PX]
        .reshape(rows, BLOCK_PX, cols, BLOCK_PX, 3)
        .transpose(0, 2, 4, 1, 3)
        .reshape(rows * cols, 3, BLOCK_PX, BLOCK_PX)
    )
    saturated = ((blocks == 0) | (blocks == 255)).any(axis=(2, 3))
    values = blocks.astype(np.float32)
    mean = values.mean(axis=(2, 3))
    values -= mean[..., None, None]
    coordinate = np.arange(BLOCK_PX, dtype=np.float32) - (BLOCK_PX - 1) / 2
    sum_x2 = BLOCK_PX * float(np.sum(coordinate**2))
    slope_x = np.einsum("ncyx,x->nc", values, coordinate) / sum_x2
    slope_y = np.einsum("ncyx,y->nc", values, coordinate) / sum_x2
    rss = np.einsum("ncyx,ncyx->nc", values, values) - (slope_x**2 + slope_y**2) * sum_x2
    variance = np.maximum(rss, 0.0) / (BLOCK_PX * BLOCK_PX - 3)
    return mean, slope_x, slope_y, variance, saturated


def _plane_image(frame: np.ndarray) -> np.ndarray:
    """The frame's top-left multiple of 8 px with each 8 × 8 block replaced by its fitted plane (float32)."""
    rows, cols = frame.shape[0] // BLOCK_PX, frame.shape[1] // BLOCK_PX
    mean, slope_x, slope_y, _, _ = _block_statistics(frame)
    coordinate = np.arange(BLOCK_PX, dtype=np.float32) - (BLOCK_PX - 1) / 2
    planes = (
        mean[:, :, None, None]
        + slope_x[:, :, None, None] * coordinate[None, None, None, :]
        + slope_y[:, :, None, None] * coordinate[None, None, :, None]
    )
    return (
        planes.reshape(rows, cols, 3, BLOCK_PX, BLOCK_PX)
        .transpose(0, 3, 1, 4, 2)
        .reshape(rows * BLOCK_PX, cols * BLOCK_PX, 3)
    )


@dataclass
class _Statistics:
    """What one pass over the reference collects (mutable while it reads; private)."""

    temporal: bool
    spatial: bool
    histogram: bool
    frames: int = 0
    shape: tuple[int, ...] | None = None
    sizes_differ: bool = False
    total: np.ndarray | None = None
    squares: np.ndarray | None = None
    squared_differences: np.ndarray | None = None
    pairs: int = 0
    skipped_pairs: int = 0
    saturated: np.ndarray | None = None
    moving: np.ndarray | None = None
    first: np.ndarray | None = None
    blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = field(default_factory=list)
    """Per frame read by the spatial method: block means, residual variances, clipped flags, (N, 3) each."""
    counts: np.ndarray = field(default_factory=lambda: np.zeros((3, 256), np.int64))
    half: _Statistics | None = None
    """The same statistics of the frames averaged over 2 × 2 pixels (temporal only), or None."""
    _previous: np.ndarray | None = None
    _previous_luma: np.ndarray | None = None

    def add(self, frame: np.ndarray) -> None:
        frame = _check_frame(self.frames, frame)
        if self.first is None:
            self.first = frame.copy()
            self.shape = frame.shape
        elif frame.shape != self.shape:
            self.sizes_differ = True
        self.frames += 1
        if self.histogram:
            for c in range(3):
                self.counts[c] += np.bincount(frame[..., c].ravel(), minlength=256)
        if self.spatial and len(self.blocks) < SPATIAL_FRAMES_MAX:
            mean, _, _, variance, saturated = _block_statistics(frame)
            self.blocks.append((mean, variance, saturated))
        if self.temporal and not self.sizes_differ:
            self._add_temporal(frame)
            if self.half is not None:
                self.half.add(_half_scale(frame))

    def _add_temporal(self, frame: np.ndarray) -> None:
        # OpenCV's accumulators add 8-bit samples (and squares) into float64 in one pass, exactly.
        luma = cv2.boxFilter(cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY), cv2.CV_32F, (MOTION_BOX_PX, MOTION_BOX_PX))
        if self.total is None:
            self.total = np.zeros(frame.shape, np.float64)
            self.squares = np.zeros(frame.shape, np.float64)
            self.squared_differences = np.zeros(frame.shape, np.float64)
            self.saturated = np.zeros(frame.shape, bool)
            self.moving = np.zeros(frame.shape[:2], bool)
        cv2.accumulate(frame, self.total)
        cv2.accumulateSquare(frame, self.squares)
        # 0 and 255 are the two values that 8-bit wrap-around of v − 1 sends to 254 and above.
        self.saturated |= (frame - np.uint8(1)) >= 254
        if self._previous is not None:
            change = cv2.absdiff(luma, self._previous_luma)
            # Most of the frame changed at once: a light or exposure step, not noise; leave the pair out.
            if float(np.median(change[::4, ::4])) > MOTION_THRESHOLD_CODES:
                self.skipped_pairs += 1
            else:
                self.moving |= change > MOTION_THRESHOLD_CODES
                cv2.accumulateSquare(cv2.absdiff(frame, self._previous), self.squared_differences)
                self.pairs += 1
        self._previous = frame.copy()  # a reader may refill the array it yielded
        self._previous_luma = luma

    @property
    def static_fraction(self) -> float:
        if self.moving is None or self.pairs == 0:
            return math.nan
        return 1.0 - float(np.mean(self.moving))


def _half_scale(frame: np.ndarray) -> np.ndarray:
    """The frame averaged over 2 × 2 pixels (rounded to 8 bits), at least 16 px a side."""
    height, width = max(MOTION_BOX_PX, frame.shape[0] // 2), max(MOTION_BOX_PX, frame.shape[1] // 2)
    return cv2.resize(frame, (width, height), interpolation=cv2.INTER_AREA)


def _collect(
    frames_rgb8: Iterable[np.ndarray], *, temporal: bool, spatial: bool, histogram: bool, half_scale: bool = False
) -> _Statistics:
    if isinstance(frames_rgb8, np.ndarray) and frames_rgb8.ndim == 3:
        raise ConfigError(
            f"the reference is one array of shape {frames_rgb8.shape}; pass a sequence of (H, W, 3) frames "
            "(or a (T, H, W, 3) array)"
        )
    statistics = _Statistics(temporal=temporal, spatial=spatial, histogram=histogram)
    if half_scale and temporal:
        statistics.half = _Statistics(temporal=True, spatial=False, histogram=False)
    for frame in frames_rgb8:
        statistics.add(frame)
    if statistics.frames == 0:
        raise ReferenceContentError(
            "the reference holds no frames; give a video or 8-bit images of the camera's output"
        )
    return statistics


def _bin_edges(bins: int | Sequence[float]) -> np.ndarray:
    if isinstance(bins, int | np.integer) and not isinstance(bins, bool):
        if not 1 <= bins <= 256:
            raise ConfigError(f"bins must be 1…256, got {bins}")
        return np.linspace(0.0, 256.0, int(bins) + 1)
    edges = np.asarray(bins, dtype=np.float64)
    if edges.ndim != 1 or edges.size < 2 or not np.all(np.diff(edges) > 0) or not np.all(np.isfinite(edges)):
        raise ConfigError(f"bins must be a count or increasing finite bin edges, got {bins!r}")
    return edges


def _truncated_mean_fraction(dof: float, threshold: float) -> float:
    """E[X | X ≤ u] / E[X] for X ~ χ²_ν/ν and u = `threshold`: F_{ν+2}(uν) / F_ν(uν)."""
    below = special.chdtr(dof, threshold * dof)
    return float(special.chdtr(dof + 2, threshold * dof) / below) if below > 0 else 1.0


def _chi2_quantile(probability: float, dof: float) -> float:
    """The `probability` quantile of χ²_ν/ν."""
    return float(special.chdtri(dof, 1.0 - probability)) / dof


def _clipped_level(
    values: np.ndarray,
    dof: float,
    *,
    start_fraction: float,
    clip_quantile: float,
    iterations: int = 20,
) -> tuple[float, np.ndarray]:
    """Robust noise variance of one bin from per-sample variances ~ σ²·χ²_ν/ν plus outliers above.

    Start: the mean of the lowest `start_fraction` of the values over that of χ²_ν/ν. Then, to a fixed
    point: keep values ≤ c = max(σ²·u, `CLIP_FLOOR_CODE2`), u the `clip_quantile` point of χ²_ν/ν, and
    σ² = mean(kept) / (F_{ν+2}(cν/σ²) / F_ν(cν/σ²)). Returns σ² and the kept mask.
    """
    count = values.size
    lowest = max(1, math.ceil(start_fraction * count))
    low = np.partition(values, lowest - 1)[:lowest]
    start_quantile = _chi2_quantile(start_fraction, dof)
    level = float(np.mean(low)) / _truncated_mean_fraction(dof, start_quantile)
    u = _chi2_quantile(clip_quantile, dof)
    keep = np.ones(count, bool)
    for _ in range(iterations):
        threshold = max(level * u, CLIP_FLOOR_CODE2)
        keep = values <= threshold
        kept_mean = float(np.mean(values[keep]))
        new = kept_mean / _truncated_mean_fraction(dof, threshold / level) if level > 0 else kept_mean
        converged = abs(new - level) <= 1e-6 * max(level, 1e-12)
        level = new
        if converged:
            break
    return level, keep


def _binned(
    means: Sequence[np.ndarray],
    variances: Sequence[np.ndarray],
    clipped: Sequence[np.ndarray],
    edges: np.ndarray,
    dof: float,
    min_count: int,
    rejection: Mapping[str, float],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per channel and bin: mean intensity, robust variance (`_clipped_level`) of the unclipped samples,
    and their count. A bin where more than `CLIPPED_BIN_FRAC_MAX` of the noise-like samples touch 0 or
    255 gets NaN: leaving those out selects the samples whose noise happened to stay inside, which
    biases low."""
    bins = edges.size - 1
    mean_out = np.full((3, bins), np.nan)
    variance_out = np.full((3, bins), np.nan)
    count_out = np.zeros((3, bins), np.int64)
    for c in range(3):
        index = np.searchsorted(edges, means[c], side="right") - 1
        inside = (index >= 0) & (index < bins)
        index, m, v, clip = index[inside], means[c][inside], variances[c][inside], clipped[c][inside]
        order = np.argsort(index, kind="stable")
        index, m, v, clip = index[order], m[order], v[order], clip[order]
        starts = np.searchsorted(index, np.arange(bins + 1))
        for b in range(bins):
            part = slice(starts[b], starts[b + 1])
            unclipped = ~clip[part]
            count_out[c, b] = np.count_nonzero(unclipped)
            if count_out[c, b] < min_count:
                continue
            if not unclipped.all():
                # The clipped share among the samples that pass as noise (edges and texture that touch a
                # clip are rejected anyway, and say nothing about truncated noise).
                _, noise_like = _clipped_level(v[part], dof, **rejection)
                if np.mean(clip[part][noise_like]) > CLIPPED_BIN_FRAC_MAX:
                    continue
            values = v[part][unclipped]
            level, keep = _clipped_level(values, dof, **rejection)
            kept = int(np.count_nonzero(keep))
            count_out[c, b] = kept
            if kept >= min_count:
                variance_out[c, b] = level
                mean_out[c, b] = float(np.mean(m[part][unclipped][keep]))
    return mean_out, variance_out, count_out


def _temporal_nlf(statistics: _Statistics, edges: np.ndarray, min_count: int) -> NoiseLevelFunction:
    if statistics.frames < 2:
        raise ConfigError(
            f"the temporal noise estimate needs at least 2 frames of one view, got {statistics.frames}; give "
            "more frames of the static camera, or use the spatial method for single images"
        )
    if statistics.sizes_differ:
        raise ConfigError(
            "the temporal noise estimate needs frames of one size (one view of a static camera), but the "
            "reference frames differ in size; give frames of one camera mode, or use the spatial method"
        )
    if statistics.pairs == 0:
        raise ConfigError(
            f"every one of the {statistics.skipped_pairs} pairs of successive frames changes over most of the "
            "picture (a moving camera or flickering light); give frames of a static view, or use the spatial method"
        )
    n = statistics.pairs
    dof = 2.0 * n * n / (3.0 * n - 1.0)
    mean = statistics.total / statistics.frames
    variance = statistics.squared_differences / (2.0 * n)
    # Each 2 × 2 phase on its own: demosaicing makes the noise of a colour differ by CFA phase (module
    # docstring); the phases are combined by their counts.
    phases = []
    for dy, dx in ((0, 0), (0, 1), (1, 0), (1, 1)):
        static = ~statistics.moving[dy::2, dx::2]
        phases.append(
            _binned(
                [mean[dy::2, dx::2, c][static] for c in range(3)],
                [variance[dy::2, dx::2, c][static] for c in range(3)],
                [statistics.saturated[dy::2, dx::2, c][static] for c in range(3)],
                edges,
                dof,
                max(1, min_count // 4),
                TEMPORAL_REJECTION,
            )
        )
    means, variances, counts = (np.stack(column) for column in zip(*phases, strict=True))
    count = counts.sum(axis=0)
    weight = counts / np.maximum(count, 1)
    with np.errstate(invalid="ignore"):
        m = np.sum(weight * means, axis=0)
        v = np.sum(weight * variances, axis=0)
    v[count < min_count] = np.nan
    m[~np.isfinite(v)] = np.nan
    ratio = _difference_to_plain_ratio(statistics)
    return NoiseLevelFunction(edges, m, v, count, "temporal", statistics.frames, statistics.static_fraction, ratio)


def _difference_to_plain_ratio(statistics: _Statistics) -> float:
    """Σ successive-difference variance / Σ plain temporal variance of the static, unclipped pixels
    (`NoiseLevelFunction.difference_to_plain_ratio`)."""
    if statistics.skipped_pairs or statistics.frames < 3:
        return math.nan
    n, frames = statistics.pairs, statistics.frames
    used = ~statistics.moving[..., None] & ~statistics.saturated
    plain = (statistics.squares - statistics.total**2 / frames) / (frames - 1)
    plain_sum = float(np.sum(plain[used]))
    if not plain_sum > 0:
        return math.nan
    return float(np.sum(statistics.squared_differences[used])) / (2.0 * n) / plain_sum


def _spatial_nlf(statistics: _Statistics, edges: np.ndarray, min_count: int) -> NoiseLevelFunction:
    mean = np.concatenate([b[0] for b in statistics.blocks])
    variance = np.concatenate([b[1] for b in statistics.blocks])
    saturated = np.concatenate([b[2] for b in statistics.blocks])
    m, v, count = _binned(
        list(mean.T),
        list(variance.T),
        list(saturated.T),
        edges,
        float(BLOCK_PX * BLOCK_PX - 3),
        min_count,
        SPATIAL_REJECTION,
    )
    return NoiseLevelFunction(edges, m, v, count, "spatial", len(statistics.blocks))


def _chosen_method(statistics: _Statistics, method: str) -> Literal["temporal", "spatial"]:
    if method != "auto":
        return method
    temporal = (
        statistics.frames >= TEMPORAL_FRAMES_MIN
        and not statistics.sizes_differ
        and statistics.pairs > 0
        and statistics.static_fraction >= STATIC_FRACTION_MIN
    )
    return "temporal" if temporal else "spatial"


def _nlf(
    statistics: _Statistics, method: str, edges: np.ndarray, min_count: int | None, *, refuse_empty: bool = True
) -> NoiseLevelFunction:
    """The NLF of collected statistics; a reference (`refuse_empty`) without a usable bin is refused."""
    chosen = _chosen_method(statistics, method)
    count = MIN_COUNT[chosen] if min_count is None else min_count
    nlf = _temporal_nlf(statistics, edges, count) if chosen == "temporal" else _spatial_nlf(statistics, edges, count)
    if refuse_empty and not nlf.usable.any():
        share = float(np.mean(statistics.first <= 0)), float(np.mean(statistics.first >= 255))
        if sum(share) < 0.5 and nlf.count.max() < count:
            # Too little data, not too much clipping: each bin's candidates fall short of `count`.
            if chosen == "temporal":
                samples, unit = int(np.count_nonzero(~statistics.moving)), "static pixels"
            else:
                samples, unit = sum(b[0].shape[0] for b in statistics.blocks), f"{BLOCK_PX} × {BLOCK_PX} blocks"
            raise ReferenceContentError(
                f"{samples} {unit} from {statistics.frames} frame(s) over {edges.size - 1} intensity bins, fewer "
                f"than the {count} needed per bin for a {chosen} noise estimate (the fullest bin holds "
                f"{int(nlf.count.max())}); give larger or more frames, or fewer bins"
            )
        raise ReferenceContentError(
            f"no intensity bin of the reference holds {count} unclipped samples for a {chosen} noise estimate "
            f"(in the first frame {share[0]:.0%} of the samples are 0 and {share[1]:.0%} are 255); give footage "
            "with mid-tone regions, neither black nor saturated"
        )
    return nlf


def _check_method(method: str) -> None:
    if method not in ("auto", "temporal", "spatial"):
        raise ConfigError(f"method must be 'auto', 'temporal' or 'spatial', got {method!r}")


def nlf_from_frames(
    frames_rgb8: Iterable[np.ndarray],
    *,
    bins: int | Sequence[float] = DEFAULT_BINS,
    method: Literal["auto", "temporal", "spatial"] = "auto",
    min_count: int | None = None,
) -> NoiseLevelFunction:
    """The noise level function of 8-bit RGB frames (method in the module docstring).

    Parameters
    ----------
    frames_rgb8 : iterable of (H, W, 3) uint8
        Frames, 8-bit codes, R, G, B; read once, in order (a generator is fine).
    bins : int or sequence of float
        Number of equal bins over 0…256 codes, or the bin edges, codes.
    method : {"auto", "temporal", "spatial"}
        "auto" is temporal for ≥ `TEMPORAL_FRAMES_MIN` frames of one size with at least
        `STATIC_FRACTION_MIN` of the pixels static, else spatial.
    min_count : int, optional
        Fewest samples (pixels; blocks) a bin needs; default `MIN_COUNT` of the method.

    Returns
    -------
    NoiseLevelFunction

    Raises
    ------
    ConfigError
        For frames that are not (H, W, 3) uint8, no frames, fewer than 2 or frames of mixed sizes for the
        temporal method, or a reference with no usable bin (all black or all saturated).
    """
    _check_method(method)
    edges = _bin_edges(bins)
    statistics = _collect(frames_rgb8, temporal=method != "spatial", spatial=method != "temporal", histogram=False)
    return _nlf(statistics, method, edges, min_count)


def _pile_up(counts: np.ndarray, codes: Sequence[int], step: int) -> int | None:
    """The clip code, walking `codes` inwards (by `step`) from an extreme: the first code holding
    ≥ `PILE_UP_MIN_FRAC` of the samples and ≥ `PILE_UP_RATIO` times the next code inwards, while the
    samples beyond it (sharpening overshoots) stay under `PILE_UP_OUTSIDE_FRAC`; None if there is none."""
    total = float(counts.sum())
    beyond = 0.0
    for code in codes:
        here = float(counts[code])
        inner = code + step
        if here >= PILE_UP_MIN_FRAC * total and 0 <= inner < 256 and here >= PILE_UP_RATIO * counts[inner]:
            return code
        beyond += here
        if beyond > PILE_UP_OUTSIDE_FRAC * total:
            return None
    return None


def _tone_from_counts(counts: np.ndarray) -> dict:
    """`estimate_tone` from the (3, 256) histograms of the channels."""
    totals = counts.sum(axis=1)
    cumulative = np.cumsum(counts, axis=1)
    low_codes, high_codes = [], []
    for c in range(3):
        median = int(np.searchsorted(cumulative[c], totals[c] / 2))
        low_codes.append(_pile_up(counts[c], range(0, median), +1))
        high_codes.append(_pile_up(counts[c], range(255, median, -1), -1))
    low = min((code for code in low_codes if code is not None), default=None)
    high = max((code for code in high_codes if code is not None), default=None)
    low_frac = [float(cumulative[c, low] / totals[c]) if low is not None else 0.0 for c in range(3)]
    high_frac = [float(1.0 - cumulative[c, high - 1] / totals[c]) if high is not None else 0.0 for c in range(3)]
    return {
        "clipped_low_frac": low_frac,
        "clipped_high_frac": high_frac,
        "output_low_code": low,
        "output_high_code": high,
        "low_percentile_max": 100.0 * float(np.mean(low_frac)) if low is not None else None,
        "high_percentile_min": 100.0 * (1.0 - float(np.mean(high_frac))) if high is not None else None,
        "output_range_low_frac": low / 255.0 if low is not None else None,
        "output_range_high_frac": high / 255.0 if high is not None else None,
    }


def estimate_tone(frames_rgb8: Iterable[np.ndarray]) -> dict:
    """The contrast stretch as the output shows it: where, and how much, the output clips.

    A stretch maps its low (high) percentile of the linear samples to the bottom (top) of its output
    range, so everything beyond piles up on one code. Walking each channel's histogram in from an
    extreme, the first code holding ≥ `PILE_UP_MIN_FRAC` of the samples and ≥ `PILE_UP_RATIO` times the
    next code inwards is taken as the clip (sharpening overshoots past it, so counts beyond it count as
    clipped).

    The clipped fraction of the output *bounds* the stretch's percentile rather than measuring it: the
    stretch counts linear samples below its limit, and the CCM, demosaicing and sharpening after it
    spread the noise, which sends more output samples over the clip (for `profiles/bullet_4mp_2p8mm.yaml`,
    a 1 % low percentile clips 1.75 % of the output without sharpening or denoise and 2.1 % with them).
    A denoise that averages across the clip hides it (the pile-up smears).

    Parameters
    ----------
    frames_rgb8 : iterable of (H, W, 3) uint8

    Returns
    -------
    dict
        ``clipped_low_frac``, ``clipped_high_frac``: per channel (R, G, B), fraction of the samples at or
        beyond the clip code (0 without a clip); ``output_low_code``, ``output_high_code``: the clip codes
        (None where the output does not pile up); ``low_percentile_max``: the largest low percentile
        consistent with the output (the mean clipped fraction over the channels, ×100, as the stretch
        pools its colours), ``high_percentile_min`` likewise; ``output_range_low_frac``,
        ``output_range_high_frac``: the clip codes over 255. Each is None where no clip is seen.

    Raises
    ------
    ConfigError
        For frames that are not (H, W, 3) uint8, or none.
    """
    statistics = _collect(frames_rgb8, temporal=False, spatial=False, histogram=True)
    return _tone_from_counts(statistics.counts)


@dataclass(frozen=True)
class MatchFit:
    """What `fit_match` found.

    Attributes
    ----------
    reference : NoiseLevelFunction
        The reference's NLF.
    fitted, base : NoiseLevelFunction
        Camgen's NLF on the same content, method and bins with the fitted and with the base profile
        (both under the fitted light).
    parameters : dict of str to float
        Fitted values by profile key path (``sensor.noise.read_noise_e``); a list entry carries its
        index (``isp.contrast_stretch.output_range_frac[0]``).
    relative_error_per_bin : (3, B) float64
        fitted.variance / reference.variance − 1; NaN where either is.
    worst_relative_error : float
        Largest |relative_error_per_bin| over the channel-bins the fit compared (NaN if none).
    profile : Profile
        The base profile with the fitted values.
    warnings : tuple of str
    tone : dict
        `estimate_tone` of the reference.
    light_rgb : (float, float, float)
        Colour of the light (R, G, B relative to G) the simulation found for the reference's scene: with
        grey-world white balance the output hides it, but the balance gains, and with them the noise of R
        and B against G, depend on it. (1, 1, 1) when not fitted.
    evaluations : int
        Simulations the optimiser ran.
    uncertainties : dict of str to float
        1σ uncertainty of each fitted noise value in `parameters` (same keys and units; the tone values
        adopted from the output's clips have none): cov ≈ (JᵀJ)⁻¹·s² of the optimiser's variables, J the
        Jacobian of the log-NLF residuals at the solution and s² their variance per degree of freedom,
        carried to the profile's values to first order. inf where the NLF does not respond to a value,
        NaN where there are no more residuals than variables.
    """

    reference: NoiseLevelFunction
    fitted: NoiseLevelFunction
    base: NoiseLevelFunction
    parameters: dict[str, float]
    relative_error_per_bin: np.ndarray
    worst_relative_error: float
    profile: Profile
    warnings: tuple[str, ...]
    tone: dict
    light_rgb: tuple[float, float, float]
    evaluations: int
    uncertainties: dict[str, float] = field(default_factory=dict)

    def profile_fragment(self) -> dict:
        """YAML-ready nested dict of only the fitted keys (plain floats and lists)."""
        dumped = self.profile.model_dump(mode="json")
        fragment: dict = {}
        for key in self.parameters:
            path = key.split("[")[0].split(".")
            value = dumped
            for part in path:
                value = value[part]
            node = fragment
            for part in path[:-1]:
                node = node.setdefault(part, {})
            node[path[-1]] = list(value) if isinstance(value, list | tuple) else value
        return fragment


@dataclass(frozen=True)
class _Content:
    """The simulation's static scene, before light colour and exposure."""

    linear_rgb: np.ndarray
    """(H, W, 3) float32: the output's linear signal (after CCM, relative to the stretch range)."""
    gain_db: float
    codec: Codec | None
    """The codec the simulated frames pass through (encoded and decoded), or None."""
    codec_fps: float | None
    """Frame rate the codec encodes at, Hz; None: the sensor's ``frame_rate_max_hz``."""
    shows_fixed_pattern: bool
    """The content is the reference's temporal mean, which already shows the camera's fixed patterns
    (PRNU, DSNU, row and column offsets, hot and dead pixels): the simulation leaves them out rather than
    apply them twice (they change the temporal noise only through edge-aware demosaicing and denoise,
    which see them as texture: +4…+16 % green variance with `edge_aware` when doubled)."""


def _inverse_tone(encoded: np.ndarray, isp: Isp) -> np.ndarray:
    """Linear signal (relative to the stretch range) of encoded output fractions, by table inversion."""
    grid = np.linspace(0.0, 1.0, 65536)
    forward = np.maximum.accumulate(tone_curve(grid, isp.tone_curve, isp.gamma))
    return np.interp(encoded, forward, grid)


def _grey_world(profile: Profile) -> bool:
    """Whether the profile balances colour by grey world (then the light's colour is not in its output)."""
    steps = isp_steps(profile.isp, profile.sensor)
    return "isp.white_balance" in steps and profile.isp.white_balance.mode == "auto_grey_world"


def _simulation_size(height: int, width: int, max_px: int) -> tuple[int, int]:
    scale = min(1.0, math.sqrt(max_px / (height * width)))
    return max(16, int(height * scale) // 2 * 2), max(16, int(width * scale) // 2 * 2)


def _output_range(isp: Isp) -> tuple[float, float]:
    return isp.contrast_stretch.output_range_frac if isp.contrast_stretch is not None else (0.0, 1.0)


def _content(
    picture_rgb8: np.ndarray,
    profile: Profile,
    *,
    max_px: int,
    gain_db: float,
    codec: Codec | None,
    shows_fixed_pattern: bool,
    codec_fps: float | None = None,
) -> _Content:
    """The reference's picture, downscaled, through the inverse output range and tone curve. A codec's
    bitrate is scaled with the pixel count (the bits per pixel stay the reference's)."""
    height, width = _simulation_size(*picture_rgb8.shape[:2], max_px)
    image = cv2.resize(picture_rgb8.astype(np.float32), (width, height), interpolation=cv2.INTER_AREA)
    low, high = _output_range(profile.isp)
    linear = _inverse_tone(np.clip((image / 255.0 - low) / (high - low), 0.0, 1.0), profile.isp)
    if codec_fps is not None and not (math.isfinite(codec_fps) and codec_fps > 0):
        raise ConfigError(f"codec_fps must be a finite frame rate > 0 Hz, got {codec_fps}")
    if codec is not None and codec.bitrate_kbps is not None:
        ratio = height * width / (picture_rgb8.shape[0] * picture_rgb8.shape[1])
        codec = codec.model_copy(update={"bitrate_kbps": codec.bitrate_kbps * ratio})
    return _Content(
        linear_rgb=linear.astype(np.float32),
        gain_db=gain_db,
        codec=codec,
        shows_fixed_pattern=shows_fixed_pattern,
        codec_fps=codec_fps,
    )


def _site_levels(content: _Content, profile: Profile, light_rgb: tuple[float, float, float]) -> np.ndarray:
    """(H, W) float32: electrons each site collects, as a fraction of saturation (module docstring).

    Camera RGB is the linear content through the inverse CCM; with grey world it is multiplied by the
    light's colour and the QE of each colour relative to the largest (what grey world then divides out),
    with fixed gains it is divided by them. Auto-exposure scales the result until the metered mean is
    at its target; a manual profile keeps it (the output range spans the raw range).

    A colour that the camera clipped after white balance comes back from the output exactly at the clip,
    where the simulation's noise would dither it in and out (and through the CCM into the other
    colours), while the camera's light went on beyond it: such values (≥ `CLIP_KNEE` of the clip) are
    set to `CLIP_OVERSHOOT` times the clip.
    """
    sensor, isp = profile.sensor, profile.isp
    steps = isp_steps(isp, sensor)
    if sensor.cfa == "mono":
        camera = content.linear_rgb.mean(axis=2, keepdims=True)
        colour = np.ones(1)
        balanced = 1.0
    else:
        ccm = np.array(isp.ccm, np.float64) if "isp.ccm" in steps else np.eye(3)
        camera = np.clip(content.linear_rgb @ np.linalg.inv(ccm).T.astype(np.float32), 0.0, None)
        if _grey_world(profile):
            qe = sensor.quantum_efficiency
            colour = np.array([qe.r, qe.g, qe.b]) / max(qe.r, qe.g, qe.b) * np.asarray(light_rgb)
            # Grey world's gains, smallest 1, bring each colour to the largest colour's level.
            balanced = float(np.max(colour))
        elif "isp.white_balance" in steps:
            gains = np.array(isp.white_balance.gains_rgb)
            colour = np.min(gains) / gains
            balanced = 1.0
        else:
            colour = np.ones(3)
            balanced = 1.0

    def sites(camera: np.ndarray) -> np.ndarray:
        weighted = (camera * colour.astype(np.float32)).astype(np.float32)
        return weighted[..., 0] if sensor.cfa == "mono" else mosaic(weighted, sensor.cfa)

    site = sites(camera)
    scale = _exposure_scale(site, profile, content.gain_db)
    # After white balance a colour reaches the clip at camera · scale · balanced = 1.
    clip = 1.0 / (scale * balanced)
    clipped = camera >= CLIP_KNEE * clip
    if clipped.any():
        camera = np.where(clipped, np.float32(CLIP_OVERSHOOT * clip), camera)
        site = sites(camera)
        scale = _exposure_scale(site, profile, content.gain_db)
    return site * np.float32(scale)


def _exposure_scale(site: np.ndarray, profile: Profile, gain_db: float) -> float:
    """The factor on the site levels at which auto-exposure has converged (the metered mean at its
    target, as `CameraPipeline.converge_exposure`), or 1 for a manual profile."""
    sensor, exposure = profile.sensor, profile.exposure
    if exposure.mode != "auto":
        return 1.0
    saturation, _ = saturation_e(
        sensor.full_well_e, sensor.conversion_gain_dn_per_e, sensor.black_level_dn, sensor.bit_depth, gain_db
    )
    level_per_frac = (
        saturation
        * sensor.conversion_gain_dn_per_e
        * gain_linear(gain_db)
        / (sensor.white_level_dn - sensor.black_level_dn)
    )
    metered = site[metering_window(*site.shape, exposure.auto.metering_region_frac)]
    scale = 1.0
    # Clipping at saturation makes it a few multiplicative steps.
    for _ in range(30):
        level = float(np.mean(np.minimum(metered * scale, 1.0))) * level_per_frac
        if level <= 0:
            break
        step = exposure.auto.target_level_frac / level
        scale *= step
        if abs(step - 1.0) < 1e-6:
            break
    return scale


def _simulate(
    profile: Profile, content: _Content, light_rgb: tuple[float, float, float], *, frames: int, seed: int
) -> list[np.ndarray]:
    """Camgen's 8-bit output of the static content through the profile's sensor and ISP."""
    height, width = content.linear_rgb.shape[:2]
    sensor = profile.sensor.model_copy(update={"width_px": width, "height_px": height})
    terms = TEMPORAL_NOISE_TERMS if content.shows_fixed_pattern else NOISE_TERMS
    model = SensorModel.build(sensor, profile.serial, terms=terms)
    isp = CameraIsp(
        profile.isp, sensor, frame_interval_s=1.0 / sensor.frame_rate_max_hz, steps=isp_steps(profile.isp, sensor)
    )
    saturation, _ = saturation_e(
        sensor.full_well_e, sensor.conversion_gain_dn_per_e, sensor.black_level_dn, sensor.bit_depth, content.gain_db
    )
    exposure_time_s = profile.exposure.exposure_time_s
    qe = sensor.quantum_efficiency
    per_photon = 1.0 if sensor.cfa == "mono" else cfa_site_values((qe.r, qe.g, qe.b), sensor.cfa, height, width)
    # Photons per second that give the site levels once the sensor model applies each colour's QE.
    rate = _site_levels(content, profile, light_rgb) * np.float32(saturation / exposure_time_s) / per_photon
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(frames):
        raw = model.capture(rate, exposure_time_s=exposure_time_s, gain_db=content.gain_db, rng=rng)
        out.append(isp.process(raw, content.gain_db))
    if content.codec is not None:
        fps = content.codec_fps if content.codec_fps is not None else sensor.frame_rate_max_hz
        out = _through_codec(out, content.codec, fps=fps)
    return out


def _through_codec(frames_rgb8: list[np.ndarray], codec: Codec, *, fps: float) -> list[np.ndarray]:
    """The frames encoded by `camgen.io.video.VideoWriter` (into a temporary file) and decoded by PyAV
    with the colour matrix and range the stream is tagged with."""
    height, width = frames_rgb8[0].shape[:2]
    with tempfile.TemporaryDirectory(prefix="camgen-match-") as directory:
        path = f"{directory}/simulation.mp4"
        with VideoWriter(path, width_px=width, height_px=height, fps=fps, codec=codec, preset=codec.preset) as writer:
            for frame in frames_rgb8:
                writer.write(frame)
        with av.open(path) as container:
            return [decoded_rgb8(frame) for frame in container.decode(video=0)]


def _round(value: float) -> float:
    if value == 0 or not math.isfinite(value):
        return value
    return float(round(value, SIGNIFICANT_DIGITS - 1 - math.floor(math.log10(abs(value)))))


def _with_values(profile: Profile, values: dict[str, float]) -> Profile:
    """`profile` with the values set by key path (an index as ``key[i]``), validated."""
    dumped = profile.model_dump()
    for key, value in values.items():
        path, _, index = key.partition("[")
        parts = path.split(".")
        node = dumped
        for part in parts[:-1]:
            node = node[part]
        if index:
            items = list(node[parts[-1]])
            items[int(index.rstrip("]"))] = value
            node[parts[-1]] = items
        else:
            node[parts[-1]] = value
    return Profile.model_validate(dumped)


def _tone_values(tone: dict, base: Profile) -> tuple[dict[str, float], list[str]]:
    """Stretch settings `estimate_tone` contradicts in the base profile, and notes on what it cannot see.

    An output range seen at a clip is adopted; a percentile only where the base's lies beyond the bound
    the output sets (it would clip more than the camera does).
    """
    stretch = base.isp.contrast_stretch
    if stretch is None:
        inside = [
            code
            for code, extreme in ((tone["output_low_code"], 0), (tone["output_high_code"], 255))
            if code not in (None, extreme)
        ]
        if inside:
            return {}, [
                f"the reference clips at code(s) {', '.join(map(str, inside))}, an output range the base profile "
                "cannot set without a contrast stretch; not fitted"
            ]
        return {}, []
    values: dict[str, float] = {}
    notes = []
    output_range = list(stretch.output_range_frac)
    for end, index in (("low", 0), ("high", 1)):
        code = tone[f"output_{end}_code"]
        if code is None:
            dark = "dark" if end == "low" else "bright"
            notes.append(
                f"the reference shows no clip at its {dark} end (the scene stays inside the stretch, or denoise or "
                f"a codec smears the clip); kept the base {end}_percentile and output range {end}"
            )
        elif code != round(255 * output_range[index]):
            output_range[index] = _round(code / 255.0)
    if output_range[0] < output_range[1]:
        for index in (0, 1):
            if output_range[index] != stretch.output_range_frac[index]:
                values[f"isp.contrast_stretch.output_range_frac[{index}]"] = output_range[index]
    low_max, high_min = tone["low_percentile_max"], tone["high_percentile_min"]
    if low_max is not None and stretch.low_percentile > low_max:
        values["isp.contrast_stretch.low_percentile"] = _round(low_max)
    if (
        high_min is not None
        and stretch.high_percentile < high_min
        and high_min > values.get("isp.contrast_stretch.low_percentile", stretch.low_percentile)
    ):
        values["isp.contrast_stretch.high_percentile"] = _round(high_min)
    return values, notes


def fit_match(
    reference_frames_rgb8: Iterable[np.ndarray],
    base: Profile,
    *,
    seed: int | np.random.Generator = 0,
    method: Literal["auto", "temporal", "spatial"] = "auto",
    bins: int | Sequence[float] = DEFAULT_BINS,
    min_count: int | None = None,
    gain_db: float | None = None,
    fit_tone: bool = True,
    fit_denoise: bool = False,
    codec: Codec | None = None,
    codec_fps: float | None = None,
    simulation_max_px: int = 320 * 240,
    max_evaluations: int = 60,
) -> MatchFit:
    """Fit the base profile's noise so that camgen's output reproduces the reference's noise level function.

    Parameters
    ----------
    reference_frames_rgb8 : iterable of (H, W, 3) uint8
        The camera's output, 8-bit R, G, B: frames of a static view (temporal NLF) or images (spatial).
    base : Profile
        The profile to start from; everything not fitted is kept.
    seed : int or numpy.random.Generator
        Seed of the simulation (a Generator gives one); every evaluation reuses it.
    method, bins, min_count
        As `nlf_from_frames`; the simulation is measured with the method chosen for the reference.
    gain_db : float, optional
        Analog gain the reference was taken at, dB (invisible in its output); default the base profile's
        ``exposure.gain_db``.
    fit_tone : bool
        Adopt the contrast stretch's output range where the reference shows its clips, and move a stretch
        percentile that the reference's clipping contradicts onto its bound (`estimate_tone`).
    fit_denoise : bool
        Also fit ``isp.denoise_strength``; the NLF of the frames averaged over 2 × 2 pixels joins the
        objective (temporal references), since denoise also correlates the noise between neighbours.
    codec : Codec, optional
        The codec the reference went through, when known: the simulated frames are encoded with it
        (bitrate scaled by the pixel count) and decoded before their NLF is measured. None compares
        with the ISP's output, and the fitted parameters take up the codec's effect on the noise.
    codec_fps : float, optional
        Frame rate the simulated frames are encoded at, Hz: the reference stream's (average) rate, which
        sets a rate-controlled codec's bits per frame; default the sensor's ``frame_rate_max_hz``.
    simulation_max_px : int
        Most pixels of the simulated frames (the reference's picture is downscaled to fit).
    max_evaluations : int
        Most evaluations of the objective the optimiser may make; each of its iterations also runs one
        simulation per fitted parameter for the finite differences.

    Returns
    -------
    MatchFit

    Raises
    ------
    ConfigError
        For a reference `nlf_from_frames` refuses, or a simulation that shares no usable bin with it.

    Notes
    -----
    Method and its limits in the module docstring. At 320 × 240 px a simulation of 64 frames with its
    NLF costs about 0.15 s on 2 cores (0.35 s through a lossless H.264 round trip); a fit runs 35–55
    of them: 5–9 s, 15–20 s with a codec.
    """
    _check_method(method)
    edges = _bin_edges(bins)
    statistics = _collect(
        reference_frames_rgb8,
        temporal=method != "spatial",
        spatial=method != "temporal",
        histogram=True,
        half_scale=fit_denoise,
    )
    reference = _nlf(statistics, method, edges, min_count)
    if not np.any(reference.variance[reference.usable] > 0):
        low, high = int(statistics.first.min()), int(statistics.first.max())
        flat = f"its first frame is one flat level ({low} in every pixel) and " if low == high else ""
        raise ReferenceContentError(
            f"the reference shows no noise: {flat}its {reference.method} variance is 0 in every intensity bin it "
            "fills, so it holds no noise-level information to fit; give the camera's own output with its noise "
            "(several frames of a static view, or images with flat but noisy regions), not a synthetic, uniform "
            "or fully denoised picture"
        )
    warnings: list[str] = []
    if method == "auto" and reference.method == "spatial" and statistics.frames >= TEMPORAL_FRAMES_MIN:
        if statistics.sizes_differ:
            why = "they differ in size"
        elif statistics.pairs == 0:
            why = "every pair of successive frames changes over most of the picture"
        else:
            why = f"only {statistics.static_fraction:.0%} of the picture is static"
        warnings.append(f"used the spatial noise estimate on {statistics.frames} frames: {why}")
    if reference.difference_to_plain_ratio < TEMPORAL_CORRELATION_RATIO_MIN:
        warnings.append(
            f"the reference's noise correlates between frames: successive differences show "
            f"{reference.difference_to_plain_ratio:.2f} of its plain temporal variance (1 for independent "
            "frames), as temporal noise reduction in the camera or a codec's inter-frame prediction make it; the "
            "temporal NLF is biased low by about that factor, and so is the fitted noise (or a slow drift or "
            "flicker of the light lifts the plain variance: check the footage)"
        )
    tone = _tone_from_counts(statistics.counts)
    values: dict[str, float] = {}
    if fit_tone:
        values, notes = _tone_values(tone, base)
        warnings += notes
    start = _with_values(base, values) if values else base
    gain = start.exposure.gain_db if gain_db is None else gain_db
    simulation_seed = (
        int(np.random.default_rng(seed).integers(2**63)) if isinstance(seed, np.random.Generator) else int(seed)
    )
    picture = statistics.total / statistics.frames if reference.method == "temporal" else _plane_image(statistics.first)
    content = _content(
        picture,
        start,
        max_px=simulation_max_px,
        gain_db=gain,
        codec=codec,
        shows_fixed_pattern=reference.method == "temporal",
        codec_fps=codec_fps,
    )
    frames = SIMULATION_FRAMES if reference.method == "temporal" else SIMULATION_FRAMES_SPATIAL
    count = min_count if min_count is not None else MIN_COUNT[reference.method]

    # Denoise trades against the full well in the NLF (strength 0.19 with 24 % more electrons matched a
    # 0.5 reference within 4 %) but not in that of 2 × 2-averaged frames (−5 % there): fit both.
    half_scale = fit_denoise and reference.method == "temporal"
    reference_half = (
        _nlf(statistics.half, "temporal", edges, max(1, count // 4), refuse_empty=False) if half_scale else None
    )
    if half_scale and not reference_half.usable.any():
        half_scale, reference_half = False, None
        warnings.append(
            "the reference averaged over 2 × 2 pixels has no usable intensity bin; fitted the denoise strength "
            "from the full-resolution NLF alone, where it trades against the full well"
        )

    def measure_both(
        profile: Profile, light_rgb: tuple[float, float, float]
    ) -> tuple[NoiseLevelFunction, NoiseLevelFunction | None]:
        output = _simulate(profile, content, light_rgb, frames=frames, seed=simulation_seed)
        temporal = reference.method == "temporal"
        simulated = _collect(output, temporal=temporal, spatial=not temporal, histogram=False, half_scale=half_scale)
        # A simulation may lose bins (an extreme trial clips them); the objective penalises those.
        nlf = _nlf(simulated, reference.method, edges, count, refuse_empty=False)
        if not half_scale:
            return nlf, None
        return nlf, _nlf(simulated.half, "temporal", edges, max(1, count // 4), refuse_empty=False)

    def measure(profile: Profile, light_rgb: tuple[float, float, float]) -> NoiseLevelFunction:
        return measure_both(profile, light_rgb)[0]

    sensor = start.sensor
    read0 = max(sensor.noise.read_noise_e, 0.1)
    fit_light = _grey_world(start)
    # x: log full-well scale, log read noise over its start, [denoise strength], [log light R/G, log B/G].
    lower = [math.log(FULL_WELL_SCALE_BOUNDS[0]), math.log(READ_NOISE_BOUNDS_E[0] / read0)]
    upper = [math.log(FULL_WELL_SCALE_BOUNDS[1]), math.log(READ_NOISE_BOUNDS_E[1] / read0)]
    x0 = [0.0, 0.0]
    if fit_denoise:
        lower.append(0.0)
        upper.append(1.0)
        # At strength 0 the bilateral's range σ is far below the noise, so its slope there is flat: start
        # where a step changes the output.
        x0.append(max(start.isp.denoise_strength, DENOISE_START_MIN))
    if fit_light:
        lower += [-math.log(LIGHT_RATIO_MAX)] * 2
        upper += [math.log(LIGHT_RATIO_MAX)] * 2
        x0 += [0.0, 0.0]
    x0 = np.clip(x0, lower, upper)

    def profile_at(x: np.ndarray) -> Profile:
        scale = math.exp(x[0])
        noise = sensor.noise.model_copy(update={"read_noise_e": read0 * math.exp(x[1])})
        fitted_sensor = sensor.model_copy(
            update={
                "full_well_e": sensor.full_well_e * scale,
                "conversion_gain_dn_per_e": sensor.conversion_gain_dn_per_e / scale,
                "noise": noise,
            }
        )
        update = {"sensor": fitted_sensor}
        if fit_denoise:
            update["isp"] = start.isp.model_copy(update={"denoise_strength": float(np.clip(x[2], 0.0, 1.0))})
        return start.model_copy(update=update)

    def light_at(x: np.ndarray) -> tuple[float, float, float]:
        return (math.exp(x[-2]), 1.0, math.exp(x[-1])) if fit_light else (1.0, 1.0, 1.0)

    start_nlf, start_half = measure_both(start, light_at(x0))
    mask = reference.usable & start_nlf.usable & (reference.variance > 0) & (start_nlf.variance > 0)
    if not mask.any():
        raise ConfigError(
            "camgen's simulation of the reference shares no usable intensity bin with it; the base profile's "
            "tone settings may map the content far from the reference's levels"
        )
    log_reference = np.log(reference.variance[mask])
    if half_scale:
        mask_half = (
            reference_half.usable & start_half.usable & (reference_half.variance > 0) & (start_half.variance > 0)
        )
        log_reference = np.concatenate([log_reference, np.log(reference_half.variance[mask_half])])
    # A first guess from the start's misfit, as if shot noise ruled: its variance in the output goes as
    # 1/full well, and that of R (B) against G as G/R (G/B) of the light (through the balance gains).
    with np.errstate(invalid="ignore", divide="ignore"):
        log_ratio = np.where(mask, np.log(start_nlf.variance / reference.variance), np.nan)
    x0[0] = float(np.nanmean(log_ratio))
    if fit_light:
        channel = np.nanmean(log_ratio, axis=1)
        x0[-2:] = np.nan_to_num(channel[[0, 2]] - channel[1])
    x0 = np.clip(x0, lower, upper)
    evaluated: dict[tuple[float, ...], np.ndarray] = {}

    def residuals(x: np.ndarray) -> np.ndarray:
        key = tuple(float(v) for v in x)
        if key not in evaluated:
            nlf, half = measure_both(profile_at(x), light_at(x))
            variance = (
                nlf.variance[mask] if half is None else np.concatenate([nlf.variance[mask], half.variance[mask_half]])
            )
            # A bin the simulation lost (too few samples) counts as a 50 % miss, so the optimiser leaves it.
            lost = ~(variance > 0)
            residual = np.log(np.where(lost, 1.0, variance)) - log_reference
            residual[lost] = math.log(1.5)
            evaluated[key] = residual
        return evaluated[key]

    def jacobian(x: np.ndarray) -> np.ndarray:
        # Forward differences of a fixed step (scipy's relative step vanishes at x = 0), away from a bound.
        here = residuals(x)
        columns = []
        for i in range(x.size):
            step = DIFF_STEP if x[i] + DIFF_STEP <= upper[i] else -DIFF_STEP
            moved = x.copy()
            moved[i] += step
            columns.append((residuals(moved) - here) / step)
        return np.column_stack(columns)

    solution = optimize.least_squares(
        residuals,
        x0,
        jac=jacobian,
        bounds=(lower, upper),
        loss="soft_l1",
        f_scale=0.05,
        max_nfev=max_evaluations,
        ftol=FIT_COST_TOLERANCE,
        xtol=FIT_STEP_TOLERANCE,
    )
    noise_keys = ("sensor.full_well_e", "sensor.noise.read_noise_e")
    for name, value, low, high in zip(noise_keys, solution.x[:2], lower[:2], upper[:2], strict=True):
        if min(value - low, high - value) < 1e-3:
            warnings.append(f"the fitted {name} sits at its bound; the NLF may need a parameter this fit lacks")
    if not solution.success:
        warnings.append(f"the optimiser stopped early: {solution.message}")

    sigma_x = _sigma(jacobian(solution.x), residuals(solution.x))
    pedestal_share = 0.0
    if start.isp.contrast_stretch is not None:
        # d log(variance)/d log(read noise) = 2 × read noise's share of the variance; the first compared
        # bin of each channel is its darkest (the residuals run channel by channel, bins ascending).
        read_column = jacobian(solution.x)[: int(mask.sum()), 1]
        channel_rows = np.argwhere(mask)[:, 0]
        darkest = [int(np.flatnonzero(channel_rows == c)[0]) for c in np.unique(channel_rows)]
        pedestal_share = float(np.max(read_column[darkest])) / 2.0
    if pedestal_share > PEDESTAL_READ_SHARE:
        warnings.append(
            "the fit attributes most of the noise variance at the darkest levels it compared to read noise; with a "
            "contrast stretch, a scene whose darkest point is not black (the stretch's low limit above 0) adds "
            "the same constant variance, so read noise and full well are not separable from this "
            "footage: include true black in the view (a shadow, a dark object) and fit again"
        )

    fitted_raw = profile_at(solution.x)
    scale = fitted_raw.sensor.full_well_e / sensor.full_well_e
    values["sensor.full_well_e"] = _round(fitted_raw.sensor.full_well_e)
    values["sensor.conversion_gain_dn_per_e"] = _round(sensor.conversion_gain_dn_per_e / scale)
    values["sensor.noise.read_noise_e"] = _round(fitted_raw.sensor.noise.read_noise_e)
    if fit_denoise:
        values["isp.denoise_strength"] = _round(fitted_raw.isp.denoise_strength)
    # First order: a value exp(x)·v₀ has σ = value·σ_x; the denoise strength is x itself.
    log_sigma = {
        "sensor.full_well_e": sigma_x[0],
        "sensor.conversion_gain_dn_per_e": sigma_x[0],
        "sensor.noise.read_noise_e": sigma_x[1],
    }
    uncertainties = {key: _round(values[key] * sigma) for key, sigma in log_sigma.items()}
    if fit_denoise:
        uncertainties["isp.denoise_strength"] = _round(sigma_x[2])
    for key in ("sensor.full_well_e", "sensor.noise.read_noise_e", "isp.denoise_strength"):
        if key not in uncertainties:
            continue
        spread = uncertainties[key] if key == "isp.denoise_strength" else log_sigma[key]
        if spread > UNCONSTRAINED_SIGMA:
            shown = f"±{spread:.2g}" if key == "isp.denoise_strength" else f"±{spread:.0%}"
            why = " (swamped by shot noise: it shows only in the darkest bins)" if "read_noise" in key else ""
            warnings.append(
                f"{key} is hardly constrained by this reference (1σ {shown}){why}; the fitted value is not a "
                "measurement"
            )
    profile = _with_values(base, values)
    light = light_at(solution.x)
    fitted = measure(profile, light)
    base_nlf = measure(base, light)
    with np.errstate(invalid="ignore", divide="ignore"):
        relative = fitted.variance / reference.variance - 1.0
    worst = float(np.nanmax(np.abs(relative[mask]))) if np.isfinite(relative[mask]).any() else math.nan
    if not worst <= WORST_BIN_WARNING:
        warnings.append(f"the fitted NLF misses the reference by up to {worst:.0%} in a bin")
    return MatchFit(
        reference=reference,
        fitted=fitted,
        base=base_nlf,
        parameters=values,
        relative_error_per_bin=relative,
        worst_relative_error=worst,
        profile=profile,
        warnings=tuple(warnings),
        tone=tone,
        light_rgb=light,
        evaluations=len(evaluated),
        uncertainties=uncertainties,
    )


def _sigma(jacobian: np.ndarray, residuals: np.ndarray) -> np.ndarray:
    """1σ of the least-squares variables: sqrt(diag((JᵀJ)⁻¹)·s²), s² = Σr²/(m − n); inf for a variable
    the residuals do not respond to, NaN without spare residuals."""
    m, n = jacobian.shape
    if m <= n:
        return np.full(n, math.nan)
    s2 = float(np.sum(residuals**2)) / (m - n)
    information = jacobian.T @ jacobian
    sigma = np.full(n, math.inf)
    responds = np.any(jacobian != 0, axis=0)
    if responds.any():
        sub = information[np.ix_(responds, responds)]
        try:
            covariance = np.linalg.inv(sub) * s2
        except np.linalg.LinAlgError:
            return sigma
        sigma[responds] = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
    return sigma
