"""Diffraction blur: the Gaussian of the Airy pattern, σ = 0.42·λ·N, per colour channel, applied as the discrete
Gaussian of that variance (Lindeberg 1990), against its defining properties: variance exactly σ², transfer
function exp(σ²(cos ω − 1)), the semigroup T(s)∗T(t) = T(s + t), and its width on a point."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from camgen.optics.diffraction import (
    CHANNEL_WAVELENGTHS_UM,
    MONO_WAVELENGTH_UM,
    diffraction_blur,
    kernel_taps,
)


@pytest.mark.parametrize("f_number", [1.6, 8.0, 16.0])
def test_point_spread_has_the_airy_gaussian_width(f_number):
    """At f/1.6 on 1.45 µm the σ is 0.28-0.37 px: a Gaussian sampled at whole pixels there has a variance of
    a tenth of σ² or less; the discrete one has σ² exactly."""
    pitch_um = 1.45
    image = np.zeros((81, 81, 3), np.float32)
    image[40, 40] = 1.0
    for mono, wavelengths in ((False, CHANNEL_WAVELENGTHS_UM), (True, (MONO_WAVELENGTH_UM,) * 3)):
        psf = diffraction_blur(image, f_number=f_number, pixel_pitch_um=pitch_um, mono=mono)
        u = np.arange(81) - 40
        for c, wavelength in enumerate(wavelengths):
            assert psf[..., c].sum() == pytest.approx(1.0, rel=1e-4)
            marginal = psf[..., c].sum(axis=0)
            sigma_px = np.sqrt((marginal * u**2).sum() / marginal.sum())
            assert sigma_px == pytest.approx(0.42 * wavelength * f_number / pitch_um, rel=0.01)


@pytest.mark.parametrize("sigma_px", [0.05, 0.0927, 0.139, 0.255, 0.6, 2.3])
def test_the_kernel_has_the_variance_and_transfer_function_of_the_discrete_gaussian(sigma_px):
    taps = kernel_taps(sigma_px).astype(np.float64)
    k = np.arange(len(taps)) - len(taps) // 2
    t = sigma_px**2
    assert taps.sum() == pytest.approx(1.0, rel=1e-6)
    np.testing.assert_array_equal(taps, taps[::-1])
    assert (taps * k**2).sum() == pytest.approx(t, rel=3e-4)
    for omega in (np.pi / 4, np.pi / 2, np.pi):  # Σ T(k) cos(ωk) = exp(t (cos ω − 1)); at Nyquist exp(−2t)
        assert (taps * np.cos(omega * k)).sum() == pytest.approx(np.exp(t * (np.cos(omega) - 1.0)), abs=2e-5)


def test_two_blurs_are_one_of_the_summed_variance():
    """T(s) ∗ T(t) = T(s + t): diffraction's blur composes with any other discrete Gaussian as variances add."""
    a, b = kernel_taps(0.3).astype(np.float64), kernel_taps(0.4).astype(np.float64)
    both = np.convolve(a, b)
    direct = kernel_taps(0.5).astype(np.float64)
    pad = (len(both) - len(direct)) // 2
    np.testing.assert_allclose(both[pad : len(both) - pad], direct, atol=2e-5)  # each truncated and normalised


def test_a_sub_pixel_gaussian_blurs_where_the_sampled_one_did_not():
    """At σ = 0.14 px (the 2.9 µm bullet at f/1.6) the sampled Gaussian's neighbour taps are e^(−25.5) = 1e-11 of
    its centre: cv2.GaussianBlur returns the image. The discrete Gaussian moves σ²/2 ≈ 1 % of each neighbour in."""
    sampled = cv2.getGaussianKernel(3, 0.14, cv2.CV_64F).ravel()
    assert sampled[0] / sampled[1] < 1e-10
    taps = kernel_taps(0.14)
    centre = len(taps) // 2
    assert taps[centre + 1] == pytest.approx(0.0098 * taps[centre], rel=0.02)
    edge = np.zeros((9, 9, 3), np.float32)
    edge[:, 5:] = 1.0
    out = diffraction_blur(edge, f_number=1.6, pixel_pitch_um=2.9)
    assert 0.005 < out[4, 4, 1] < 0.02 and 0.98 < out[4, 5, 1] < 0.995


def test_each_channel_gets_its_own_wavelength():
    rng = np.random.default_rng(5)
    image = rng.uniform(0.0, 1.0, (40, 50, 3)).astype(np.float32)
    f_number, pitch_um = 2.8, 2.0
    out = diffraction_blur(image, f_number=f_number, pixel_pitch_um=pitch_um)
    for c, wavelength in enumerate(CHANNEL_WAVELENGTHS_UM):
        taps = kernel_taps(0.42 * wavelength * f_number / pitch_um)
        reference = cv2.sepFilter2D(image[..., c], cv2.CV_64F, taps, taps, borderType=cv2.BORDER_REFLECT)
        np.testing.assert_allclose(out[..., c], reference, rtol=1e-5, atol=1e-6)
    assert not np.allclose(out[..., 0], out[..., 2])  # red's kernel is wider than blue's


@pytest.mark.parametrize("sigma", [0.0, -0.1, float("nan"), float("inf")])
def test_kernel_taps_refuse_a_sigma_that_is_no_blur(sigma):
    with pytest.raises(ValueError, match="sigma_px must be finite and > 0"):
        kernel_taps(sigma)
