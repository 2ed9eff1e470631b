"""A quick look at linear radiance: global exposure and the sRGB transfer function, nothing else.

This is not a camera model. It shows the ideal pinhole image (and lets tests and demos look at
renders) until the sensor and ISP stages turn radiance into what a camera records.
"""

from __future__ import annotations

import numpy as np

LUMINANCE_WEIGHTS_BT709 = np.array([0.2126, 0.7152, 0.0722], np.float32)


def luminance_cd_m2(radiance_cd_m2: np.ndarray) -> np.ndarray:
    """Y of linear BT.709 RGB radiance (…, 3) → (…), cd/m²."""
    return radiance_cd_m2 @ LUMINANCE_WEIGHTS_BT709


def preview_exposure_scale(radiance_cd_m2: np.ndarray, key: float = 0.18) -> float:
    """Scale that maps the log-average luminance to `key` (Reinhard et al. 2002, eq. 1).

    Parameters
    ----------
    radiance_cd_m2 : (H, W, 3) float
        Linear radiance.
    key : float
        Display value the scene's log-average luminance is mapped to (0.18: middle grey).

    Returns
    -------
    float
        Multiplier, m²/cd; 1.0 for an all-black image.
    """
    luminance = luminance_cd_m2(radiance_cd_m2).astype(np.float64)
    positive = luminance[luminance > 0]
    if positive.size == 0:
        return 1.0
    return float(key / np.exp(np.mean(np.log(positive))))


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) on [0, 1]; values outside are clipped first."""
    x = np.clip(linear, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def preview_srgb8(radiance_cd_m2: np.ndarray, exposure_scale: float) -> np.ndarray:
    """(H, W, 3) radiance → (H, W, 3) uint8 sRGB: scale, clip at white, encode, round."""
    encoded = srgb_encode(radiance_cd_m2.astype(np.float32) * np.float32(exposure_scale))
    return np.round(encoded * 255).astype(np.uint8)
