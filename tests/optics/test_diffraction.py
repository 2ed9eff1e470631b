"""Diffraction blur: the Gaussian of the Airy pattern, σ = 0.42·λ·N, per colour channel; its sampled taps and
their off-centre weight, on which the plan decides (identity at float32's resolution)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from camgen.optics.diffraction import (
    CHANNEL_WAVELENGTHS_UM,
    FLOAT32_RESOLUTION,
    MONO_WAVELENGTH_UM,
    diffraction_blur,
    kernel_taps,
    off_centre_weight_rel,
)


@pytest.mark.parametrize("f_number", [8.0, 16.0])
def test_point_spread_has_the_airy_gaussian_width(f_number):
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
            assert sigma_px == pytest.approx(0.42 * wavelength * f_number / pitch_um, rel=0.02)


def _closed_form_ratios(sigma_px):
    """exp(−k²/2σ²) for k = 1…⌈4σ⌉: the Gaussian sampled at whole pixels, relative to its centre."""
    k = np.arange(1, int(np.ceil(4 * sigma_px)) + 1)
    return np.exp(-(k**2) / (2 * sigma_px**2))


@pytest.mark.parametrize("sigma_px", [0.05, 0.0927, 0.139, 0.1666, 0.255, 0.6, 2.3])
def test_kernel_taps_are_the_gaussian_sampled_at_whole_pixels(sigma_px):
    taps = kernel_taps(sigma_px)
    ratios = _closed_form_ratios(sigma_px)
    centre = len(taps) // 2
    assert len(taps) == 2 * len(ratios) + 1 and taps.dtype == np.float32
    assert taps.sum(dtype=np.float64) == pytest.approx(1.0, rel=1e-6)
    np.testing.assert_array_equal(taps, taps[::-1])
    # float32 taps: relative 1e-6 where they are normal numbers (σ = 0.05 px: exp(−200) underflows to 0).
    expected = ratios * taps[centre]
    normal = expected > np.finfo(np.float32).tiny
    np.testing.assert_allclose(taps[centre + 1 :][normal], expected[normal], rtol=1e-6)
    assert np.all(taps[centre + 1 :][~normal] < 1e-37)


@pytest.mark.parametrize("sigma_px", [0.0927, 0.139, 0.1638, 0.168, 0.255, 0.6, 2.3])
def test_off_centre_weight_is_the_closed_form_without_cancellation(sigma_px):
    """(1 + s)² − 1 with s = 2·Σ exp(−k²/2σ²): at σ = 0.0927 px it is 2e-25, which 1 − w_centre² in float64
    would round to 0."""
    s = 2 * _closed_form_ratios(sigma_px).sum()
    assert off_centre_weight_rel(sigma_px) == pytest.approx(2 * s + s * s, rel=1e-6)


def test_identity_threshold_lies_between_the_two_sigmas_either_side_of_it():
    # 4·exp(−1/2σ²) = 2⁻²⁴ at σ = 1/√(2·ln(2²⁶)) = 0.16657 px (the 3×3 kernel's four side taps).
    sigma_threshold_px = 1 / np.sqrt(2 * np.log(2.0**26))
    assert (
        off_centre_weight_rel(0.99 * sigma_threshold_px)
        < FLOAT32_RESOLUTION
        < off_centre_weight_rel(1.01 * sigma_threshold_px)
    )


def test_a_kernel_at_the_float32_resolution_leaves_an_image_as_it_is():
    """What the plan's skip rests on: cv2.GaussianBlur with a kernel whose off-centre weight is at most
    2⁻²⁴ of its centre returns every pixel unchanged where neighbours differ by less than a factor of
    two, and elsewhere changes a pixel by at most that weight times its largest neighbour difference
    (plus its own rounding)."""
    rng = np.random.default_rng(3)
    sigma = 0.99 / np.sqrt(2 * np.log(2.0**26))
    weight = off_centre_weight_rel(sigma)
    assert 0 < weight <= FLOAT32_RESOLUTION
    size = len(kernel_taps(sigma))
    narrow = rng.uniform(0.5, 1.0, (64, 80)).astype(np.float32)
    blurred = cv2.GaussianBlur(narrow, (size, size), sigma, borderType=cv2.BORDER_REFLECT)
    np.testing.assert_array_equal(blurred, narrow)
    hdr = np.exp(rng.uniform(np.log(1e-3), np.log(1e3), (64, 80))).astype(np.float32)
    blurred = cv2.GaussianBlur(hdr, (size, size), sigma, borderType=cv2.BORDER_REFLECT)
    padded = np.pad(hdr, 1, mode="symmetric").astype(np.float64)
    neighbour_difference = np.max(
        [np.abs(padded[1 + dy : 65 + dy, 1 + dx : 81 + dx] - hdr) for dy in (-1, 0, 1) for dx in (-1, 0, 1)], axis=0
    )
    bound = weight * neighbour_difference + np.spacing(hdr)
    assert np.all(np.abs(blurred.astype(np.float64) - hdr) <= bound)
    assert np.any(blurred != hdr)  # contrasts of up to 10⁶ do move the last bit somewhere


def test_the_blur_leaves_identity_channels_as_they_are_and_convolves_the_others():
    # f/2.26 on 3 µm: σ = 0.190 px in red (weight 4e-6), 0.146 px in blue (2e-10).
    f_number, pitch_um = 2.26, 3.0
    sigmas = [0.42 * wavelength * f_number / pitch_um for wavelength in CHANNEL_WAVELENGTHS_UM]
    assert off_centre_weight_rel(sigmas[0]) > FLOAT32_RESOLUTION >= off_centre_weight_rel(sigmas[2])
    rng = np.random.default_rng(5)
    image = np.exp(rng.uniform(np.log(1e-2), np.log(1e2), (40, 50, 3))).astype(np.float32)
    out = diffraction_blur(image, f_number=f_number, pixel_pitch_um=pitch_um)
    np.testing.assert_array_equal(out[..., 2], image[..., 2])
    reference = cv2.sepFilter2D(
        image[..., 0], cv2.CV_64F, kernel_taps(sigmas[0]), kernel_taps(sigmas[0]), borderType=cv2.BORDER_REFLECT
    )
    np.testing.assert_allclose(out[..., 0], reference, rtol=1e-5)
    assert np.count_nonzero(out[..., 0] != image[..., 0]) > 0.9 * image[..., 0].size  # red is blurred
    # The 30× dome at 1280×720, wide (f/1.6 on 4.35 µm): no channel to convolve, the image handed back.
    assert diffraction_blur(image, f_number=1.6, pixel_pitch_um=4.35) is image
