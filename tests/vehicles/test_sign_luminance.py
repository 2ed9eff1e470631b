"""A bus's LED destination display dims with the ambient light (`camgen.vehicles.sign.display_luminance_cd_m2`).

- The function: EN 12966's class L1, 3,100 cd/m², from 40,000 lx up; 50 cd/m² at night (up to 10.4 lx); the
  square root of the illuminance between; any shape, NaN kept.
- The scene graph sets the display's emission from the horizontal illuminance at its middle: by day a sun's
  E·sin(elevation) plus the sky's E; at night the skyglow plus a street lamp's I(θ)·cos θ / d², I from the
  lamp's flux and beam (`camgen.world.night`), both computed here from the scene's numbers; and it follows a
  bus driving out from under the lamp; under an IES lamp, its table (read with the file's own interpolation)
  at the display's γ and C; and a bus standing through a dusk follows the site's daylight.
- Rendered (OpenGL, 160×120), a bus's front over grey ground under a uniform sky of 2 lx (night) and 20,000 lx
  (day): the display's dots are its emission plus their amber base colour's E/π, and the ground ρ·E/π. Against
  the ground, the dots' contrast is 126 times higher at night than by day (630 against 5.0): with a fixed
  luminance it was ≈ 5,300 times higher (a camera metering the ground at 18 % grey drove every night dot ≈ 4,500
  times past full scale, now ≈ 110; the day's stay under it), so the test asks under 500 (a twentieth of the
  10⁴ illuminance ratio), which the fixed luminance fails.
"""

from __future__ import annotations

import math
from datetime import timedelta
from pathlib import Path

import numpy as np
import pytest

from camgen.io.ies import read_ies
from camgen.render.scene_graph import build_scene_graph
from camgen.vehicles import LAMP_COLOUR_RGB
from camgen.vehicles.sign import DISPLAY_DAY_CD_M2, DISPLAY_DAY_LUX, DISPLAY_NIGHT_CD_M2, display_luminance_cd_m2
from camgen.world.ies import flux_lm as ies_flux_lm
from camgen.world.ies import intensity_grid_cd
from camgen.world.night import beam_intensity_cd, peak_intensity_cd
from camgen.world.site import site_daylight
from tests.render.conftest import camera_matrix, look_at, scene_from

AMBER = np.asarray(LAMP_COLOUR_RGB["destination"])
BUS = {
    "name": "bus",
    "class": "bus",
    "vehicle": {"seed": 302},
    "path": {"waypoints_m": [[0, 0], [60, 0]], "speed_m_s": 10},
}
LAMP_M = np.array([6.0, 2.0, 8.0])
LAMP_FLUX_LM = 6000.0
LAMP_CONE_DEG = 70.0  # the lamp light's default
SCENES = Path(__file__).parents[2] / "scenes"


def test_the_display_luminance_follows_the_ambient_light():
    lux = np.array([0.0, 1.0, 10.0, 1_000.0, 20_000.0, 40_000.0, 1e5])
    luminance = display_luminance_cd_m2(lux)
    assert luminance[:3] == pytest.approx([DISPLAY_NIGHT_CD_M2] * 3)
    assert luminance[3:5] == pytest.approx(DISPLAY_DAY_CD_M2 * np.sqrt(lux[3:5] / DISPLAY_DAY_LUX))
    assert luminance[5:] == pytest.approx([DISPLAY_DAY_CD_M2] * 2)
    assert (DISPLAY_NIGHT_CD_M2, DISPLAY_DAY_CD_M2) == (50.0, 3_100.0)
    # Continuous where the floor meets the square root, 10.4 lx; monotone; any shape; NaN stays NaN.
    knee_lux = DISPLAY_DAY_LUX * (DISPLAY_NIGHT_CD_M2 / DISPLAY_DAY_CD_M2) ** 2
    assert display_luminance_cd_m2(knee_lux) == pytest.approx(DISPLAY_NIGHT_CD_M2)
    assert np.all(np.diff(display_luminance_cd_m2(np.geomspace(1e-3, 1e6, 200))) >= 0)
    assert display_luminance_cd_m2(np.full((2, 3), 1e5)).shape == (2, 3)
    assert np.isnan(display_luminance_cd_m2(np.nan))


