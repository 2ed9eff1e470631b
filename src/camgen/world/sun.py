"""Where the sun stands, seen from a place on Earth at a moment: NOAA's solar calculator algorithm.

The equations are those of NOAA's Global Monitoring Laboratory solar calculator (its spreadsheet
"NOAA_Solar_Calculations_day.xls", https://gml.noaa.gov/grad/solcalc/calcdetails.html), which
follows Meeus, *Astronomical Algorithms* (1991), chapters 24–25: from the Julian century T of the
instant (UT),

    L0 = 280.46646 + T (36000.76983 + 0.0003032 T)         geometric mean longitude of the sun, °
    M  = 357.52911 + T (35999.05029 − 0.0001537 T)         mean anomaly, °
    e  = 0.016708634 − T (0.000042037 + 0.0000001267 T)    eccentricity of Earth's orbit
    C  = sin M (1.914602 − T (0.004817 + 0.000014 T)) + sin 2M (0.019993 − 0.000101 T) + 0.000289 sin 3M
    λ  = L0 + C − 0.00569 − 0.00478 sin Ω,  Ω = 125.04 − 1934.136 T     apparent longitude, °
    ε  = ε0(T) + 0.00256 cos Ω                                          corrected obliquity, °
    δ  = asin(sin ε sin λ)                                              declination
    EoT = 4 deg(y sin 2L0 − 2e sin M + 4ey sin M cos 2L0 − ½y² sin 4L0 − 1.25e² sin 2M),  y = tan²(ε/2)  (min)

The true solar time is the UT time of day plus EoT plus 4 min per degree of east longitude; the hour
angle H = TST/4 − 180°; then cos Z = sin φ sin δ + cos φ cos δ cos H, the azimuth (clockwise from
geographic north) from the same spherical triangle, and the elevation is raised by NOAA's
piecewise approximation of atmospheric refraction (standard atmosphere).

NOAA states the algorithm is accurate to about 1 arc minute for dates between 1901 and 2099; the
tests check it against the worked example of Reda & Andreas' SPA (NREL/TP-560-34302, 2008, table A5.1)
and pvlib's implementation of SPA (`tests/world/test_sun.py`).

Scene directions: camgen's world has z up and measures a light's azimuth counter-clockwise from +X
(`camgen.config.scene.SunLight`); a site's `north_deg` says where geographic north points in those
terms, so the scene azimuth is north_deg − (compass azimuth), east lying 90° clockwise of north.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime, timedelta

import numpy as np

UNIX_EPOCH_JULIAN_DAY = 2440587.5
"""Julian day of 1970-01-01 00:00 UT."""
J2000_JULIAN_DAY = 2451545.0


@dataclass(frozen=True)
class SolarPosition:
    """The sun seen from a site; arrays of the times' shape."""

    elevation_deg: np.ndarray
    """Apparent elevation above the horizon (refraction included), degrees."""
    azimuth_deg: np.ndarray
    """Compass azimuth: clockwise from geographic north (90° east), degrees in [0, 360)."""
    declination_deg: np.ndarray
    equation_of_time_min: np.ndarray

    @property
    def zenith_deg(self) -> np.ndarray:
        """Apparent zenith angle, degrees."""
        return 90.0 - self.elevation_deg


def unix_time_s(time: datetime) -> float:
    """Seconds since 1970-01-01 00:00 UTC of a timezone-aware datetime."""
    if time.tzinfo is None or time.utcoffset() is None:
        raise ValueError(f"time {time.isoformat()} has no UTC offset; give one (e.g. +02:00 or Z)")
    return time.timestamp()


def refraction_deg(elevation_deg: np.ndarray) -> np.ndarray:
    """Atmospheric refraction that raises a true elevation to the apparent one, degrees (NOAA's
    approximation, after Bennett and Sæmundsson, for a standard atmosphere; 0 above 85°)."""
    e = np.asarray(elevation_deg, dtype=np.float64)
    t = np.tan(np.radians(np.clip(e, -89.0, 89.0)))
    with np.errstate(divide="ignore", invalid="ignore"):
        high = 58.1 / t - 0.07 / t**3 + 0.000086 / t**5
        middle = 1735.0 + e * (-518.2 + e * (103.4 + e * (-12.79 + e * 0.711)))
        low = -20.772 / t
    arcsec = np.where(e > 85.0, 0.0, np.where(e > 5.0, high, np.where(e > -0.575, middle, low)))
    return arcsec / 3600.0


