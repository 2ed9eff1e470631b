"""Spatial non-uniformity of an averaged channel image, after EMVA 1288 release 4.0 [1]_ §8.

The split of the image's spatial variance into its pixel, row and column parts, on the whole image, its
tiles and its horizontal and vertical bands (`_spatial_variances`); the horizontal and vertical
spectrograms (§8.6, `Spectrogram`); the corrections of a flat for uneven illumination: the standard's
high-pass filter (`highpass_filtered`) or a fitted illumination surface (`_shading_surface`); and the
local block median that fills hot and dead pixels (`_filled`). The `emva1288` reference implementation
[2]_ computes the same spatial variances.

References
----------
.. [1] EMVA Standard 1288, "Standard for Characterization of Image Sensors and Cameras", release 4.0
   Linear, European Machine Vision Association, 2021.
.. [2] EMVA 1288 reference implementation, `emva1288` 1.0.2 (release 4.0), https://github.com/EMVA1288/emva1288
   (``process/results.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from camgen.fit.noise_statistics import Estimate, Region, _estimate, _grid_regions

DEAD_MEDIAN_BLOCK_PX = 16
"""Side of the blocks (channel pixels) whose median is the local response for dead pixels."""
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
