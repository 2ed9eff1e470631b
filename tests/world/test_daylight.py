"""Daylight levels (camgen.world.daylight): the IES model's values, and the CIE sky's zenith luminance
that gives them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.world.daylight import (
    direct_normal_illuminance_lux,
    extraterrestrial_illuminance_lux,
    sky_horizontal_illuminance_lux,
    zenith_luminance_cd_m2,
)
from camgen.world.sky import relative_luminance

SUMMER_SOLSTICE_DAY = 172

# The IES daylight availability model's values (RP-21, 1984; IESNA Lighting Handbook 9th ed., §8), in
# klx, for day 172 (E_xt = 127.5 (1 + 0.034 cos(2π·170/365)) = 123.31 klx), worked by hand from its
# published constants: E_dn = E_xt e^(−c / sin α), E_kh = A + B sin^C α.
# (elevation °, clear E_dn, partly cloudy E_dn, clear E_kh, partly cloudy E_kh, overcast E_kh)
IES_TABLE_KLX = [
    (10.0, 36.78, 1.23, 7.26, 8.11, 3.95),
    (30.0, 80.99, 24.89, 11.76, 22.80, 10.80),
    (60.0, 96.72, 48.94, 15.22, 39.27, 18.49),
    (90.0, 99.92, 55.39, 16.30, 45.30, 21.30),
]


@pytest.mark.parametrize("row", IES_TABLE_KLX, ids=lambda row: f"{row[0]:g}deg")
def test_illuminance_matches_the_ies_model(row):
    elevation = row[0]
    got = [
        direct_normal_illuminance_lux(elevation, SUMMER_SOLSTICE_DAY, "clear"),
        direct_normal_illuminance_lux(elevation, SUMMER_SOLSTICE_DAY, "partly_cloudy"),
        sky_horizontal_illuminance_lux(elevation, "clear"),
        sky_horizontal_illuminance_lux(elevation, "partly_cloudy"),
        sky_horizontal_illuminance_lux(elevation, "overcast"),
    ]
    # Within 10 % of the model (the acceptance bound); in fact to the rounding of the table.
    np.testing.assert_allclose(np.array(got, dtype=float) / 1000.0, row[1:], rtol=0.1)
    np.testing.assert_allclose(np.array(got, dtype=float) / 1000.0, row[1:], rtol=2e-3)


def test_sunlight_at_noon_is_about_100_klx():
    """Clear noon with the sun 60° up: global horizontal illuminance E_dn sin α + E_kh ≈ 100 klx, the
    usual figure for full daylight (e.g. the IESNA handbook's daylight availability figures)."""
    global_lux = direct_normal_illuminance_lux(60.0, 172, "clear") * math.sin(math.radians(60.0))
    global_lux += sky_horizontal_illuminance_lux(60.0, "clear")
    assert 90_000 < float(global_lux) < 115_000


def test_extraterrestrial_illuminance_peaks_at_perihelion():
    assert float(extraterrestrial_illuminance_lux(2)) == pytest.approx(127_500 * 1.034)
    assert float(extraterrestrial_illuminance_lux(184)) == pytest.approx(127_500 * (1 - 0.034), rel=2e-4)


def test_no_direct_sun_under_overcast_or_below_the_horizon():
    assert float(direct_normal_illuminance_lux(45.0, 100, "overcast")) == 0.0
    assert float(direct_normal_illuminance_lux(0.0, 100, "clear")) == 0.0
    assert float(direct_normal_illuminance_lux(-5.0, 100, "clear")) == 0.0


def test_overcast_zenith_luminance_is_the_cie_closed_form():
    """The CIE overcast sky L = L_z (1 + 2 cos Z)/3 (Moon & Spencer 1942) gives E = (7π/9) L_z; the
    standard's type 1 approximates that gradation, so its ratio agrees within 1 %."""
    for elevation in (10.0, 40.0, 70.0):
        lz = zenith_luminance_cd_m2(10_000.0, elevation, "overcast")
        assert lz == pytest.approx(10_000.0 * 9 / (7 * math.pi), rel=0.01)


def test_uniform_sky_luminance_is_illuminance_over_pi():
    assert zenith_luminance_cd_m2(9_000.0, 30.0, "uniform") == pytest.approx(9_000.0 / math.pi)


@pytest.mark.parametrize("sky", ["clear", "partly_cloudy", "overcast"])
@pytest.mark.parametrize("elevation", [8.0, 35.0, 65.0])
def test_the_sky_drawn_gives_the_illuminance_it_was_scaled_to(sky, elevation):
    """An independent quadrature (a Fibonacci lattice of 200 000 equal-area directions on the hemisphere)
    of the sky's luminance × cos Z, with L_z from `zenith_luminance_cd_m2`, returns E_kh within 1 %."""
    e_kh = float(sky_horizontal_illuminance_lux(elevation, sky))
    lz = zenith_luminance_cd_m2(e_kh, elevation, sky)
    n = 200_000
    i = np.arange(n) + 0.5
    cos_z = 1.0 - i / n  # equal-area bands of the hemisphere
    azimuth = math.pi * (1 + 5**0.5) * i
    sin_z = np.sqrt(1.0 - cos_z**2)
    directions = np.stack([sin_z * np.cos(azimuth), sin_z * np.sin(azimuth), cos_z], axis=-1)
    el = math.radians(elevation)
    sun = np.array([math.cos(el) * math.cos(0.3), math.cos(el) * math.sin(0.3), math.sin(el)])
    luminance = lz * relative_luminance(directions, sun, sky)
    illuminance = float(np.mean(luminance * cos_z) * 2 * math.pi)
    assert illuminance == pytest.approx(e_kh, rel=0.01)
