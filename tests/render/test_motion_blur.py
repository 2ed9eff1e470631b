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
    path: {{waypoints_m: [[-20, {DISTANCE_M}], [20, {DISTANCE_M}]], speed_m_s: {SPEED_M_S}, motion: linear}}
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


POLE = """\
    - {type: box, name: pole, size_m: [0.31, 0.2, 0.8], position_m: [2.2, 8.5, 2.9], rotation_deg: [0, 20, 0],
       material: {color_rgb: [0.8, 0.7, 0.2]}}
"""


def test_sub_frames_carry_the_supersampling_so_static_edges_equal_the_box_average(workspace, renderer):
    """With supersampling 2, each motion sub-frame is drawn at 1× through one of the 2×2 sub-pixel
    positions (`jittered_samples`): a static edge (a slanted pole above the mover's path) comes out as
    the 2×2 box average of a sharp 2× render, not as the aliased 1× render, and the moving edge still
    smears by the image motion."""
    write(
        workspace, "profiles/fixed.yaml", FIXED_PROFILE + f"exposure: {{mode: manual, exposure_time_s: {EXPOSURE_S}}}\n"
    )
    scene = SCENE.replace("lights:\n", POLE + "lights:\n", 1)
    job = compile_scene(load_scene(write(workspace, "scenes/s.yaml", scene)), PlanSettings(supersampling=2))
    camera = job.cameras[0]
    (stage,) = [s for s in camera.stages if s.name == "optics.motion_blur"]
    sharp_camera = camera.model_copy(update={"stages": tuple(s for s in camera.stages if s is not stage)})
    one_x = sharp_camera.model_copy(update={"render": camera.render.model_copy(update={"supersampling": 1})})
    index = 40
    state = camera.states[index]
    samples = CameraRenderer(renderer, build_scene_graph(job.scene), camera).motion_samples(state)
    assert samples > 4 and samples % 4 != 0  # rounded up to a multiple of 4 sub-frames
    blurred = next(render_camera(renderer, job, camera, frames=[index])).passes.radiance
    box = next(render_camera(renderer, job, sharp_camera, frames=[index])).passes.radiance
    aliased = next(render_camera(renderer, job, one_x, frames=[index])).passes.radiance
    yellow = (box[..., 0] > 2 * box[..., 2] + 1) & (box[..., 1] > 2 * box[..., 2] + 1)  # the pole, not the grey box
    rows, columns = np.nonzero(yellow)
    assert len(rows) > 500
    pole = (slice(max(rows.min() - 3, 0), rows.max() + 4), slice(max(columns.min() - 3, 0), columns.max() + 4))
    edge = np.abs(box[pole] - aliased[pole]).max()
    assert edge > 0.05 * box[pole].max()  # the window holds anti-aliased edges
    assert np.abs(blurred[pole] - box[pole]).max() < 1e-3 * box[pole].max()

    K = np.array(state.K_px)
    x_edge_m = -20 + SPEED_M_S * state.time_s + 0.5
    u_edge = K[0, 2] + K[0, 0] * x_edge_m / DISTANCE_M
    variance, _ = _variance(_edge_profile(blurred, u_edge))
    variance_0, _ = _variance(_edge_profile(box, u_edge))
    expected_px = SPEED_M_S * EXPOSURE_S * K[0, 0] / DISTANCE_M
    assert np.sqrt(12 * (variance - variance_0)) == pytest.approx(expected_px, rel=0.05)
