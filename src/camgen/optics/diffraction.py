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

The plan keeps the stage wherever its kernel changes a pixel (`off_centre_weight_rel` above float32's
resolution), which with the discrete kernel is wherever there is an aperture: skipping it at σ ≈ 0.1 px (a spot
4σ of 0.4 px, under the 0.5 px threshold defocus is skipped at) changed the parking lot's 8-bit frame by 0.37
of its noise RMS and the night street's by 0.88 (`camgen bench --section skipping`), far above the quarter of
the noise the plan's skips are held to.
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


def kernel_reach_px(sigma_px: float) -> int:
    """R = ⌈4σ⌉ + 1: how far, px, `kernel_taps` reaches each side (`REACH_SIGMAS`); the render margin the stage
    needs (`camgen.plan.compile`)."""
    return math.ceil(REACH_SIGMAS * sigma_px) + 1


def kernel_taps(sigma_px: float) -> np.ndarray:
    """The 1-D taps, (2·R + 1,) float32 with R = `kernel_reach_px`, that `diffraction_blur` applies along each
    axis: Lindeberg's discrete Gaussian T(k; σ²) = e^(−σ²)·I_|k|(σ²) (scipy's exponentially scaled `ive`),
    normalised to sum 1 over the reach."""
    if not (math.isfinite(sigma_px) and sigma_px > 0):
        raise ValueError(f"sigma_px must be finite and > 0, got {sigma_px}")
    reach = kernel_reach_px(sigma_px)
    taps = ive(np.abs(np.arange(-reach, reach + 1)), sigma_px * sigma_px)
    return (taps / taps.sum()).astype(np.float32)


FLOAT32_RESOLUTION = 2.0**-24
"""float32's unit roundoff. A kernel whose off-centre weight relative to its centre is at most this changes no
pixel by more than this fraction of the pixel's largest difference from a neighbour: the identity."""


def off_centre_weight_rel(sigma_px: float) -> float:
    """Weight of the separable 2-D kernel's off-centre taps relative to its centre tap, for `sigma_px`: with s the
    1-D taps' off-centre sum over their centre, (1 + s)² − 1 = 2s + s² (summed without cancellation). A pixel x
    with neighbours y_k becomes x + Σ w_k (y_k − x), so this bounds the change as a fraction of the pixel's largest
    neighbour difference. About 2σ² for σ under half a pixel."""
    taps = kernel_taps(sigma_px).astype(np.float64)
    centre = len(taps) // 2
    s = (taps[:centre].sum() + taps[centre + 1 :].sum()) / taps[centre]
    return float(2 * s + s * s)


def diffraction_effect_rel(f_number: float, pixel_pitch_um: float, mono: bool = False) -> float:
    """The largest `off_centre_weight_rel` over the channels' kernels at `f_number` (what the plan decides on)."""
    return max(off_centre_weight_rel(sigma) for sigma in channel_sigmas_px(f_number, pixel_pitch_um, mono))


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
