"""Optional ISP post-processing on the 8-bit output, as camera ISPs do: spatial denoise and sharpening.

Both work on (H, W, 3) RGB or (H, W) grey uint8 images and return the input object itself when
switched off (strength or amount 0), so an unused stage costs nothing.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

DENOISE_DIAMETER_PX = 5
"""Bilateral window: the sites within 2 px of the centre (13 taps)."""
DENOISE_SIGMA_COLOR_AT_FULL_STRENGTH = 50.0
"""σ_r of the bilateral range weight at strength 1, 8-bit codes (summed |Δ| over channels for RGB)."""
DENOISE_SIGMA_SPACE_PX = 2.0
"""σ_s of the bilateral spatial weight, px."""


def denoise(rgb8: np.ndarray, strength: float) -> np.ndarray:
    """Edge-preserving spatial denoise (bilateral filter).

    Parameters
    ----------
    rgb8 : (H, W, 3) or (H, W) uint8
        RGB or grey image.
    strength : float
        0 … 1. It scales the range σ_r = 50·strength codes: differences well below σ_r are averaged
        away as noise, steps well above it are kept as edges. 0 returns `rgb8` itself.

    Returns
    -------
    uint8 array, the shape of `rgb8`

    Raises
    ------
    ValueError
        For an image that is not uint8 (H, W) or (H, W, 3), or a strength outside [0, 1].

    Notes
    -----
    out(p) = Σ_q w(p, q)·I(q) / Σ_q w(p, q) over |q − p| ≤ 2 px, with
    w = exp(−|q − p|²/(2σ_s²))·exp(−‖I(q) − I(p)‖₁²/(2σ_r²)), σ_s = 2 px (``cv2.bilateralFilter``,
    d = 5). ≈ 7–8 ms at 1080p RGB on 2 cores; d = 3 (5 taps, less smoothing) costs 2.2 ms, filtering
    luma only 4.2 ms plus two colour conversions, ``cv2.edgePreservingFilter`` 350 ms.

    Reference: C. Tomasi and R. Manduchi, "Bilateral filtering for gray and color images", ICCV 1998.
    """
    _check_image(rgb8)
    if not (math.isfinite(strength) and 0.0 <= strength <= 1.0):
        raise ValueError(f"strength must be in [0, 1], got {strength}")
    if strength == 0:
        return rgb8
    return cv2.bilateralFilter(
        rgb8, DENOISE_DIAMETER_PX, DENOISE_SIGMA_COLOR_AT_FULL_STRENGTH * strength, DENOISE_SIGMA_SPACE_PX
    )


def sharpen(rgb8: np.ndarray, amount: float, radius_px: float) -> np.ndarray:
    """Unsharp mask: add back `amount` times the detail a Gaussian blur removes.

    Parameters
    ----------
    rgb8 : (H, W, 3) or (H, W) uint8
        RGB or grey image.
    amount : float
        Gain a of the detail, ≥ 0; 0 returns `rgb8` itself.
    radius_px : float
        σ of the Gaussian blur, px (> 0).

    Returns
    -------
    uint8 array, the shape of `rgb8`
        out = round((1 + a)·I − a·G_σ * I), saturated to 0 … 255 (no wrap-around).

    Raises
    ------
    ValueError
        For an image that is not uint8 (H, W) or (H, W, 3), a negative or non-finite amount, or a
        radius that is not > 0.

    Notes
    -----
    out = I + a·(I − G_σ * I). The blur is ``cv2.GaussianBlur`` (kernel round(6σ + 1) made odd,
    mirrored border) rounded to 8 bits, the sum ``cv2.addWeighted`` with saturation; the rounded blur
    puts the output within a/2 + 1/2 code of the exact formula. ≈ 2.7 ms at 1080p RGB on 2 cores for
    σ = 1 px (blur 1.5–2 ms, sum 0.7 ms), 4.2 ms for σ = 2 px; blurring in float32 or uint16 instead
    costs 10–14 ms and measured no closer to the exact result for a = 0.5.

    Reference: R. C. Gonzalez and R. E. Woods, *Digital Image Processing*, 4th ed., §3.6 (unsharp
    masking).
    """
    _check_image(rgb8)
    if not (math.isfinite(amount) and amount >= 0):
        raise ValueError(f"amount must be finite and ≥ 0, got {amount}")
    if not (math.isfinite(radius_px) and radius_px > 0):
        raise ValueError(f"radius_px must be finite and > 0, got {radius_px}")
    if amount == 0:
        return rgb8
    blurred = cv2.GaussianBlur(rgb8, (0, 0), sigmaX=radius_px, sigmaY=radius_px)
    return cv2.addWeighted(rgb8, 1.0 + amount, blurred, -amount, 0.0)


def _check_image(rgb8: object) -> None:
    if (
        not isinstance(rgb8, np.ndarray)
        or rgb8.dtype != np.uint8
        or not (rgb8.ndim == 2 or (rgb8.ndim == 3 and rgb8.shape[2] == 3))
        or rgb8.size == 0
    ):
        got = f"{rgb8.dtype} array of shape {rgb8.shape}" if isinstance(rgb8, np.ndarray) else type(rgb8)
        raise ValueError(f"image must be a non-empty (H, W, 3) or (H, W) uint8 array, got {got}")