def _display(graph):
    rig = graph.vehicles[0]
    parts = zip(graph.actor_nodes[0].mesh.primitives, rig.model.parts, strict=True)
    primitive = next(p for p, part in parts if part.surface == "destination")
    return rig.sign_centre_m, np.asarray(primitive.material.emissiveFactor)


def test_the_scene_graph_lights_the_display_by_the_illuminance_at_it():
    sun_lux, elevation_deg, sky_lux = 50_000.0, 30.0, 10_000.0
    day = build_scene_graph(
        scene_from(
            lights=[
                {"type": "sun", "illuminance_lux": sun_lux, "elevation_deg": elevation_deg, "azimuth_deg": 200.0},
                {"type": "ambient", "illuminance_lux": sky_lux},
            ],
            actors=[BUS],
        )
    )
    _, emission = _display(day)
    day_lux = sun_lux * math.sin(math.radians(elevation_deg)) + sky_lux  # 35,000 lx: 2,900 cd/m²
    np.testing.assert_allclose(emission, display_luminance_cd_m2(day_lux) * AMBER, rtol=1e-6)

    skyglow_lux = 0.031
    night = build_scene_graph(
        scene_from(
            duration_s=8.0,
            lights=[
                {"type": "ambient", "illuminance_lux": skyglow_lux},
                {"type": "lamp", "position_m": LAMP_M.tolist(), "flux_lm": LAMP_FLUX_LM},  # straight down
            ],
            actors=[BUS],
        )
    )
    peak_cd = peak_intensity_cd(LAMP_FLUX_LM, math.radians(LAMP_CONE_DEG))
    seen = []
    for time_s in (0.0, 4.0, 8.0):
        night.place_actors(time_s)
        centre, emission = _display(night)
        offset = LAMP_M - centre
        distance_m = float(np.linalg.norm(offset))
        cos_theta = offset[2] / distance_m  # off the lamp's downward axis, and off the display's vertical
        lamp_lux = float(beam_intensity_cd(peak_cd, math.acos(cos_theta), math.radians(LAMP_CONE_DEG)))
        lamp_lux *= cos_theta / distance_m**2
        expected = display_luminance_cd_m2(skyglow_lux + lamp_lux)
        np.testing.assert_allclose(emission, expected * AMBER, rtol=1e-6)
        seen.append(float(expected))
    # Under the lamp the display is above its night floor; driven on past the lamp's beam, back on it.
    assert seen[0] > 1.5 * DISPLAY_NIGHT_CD_M2 and seen[-1] == pytest.approx(DISPLAY_NIGHT_CD_M2)


def test_a_standing_bus_dims_its_display_with_the_dusk():
    site = {"latitude_deg": 53.55, "longitude_deg": 9.99, "time": "2026-10-15T17:45:00+02:00"}
    graph = build_scene_graph(
        scene_from(
            duration_s=300.0,
            environment={"site": site},
            lights=[{"type": "sun"}, {"type": "ambient"}],  # the site's clear sky gives both
            actors=[{**BUS, "path": {"waypoints_m": [[0, 0]]}}],
        )
    )
    scene_site = graph.daylight.site
    seen = []
    for time_s in (0.0, 300.0):
        graph.set_daylight(time_s)
        graph.place_actors(time_s)
        now = site_daylight(
            scene_site.latitude_deg,
            scene_site.longitude_deg,
            scene_site.time + timedelta(seconds=time_s),
            scene_site.north_deg,
            graph.daylight.sky,
        )
        lux = now.sun_illuminance_lux * math.sin(math.radians(now.elevation_deg)) + now.sky_illuminance_lux
        _, emission = _display(graph)
        np.testing.assert_allclose(emission, display_luminance_cd_m2(lux) * AMBER, rtol=1e-4)
        seen.append(emission[0])
    assert seen[1] < 0.97 * seen[0]  # five minutes before sunset: 6,200 lx to 5,500


