"""Diffraction at the aperture: the Airy pattern approximated by a Gaussian, σ ≈ 0.42·λ·N.

The Airy disc (first dark ring) has diameter 2.44·λ·N; its best-fitting Gaussian has σ = 0.42·λ·N
(Zhang, Zerubia and Olivo-Marin, "Gaussian approximations of fluorescence microscope point-spread
function models", Appl. Opt. 46, 2007). λ per colour channel is the centre of a typical Bayer
filter's passband.

The blur runs on the render-size radiance at the sensor's own pixel pitch (after supersampling's box
average, before the lens remap: `camgen.plan.lens_stages`), so σ is in sensor pixels, and the kernel is the
*discrete* Gaussian of variance σ² (Lindeberg, "Scale-space for discrete signals", IEEE TPAMI 12(3), 1990):
T(k; t) = e^(−t)·I_k(t), t = σ², I_k the modified Bessel function of the first kind. A Gaussian *sampled* at
whole pixels is not a blur of variance σ² when σ is under a pixel: at σ = 0.14 px (a 2.9 µm bullet at f/1.6)
its neighbour taps are 1e-11 of its centre and it leaves every pixel as it is, while the optics' MTF at the
sensor's Nyquist frequency is 0.91 (a Gaussian's exp(−π²σ²/2)); the discrete Gaussian keeps the variance
exactly at any σ (its taps 0.0096, 0.981, 0.0096 there), and its transfer function is exp(t(cos ω − 1)).

The plan keeps the stage where the blur's spot is at least the plan's blur threshold, as for defocus and
motion (`camgen.plan.compile`): a Gaussian's spot diameter taken as 4σ, the diameter of the uniform disc of
the same variance (a disc of diameter c has σ = c/4, as a blur circle of defocus).
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from scipy.special import ive

from camgen.optics.intrinsics import airy_sigma_um

CHANNEL_WAVELENGTHS_UM = (0.60, 0.53, 0.46)
"""Centre wavelengths of the R, G, B filters, µm."""
MONO_WAVELENGTH_UM = 0.55
REACH_SIGMAS = 4.0
"""The kernel spans ±(⌈4σ⌉ + 1) px: its variance then errs by at most 1.6e-4 of σ² (σ from 0.05 to 2.3 px;
±⌈4σ⌉ loses 0.25 % at σ = 0.05 px and 1.9 % at 0.14, where one tap each side holds it), and what the
truncation drops is put back by normalising."""


def airy_sigma_px(f_number: float, pixel_pitch_um: float, wavelength_um: float) -> float:
    """Gaussian σ of the Airy pattern on the sensor, px."""
    return airy_sigma_um(f_number, wavelength_um) / pixel_pitch_um


def channel_sigmas_px(f_number: float, pixel_pitch_um: float, mono: bool = False) -> tuple[float, float, float]:
    """σ, px, of the Gaussian `diffraction_blur` applies to each channel (R, G, B; one λ for a mono sensor)."""
    wavelengths = (MONO_WAVELENGTH_UM,) * 3 if mono else CHANNEL_WAVELENGTHS_UM
    return tuple(airy_sigma_px(f_number, pixel_pitch_um, wavelength) for wavelength in wavelengths)


def kernel_taps(sigma_px: float) -> np.ndarray:
    """The 1-D taps, (2·R + 1,) float32 with R = ⌈4σ⌉ + 1, that `diffraction_blur` applies along each axis:
    Lindeberg's discrete Gaussian T(k; σ²) = e^(−σ²)·I_|k|(σ²) (scipy's exponentially scaled `ive`), normalised
    to sum 1 over the reach."""
    if not (math.isfinite(sigma_px) and sigma_px > 0):
        raise ValueError(f"sigma_px must be finite and > 0, got {sigma_px}")
    reach = math.ceil(REACH_SIGMAS * sigma_px) + 1
    taps = ive(np.abs(np.arange(-reach, reach + 1)), sigma_px * sigma_px)
    return (taps / taps.sum()).astype(np.float32)


def spot_diameter_px(sigma_px: float) -> float:
    """The diameter of the uniform disc with the Gaussian's variance, 4σ px: the spot the plan compares with its
    blur threshold, as it compares a defocus blur circle's diameter."""
    return 4.0 * sigma_px


def diffraction_blur(radiance: np.ndarray, *, f_number: float, pixel_pitch_um: float, mono: bool = False) -> np.ndarray:
    """Blur (H, W, 3) float32 radiance with each channel's Airy Gaussian (one λ for a mono sensor), as the
    discrete Gaussian of its variance (`kernel_taps`); the image border is reflected (the caller renders a
    margin). A mono sensor's three equal kernels run as one filter over the three channels."""
    sigmas = channel_sigmas_px(f_number, pixel_pitch_um, mono)
    if len(set(sigmas)) == 1:
        taps = kernel_taps(sigmas[0])
        return cv2.sepFilter2D(radiance, cv2.CV_32F, taps, taps, borderType=cv2.BORDER_REFLECT)
    out = np.empty_like(radiance)
    for c, sigma in enumerate(sigmas):
        taps = kernel_taps(sigma)
        out[..., c] = cv2.sepFilter2D(
            np.ascontiguousarray(radiance[..., c]), cv2.CV_32F, taps, taps, borderType=cv2.BORDER_REFLECT
        )
    return out
