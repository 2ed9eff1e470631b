"""camgen's daylight (world/daylight.py, world/sky.py) against values published by others, typed in from the
source each row names (issue 20: "sky and sun illuminance within 10 % of the model's published values").

`tests/world/test_daylight.py` checks the IES equations against values worked by hand from their constants;
the references here were published or transcribed by someone else:

- ISO 15469:2004 / CIE S 011/E:2003 Table 1 (the 15 standard skies' a, b, c, d, e), as F. Rudawski's Lighting
  Toolbox writes it (github.com/Frudawski/LightingToolbox, ciesky.m, `cietable`, citing the standard);
- the CIE clear sky's luminance formula as Radiance writes it (github.com/NREL/Radiance, src/gen/skybright.cal
  `sunnysky` with src/gen/gensky.c's normalisation F2), and gensky.c's polynomial fit of that sky's horizontal
  illuminance per zenith luminance (`normsc`) and its overcast zenith luminance (`zenithbr = 8.6 sin α + 0.123`
  kcd/m²);
- IES RP-21-1984 ("Recommended practice for the calculation of daylight availability", J. IES 13:4, 381–392)
  as a 1991 C++ program ("Cálculo da disponibilidade de luz natural", github.com/Rogreis/DLN,
  Antigos/DLN.CPP) transcribes it equation by equation, (07)–(27). The file names no source: it is RP-21 by its
  contents (its equation of time, declination, E_xt, extinction and sky illuminance constants are those camgen
  cites from RP-21). Used: its zenith luminance factor table for the clear sky (`FatLumCC`, π L_z / E_kh from
  90° down to 0° sun altitude in 5° steps: the program indexes it 18 − α/5; its partly cloudy table is the
  integral of its own partly cloudy sky in the same order, to 0.06 %), its overcast factor 1.286, its overcast
  vertical sky illuminance 8.5 sin α klx (eq. 23), and its constants (eqs. 15, 16, 19, 22);
- the certification values of Table A of Janiczek & DeYoung, "Computer programs for sun and moon
  illuminance with contingent tables and diagrams" (US Naval Observatory Circular 171, 1987), as the R package
  skylight reproduces them in its unit test (github.com/bluegreen-labs/skylight, tests/testthat/test_skylight.R).

Where camgen departs from a published model (RP-21's partly cloudy sky, its clear-sky vertical illuminance
away from the sun, USNO's low-sun totals) the figures are in the report of the change, not tested here: those
are other models than camgen's, not errors in it.
"""

from __future__ import annotations

import math
from datetime import UTC, datetime, timedelta

import numpy as np
import pytest

from camgen.world.daylight import (
    direct_normal_illuminance_lux,
    extraterrestrial_illuminance_lux,
    sky_horizontal_illuminance_lux,
    zenith_luminance_cd_m2,
)
from camgen.world.sky import SKY_TYPES, relative_luminance
from camgen.world.sun import solar_position, unix_time_s

ACCEPTANCE_RTOL = 0.10
"""Issue 20: within 10 % of the published value."""


def _direction(elevation_deg, azimuth_deg) -> np.ndarray:
    el, az = np.radians(elevation_deg), np.radians(azimuth_deg)
    return np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=-1)


# ISO 15469:2004 Table 1 rows, (a, b, c, d, e), from Rudawski's ciesky.m `cietable` (rows 1, 7 and 12).
ISO_15469_TABLE_1 = {
    "overcast": (1, (4.0, -0.7, 0.0, -1.0, 0.0)),
    "partly_cloudy": (7, (0.0, -1.0, 5.0, -2.5, 0.30)),
    "clear": (12, (-1.0, -0.32, 10.0, -3.0, 0.45)),
}


@pytest.mark.parametrize("sky", sorted(ISO_15469_TABLE_1))
def test_sky_parameters_are_the_iso_15469_table(sky):
    _, published = ISO_15469_TABLE_1[sky]
    assert SKY_TYPES[sky] == pytest.approx(published, abs=1e-12)


@pytest.mark.parametrize("sun_elevation_deg", [5.0, 15.0, 30.0, 45.0, 60.0, 75.0, 87.0])
def test_clear_sky_is_the_cie_clear_sky_formula(sun_elevation_deg):
    """ISO 15469's type 12 is the CIE standard clear sky; Radiance writes that sky as
    L/L_z = (0.91 + 10 e^(−3γ) + 0.45 cos²γ)(1 − e^(−0.32/cos Z)) / F2, F2 = 0.274 (0.91 + 10 e^(−3 Z_s)
    + 0.45 cos² Z_s) (skybright.cal, gensky.c). Radiance rounds 1 − 10 e^(−3π/2) to 0.91 and 1 − e^(−0.32) to
    0.274: the two agree within 0.1 % over the whole sky (camgen: 0.07 %)."""
    elevation, azimuth = np.meshgrid(np.arange(1.0, 90.0, 2.0), np.arange(0.0, 360.0, 5.0), indexing="ij")
    directions = _direction(elevation, azimuth)
    sun = _direction(sun_elevation_deg, 0.0)
    cos_gamma = np.clip(directions @ sun, -1.0, 1.0)
    gamma = np.arccos(cos_gamma)
    sun_zenith = math.radians(90.0 - sun_elevation_deg)
    f2 = 0.274 * (0.91 + 10.0 * math.exp(-3.0 * sun_zenith) + 0.45 * math.cos(sun_zenith) ** 2)
    radiance_sky = (
        (0.91 + 10.0 * np.exp(-3.0 * gamma) + 0.45 * cos_gamma**2) * (1.0 - np.exp(-0.32 / directions[..., 2])) / f2
    )
    np.testing.assert_allclose(relative_luminance(directions, sun, "clear"), radiance_sky, rtol=1e-3)