def test_an_ies_lamp_lights_the_display_by_its_table():
    ies_file, c0_azimuth_deg = "ies/street_lantern_synthetic.ies", 30.0
    graph = build_scene_graph(
        scene_from(
            lights=[
                {"type": "ambient", "illuminance_lux": 0.031},
                {
                    "type": "lamp",
                    "position_m": LAMP_M.tolist(),
                    "ies_file": ies_file,
                    "c0_azimuth_deg": c0_azimuth_deg,
                    "flux_lm": LAMP_FLUX_LM,
                },
            ],
            actors=[BUS],
        ),
        resolve_path=lambda name: SCENES / name,
    )
    centre, emission = _display(graph)
    photometry = read_ies(SCENES / ies_file)
    scale = LAMP_FLUX_LM / ies_flux_lm(intensity_grid_cd(photometry))
    offset = centre - LAMP_M  # from the lamp, aimed straight down: γ from the nadir, C anticlockwise from C = 0
    distance_m = float(np.linalg.norm(offset))
    gamma_deg = math.degrees(math.acos(-offset[2] / distance_m))
    c_deg = math.degrees(math.atan2(offset[1], offset[0])) - c0_azimuth_deg
    lamp_lux = scale * float(photometry.intensity_cd(gamma_deg, c_deg)) * (-offset[2] / distance_m) / distance_m**2
    assert lamp_lux > 10.0
    np.testing.assert_allclose(emission, display_luminance_cd_m2(0.031 + lamp_lux) * AMBER, rtol=0.01)


@pytest.mark.opengl
def test_at_night_the_display_stands_out_far_less_than_a_fixed_luminance_would(renderer):
    from camgen.render.renderer import View

    ground_rgb, dot_base_red = 0.2, 0.45  # the ground's colour here; the dots' base colour (scene_graph)
    contrast = {}
    for name, lux in (("night", 2.0), ("day", 20_000.0)):
        scene = scene_from(
            environment={
                "sky_luminance_cd_m2": 0.0,
                "shadows": False,
                "meshes": [
                    {
                        "type": "plane",
                        "name": "ground",
                        "size_m": [80, 80],
                        "material": {"color_rgb": [ground_rgb] * 3, "roughness": 0.9},
                    }
                ],
            },
            lights=[{"type": "ambient", "illuminance_lux": lux}],
            actors=[{**BUS, "path": {"waypoints_m": [[0, 0]]}}],
        )
        graph = build_scene_graph(scene)
        centre, _ = _display(graph)
        T = look_at(centre + np.array([9.0, 0.0, 0.0]), centre - np.array([0.0, 0.0, 1.2]))  # 9 m ahead; ground below
        view = View(camera_matrix(300.0, 300.0, 79.5, 59.5), T, 160, 120)
        passes = renderer.draw(graph, view, ("radiance", "instance_id"))
        red = passes.radiance[..., 0]
        ground = red[passes.instance_id == 2]
        dots = red[passes.instance_id == 1].max()  # the brightest of the bus: its display's dots
        assert len(ground) > 1000
        np.testing.assert_allclose(np.median(ground), ground_rgb * lux / math.pi, rtol=1e-4)
        lit = AMBER[0] * display_luminance_cd_m2(lux) + dot_base_red * lux / math.pi
        assert dots == pytest.approx(lit, rel=1e-3)
        contrast[name] = dots / np.median(ground)
    # A fixed luminance made the night's contrast about 5,300 times the day's (the illuminance ratio, 10⁴,
    # less the dots' own reflection by day); the dimmed display's is 126 times.
    assert contrast["night"] / contrast["day"] < 0.05 * 20_000.0 / 2.0
