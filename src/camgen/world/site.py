"""Daylight at a place and a moment: the sun's direction in a scene's axes and the illuminance of the
sun and the sky (`camgen.world.sun`, `camgen.world.daylight`), as a scene's lights take them."""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime

from camgen.world.daylight import direct_normal_illuminance_lux, sky_horizontal_illuminance_lux, zenith_luminance_cd_m2
from camgen.world.sun import scene_azimuth_deg, solar_position, unix_time_s


@dataclass(frozen=True)
class SiteDaylight:
    """What a site's sky gives at one moment."""

    azimuth_deg: float
    """Towards the sun, counter-clockwise from the scene's +X, degrees in [0, 360)."""
    elevation_deg: float
    """The sun's apparent elevation, degrees (negative below the horizon)."""
    compass_azimuth_deg: float
    """Towards the sun, clockwise from geographic north, degrees."""
    sun_illuminance_lux: float
    """Direct normal illuminance (on a surface facing the sun); 0 under an overcast sky."""
    sky_illuminance_lux: float
    """The sky's illuminance on a horizontal surface, the sun's own light excluded."""
    zenith_luminance_cd_m2: float
    """The sky's zenith luminance for that illuminance and the sky's luminance distribution."""


def site_daylight(
    latitude_deg: float, longitude_deg: float, time: datetime, north_deg: float, sky: str
) -> SiteDaylight:
    """Daylight at a site (latitude north, longitude east, degrees) at a timezone-aware `time`, for a
    scene whose geographic north lies `north_deg` counter-clockwise from +X and whose sky is `sky`
    ("uniform", "clear", "partly_cloudy" or "overcast"). Below the horizon the illuminances are those
    of a sun on it (the model has no twilight): callers refuse such a sun."""
    position = solar_position(latitude_deg, longitude_deg, unix_time_s(time))
    elevation = float(position.elevation_deg)
    day_of_year = time.timetuple().tm_yday
    sky_lux = float(sky_horizontal_illuminance_lux(elevation, sky))
    return SiteDaylight(
        azimuth_deg=float(scene_azimuth_deg(position.azimuth_deg, north_deg)),
        elevation_deg=elevation,
        compass_azimuth_deg=float(position.azimuth_deg),
        sun_illuminance_lux=float(direct_normal_illuminance_lux(elevation, day_of_year, sky)),
        sky_illuminance_lux=sky_lux,
        zenith_luminance_cd_m2=zenith_luminance_cd_m2(sky_lux, elevation, sky),
    )


DIRECTION_CHANGE_DEG = 0.5
"""A sequence's daylight is held at its first frame's unless the sun turns by more than this (a 10 m
wall's shadow edge 15 m away moves under 15 cm)…"""
ILLUMINANCE_CHANGE_REL = 0.01
"""…or the sun's or the sky's illuminance changes by more than this fraction (under the shot noise an
auto-exposed frame shows, and under auto-exposure's own tolerance)."""


@dataclass(frozen=True)
class DaylightChange:
    """How far daylight moves over a sequence, relative to its first frame."""

    direction_deg: float
    """Largest angle between the sun's direction then and at any later time, degrees."""
    illuminance_rel: float
    """Largest relative change of the direct or the sky illuminance."""

    @property
    def varies(self) -> bool:
        """Whether the frames need their own daylight (above `DIRECTION_CHANGE_DEG` or `ILLUMINANCE_CHANGE_REL`)."""
        return self.direction_deg > DIRECTION_CHANGE_DEG or self.illuminance_rel > ILLUMINANCE_CHANGE_REL


def daylight_change(
    latitude_deg: float, longitude_deg: float, time: datetime, sky: str, duration_s: float
) -> DaylightChange:
    """The change of daylight over [time, time + duration_s], sampled every minute (at most 1000 times)."""
    import numpy as np

    count = int(min(1000, max(2, duration_s // 60 + 2)))
    unix_s = unix_time_s(time) + np.linspace(0.0, duration_s, count)
    position = solar_position(latitude_deg, longitude_deg, unix_s)
    el, az = np.radians(position.elevation_deg), np.radians(position.azimuth_deg)
    towards = np.stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)], axis=-1)
    direction = np.degrees(np.arccos(np.clip(towards @ towards[0], -1.0, 1.0)))
    day_of_year = time.timetuple().tm_yday
    changes = [0.0]
    for values in (
        direct_normal_illuminance_lux(position.elevation_deg, day_of_year, sky),
        sky_horizontal_illuminance_lux(position.elevation_deg, sky),
    ):
        if values[0] > 0:
            changes.append(float(np.max(np.abs(values / values[0] - 1.0))))
    return DaylightChange(direction_deg=float(direction.max()), illuminance_rel=max(changes))