# IES RP-21-1984, zenith luminance factor of the clear sky, π L_z / E_kh, at sun altitudes 90°, 85°, ..., 0°
# (Rogreis/DLN Antigos/DLN.CPP `FatLumCC`).
RP21_CLEAR_ZENITH_FACTOR = [
    3.248, 2.591, 2.086, 1.698, 1.398, 1.165, 0.985, 0.844, 0.734, 0.648,
    0.581, 0.530, 0.491, 0.464, 0.446, 0.436, 0.435, 0.440, 0.452,
]  # fmt: skip


@pytest.mark.parametrize(
    ("sun_elevation_deg", "factor"),
    [(90.0 - 5.0 * i, f) for i, f in enumerate(RP21_CLEAR_ZENITH_FACTOR)],
    ids=lambda value: f"{value:g}",
)
def test_clear_sky_zenith_luminance_is_the_ies_table(sun_elevation_deg, factor):
    """The zenith luminance camgen gives a clear sky of horizontal illuminance E_kh is RP-21's: the table's three
    decimals (±0.12 % at 0.435) bound the difference (camgen: 0.12 % at worst). This checks the sky's luminance
    distribution and its integral at once: the table is RP-21's integral of the same CIE clear sky."""
    e_kh_lux = 10_000.0
    got = math.pi * zenith_luminance_cd_m2(e_kh_lux, sun_elevation_deg, "clear") / e_kh_lux
    assert got == pytest.approx(factor, rel=2e-3)
    assert got == pytest.approx(factor, rel=ACCEPTANCE_RTOL)


def _gensky_clear_illuminance_per_zenith_luminance(sun_elevation_deg: float) -> float:
    """E_kh / L_z of the CIE clear sky by Radiance gensky.c: normsc() / F2 (E = π·L_z·normsc/(F2·π))."""
    coefficients = (2.766521, 0.547665, -0.369832, 0.009237, 0.059229)
    altitude = math.radians(sun_elevation_deg)
    x = (altitude - math.pi / 4) / (math.pi / 4)
    normsc = sum(c * x**k for k, c in enumerate(coefficients))
    f2 = 0.274 * (0.91 + 10.0 * math.exp(-3.0 * (math.pi / 2 - altitude)) + 0.45 * math.sin(altitude) ** 2)
    return normsc / f2


@pytest.mark.parametrize("sun_elevation_deg", [5.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 87.0])
def test_clear_sky_illuminance_per_zenith_luminance_is_radiance_gensky(sun_elevation_deg):
    """gensky's fit and camgen's quadrature of the same sky agree within 0.5 % (camgen: 0.21 % at worst)."""
    got = 10_000.0 / zenith_luminance_cd_m2(10_000.0, sun_elevation_deg, "clear")
    assert got == pytest.approx(_gensky_clear_illuminance_per_zenith_luminance(sun_elevation_deg), rel=5e-3)


@pytest.mark.parametrize("sun_elevation_deg", [5.0, 10.0, 20.0, 30.0, 45.0, 60.0, 75.0, 90.0])
def test_overcast_zenith_luminance_is_published(sun_elevation_deg):
    """Radiance gensky.c's overcast zenith luminance 8.6 sin α + 0.123 kcd/m², and RP-21's overcast factor
    π L_z / E_kh = 1.286, against camgen's overcast sky lit to the IES E_kh = 0.3 + 21.0 sin α klx (camgen: 0.33 %
    and 0.27 % apart: the standard's type 1 approximates Moon & Spencer's 7π/9)."""
    e_kh = float(sky_horizontal_illuminance_lux(sun_elevation_deg, "overcast"))
    zenith = zenith_luminance_cd_m2(e_kh, sun_elevation_deg, "overcast")
    gensky = 1000.0 * (8.6 * math.sin(math.radians(sun_elevation_deg)) + 0.123)
    assert zenith == pytest.approx(gensky, rel=0.01)
    assert math.pi * zenith / e_kh == pytest.approx(1.286, rel=0.005)


