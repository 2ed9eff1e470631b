"""Per-mover motion blur (`CameraRenderer._blurred_groups`) and shadows: a mover's sub-frames count the image
path of its shadow too, so a shadow that sweeps the view faster than its caster (here a car behind the camera,
out of view, whose long shadow under a low sun lies across the view) is smeared as drawing every sub-frame whole
smears it (~15 px), not drawn sharp (found by review of db02ab6, which counted the caster's vertices only)."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.plan import PlanSettings, compile_scene
from camgen.render.scene_graph import build_scene_graph
from camgen.render.sequence import CameraRenderer
from tests.conftest import write
from tests.render.test_moving_regions import SMALL_PROFILE

pytestmark = pytest.mark.opengl

SCENE = """\
duration_s: 2
fps: 10
environment:
  sky: clear
  meshes:
    - {type: plane, name: ground, size_m: [80, 80], material: {color_rgb: [0.5, 0.5, 0.5]}}
lights:
  - {type: sun, illuminance_lux: 50000, azimuth_deg: 270, elevation_deg: 7}
  - {type: ambient, illuminance_lux: 3000}
actors:
  - name: passer
    class: car
    shape: {type: box, name: body, size_m: [4, 1.8, 1.5], position_m: [0, 0, 0.75],
            material: {color_rgb: [0.8, 0.1, 0.1]}}
    path: {waypoints_m: [[-30, -3], [30, -3]], speed_m_s: 15, motion: linear}
  - name: racer
    class: car
    shape: {type: box, name: body, size_m: [1.6, 0.8, 1.4], position_m: [0, 0, 0.7],
            material: {color_rgb: [0.1, 0.1, 0.8]}}
    path: {waypoints_m: [[-12, 7], [12, 7]], speed_m_s: 30, motion: linear}
outputs: {annotations: []}
cameras:
  - {name: cam, profile: fixed, mount: {position_m: [0, 0, 4], yaw_deg: 90, pitch_deg: -35}}
"""
FRAME = 19  # t = 1.9 s: the passer at x = -1.5, 3 m behind the camera; its shadow's trailing edge crosses the view


def _transition_px(radiance: np.ndarray) -> int:
    """Pixels of the middle row between 10 % and 90 % of the way from the shadow to the lit ground."""
    row = radiance.mean(axis=2)[radiance.shape[0] // 2]
    lo, hi = row.min(), row.max()
    return int(((row > lo + 0.1 * (hi - lo)) & (row < hi - 0.1 * (hi - lo))).sum())


def test_a_shadow_sweeping_the_view_is_blurred_as_whole_sub_frames_blur_it(tmp_path, renderer):
    write(tmp_path, "profiles/fixed.yaml", SMALL_PROFILE)
    job = compile_scene(load_scene(write(tmp_path, "scenes/s.yaml", SCENE)), PlanSettings(supersampling=2))
    camera = job.cameras[0]
    assert any(stage.name == "optics.motion_blur" for stage in camera.stages)
    per_mover = CameraRenderer(renderer, build_scene_graph(job.scene), camera).frame(FRAME).passes.radiance
    whole = CameraRenderer(renderer, build_scene_graph(job.scene), camera, moving_regions=False)
    whole._blurred_groups = lambda *args, **kwargs: None  # the plan's sub-frames, each drawn whole
    reference = whole.frame(FRAME).passes.radiance
    assert _transition_px(reference) >= 8  # the reference smears the shadow's edge
    assert _transition_px(per_mover) >= 0.7 * _transition_px(reference)
