"""The sun's position (camgen.world.sun, NOAA's algorithm) against published values and NREL's SPA."""

from __future__ import annotations

import math
from datetime import UTC, datetime, timedelta, timezone

import numpy as np
import pytest

from camgen.world.sun import scene_azimuth_deg, solar_position, sunrise_sunset, unix_time_s

TOLERANCE_DEG = 0.1


def _angle_between_deg(elevation_a, azimuth_a, elevation_b, azimuth_b) -> np.ndarray:
    """Great-circle angle between two (elevation, compass azimuth) directions, degrees."""
    ea, aa, eb, ab = (
        np.radians(np.asarray(x, dtype=np.float64)) for x in (elevation_a, azimuth_a, elevation_b, azimuth_b)
    )
    cos = np.sin(ea) * np.sin(eb) + np.cos(ea) * np.cos(eb) * np.cos(aa - ab)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def test_spa_worked_example():
    """Reda & Andreas, "Solar position algorithm for solar radiation applications" (NREL/TP-560-34302,
    2008), appendix A.5: 17 October 2003, 12:30:30 local time (UTC−7), 39.742476° N, 105.1786° W, 1830 m:
    topocentric zenith 50.11162°, azimuth 194.34024° (the SPA's refraction for 820 mbar and 11 °C and its
    parallax differ from NOAA's standard-atmosphere refraction by under 0.01° here)."""
    time = datetime(2003, 10, 17, 12, 30, 30, tzinfo=timezone(timedelta(hours=-7)))
    sun = solar_position(39.742476, -105.1786, unix_time_s(time))
    assert abs(float(sun.zenith_deg) - 50.11162) < TOLERANCE_DEG
    assert abs(float(sun.azimuth_deg) - 194.34024) < TOLERANCE_DEG


@pytest.mark.parametrize(
    ("instant", "declination_deg"),
    [
        # Solstices and equinoxes of 2026 (US Naval Observatory, "Earth's Seasons 2026"): the declination
        # is ±ε (23.436° in 2026) at a solstice and 0 at an equinox.
        (datetime(2026, 3, 20, 14, 46, tzinfo=UTC), 0.0),
        (datetime(2026, 6, 21, 8, 24, tzinfo=UTC), 23.436),
        (datetime(2026, 9, 23, 0, 5, tzinfo=UTC), 0.0),
        (datetime(2026, 12, 21, 20, 50, tzinfo=UTC), -23.436),
    ],
)
def test_declination_at_the_solstices_and_equinoxes(instant, declination_deg):
    assert float(solar_position(0.0, 0.0, unix_time_s(instant)).declination_deg) == pytest.approx(
        declination_deg, abs=0.01
    )


def test_against_nrel_spa_over_places_and_dates():
    """NREL's SPA as pvlib implements it (`pvlib.solarposition.spa_python`, standard atmosphere), at 250
    instants over 1950–2080 and places from 70° S to 70° N with the sun at least 1° up: the direction
    differs by less than 0.1°."""
    pd = pytest.importorskip("pandas")
    pvlib = pytest.importorskip("pvlib")
    rng = np.random.default_rng(20)
    start, end = datetime(1950, 1, 1, tzinfo=UTC).timestamp(), datetime(2080, 1, 1, tzinfo=UTC).timestamp()
    worst = 0.0
    checked = 0
    for _ in range(250):
        latitude, longitude = rng.uniform(-70, 70), rng.uniform(-180, 180)
        unix_s = float(rng.uniform(start, end))
        reference = pvlib.solarposition.spa_python(
            pd.DatetimeIndex([pd.Timestamp(unix_s, unit="s", tz="UTC")]), latitude, longitude
        )
        elevation = float(reference["apparent_elevation"].iloc[0])
        if elevation < 1.0:
            continue
        sun = solar_position(latitude, longitude, unix_s)
        worst = max(
            worst,
            float(_angle_between_deg(sun.elevation_deg, sun.azimuth_deg, elevation, reference["azimuth"].iloc[0])),
        )
        checked += 1
    assert checked > 90
    assert worst < TOLERANCE_DEG, worst


def test_arrays_of_times_give_arrays():
    t0 = unix_time_s(datetime(2026, 6, 21, 12, tzinfo=UTC))
    times = t0 + np.arange(6).reshape(2, 3) * 3600.0
    sun = solar_position(51.5, 0.0, times)
    assert sun.elevation_deg.shape == (2, 3)
    np.testing.assert_allclose(sun.elevation_deg[0, 1], float(solar_position(51.5, 0.0, times[0, 1]).elevation_deg))


def test_noon_sun_is_due_south_in_the_north_and_due_north_in_the_south():
    # Greenwich on the June solstice: apparent noon at 12:02 UTC (equation of time −1.7 min).
    noon = unix_time_s(datetime(2026, 6, 21, 12, 1, 45, tzinfo=UTC))
    north = solar_position(51.48, 0.0, noon)
    south = solar_position(-33.9, 0.0, noon)
    assert float(north.azimuth_deg) == pytest.approx(180.0, abs=0.3)
    assert abs((float(south.azimuth_deg) + 180.0) % 360.0 - 180.0) < 0.3
    # Noon elevation 90 − |φ − δ|, plus a few arc minutes of refraction.
    assert float(north.elevation_deg) == pytest.approx(90 - (51.48 - 23.436), abs=0.05)


def test_scene_azimuth_turns_the_compass_into_the_scene():
    # North along +Y (the default): east is +X (0°), south −Y (270°), west −X (180°).
    np.testing.assert_allclose(scene_azimuth_deg([0.0, 90.0, 180.0, 270.0], 90.0), [90.0, 0.0, 270.0, 180.0])
    # North along +X: east is −Y.
    assert float(scene_azimuth_deg(90.0, 0.0)) == pytest.approx(270.0)


def test_sunrise_and_sunset_bracket_the_day():
    """Paris on 21 June 2026: the sun's centre crosses the horizon (refracted) near 05:49 and 21:56
    CEST; published rise and set (upper limb, 34′ refraction) are 05:47 and 21:58."""
    time = datetime(2026, 6, 21, 14, 30, tzinfo=timezone(timedelta(hours=2)))
    rise, sets = sunrise_sunset(48.8566, 2.3522, time)
    assert abs((rise - time.replace(hour=5, minute=47)).total_seconds()) < 4 * 60
    assert abs((sets - time.replace(hour=21, minute=58)).total_seconds()) < 4 * 60
    assert sunrise_sunset(78.2, 15.6, time) is None  # Svalbard: midnight sun


def test_a_time_without_an_offset_is_refused():
    with pytest.raises(ValueError, match="UTC offset"):
        unix_time_s(datetime(2026, 6, 21, 12))


def test_azimuth_of_the_sun_is_where_its_direction_points():
    """Geometry check independent of the algorithm's own formula: the sun's direction rotates by
    15°/h about Earth's axis, so two instants an hour apart are 15° cos δ apart on the sky."""
    t0 = unix_time_s(datetime(2026, 4, 10, 9, tzinfo=UTC))
    a, b = solar_position(40.0, 10.0, t0), solar_position(40.0, 10.0, t0 + 3600.0)
    # Refraction is below 0.01° at these elevations' difference; use true directions via small tolerance.
    angle = float(_angle_between_deg(a.elevation_deg, a.azimuth_deg, b.elevation_deg, b.azimuth_deg))
    expected = math.degrees(
        2 * math.asin(math.cos(math.radians(float(a.declination_deg))) * math.sin(math.radians(7.5)))
    )
    assert angle == pytest.approx(expected, abs=0.05)
