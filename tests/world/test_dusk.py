"""Daylight that changes during a sequence: the site's sun sinks frame by frame, the lights and the sky
follow the model, and the camera's auto-exposure follows the light."""

from __future__ import annotations

import json
import math
from datetime import datetime, timedelta

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.plan import PlanSettings, compile_scene
from camgen.world.daylight import direct_normal_illuminance_lux, sky_horizontal_illuminance_lux
from camgen.world.site import site_daylight
from camgen.world.sun import solar_position, unix_time_s
from tests.conftest import FIXED_PROFILE, write
from tests.render.conftest import scene_from

HAMBURG = {"latitude_deg": 53.55, "longitude_deg": 9.99, "time": "2026-10-15T17:15:00+02:00"}
"""An October evening: the sun sets at 18:22 CEST there."""
DUSK_S = 2700.0
REFLECTANCE = 0.4

DUSK_SCENE = f"""\
duration_s: {DUSK_S:g}
fps: {1 / 900}
environment:
  sky: clear
  site: {{latitude_deg: 53.55, longitude_deg: 9.99, time: "{HAMBURG["time"]}"}}
  shadows: false
  meshes:
    - type: plane
      name: ground
      size_m: [200, 200]
      material: {{color_rgb: [{REFLECTANCE}, {REFLECTANCE}, {REFLECTANCE}], roughness: 1.0}}
lights:
  - {{type: sun}}
  - {{type: ambient}}
cameras:
  - name: cam
    profile: fixed
    mount: {{position_m: [0, 0, 10], yaw_deg: 90, pitch_deg: -60}}
outputs: {{video: false, frames: png, annotations: []}}
"""


def _graph(duration_s: float):
    from camgen.render.scene_graph import build_scene_graph

    scene = scene_from(
        duration_s=duration_s,
        environment={"sky": "clear", "site": HAMBURG},
        lights=[{"type": "sun"}, {"type": "ambient", "illuminance_lux": 2000.0}],
    )
    return scene, build_scene_graph(scene)


@pytest.mark.opengl
def test_the_sun_sinks_and_the_lights_follow_the_model():
    scene, graph = _graph(DUSK_S)
    assert graph.daylight is not None
    start = datetime.fromisoformat(HAMBURG["time"])
    sun_node = next(iter(graph.scene.directional_light_nodes))
    first = site_daylight(53.55, 9.99, start, 90.0, "clear")
    for time_s in (0.0, 1200.0, DUSK_S):
        graph.set_daylight(time_s)
        now = start + timedelta(seconds=time_s)
        position = solar_position(53.55, 9.99, unix_time_s(now))
        el, az = math.radians(float(position.elevation_deg)), math.radians(90.0 - float(position.azimuth_deg))
        towards = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
        np.testing.assert_allclose(graph.sun_direction, towards, atol=1e-9)
        # The light shines along −towards: its node's −z axis.
        np.testing.assert_allclose(-graph.scene.get_pose(sun_node)[:3, 2], -towards, atol=1e-9)
        direct = float(direct_normal_illuminance_lux(position.elevation_deg, 288, "clear"))
        assert sun_node.light.intensity == pytest.approx(direct, rel=1e-6)
        # The ambient light the scene gave (2000 lux) follows the model's sky through its own level.
        sky_ratio = float(sky_horizontal_illuminance_lux(position.elevation_deg, "clear")) / first.sky_illuminance_lux
        assert graph.scene.ambient_light[0] * math.pi == pytest.approx(2000.0 * sky_ratio, rel=1e-6)
    assert sun_node.light.intensity < 0.25 * scene.lights[0].illuminance_lux  # a low sun at 18:00


def test_a_short_sequence_holds_its_first_daylight():
    _, graph = _graph(10.0)
    assert graph.daylight is None


@pytest.fixture(scope="module")
def dusk_run(renderer, tmp_path_factory):
    from camgen.plan.execute import execute

    root = tmp_path_factory.mktemp("dusk")
    small = FIXED_PROFILE.replace("width_px: 640", "width_px: 160").replace("height_px: 480", "height_px: 120")
    write(root, "profiles/fixed.yaml", small.replace("pixel_pitch_um: 3.0", "pixel_pitch_um: 12.0"))
    loaded = load_scene(write(root, "scenes/dusk.yaml", DUSK_SCENE))
    job = compile_scene(loaded, PlanSettings(supersampling=1))
    [result] = execute(job, root / "out", renderer=renderer, save_passes=True)
    return loaded.scene, job, result.directory


@pytest.mark.opengl
def test_the_plan_lights_each_frame_for_its_time(dusk_run):
    _, job, _ = dusk_run
    decisions = {d.stage: d for d in job.cameras[0].decisions}
    assert decisions["world.daylight"].included
    assert not decisions["render.static_background"].included


@pytest.mark.opengl
def test_the_ground_dims_as_the_model_and_auto_exposure_follows(dusk_run):
    """The ground's radiance, frame by frame, is ρ/π (E_dn sin α + E_kh) at each frame's time, and the
    auto-exposure lengthens as it falls."""
    scene, job, directory = dusk_run
    start = scene.environment.site.time
    states = [json.loads(line) for line in (directory / "camera.jsonl").read_text().splitlines()]
    exposures = [state["exposure_time_s"] * 10 ** (state["gain_db"] / 20) for state in states]
    ground = []
    for frame in range(job.frame_count):
        radiance = np.load(directory / "passes" / f"{frame:06d}.npz")["radiance_cd_m2"]
        ground.append(float(np.median(radiance[40:80, 60:100] @ np.array([0.2126, 0.7152, 0.0722]))))
        daylight = site_daylight(53.55, 9.99, start + timedelta(seconds=frame * 900.0), 90.0, "clear")
        expected = (
            REFLECTANCE
            / math.pi
            * (
                daylight.sun_illuminance_lux * math.sin(math.radians(daylight.elevation_deg))
                + daylight.sky_illuminance_lux
            )
        )
        # Diffuse, plus the renderer's small specular part at roughness 1 (as test_renderer's bound).
        assert expected <= ground[-1] <= 1.05 * expected, (frame, ground[-1], expected)
    assert ground[0] > 1.3 * ground[-1]
    # Auto-exposure sets each frame's exposure from the one before: exposure × the light it metered
    # stays at the target level while the light falls.
    metered = [exposure * light for exposure, light in zip(exposures[1:], ground[:-1], strict=True)]
    np.testing.assert_allclose(metered, metered[0], rtol=0.02)
    assert exposures[-1] > 1.3 * exposures[0]
