"""Tone curves: linear signal in [0, 1] → encoded output, and the 16-bit → 8-bit tables that apply them.

Curves (`TONE_CURVES`); the two standard ones come from colour-science:

- "srgb": the inverse sRGB EOTF (IEC 61966-2-1), V = 12.92·L for L ≤ 0.0031308, else
  1.055·L^(1/2.4) − 0.055 (``colour.models.eotf_inverse_sRGB``);
- "bt709": the BT.709 OETF (ITU-R BT.709-6), V = 4.5·L for L < 0.018, else 1.099·L^0.45 − 0.099
  (``colour.models.oetf_BT709``); with these rounded constants the two pieces meet with a step of
  +2.5·10⁻⁴ at L = 0.018 (0.081 below, 0.0812479 at it), so the curve is still non-decreasing;
- "gamma": V = L^(1/γ);
- "linear": V = L.

A camera applies its curve as one table look-up per sample: `tone_lut` builds the table and
`apply_lut` applies it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from concurrent.futures import Executor

import colour
import cv2
import numpy as np

_U16_VALUES = 65536

_CURVES: dict[str, Callable[[np.ndarray, float], np.ndarray]] = {
    "srgb": lambda x, _gamma: colour.models.eotf_inverse_sRGB(x),
    "bt709": lambda x, _gamma: colour.models.oetf_BT709(x),
    "gamma": lambda x, gamma: np.power(x, 1.0 / gamma),
    "linear": lambda x, _gamma: x,
}
TONE_CURVES = tuple(_CURVES)


def tone_curve(x: np.ndarray, curve: str, gamma: float = 2.2) -> np.ndarray:
    """Encode linear values with a tone curve.

    Parameters
    ----------
    x : array_like, any shape
        Linear signal, relative to white (1). Clipped to [0, 1] first; NaN stays NaN.
    curve : {"srgb", "bt709", "gamma", "linear"}
        The curve (see the module docstring for the equations).
    gamma : float
        Display gamma γ of the "gamma" curve V = x^(1/γ) (finite, > 0); checked but unused otherwise.

    Returns
    -------
    float64 array, the shape of `x`
        Encoded values in [0, 1].

    Raises
    ------
    ValueError
        For an unknown curve (the message names the alternatives) or a bad gamma.

    References
    ----------
    IEC 61966-2-1:1999 (sRGB); ITU-R BT.709-6 (2015), item 1.2.
    """
    transfer = _curve_function(curve, gamma)
    return np.asarray(transfer(np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0), gamma), dtype=np.float64)


def tone_lut(
    curve: str,
    gamma: float = 2.2,
    *,
    size: int = _U16_VALUES,
    output_low_frac: float = 0.0,
    output_high_frac: float = 1.0,
) -> np.ndarray:
    """A table from input code to 8-bit output for a tone curve.

    Parameters
    ----------
    curve : {"srgb", "bt709", "gamma", "linear"}
        The curve (see the module docstring).
    gamma : float
        Display gamma of the "gamma" curve (finite, > 0).
    size : int
        Number of entries (2 … 65536): input code i stands for the linear value i / (size − 1), so
        code size − 1 is white. 65536 for full-range 16-bit input, 2^b for b-bit data.
    output_low_frac, output_high_frac : float
        Output black and white as fractions of 255, 0 ≤ low < high ≤ 1: a camera whose output sits
        inside 0–255 (e.g. 16–235 video levels: 16/255, 235/255).

    Returns
    -------
    (size,) uint8
        Entry i = round(255·(low + (high − low)·curve(i / (size − 1)))) (round half to even);
        non-decreasing, since every curve is.

    Raises
    ------
    ValueError
        For an unknown curve, a bad gamma, a size outside 2 … 65536, or output fractions out of order.

    Notes
    -----
    ≈ 0.3 ms for 65 536 entries; built once per camera, not per frame.
    """
    transfer = _curve_function(curve, gamma)
    if isinstance(size, bool) or not isinstance(size, int | np.integer) or not 2 <= size <= _U16_VALUES:
        raise ValueError(f"size must be an integer in 2 … {_U16_VALUES}, got {size!r}")
    if not 0.0 <= output_low_frac < output_high_frac <= 1.0:
        raise ValueError(
            "output fractions must satisfy 0 ≤ output_low_frac < output_high_frac ≤ 1, "
            f"got low {output_low_frac}, high {output_high_frac}"
        )
    encoded = transfer(np.linspace(0.0, 1.0, int(size)), gamma)
    levels = 255.0 * (output_low_frac + (output_high_frac - output_low_frac) * encoded)
    return np.rint(levels).astype(np.uint8)


def apply_lut(image_u16: np.ndarray, lut_u8: np.ndarray, *, executor: Executor | None = None) -> np.ndarray:
    """Look every sample of a 16-bit image up in an 8-bit table.

    Parameters
    ----------
    image_u16 : uint16 array, any shape (typically (H, W, 3))
        Input codes.
    lut_u8 : (N,) uint8, 1 ≤ N ≤ 65536
        The table (`tone_lut`); codes ≥ N read its last entry, the table's white.
    executor : concurrent.futures.Executor, optional
        Used only while OpenCV runs single-threaded (``cv2.getNumThreads() == 1``, as in a process
        pool that turns OpenCV's threads off): the image is then looked up in two halves (rows), one on
        the executor and one on the calling thread. Otherwise OpenCV already splits the work over its
        own threads, and adding the executor measured 0.3 ms slower.

    Returns
    -------
    uint8 array, the shape of `image_u16`
        out[...] = lut_u8[min(image_u16[...], N − 1)], exactly.

    Raises
    ------
    ValueError
        For an image that is not uint16, or a table that is not 1-D uint8 with 1 … 65536 entries.

    Notes
    -----
    ``cv2.LUT`` accepts 16-bit input with a 65 536-entry table. For (1080, 1920, 3) on 2 cores:
    ≈ 0.9 ms on OpenCV's 2 threads (an executor splitting the work as well measured 1.3 ms, so it is
    left out); on one OpenCV thread 1.7 ms, or 0.9 ms split over a 2-thread ``ThreadPoolExecutor``.
    Measured alternatives, same image: ``lut[image]`` 7.6–7.9 ms, ``np.take(lut, image, out=out)``
    11.9 ms, ``np.take`` on two halves over a 2-thread executor 5.6 ms. A table shorter than 65 536
    entries is padded with its last entry (≈ 10 µs) so that no code can read outside it.
    """
    if not isinstance(image_u16, np.ndarray) or image_u16.dtype != np.uint16:
        got = f"{image_u16.dtype} array" if isinstance(image_u16, np.ndarray) else type(image_u16)
        raise ValueError(f"image_u16 must be a uint16 array, got {got}")
    if (
        not isinstance(lut_u8, np.ndarray)
        or lut_u8.dtype != np.uint8
        or lut_u8.ndim != 1
        or not 1 <= lut_u8.size <= _U16_VALUES
    ):
        got = f"{lut_u8.dtype} array of shape {lut_u8.shape}" if isinstance(lut_u8, np.ndarray) else type(lut_u8)
        raise ValueError(f"lut_u8 must be a 1-D uint8 array of 1 … {_U16_VALUES} entries, got {got}")
    if image_u16.size == 0:
        return np.empty(image_u16.shape, np.uint8)
    if lut_u8.size < _U16_VALUES:
        lut_u8 = np.concatenate([lut_u8, np.full(_U16_VALUES - lut_u8.size, lut_u8[-1], np.uint8)])
    rows = image_u16.reshape(image_u16.shape[0] if image_u16.ndim >= 2 else 1, -1)
    if executor is None or rows.shape[0] < 2 or cv2.getNumThreads() > 1:
        return cv2.LUT(rows, lut_u8).reshape(image_u16.shape)
    out = np.empty(rows.shape, np.uint8)
    half = rows.shape[0] // 2
    first = executor.submit(cv2.LUT, rows[:half], lut_u8, out[:half])
    cv2.LUT(rows[half:], lut_u8, out[half:])
    first.result()
    return out.reshape(image_u16.shape)


def _curve_function(curve: object, gamma: float) -> Callable[[np.ndarray, float], np.ndarray]:
    if not isinstance(curve, str) or curve not in _CURVES:
        raise ValueError(f"unknown tone curve {curve!r}; expected one of {', '.join(TONE_CURVES)}")
    if not (math.isfinite(gamma) and gamma > 0):
        raise ValueError(f"gamma must be finite and > 0, got {gamma}")
    return _CURVES[curve]
