"""Contrast stretch with adaptation: the output range follows the image's percentiles, slowly.

A surveillance ISP maps the [low, high] percentiles of the image to the output range (the seed paper's
Fig. 7) and, after a sudden change of light, moves those limits towards the new ones with a time
constant, the "adaptation speed": the picture is briefly too dark or too bright, then recovers.

The limits come cheaply from a histogram of a strided subsample of the 16-bit image
(`stretch_limits`); `adapt_limits` is the first-order low-pass filter between frames.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import cv2
import numpy as np

_FLOAT32_EXACT_COUNT = 2**24
"""OpenCV's histogram counts in float32, exact up to this many samples."""


def percentiles_from_histogram(hist: np.ndarray, percentiles: float | Sequence[float]) -> np.ndarray:
    """Percentiles of integer samples given only their histogram.

    Parameters
    ----------
    hist : (N,) int or float
        hist[v] is the number of samples of value v (non-negative, total > 0).
    percentiles : float or sequence of float
        Percentiles to compute, each in [0, 100].

    Returns
    -------
    ndarray of float64, the shape of `percentiles`
        Values in bin-index units (bin v holds value v).

    Raises
    ------
    ValueError
        For a histogram that is not 1-D, has negative or non-finite counts or none at all, or a
        percentile outside [0, 100].

    Notes
    -----
    Exactly ``np.percentile(samples, p, method="linear")`` of the samples the histogram counts: with
    n samples sorted as s_0 ≤ … ≤ s_{n−1} and cumulative counts C_v = Σ_{u ≤ v} hist[u], the sample of
    rank r is s_r = min{v : C_v > r}, and at the position h = (p/100)·(n − 1)

        P(p) = s_⌊h⌋ + (h − ⌊h⌋)·(s_{⌊h⌋+1} − s_⌊h⌋),

    interpolating linearly between the two samples that bracket it (Hyndman & Fan 1996, definition 7).
    For a histogram of binned data the result is within one bin of the percentile of the samples.
    ≈ 0.05 ms for 65 536 bins.

    Reference: R. J. Hyndman and Y. Fan, "Sample quantiles in statistical packages", The American
    Statistician 50(4), 361–365 (1996).
    """
    counts = np.asarray(hist)
    if counts.ndim != 1 or counts.size == 0:
        raise ValueError(f"hist must be a non-empty 1-D array of counts, got shape {counts.shape}")
    # Integer counts are summed as int64, 10× faster than floats; the sum runs in place in a fresh
    # copy, since a second 0.5 MB temporary costs 0.4 ms of page faults.
    integer = np.issubdtype(counts.dtype, np.integer) or counts.dtype == np.bool_
    cumulative = counts.astype(np.int64 if integer else np.float64)
    np.cumsum(cumulative, out=cumulative)
    total = cumulative[-1]
    if not np.isfinite(total) or counts.min() < 0:
        raise ValueError("hist must hold finite counts ≥ 0")
    if total <= 0:
        raise ValueError("hist holds no samples (all counts are 0); percentiles are undefined")
    p = np.asarray(percentiles, dtype=np.float64)
    if not np.all((p >= 0) & (p <= 100)):
        raise ValueError(f"percentiles must lie in [0, 100], got {percentiles!r}")
    position = p / 100.0 * max(float(total) - 1.0, 0.0)
    rank = np.floor(position).astype(cumulative.dtype)
    below = np.searchsorted(cumulative, rank, side="right")
    above = np.searchsorted(cumulative, np.minimum(rank + 1, total - 1), side="right")
    return below + (position - rank) * (above - below)


