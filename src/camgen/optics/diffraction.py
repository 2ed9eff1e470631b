"""Diffraction at the aperture: the Airy pattern approximated by a Gaussian, σ ≈ 0.42·λ·N.

The Airy disc (first dark ring) has diameter 2.44·λ·N; its best-fitting Gaussian has σ = 0.42·λ·N
(Zhang, Zerubia and Olivo-Marin, "Gaussian approximations of fluorescence microscope point-spread
function models", Appl. Opt. 46, 2007). λ per colour channel is the centre of a typical Bayer
filter's passband.
"""

from __future__ import annotations

import cv2
import numpy as np

from camgen.optics.intrinsics import airy_sigma_um

CHANNEL_WAVELENGTHS_UM = (0.60, 0.53, 0.46)
"""Centre wavelengths of the R, G, B filters, µm."""
MONO_WAVELENGTH_UM = 0.55


def airy_sigma_px(f_number: float, pixel_pitch_um: float, wavelength_um: float) -> float:
    """Gaussian σ of the Airy pattern on the sensor, px."""
    return airy_sigma_um(f_number, wavelength_um) / pixel_pitch_um


def diffraction_blur(radiance: np.ndarray, *, f_number: float, pixel_pitch_um: float, mono: bool = False) -> np.ndarray:
    """Blur (H, W, 3) float32 radiance with each channel's Airy Gaussian (one λ for a mono sensor).

    The kernel spans ±4σ; the image border is reflected (the caller renders a margin).
    """
    out = np.empty_like(radiance)
    wavelengths = (MONO_WAVELENGTH_UM,) * 3 if mono else CHANNEL_WAVELENGTHS_UM
    for c, wavelength in enumerate(wavelengths):
        sigma = airy_sigma_px(f_number, pixel_pitch_um, wavelength)
        size = 2 * int(np.ceil(4 * sigma)) + 1
        out[..., c] = cv2.GaussianBlur(
            np.ascontiguousarray(radiance[..., c]), (size, size), sigma, borderType=cv2.BORDER_REFLECT
        )
    return out