@pytest.mark.parametrize("sun_elevation_deg", [5.0, 10.0, 20.0, 30.0, 45.0, 60.0, 75.0])
def test_overcast_vertical_sky_illuminance_is_ies(sun_elevation_deg):
    """RP-21 eq. (23): a vertical surface under the overcast sky gets 8.5 sin α klx from it. camgen's sky,
    integrated over a vertical plane's half of the hemisphere (200 000 equal-area directions), gives that within
    the acceptance's 10 % (camgen: +9.0 % at 5°, where RP-21's horizontal constant 0.3 klx, which its vertical
    formula lacks, weighs most; +1.4 % at 10°; −4.9 % at 75°)."""
    n = 200_000
    i = np.arange(n) + 0.5
    cos_z = 1.0 - i / n
    azimuth = math.pi * (1 + 5**0.5) * i
    sin_z = np.sqrt(1.0 - cos_z**2)
    directions = np.stack([sin_z * np.cos(azimuth), sin_z * np.sin(azimuth), cos_z], axis=-1)
    sun = _direction(sun_elevation_deg, 0.0)
    e_kh = float(sky_horizontal_illuminance_lux(sun_elevation_deg, "overcast"))
    luminance = zenith_luminance_cd_m2(e_kh, sun_elevation_deg, "overcast") * relative_luminance(
        directions, sun, "overcast"
    )
    vertical_lux = float(np.mean(luminance * np.clip(directions[:, 0], 0.0, None)) * 2 * math.pi)
    assert vertical_lux == pytest.approx(8500.0 * math.sin(math.radians(sun_elevation_deg)), rel=ACCEPTANCE_RTOL)


def test_the_ies_constants_match_an_independent_transcription():
    """Not a published table: the IES equations as another hand typed them from RP-21 in 1991 (DLN.CPP eqs. 15,
    16, 19, 22: E_xt = 127.5 (1 + 0.034 cos(2π (J − 2)/365)) klx, m = 1/sin α, E_dn = E_xt e^(−0.21 m) clear and
    e^(−0.80 m) partly cloudy, E_kh = 0.8 + 15.5 √sin α, 0.3 + 45.0 sin α, 0.3 + 21.0 sin α klx). A typo in either
    transcription of a constant would show here."""
    for day in (2, 80, 172, 264, 355):
        for elevation in (3.0, 12.0, 27.0, 48.0, 66.0, 89.0):
            sin_a = math.sin(math.radians(elevation))
            e_xt = 127.5 * (1.0 + 0.034 * math.cos(2 * math.pi * (day - 2) / 365.0))
            assert float(extraterrestrial_illuminance_lux(day)) / 1000 == pytest.approx(e_xt, rel=1e-12)
            for sky, c in (("clear", 0.21), ("partly_cloudy", 0.80)):
                got = float(direct_normal_illuminance_lux(elevation, day, sky)) / 1000
                assert got == pytest.approx(e_xt * math.exp(-c / sin_a), rel=1e-9)
            for sky, e_kh in (
                ("clear", 0.8 + 15.5 * math.sqrt(sin_a)),
                ("partly_cloudy", 0.3 + 45.0 * sin_a),
                ("overcast", 0.3 + 21.0 * sin_a),
            ):
                assert float(sky_horizontal_illuminance_lux(elevation, sky)) / 1000 == pytest.approx(e_kh, rel=1e-12)


def test_clear_daylight_with_the_sun_at_the_zenith_is_usno_table_a():
    """USNO Circular 171, Table A: on 1986-12-18 at 21:00 UT at 23.4° S 135.8° W the sun stands at the zenith
    (printed altitude 90°) and sun and clear sky give a horizontal surface 123 786 lx (the circular's own
    clear-sky model, independent of the IES one: 133 775 lx outside the air). camgen's sun there is within the
    table's rounding of the zenith, and its direct plus sky illuminance E_dn sin α + E_kh is within 10 %
    (camgen: 123 047 lx, −0.6 %)."""
    time = datetime(1986, 12, 18, 21, 0, tzinfo=UTC)
    sun = solar_position(-23.4, -135.8, unix_time_s(time))
    elevation = float(sun.elevation_deg)
    assert elevation > 89.5
    day = time.timetuple().tm_yday
    total_lux = float(direct_normal_illuminance_lux(elevation, day, "clear")) * math.sin(math.radians(elevation))
    total_lux += float(sky_horizontal_illuminance_lux(elevation, "clear"))
    assert total_lux == pytest.approx(123_786.0, rel=ACCEPTANCE_RTOL)


def test_sun_at_sunset_is_usno_table_a_to_its_rounding():
    """USNO Circular 171, Table A: at 18:31 local mean time on 1988-08-13 at 21.3° N 39.5° E (15:53 UT) the sun
    is at altitude 0° and azimuth 286°, printed to the degree. camgen's apparent sun is within that rounding
    (camgen: −0.24°, 285.84°); the circular's own low-precision solar coordinates add about 0.1°. Its 697 lx there
    is outside camgen's daylight model, which needs the sun up (camgen's clear sky alone gives A = 800 lx at 0°)."""
    time = datetime(1988, 8, 13, 18, 31, tzinfo=UTC) - timedelta(hours=39.5 / 15.0)
    sun = solar_position(21.3, 39.5, unix_time_s(time))
    assert abs(float(sun.elevation_deg)) < 0.5 + 0.1
    assert abs(float(sun.azimuth_deg) - 286.0) < 0.5 + 0.1
