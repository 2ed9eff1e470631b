"""Motion blur: an actor moving across a static camera during the exposure smears its edge into a ramp
as long as the distance its image travels, L = v·t_exp·f_px / d (a box line-spread function of
variance L²/12), centred on where the actor is at the frame time."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.plan import PlanSettings, compile_scene
from camgen.render.scene_graph import build_scene_graph
from camgen.render.sequence import CameraRenderer, render_camera
from tests.conftest import FIXED_PROFILE, write

pytestmark = pytest.mark.opengl

SPEED_M_S, DISTANCE_M, EXPOSURE_S = 5.0, 8.0, 0.02
SCENE = f"""\
duration_s: 5
fps: 10
environment:
  meshes:
    - {{type: plane, name: wall, size_m: [40, 20], position_m: [0, 12, 0], rotation_deg: [90, 0, 0],
       material: {{color_rgb: [0.1, 0.1, 0.1]}}}}
lights:
  - {{type: ambient, illuminance_lux: 1000}}
actors:
  - name: mover
    class: car
    shape: {{type: box, name: body, size_m: [1.0, 0.5, 1.0], position_m: [0, 0, 1.5],
             material: {{color_rgb: [0.9, 0.9, 0.9]}}}}
    path: {{waypoints_m: [[-20, {DISTANCE_M}], [20, {DISTANCE_M}]], speed_m_s: {SPEED_M_S}}}
outputs: {{annotations: []}}
cameras:
  - {{name: cam, profile: fixed, mount: {{position_m: [0, 0, 1.5], yaw_deg: 90, pitch_deg: 0}}}}
"""


def _edge_profile(radiance: np.ndarray, u_edge: float) -> np.ndarray:
    rows = slice(230, 250)  # the box's middle rows (it spans 1–2 m high at 8 m: ±83 px about the centre)
    columns = slice(int(u_edge) - 40, int(u_edge) + 41)
    return radiance[rows, columns, 1].astype(np.float64).mean(axis=0)


def _variance(profile: np.ndarray) -> tuple[float, float]:
    lsf = np.abs(np.diff(profile))
    u = np.arange(len(lsf))
    mean = (lsf * u).sum() / lsf.sum()
    return float((lsf * (u - mean) ** 2).sum() / lsf.sum()), float(mean)


def test_moving_edge_is_smeared_by_the_image_motion_during_the_exposure(workspace, renderer):
    write(
        workspace, "profiles/fixed.yaml", FIXED_PROFILE + f"exposure: {{mode: manual, exposure_time_s: {EXPOSURE_S}}}\n"
    )
    job = compile_scene(load_scene(write(workspace, "scenes/s.yaml", SCENE)), PlanSettings(supersampling=1))
    camera = job.cameras[0]
    (stage,) = [s for s in camera.stages if s.name == "optics.motion_blur"]
    sharp_camera = camera.model_copy(update={"stages": tuple(s for s in camera.stages if s is not stage)})
    index = 40  # t = 4 s: the box centre crosses x = 0 (path starts at −20 m, 5 m/s)
    state = camera.states[index]
    K = np.array(state.K_px)
    f_px = K[0, 0]
    expected_px = SPEED_M_S * EXPOSURE_S * f_px / DISTANCE_M
    assert CameraRenderer(renderer, build_scene_graph(job.scene), camera).motion_samples(state) >= expected_px
    blurred = next(render_camera(renderer, job, camera, frames=[index])).passes.radiance
    sharp = next(render_camera(renderer, job, sharp_camera, frames=[index])).passes.radiance
    x_edge_m = -20 + SPEED_M_S * state.time_s + 0.5  # the box's leading face at the frame time
    u_edge = K[0, 2] + f_px * x_edge_m / DISTANCE_M
    variance, centre = _variance(_edge_profile(blurred, u_edge))
    variance_0, centre_0 = _variance(_edge_profile(sharp, u_edge))
    measured_px = np.sqrt(12 * (variance - variance_0))
    assert measured_px == pytest.approx(expected_px, rel=0.05)
    assert centre == pytest.approx(centre_0, abs=0.25)  # the exposure is centred on the frame time
