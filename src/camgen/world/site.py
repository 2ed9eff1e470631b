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
