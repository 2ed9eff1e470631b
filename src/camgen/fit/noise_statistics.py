"""Channels, tiles and the small statistics of the sensor noise fit, after EMVA 1288 release 4.0 [1]_.

A measured figure with its 1σ standard uncertainty (`Estimate`); the channels of a CFA and the Bayer
phase each samples (`channel_phases`); a channel image and its tiles, whose scatter gives each figure's
uncertainty (`_regions`, `_estimate`; see `camgen.fit.noise`); masked means and variances,
least-squares lines, robust σ [2]_, medians and weighted means, and the conversion of a figure in DN
to electrons with its uncertainty.

References
----------
.. [1] EMVA Standard 1288, "Standard for Characterization of Image Sensors and Cameras", release 4.0
   Linear, European Machine Vision Association, 2021.
.. [2] P. J. Rousseeuw, C. Croux, "Alternatives to the median absolute deviation", JASA 88(424),
   pp. 1273–1283, 1993 (MAD, scaled by 1.4826 to estimate a normal σ).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

MAD_TO_SIGMA = 1.4826
"""σ of a normal distribution per median absolute deviation [2]_."""
CHANNEL_ORDER = ("R", "Gr", "Gb", "B")


@dataclass(frozen=True)
class Estimate:
    """A measured figure and its 1σ standard uncertainty, in the same unit (NaN: not known)."""

    value: float
    uncertainty: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "value", float(self.value))
        object.__setattr__(self, "uncertainty", float(self.uncertainty))


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
