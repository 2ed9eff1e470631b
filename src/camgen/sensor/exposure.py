"""Exposure: scene radiance → photons per pixel (the camera equation) and analog gain.

The image-side illuminance of a distant object of luminance L through a lens of working f-number N is
E = π·L / (4·N²) (the paraxial camera equation; transmission 1; the off-axis fall-off is the
vignetting stage's). A pixel of area A collects E·A·t lumen-seconds in an exposure t, which this
module counts in photons of the candela's defining frequency (540 THz, λ ≈ 555 nm): one lumen is
1/683 W there, so one lumen-second is 1/(683 · h · 540 THz) ≈ 4.09·10¹⁵ photons.

Each rendered RGB channel is treated this way, as the photon count of that colour band. For an
equal-energy white, the band of a Bayer filter holds about a third of the visible photons, which comes
within about 20 % of this count; colour-filter transmission beyond that belongs in the profile's QE.
"""

from __future__ import annotations

import math

PLANCK_J_S = 6.62607015e-34
LUMINOUS_EFFICACY_LM_PER_W = 683.0
CANDELA_FREQUENCY_HZ = 540e12
PHOTONS_PER_LUMEN_S = 1.0 / (LUMINOUS_EFFICACY_LM_PER_W * PLANCK_J_S * CANDELA_FREQUENCY_HZ)
"""Photons in one lumen-second of 540 THz light (≈ 4.092·10¹⁵)."""


def sensor_illuminance_lux(radiance_cd_m2: float, f_number: float) -> float:
    """E = π·L / (4·N²): illuminance on the sensor on axis, lux, for scene luminance L (cd/m²)."""
    return math.pi * radiance_cd_m2 / (4.0 * f_number * f_number)


def photons_per_cd_m2_s(pixel_area_um2: float, f_number: float) -> float:
    """Photons one pixel collects per second per cd/m² of scene radiance, on axis.

    Φ/(L·t) = π / (4·N²) · A · 4.09·10¹⁵ photons/(lm·s), with A the pixel area in m².
    """
    if pixel_area_um2 <= 0 or f_number <= 0:
        raise ValueError(f"pixel area and f-number must be > 0, got {pixel_area_um2} µm², N = {f_number}")
    return sensor_illuminance_lux(1.0, f_number) * pixel_area_um2 * 1e-12 * PHOTONS_PER_LUMEN_S


def gain_linear(gain_db: float) -> float:
    """Amplitude gain of `gain_db` decibels: 10^(dB/20)."""
    return 10.0 ** (gain_db / 20.0)


def gain_db(gain_linear_: float) -> float:
    """Decibels of an amplitude gain: 20·log10(G)."""
    return 20.0 * math.log10(gain_linear_)
