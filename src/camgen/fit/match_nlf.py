"""The noise level function (NLF) of 8-bit output: its noise variance against its mean intensity, per
channel, after Liu et al. (2006, 2008), estimated from frames of a static view or from images.

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
below `camgen.fit.match.TEMPORAL_CORRELATION_RATIO_MIN` earns `fit_match` a warning.

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
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Literal

import numpy as np
from scipy import special

from camgen.errors import ConfigError
from camgen.fit.match_statistics import BLOCK_PX, ReferenceContentError, _collect, _Statistics

DEFAULT_BINS = 32
"""Intensity bins over 0…256 (8 codes each)."""
MIN_COUNT = MappingProxyType({"temporal": 200, "spatial": 24})
"""Default fewest samples (pixels; blocks) a bin needs for its variance."""
STATIC_FRACTION_MIN = 0.5
"""`method="auto"` takes the temporal method only if at least this fraction of the pixels is static."""
TEMPORAL_FRAMES_MIN = 8
"""`method="auto"` takes the temporal method from this many frames of one size."""
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