def stretch_limits(
    samples_u16: np.ndarray,
    low_percentile: float,
    high_percentile: float,
    *,
    subsample: int = 4,
) -> tuple[float, float]:
    """The [low, high] percentiles of a 16-bit image, from a strided subsample, as stretch limits.

    Parameters
    ----------
    samples_u16 : uint16 array, any shape
        The image, DN. For ndim ≥ 2 the first two axes (rows, columns) are subsampled and all further
        axes (channels) kept; a 1-D array is subsampled along its only axis.
    low_percentile, high_percentile : float
        Percentiles in [0, 100] mapped to the bottom and the top of the output range,
        low_percentile < high_percentile.
    subsample : int
        Sampling stride along each subsampled axis (≥ 1), raised to the next odd number (4 → 5) so that
        rows and columns of both parities are read: on a Bayer mosaic an even stride would sample a
        single CFA phase, i.e. one colour.

    Returns
    -------
    (low, high) : tuple of float
        Limits, DN, with high ≥ low + 1: a flat image (high = low) is widened to high = low + 1 so the
        stretch (x − low)/(high − low) stays finite.

    Raises
    ------
    ValueError
        For a non-uint16 or empty image, percentiles outside [0, 100] or not increasing, or a subsample
        below 1.

    Notes
    -----
    The histogram (``cv2.calcHist``, exact below 2^24 samples, beyond which ``np.bincount`` is used)
    is read by `percentiles_from_histogram`, so the limits equal ``np.percentile`` of the subsample.
    ≈ 0.6 ms at 1080p (H, W, 3) on 2 cores with subsample 4 (stride 5, 250 000 samples): 0.3 ms
    gathering the strided subsample, 0.2 ms for the histogram; ≈ 0.26 ms for a 1080p mosaic (83 000
    samples). ``np.bincount`` instead of ``cv2.calcHist`` doubles the histogram's cost (it widens every
    sample to int64).
    """
    if not isinstance(samples_u16, np.ndarray) or samples_u16.dtype != np.uint16 or samples_u16.size == 0:
        got = (
            f"{samples_u16.dtype} array of shape {samples_u16.shape}"
            if isinstance(samples_u16, np.ndarray)
            else type(samples_u16)
        )
        raise ValueError(f"samples_u16 must be a non-empty uint16 array, got {got}")
    if not 0 <= low_percentile < high_percentile <= 100:
        raise ValueError(
            "percentiles must satisfy 0 ≤ low_percentile < high_percentile ≤ 100, "
            f"got low {low_percentile}, high {high_percentile}"
        )
    if isinstance(subsample, bool) or not isinstance(subsample, int | np.integer) or subsample < 1:
        raise ValueError(f"subsample must be an integer ≥ 1, got {subsample!r}")
    stride = int(subsample) | 1
    strided = samples_u16[::stride] if samples_u16.ndim == 1 else samples_u16[::stride, ::stride]
    flat = np.ascontiguousarray(strided).reshape(1, -1)
    if flat.size < _FLOAT32_EXACT_COUNT:
        hist = cv2.calcHist([flat], [0], None, [65536], [0, 65536]).ravel().astype(np.int64)
    else:
        hist = np.bincount(flat.ravel(), minlength=65536)
    low, high = percentiles_from_histogram(hist, (low_percentile, high_percentile))
    return float(low), float(max(high, low + 1.0))


def adapt_limits(
    previous: tuple[float, float] | None,
    target: tuple[float, float],
    *,
    frame_interval_s: float,
    adaptation_time_s: float,
) -> tuple[float, float]:
    """Move the stretch limits one frame towards their target (first-order adaptation).

    Parameters
    ----------
    previous : (low, high) or None
        Limits used for the previous frame, DN; None for the first frame.
    target : (low, high)
        Limits measured on this frame (`stretch_limits`), DN.
    frame_interval_s : float
        Time between frames Δt, s (> 0).
    adaptation_time_s : float
        Time constant τ, s (≥ 0); 0 adapts instantly.

    Returns
    -------
    (low, high) : tuple of float
        Limits for this frame, DN. If both `previous` and `target` have high > low, so does the result.

    Raises
    ------
    ValueError
        For Δt ≤ 0, τ < 0, either not finite, or limits that are not two finite numbers.

    Notes
    -----
    Each limit follows the exact discretisation of dx/dt = (target − x)/τ over one frame,

        x_n = x_{n−1} + (target − x_{n−1})·(1 − exp(−Δt/τ)),

    so after a step in the target the remaining fraction of the step after k frames is exp(−k·Δt/τ)
    (37 % after τ, 5 % after 3τ), independent of the frame rate. τ = 0 or no previous limits return
    the target.
    """
    if not (math.isfinite(frame_interval_s) and frame_interval_s > 0):
        raise ValueError(f"frame_interval_s must be finite and > 0, got {frame_interval_s}")
    if not (math.isfinite(adaptation_time_s) and adaptation_time_s >= 0):
        raise ValueError(f"adaptation_time_s must be finite and ≥ 0, got {adaptation_time_s}")
    target_low, target_high = _check_limits("target", target)
    if previous is None or adaptation_time_s == 0:
        return target_low, target_high
    previous_low, previous_high = _check_limits("previous", previous)
    step = -math.expm1(-frame_interval_s / adaptation_time_s)
    return (
        previous_low + (target_low - previous_low) * step,
        previous_high + (target_high - previous_high) * step,
    )


def _check_limits(name: str, limits: object) -> tuple[float, float]:
    values = np.asarray(limits, dtype=np.float64)
    if values.shape != (2,) or not np.all(np.isfinite(values)):
        raise ValueError(f"{name} must be two finite numbers (low, high), got {limits!r}")
    return float(values[0]), float(values[1])


def limit_stretch_gain(limits: tuple[float, float], *, full_scale: float, max_gain: float) -> tuple[float, float]:
    """Widen stretch limits about their midpoint so the stretch amplifies at most `max_gain` times.

    A camera's auto-contrast has a largest gain: a nearly flat scene (fog, a saturated frame) keeps its
    low contrast instead of having its noise stretched over the whole output range. The widened window
    [lo, hi] with hi − lo = full_scale / max_gain is shifted back inside [0, full_scale] if needed.
    """
    lo, hi = limits
    span = full_scale / max_gain
    if hi - lo >= span:
        return limits
    lo = min(max(0.5 * (lo + hi) - 0.5 * span, 0.0), full_scale - span)
    return lo, lo + span
