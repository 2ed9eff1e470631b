"""Judging a `camgen.fit.match.fit_match` result by what it renders.

After the fit, the matched profile films the reference-like content once more, *through its own exposure
block* (the operating point the match pins: `OperatingPoint`) under the light that gave the fit its
output levels, with a seed independent of the fit's, through the reference's codec when there is one.
Its output is measured as the reference was and compared on three figures:

- the noise level function (NLF, Liu et al. 2006), per channel and intensity bin: the relative error
  camgen / reference − 1, checked in every bin whose statistical error is small against the tolerance
  (`STANDARD_ERROR_MAX`);
- the temporal noise spectrum, as the normalised structure function S_k = D_k / D_1 of the noise at
  frame lags k = 1 … 4, D_k = E[(x_{t+k} − x_t)²] / 2 = σ²(1 − ρ_k) with ρ_k the autocorrelation at lag k
  (pooled over the static, unclipped pixels). Frame-independent noise gives S_k = 1; noise filtered in
  time (temporal noise reduction, AR(1) with ρ) gives (1 − ρ^k)/(1 − ρ), 1, 1.6, 1.96, 2.18 for ρ = 0.6;
  a codec that skips static blocks makes it grow until the next intra frame. The structure function
  is preferred to ρ_k from the plain temporal variance because a slow drift or flicker of the light
  (δ codes per frame) lifts that variance by δ²(T² − 1)/12 over T frames (1.3 code² for 0.02 code per frame
  over 200 frames, as much as the noise itself) but D_k only by δ²k²/2;
- blockiness: the mean squared step of the frame-to-frame difference (the noise, with the static scene
  cancelled) across the 8 × 8 block grid (offset 7 → 8) over that inside the blocks at the same CFA
  parity (offsets 1 → 2, 3 → 4, 5 → 6), in flat regions of the picture: 1 for noise without block
  structure, above 1 where a block-based codec quantises the noise block by block (after Wang, Bovik and
  Evans 2000, who compare differences across and inside block boundaries of the picture itself).

A spatial reference (single images) has no frame sequence: its spectrum and blockiness are not
measured (NaN), only its NLF is checked.

Every figure must agree within `TOLERANCE` (15 %, issue 24's goal); otherwise `fit_match` refuses with
`MatchNotReproducedError` unless the caller accepts a poor match, in which case the doubts become the
fit's warnings.

References
----------
C. Liu, W. T. Freeman, R. Szeliski and S. B. Kang, "Noise estimation from a single image", CVPR 2006.
Z. Wang, A. C. Bovik and B. L. Evans, "Blind measurement of blocking artifacts in images", ICIP 2000.
A. N. Kolmogorov, structure functions of random processes (1941); D_k as used here is the
semi-variogram of the per-pixel time series (G. Matheron, "Principles of geostatistics", 1963).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from camgen.fit.match_nlf import NoiseLevelFunction
from camgen.fit.match_statistics import BLOCK_PX, SPECTRUM_LAGS, ReferenceContentError, _Statistics

TOLERANCE = 0.15
"""Largest relative disagreement of any checked figure (issue 24: "agreement within 15 % in every
intensity bin with enough samples"); the structure function and the blockiness are held to it too."""
STANDARD_ERROR_MAX = TOLERANCE / 4
"""An NLF bin is checked when the statistical relative error of camgen / reference there (both sides,
`_relative_standard_error`) is at most this: a correct match then passes a bin with 4σ to spare, so over
the ~40 bins of three channels a refusal by chance has a probability of about 0.3 %."""
CORRELATED_NEIGHBOURS = 4
"""Demosaicing, sharpening and codecs correlate the noise of neighbouring pixels: a bin's samples count
as this many times fewer independent ones in its standard error (a 2 × 2 neighbourhood)."""
SPATIAL_DOF = 61.0
"""Degrees of freedom of an 8 × 8 block's plane residual (`camgen.fit.match_nlf`)."""
FLAT_RANGE_CODES = 12.0
"""Blockiness counts a pair of pixels only where the temporal mean varies by at most this many codes over
the 5 × 5 pixels around each (`FLAT_WINDOW_PX`): the noise beside a content edge differs from the noise
away from it (edge-aware denoise, sharpening), and edges that happen to fall on the block grid (a
40-px-banded test scene: 1.135 in a lossless reference) would count as blockiness."""
FLAT_WINDOW_PX = 5
STRUCTURE_VARIANCE_MIN_CODE2 = 0.02
"""Below this pooled successive-difference variance (codes²) the noise is mostly 8-bit rounding, whose
structure function is not the sensor's: the spectrum is then not compared."""
CHANNELS = "RGB"


class MatchNotReproducedError(ReferenceContentError):
    """The matched profile does not reproduce the reference (`fit_match` refuses it); `fit` holds the
    `MatchFit` it refused, with its verification, for a report."""

    def __init__(self, message: str, fit=None):
        super().__init__(message)
        self.fit = fit


@dataclass(frozen=True)
class OperatingPoint:
    """The exposure the match was fitted at and pins in the matched profile.

    Attributes
    ----------
    exposure_time_s : float
    gain_db : float
        Analog gain, dB: invisible in 8-bit output, so the fit's assumption (``gain_db``, default the
        base profile's); the fitted full well is the effective one at this gain.
    f_number : float
    mean_luminance_cd_m2 : float
        Mean scene luminance over the metering window that gives the reference's output levels at this
        exposure (per colour band, the camera equation of `camgen.sensor.exposure`); scale the exposure
        time inversely to render the same noise under another light.
    was_auto : bool
        The base profile left exposure to auto-exposure, which the matched profile replaces by this
        manual setting.
    """

    exposure_time_s: float
    gain_db: float
    f_number: float
    mean_luminance_cd_m2: float
    was_auto: bool

    def describe(self) -> str:
        """One line: what was pinned and why."""
        why = (
            "the noise of 8-bit output is set by the electrons per output code, which the fitted full well and "
            "read noise give only at the gain the fit assumed; auto-exposure would pick its own gain (and time) "
            "for a rendered scene"
        )
        pinned = (
            "replaces the base profile's auto-exposure"
            if self.was_auto
            else "the base profile's manual exposure time, at the gain the fit assumed"
        )
        return (
            f"operating point pinned: manual exposure {self.exposure_time_s:.4g} s at {self.gain_db:.3g} dB "
            f"({pinned}): {why}; at f/{self.f_number:.3g} a scene of mean luminance "
            f"{self.mean_luminance_cd_m2:.4g} cd/m² gives the reference's levels (scale the exposure time "
            "inversely for another light)"
        )


@dataclass(frozen=True)
class MatchVerification:
    """The matched profile's output at its operating point against the reference (module docstring).

    Attributes
    ----------
    nlf : NoiseLevelFunction
        Camgen's NLF through the matched profile (independent seed), same method and bins.
    relative_error_per_bin : (3, B) float64
        nlf.variance / reference.variance − 1 (NaN where either is).
    checked : (3, B) bool
        The bins held to `TOLERANCE`: usable on both sides, statistical error ≤ `STANDARD_ERROR_MAX`.
    worst_relative_error : float
        Largest |error| over the checked bins (NaN if none).
    reference_structure, structure : (K,) float64
        S_k = D_k / D_1 for k = 1 … K of the reference and of camgen (NaN when not measured).
    structure_error : (K,) float64
        structure / reference_structure − 1.
    reference_blockiness, blockiness : float
        Boundary over interior mean squared step of the frame difference (NaN when not measured).
    blockiness_error : float
    exposure_time_s, gain_db : float
        The exposure the matched profile's exposure block set for the verification.
    seed : int
        The verification's seed (independent of the fit's).
    doubts : tuple of str
        Every figure outside `TOLERANCE`, as sentences; empty when the match reproduces the reference.
    """

    nlf: NoiseLevelFunction
    relative_error_per_bin: np.ndarray
    checked: np.ndarray
    worst_relative_error: float
    reference_structure: np.ndarray
    structure: np.ndarray
    structure_error: np.ndarray
    reference_blockiness: float
    blockiness: float
    blockiness_error: float
    exposure_time_s: float
    gain_db: float
    seed: int
    doubts: tuple[str, ...]

    @property
    def reproduces(self) -> bool:
        return not self.doubts

    def summary(self) -> str:
        """The figures in one line."""
        worst = self.worst_relative_error
        parts = [
            f"worst NLF bin {worst:.1%} off, of {int(self.checked.sum())} bins with enough samples"
            if math.isfinite(worst)
            else "no NLF bin with enough samples"
        ]
        if np.isfinite(self.structure_error).any():
            lags = ", ".join(
                f"{s:.2f}/{r:.2f}" for s, r in zip(self.structure[1:], self.reference_structure[1:], strict=True)
            )
            parts.append(
                f"temporal structure D_k/D_1 at lags 2–{self.structure.size} camgen/reference {lags} "
                f"(worst {np.nanmax(np.abs(self.structure_error)):.1%})"
            )
        if math.isfinite(self.blockiness_error):
            parts.append(
                f"blockiness {self.blockiness:.3f}/{self.reference_blockiness:.3f} ({self.blockiness_error:+.1%})"
            )
        return "; ".join(parts)


def _relative_standard_error(nlf: NoiseLevelFunction) -> np.ndarray:
    """(3, B) statistical relative standard error of each bin's variance: sqrt(2 / (ν · N_eff)), ν the
    per-sample degrees of freedom (temporal: Satterthwaite's 2n²/(3n − 1) of n successive differences;
    spatial: 61), N_eff the bin's samples over `CORRELATED_NEIGHBOURS`."""
    if nlf.method == "temporal":
        n = max(nlf.frames - 1, 1)
        dof = 2.0 * n * n / (3.0 * n - 1.0)
    else:
        dof = SPATIAL_DOF
    with np.errstate(divide="ignore"):
        return np.sqrt(2.0 * CORRELATED_NEIGHBOURS / (dof * np.maximum(nlf.count, 0)))


def _used_pixels(statistics: _Statistics) -> np.ndarray:
    """(H, W, 3) bool: static pixels whose samples never touch 0 or 255."""
    return ~statistics.moving[..., None] & ~statistics.saturated


def _flat_pixels(statistics: _Statistics) -> np.ndarray:
    """(H, W, 3) bool: pixels whose temporal mean ranges over at most `FLAT_RANGE_CODES` in the
    `FLAT_WINDOW_PX` square around them."""
    mean = (statistics.total / statistics.frames).astype(np.float32)
    kernel = np.ones((FLAT_WINDOW_PX, FLAT_WINDOW_PX), np.uint8)
    return (cv2.dilate(mean, kernel) - cv2.erode(mean, kernel)) <= FLAT_RANGE_CODES


def temporal_structure(statistics: _Statistics) -> np.ndarray:
    """(K,) S_k = D_k / D_1 pooled over the static, unclipped pixels (module docstring); NaN when the
    spectrum was not collected, a light step left a pair of frames out, there are too few frames, or
    the noise is below `STRUCTURE_VARIANCE_MIN_CODE2`."""
    out = np.full(SPECTRUM_LAGS, math.nan)
    frames = statistics.frames
    if (
        not statistics.lag_squared_differences
        or statistics.skipped_pairs
        or frames < 2 * SPECTRUM_LAGS
        or statistics.pairs != frames - 1
    ):
        return out
    used = _used_pixels(statistics)
    if not used.any():
        return out
    pixels = int(np.count_nonzero(used))
    d1 = float(np.sum(statistics.squared_differences[used])) / (2.0 * (frames - 1) * pixels)
    if not d1 >= STRUCTURE_VARIANCE_MIN_CODE2:
        return out
    out[0] = 1.0
    for k, sums in enumerate(statistics.lag_squared_differences, start=2):
        out[k - 1] = float(np.sum(sums[used])) / (2.0 * (frames - k) * pixels) / d1
    return out


def blockiness(statistics: _Statistics) -> float:
    """Mean squared step of the frame difference across the 8 × 8 block grid over inside it, at the same
    CFA parity, pooled over rows and columns of static unclipped pixel pairs (module docstring); NaN
    without the spectrum pass or where nothing is measured."""
    if not statistics.block_steps or statistics.pairs == 0:
        return math.nan
    used = _used_pixels(statistics) & _flat_pixels(statistics)
    across = inside = 0.0
    count_across = count_inside = 0
    for name, axis in (("x", 1), ("y", 0)):
        steps = statistics.block_steps[name]
        length = steps.shape[axis]
        first = np.take(used, np.arange(1, 2 * length, 2), axis=axis)
        second = np.take(used, np.arange(2, 2 * length + 1, 2), axis=axis)
        both = first & second
        offset = np.arange(1, 2 * length, 2) % BLOCK_PX
        shape = [1, 1, 1]
        shape[axis] = length
        boundary = (offset == BLOCK_PX - 1).reshape(shape)
        across += float(np.sum(steps[both & boundary]))
        count_across += int(np.count_nonzero(both & boundary))
        inside += float(np.sum(steps[both & ~boundary]))
        count_inside += int(np.count_nonzero(both & ~boundary))
    if count_across == 0 or count_inside == 0 or inside <= 0:
        return math.nan
    return (across / count_across) / (inside / count_inside)


def compare(
    reference: NoiseLevelFunction,
    reference_statistics: _Statistics,
    simulated: NoiseLevelFunction,
    simulated_statistics: _Statistics | None,
    *,
    exposure_time_s: float,
    gain_db: float,
    seed: int,
) -> MatchVerification:
    """The verification's figures and doubts from both sides' NLF and statistics (module docstring)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        relative = simulated.variance / reference.variance - 1.0
    error = np.hypot(_relative_standard_error(reference), _relative_standard_error(simulated))
    checked = (
        reference.usable
        & simulated.usable
        & (reference.variance > 0)
        & (simulated.variance > 0)
        & (error <= STANDARD_ERROR_MAX)
    )
    worst = float(np.max(np.abs(relative[checked]))) if checked.any() else math.nan
    doubts = []
    if checked.any() and worst > TOLERANCE:
        c, b = np.unravel_index(np.argmax(np.where(checked, np.abs(relative), -1.0)), relative.shape)
        low, high = reference.bin_edges[b], reference.bin_edges[b + 1]
        doubts.append(
            f"rendered through the matched profile at its operating point, camgen's noise level function misses "
            f"the reference by {relative[c, b]:+.0%} in the {CHANNELS[c]} channel's bin {low:g}–{high:g} codes "
            f"(variance {simulated.variance[c, b]:.3g} against {reference.variance[c, b]:.3g} code²; worst of "
            f"{int(checked.sum())} bins with enough samples, tolerance {TOLERANCE:.0%})"
        )
    elif not checked.any():
        doubts.append(
            "no intensity bin holds enough samples on both sides to check the matched profile's noise level "
            f"function (statistical error ≤ {STANDARD_ERROR_MAX:.1%}); give more or larger reference frames"
        )
    if simulated_statistics is not None and reference.method == "temporal":
        reference_structure = temporal_structure(reference_statistics)
        structure = temporal_structure(simulated_statistics)
        reference_blocks, blocks = blockiness(reference_statistics), blockiness(simulated_statistics)
    else:
        reference_structure = structure = np.full(SPECTRUM_LAGS, math.nan)
        reference_blocks = blocks = math.nan
    structure_error = structure / reference_structure - 1.0
    if np.isfinite(structure_error).any() and np.nanmax(np.abs(structure_error)) > TOLERANCE:
        k = int(np.nanargmax(np.abs(structure_error)))
        doubts.append(
            f"the temporal noise spectrum differs: the noise's structure function D_k/D_1 at a lag of {k + 1} "
            f"frames is {structure[k]:.2f} in camgen's output against {reference_structure[k]:.2f} in the "
            f"reference ({structure_error[k]:+.0%}; 1 for noise independent from frame to frame): the reference's "
            "noise is filtered in time (temporal noise reduction in the camera, or a codec's inter-frame "
            "prediction) in a way camgen's sensor and codec do not reproduce"
        )
    blockiness_error = blocks / reference_blocks - 1.0 if math.isfinite(blocks / reference_blocks) else math.nan
    if math.isfinite(blockiness_error) and abs(blockiness_error) > TOLERANCE:
        doubts.append(
            f"the noise's blockiness (mean squared step across the 8 × 8 block grid over inside it) is "
            f"{blocks:.3f} in camgen's output against {reference_blocks:.3f} in the reference "
            f"({blockiness_error:+.0%}): the reference's codec quantises its noise differently from the profile's"
        )
    return MatchVerification(
        nlf=simulated,
        relative_error_per_bin=relative,
        checked=checked,
        worst_relative_error=worst,
        reference_structure=reference_structure,
        structure=structure,
        structure_error=structure_error,
        reference_blockiness=reference_blocks,
        blockiness=blocks,
        blockiness_error=blockiness_error,
        exposure_time_s=exposure_time_s,
        gain_db=gain_db,
        seed=seed,
        doubts=tuple(doubts),
    )