def solar_position(latitude_deg: float, longitude_deg: float, unix_s: np.ndarray | float) -> SolarPosition:
    """The sun's apparent position at a site (latitude north, longitude east, degrees) at the
    instants `unix_s` (seconds since 1970-01-01 00:00 UTC, any shape). See the module docstring."""
    unix_s = np.asarray(unix_s, dtype=np.float64)
    julian_day = unix_s / 86400.0 + UNIX_EPOCH_JULIAN_DAY
    T = (julian_day - J2000_JULIAN_DAY) / 36525.0
    L0 = np.mod(280.46646 + T * (36000.76983 + T * 0.0003032), 360.0)
    M = 357.52911 + T * (35999.05029 - 0.0001537 * T)
    e = 0.016708634 - T * (0.000042037 + 0.0000001267 * T)
    Mr = np.radians(M)
    C = (
        np.sin(Mr) * (1.914602 - T * (0.004817 + 0.000014 * T))
        + np.sin(2 * Mr) * (0.019993 - 0.000101 * T)
        + np.sin(3 * Mr) * 0.000289
    )
    omega = np.radians(125.04 - 1934.136 * T)
    apparent_longitude = np.radians(L0 + C - 0.00569 - 0.00478 * np.sin(omega))
    mean_obliquity = 23.0 + (26.0 + (21.448 - T * (46.815 + T * (0.00059 - T * 0.001813))) / 60.0) / 60.0
    obliquity = np.radians(mean_obliquity + 0.00256 * np.cos(omega))
    declination = np.arcsin(np.sin(obliquity) * np.sin(apparent_longitude))
    y = np.tan(obliquity / 2) ** 2
    L0r = np.radians(L0)
    equation_of_time_min = 4.0 * np.degrees(
        y * np.sin(2 * L0r)
        - 2 * e * np.sin(Mr)
        + 4 * e * y * np.sin(Mr) * np.cos(2 * L0r)
        - 0.5 * y**2 * np.sin(4 * L0r)
        - 1.25 * e**2 * np.sin(2 * Mr)
    )
    minutes_of_day = np.mod(unix_s, 86400.0) / 60.0
    true_solar_time_min = np.mod(minutes_of_day + equation_of_time_min + 4.0 * longitude_deg, 1440.0)
    hour_angle = np.radians(true_solar_time_min / 4.0 - 180.0)
    phi = math.radians(latitude_deg)
    cos_zenith = np.clip(
        math.sin(phi) * np.sin(declination) + math.cos(phi) * np.cos(declination) * np.cos(hour_angle), -1.0, 1.0
    )
    true_elevation = 90.0 - np.degrees(np.arccos(cos_zenith))
    # Azimuth from north through east: the sun's direction in the local east-north-up frame.
    east = -np.cos(declination) * np.sin(hour_angle)
    north = math.cos(phi) * np.sin(declination) - math.sin(phi) * np.cos(declination) * np.cos(hour_angle)
    azimuth = np.mod(np.degrees(np.arctan2(east, north)), 360.0)
    return SolarPosition(
        elevation_deg=true_elevation + refraction_deg(true_elevation),
        azimuth_deg=azimuth,
        declination_deg=np.degrees(declination),
        equation_of_time_min=equation_of_time_min,
    )


def scene_azimuth_deg(compass_azimuth_deg: np.ndarray | float, north_deg: float) -> np.ndarray:
    """A compass azimuth (clockwise from north) as a scene azimuth (counter-clockwise from +X, where
    north lies at `north_deg`), degrees in [0, 360)."""
    return np.mod(north_deg - np.asarray(compass_azimuth_deg, dtype=np.float64), 360.0)


def sunrise_sunset(latitude_deg: float, longitude_deg: float, time: datetime) -> tuple[datetime, datetime] | None:
    """The last sunrise and the next sunset (apparent elevation 0°, the sun's centre) around `time`'s
    local day, in `time`'s time zone, to the minute; None where the sun neither rises nor sets that
    day (polar day or night)."""
    start = time.replace(hour=0, minute=0, second=0, microsecond=0)
    minutes = np.arange(0, 24 * 60 + 1)
    elevation = solar_position(latitude_deg, longitude_deg, unix_time_s(start) + 60.0 * minutes).elevation_deg
    up = elevation > 0
    rises = np.flatnonzero(~up[:-1] & up[1:])
    sets = np.flatnonzero(up[:-1] & ~up[1:])
    if not len(rises) or not len(sets):
        return None
    return start + timedelta(minutes=int(rises[0]) + 1), start + timedelta(minutes=int(sets[-1]) + 1)
