"""Diffraction blur: the Gaussian of the Airy pattern, σ = 0.42·λ·N, per colour channel."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.optics.diffraction import CHANNEL_WAVELENGTHS_UM, MONO_WAVELENGTH_UM, diffraction_blur


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
