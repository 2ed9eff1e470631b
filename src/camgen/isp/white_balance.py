"""White balance on the raw mosaic: grey-world gains and the per-site gain map that applies them.

Grey world (Buchsbaum 1980) assumes the scene averages to grey, so the mean raw signal of each colour
channel differs only by the light's colour and the sensor's response; scaling each channel by
mean_G / mean_c makes the means equal and leaves green (the channel with most sites and least noise)
unchanged. Gains are computed and applied on the Bayer mosaic, before demosaicing, where a gain is one
multiplication per site instead of three.

Reference: G. Buchsbaum, "A spatial processor model for object colour perception", Journal of the
Franklin Institute 310(1), 1–26 (1980).
"""

from __future__ import annotations

import math

import numpy as np

from camgen.sensor.cfa import cfa_phase_channels, cfa_site_values

UNITY_GAINS_RGB = (1.0, 1.0, 1.0)


def grey_world_gains(
    mosaic: np.ndarray,
    cfa: str,
    black_level_dn: float,
    *,
    white_level_dn: float = 65535.0,
    subsample: int = 4,
) -> np.ndarray:
    """White-balance gains that make the mean signal of R, G and B equal (grey-world assumption).

    Parameters
    ----------
    mosaic : (H, W) uint16
        Raw Bayer mosaic, DN, black level included.
    cfa : {"RGGB", "BGGR", "GRBG", "GBRG"}
        The pattern, named by its top-left 2×2 block read row by row.
    black_level_dn : float
        Offset of a dark site, DN (≥ 0).
    white_level_dn : float
        Sites at or above this value are clipped (saturated): their 2×2 cell, every channel of it, is left
        out of the means, as a camera's AWB leaves out clipped pixels: their values no longer follow the
        light's colour. Default: the uint16 maximum; pass the sensor's 2^bits − 1 (or its lower clip level).
    subsample : int
        Stride, in sites of one Bayer phase, of the samples taken along each axis (≥ 1): every phase is
        sampled at rows ``py + 2·subsample·i`` and columns ``px + 2·subsample·j``, so each colour is
        averaged over the same subset of 2×2 cells.

    Returns
    -------
    (3,) float64
        Gains (g_R, g_G, g_B) with g_G = 1. Unity gains (1, 1, 1) when no sampled cell is free of clipping
        or a channel's mean above black is ≤ 0 (a black or fully clipped frame has no colour to balance).

    Raises
    ------
    ValueError
        For a mosaic that is not a 2-D uint16 array, "mono" or an unknown pattern, a black level that is
        negative or not below the white level, or a subsample below 1.

    Notes
    -----
    With S_c the samples of channel c in cells without a clipped site and b the black level,

        m_c = (1/|S_c|) Σ_{x ∈ S_c} (x − b),        g_c = m_G / m_c.

    Samples below black are kept (as negative signal) so read noise does not bias dark scenes.
    ≈ 0.2 ms at 1080p on 2 cores with subsample 4 (130 000 of the 2.1 M sites).
    """
    if not isinstance(mosaic, np.ndarray) or mosaic.dtype != np.uint16 or mosaic.ndim != 2:
        got = f"{mosaic.dtype} array of shape {mosaic.shape}" if isinstance(mosaic, np.ndarray) else type(mosaic)
        raise ValueError(f"mosaic must be a 2-D (H, W) uint16 array, got {got}")
    phases = cfa_phase_channels(cfa)
    if not math.isfinite(black_level_dn) or black_level_dn < 0:
        raise ValueError(f"black_level_dn must be finite and ≥ 0, got {black_level_dn}")
    if not white_level_dn > black_level_dn:
        raise ValueError(f"white_level_dn must be above black_level_dn ({black_level_dn}), got {white_level_dn}")
    if isinstance(subsample, bool) or not isinstance(subsample, int | np.integer) or subsample < 1:
        raise ValueError(f"subsample must be an integer ≥ 1, got {subsample!r}")
    step = 2 * int(subsample)
    # The same 2×2 cells in every phase (a mosaic of odd size has one row or column fewer of some phases).
    planes = [mosaic[phase // 2 :: step, phase % 2 :: step] for phase in range(4)]
    rows = min(plane.shape[0] for plane in planes)
    cols = min(plane.shape[1] for plane in planes)
    planes = [plane[:rows, :cols] for plane in planes]
    # A cell counts only when none of its sites is clipped: where one channel clips (the blue of a bright
    # sky, the red of a sunset) the others keep rising, and keeping them alone would weigh the cell's colour
    # by the channel that clipped (a dusk sky turned a street green this way).
    unclipped = np.logical_and.reduce([plane < white_level_dn for plane in planes])
    sums = np.zeros(3)
    counts = np.zeros(3)
    for plane, channel in zip(planes, phases, strict=True):
        sums[channel] += np.sum(plane, where=unclipped, dtype=np.float64)
        counts[channel] += np.count_nonzero(unclipped)
    if np.any(counts == 0):
        return np.array(UNITY_GAINS_RGB)
    means = sums / counts - black_level_dn
    if np.any(means <= 0):
        return np.array(UNITY_GAINS_RGB)
    return means[1] / means


def cfa_gain_image(gains_rgb: np.ndarray, cfa: str, height_px: int, width_px: int) -> np.ndarray:
    """The gain of every site of a mosaic, for applying per-channel gains before demosaicing.

    Parameters
    ----------
    gains_rgb : (3,) float
        Gains (g_R, g_G, g_B), finite and ≥ 0.
    cfa : {"RGGB", "BGGR", "GRBG", "GBRG"}
        The pattern, named by its top-left 2×2 block read row by row.
    height_px, width_px : int
        Mosaic size, px (≥ 1).

    Returns
    -------
    (height_px, width_px) float32
        Entry (y, x) = g_c with c the channel of site (y, x) (`camgen.sensor.cfa.cfa_channel_index`).

    Raises
    ------
    ValueError
        For gains that are not 3 finite non-negative numbers, "mono", an unknown pattern or a bad size.

    Notes
    -----
    ≈ 0.15 ms at 1080p on 2 cores (a tiled 2×2 block; indexing the gains with `cfa_channel_index`
    costs 2.7 ms).
    """
    gains = np.asarray(gains_rgb, dtype=np.float64)
    if gains.shape != (3,) or not np.all(np.isfinite(gains)) or np.any(gains < 0):
        raise ValueError(f"gains_rgb must be 3 finite numbers ≥ 0 (R, G, B), got {gains_rgb!r}")
    return cfa_site_values(gains, cfa, height_px, width_px)
