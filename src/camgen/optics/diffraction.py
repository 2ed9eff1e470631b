"""Diffraction at the aperture: the Airy pattern approximated by a Gaussian, σ ≈ 0.42·λ·N.

The Airy disc (first dark ring) has diameter 2.44·λ·N; its best-fitting Gaussian has σ = 0.42·λ·N
(Zhang, Zerubia and Olivo-Marin, "Gaussian approximations of fluorescence microscope point-spread
function models", Appl. Opt. 46, 2007). λ per colour channel is the centre of a typical Bayer
filter's passband.

The blur runs on the render-size radiance at the sensor's own pixel pitch (after supersampling's box
average, before the lens remap: `camgen.plan.lens_stages`), so σ is in sensor pixels. Sampled on that
grid, a narrow Gaussian is the identity: at σ = 0.09 px its neighbour taps are 5e-26 of its centre. Its
effect is measured on the taps applied (`off_centre_weight_rel`), not on the Airy disc's diameter.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from camgen.optics.intrinsics import airy_sigma_um

CHANNEL_WAVELENGTHS_UM = (0.60, 0.53, 0.46)
"""Centre wavelengths of the R, G, B filters, µm."""
MONO_WAVELENGTH_UM = 0.55
FLOAT32_RESOLUTION = 2.0**-24
"""float32's unit roundoff (half the spacing of float32 numbers just below 1). A kernel whose off-centre
weight relative to its centre is at most this changes no pixel by more than this fraction of the pixel's
largest difference from a neighbour: the identity on float32 radiance, up to the last bit at edges of
more than a few times contrast."""


def airy_sigma_px(f_number: float, pixel_pitch_um: float, wavelength_um: float) -> float:
    """Gaussian σ of the Airy pattern on the sensor, px."""
    return airy_sigma_um(f_number, wavelength_um) / pixel_pitch_um


def channel_sigmas_px(f_number: float, pixel_pitch_um: float, mono: bool = False) -> tuple[float, float, float]:
    """σ, px, of the Gaussian `diffraction_blur` applies to each channel (R, G, B; one λ for a mono sensor)."""
    wavelengths = (MONO_WAVELENGTH_UM,) * 3 if mono else CHANNEL_WAVELENGTHS_UM
    return tuple(airy_sigma_px(f_number, pixel_pitch_um, wavelength) for wavelength in wavelengths)


def kernel_taps(sigma_px: float) -> np.ndarray:
    """The 1-D taps, (2·⌈4σ⌉ + 1,) float32, that `diffraction_blur` applies along each axis for `sigma_px`:
    the kernel `cv2.GaussianBlur` builds for a float32 image (`cv2.getGaussianKernel` at CV_32F),
    t_k = exp(−k²/2σ²) / Σ exp(−j²/2σ²) for |k| ≤ ⌈4σ⌉."""
    if not sigma_px > 0:
        raise ValueError(f"sigma_px must be > 0, got {sigma_px}")
    size = 2 * math.ceil(4 * sigma_px) + 1
    return cv2.getGaussianKernel(size, sigma_px, cv2.CV_32F).ravel()


def off_centre_weight_rel(sigma_px: float) -> float:
    """Weight of the separable 2-D kernel's off-centre taps relative to its centre tap, for `sigma_px`.

    With s the 1-D taps' off-centre sum over their centre, the 2-D kernel's is (1 + s)² − 1 = 2s + s²
    (summed without cancellation: s ≈ 1e-25 at σ = 0.09 px). A pixel x with neighbours y_k becomes
    x + Σ w_k (y_k − x), so this bounds the change as a fraction of the pixel's largest neighbour
    difference.
    """
    taps = kernel_taps(sigma_px).astype(np.float64)
    centre = len(taps) // 2
    s = (taps[:centre].sum() + taps[centre + 1 :].sum()) / taps[centre]
    return float(2 * s + s * s)


def diffraction_effect_rel(f_number: float, pixel_pitch_um: float, mono: bool = False) -> float:
    """The largest `off_centre_weight_rel` over the channels' kernels at `f_number`: what the blur
    changes, as a fraction of a pixel's largest difference from a neighbour (0 when it is the identity)."""
    return max(off_centre_weight_rel(sigma) for sigma in channel_sigmas_px(f_number, pixel_pitch_um, mono))


def diffraction_blur(radiance: np.ndarray, *, f_number: float, pixel_pitch_um: float, mono: bool = False) -> np.ndarray:
    """Blur (H, W, 3) float32 radiance with each channel's Airy Gaussian (one λ for a mono sensor).

    The kernel spans ±⌈4σ⌉ (`kernel_taps`); the image border is reflected (the caller renders a margin). A
    channel whose kernel is the identity on float32 (`off_centre_weight_rel` ≤ `FLOAT32_RESOLUTION`: a
    zoom's wide frames in a sequence that blurs its tele ones) is not convolved; where no channel's kernel
    changes a pixel, `radiance` itself is returned.
    """
    blurred = [
        (c, sigma)
        for c, sigma in enumerate(channel_sigmas_px(f_number, pixel_pitch_um, mono))
        if off_centre_weight_rel(sigma) > FLOAT32_RESOLUTION
    ]
    if not blurred:
        return radiance
    out = radiance.copy()
    for c, sigma in blurred:
        size = len(kernel_taps(sigma))
        out[..., c] = cv2.GaussianBlur(
            np.ascontiguousarray(radiance[..., c]), (size, size), sigma, borderType=cv2.BORDER_REFLECT
        )
    return out
