"""A scene's `environment.site` places its sun and gives the daylight levels it leaves out."""

from __future__ import annotations

import json
import math
from datetime import datetime, timedelta, timezone

import numpy as np
import pytest

from camgen.config.scene import Scene
from camgen.world.daylight import direct_normal_illuminance_lux, sky_horizontal_illuminance_lux, zenith_luminance_cd_m2
from camgen.world.site import site_daylight
from camgen.world.sun import solar_position, unix_time_s
from tests.render.conftest import scene_from

PARIS = {"latitude_deg": 48.8566, "longitude_deg": 2.3522, "time": "2026-06-21T14:30:00+02:00"}


def _scene(site: dict, sky: str = "clear", lights=({"type": "sun"}, {"type": "ambient"}), **environment) -> Scene:
    return scene_from(environment={"sky": sky, "site": site, **environment}, lights=list(lights))


def test_the_site_places_the_sun_and_sets_the_daylight():
    scene = _scene(PARIS)
    sun, ambient = scene.lights
    time = datetime(2026, 6, 21, 14, 30, tzinfo=timezone(timedelta(hours=2)))
    position = solar_position(PARIS["latitude_deg"], PARIS["longitude_deg"], unix_time_s(time))
    assert sun.elevation_deg == pytest.approx(float(position.elevation_deg))
    # North along +Y by default: compass azimuth a lies at 90° − a from +X.
    assert sun.azimuth_deg == pytest.approx((90.0 - float(position.azimuth_deg)) % 360.0)
    assert sun.illuminance_lux == pytest.approx(float(direct_normal_illuminance_lux(sun.elevation_deg, 172, "clear")))
    assert ambient.illuminance_lux == pytest.approx(float(sky_horizontal_illuminance_lux(sun.elevation_deg, "clear")))
    assert scene.environment.sky_luminance_cd_m2 == pytest.approx(
        zenith_luminance_cd_m2(ambient.illuminance_lux, sun.elevation_deg, "clear")
    )
    # A June afternoon in Paris: the sun high in the south-west, about 100 klx of daylight.
    assert 60 < sun.elevation_deg < 66 and 190 < float(position.azimuth_deg) < 215
    total = sun.illuminance_lux * math.sin(math.radians(sun.elevation_deg)) + ambient.illuminance_lux
    assert 90_000 < total < 115_000


def test_north_turns_the_sun_with_the_scene():
    base = _scene(PARIS).lights[0].azimuth_deg
    turned = _scene({**PARIS, "north_deg": 30.0}).lights[0].azimuth_deg
    assert (turned - base) % 360 == pytest.approx(300.0)  # north 60° clockwise: so is the sun


def test_values_given_win_over_the_site_but_the_direction_does_not():
    scene = _scene(
        PARIS,
        lights=({"type": "sun", "illuminance_lux": 5000.0}, {"type": "ambient", "illuminance_lux": 700.0}),
        sky_luminance_cd_m2=123.0,
    )
    assert [light.illuminance_lux for light in scene.lights] == [5000.0, 700.0]
    assert scene.environment.sky_luminance_cd_m2 == 123.0
    assert scene.lights[0].elevation_deg > 60


def test_a_resolved_scene_validates_again_unchanged():
    scene = _scene(PARIS)
    assert Scene.model_validate(scene.model_dump()) == scene
    assert Scene.model_validate(json.loads(scene.model_dump_json())) == scene


def test_overcast_site_lights_only_the_sky():
    scene = _scene(PARIS, sky="overcast", lights=({"type": "ambient"},))
    daylight = site_daylight(48.8566, 2.3522, datetime.fromisoformat(PARIS["time"]), 90.0, "overcast")
    assert daylight.sun_illuminance_lux == 0.0
    assert scene.lights[0].illuminance_lux == pytest.approx(daylight.sky_illuminance_lux)
    assert scene.environment.sky_luminance_cd_m2 == pytest.approx(
        daylight.sky_illuminance_lux * 9 / (7 * np.pi), rel=0.01
    )


def test_southern_winter_morning_sun_is_low_in_the_north_east():
    """Sydney, 21 June 2026, 09:00 AEST: the sun about 18° up, compass azimuth about 45° (NE)."""
    site = {"latitude_deg": -33.87, "longitude_deg": 151.21, "time": "2026-06-21T09:00:00+10:00"}
    daylight = site_daylight(-33.87, 151.21, datetime.fromisoformat(site["time"]), 90.0, "clear")
    assert 14 < daylight.elevation_deg < 22
    assert 35 < daylight.compass_azimuth_deg < 60
    assert _scene(site).lights[0].azimuth_deg == pytest.approx(90.0 - daylight.compass_azimuth_deg)
