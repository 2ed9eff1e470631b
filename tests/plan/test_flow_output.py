"""outputs.flow and outputs.scene_flow on rendered frames: a PTZ head panning over a static scene gives
the rotation's flow through the lens (OpenCV's projection as the reference), so does a virtual PTZ's
moving crop (the same rays through the next frame's stream camera matrix), a box moving sideways
flows by f·Δx/z, the flow carries each frame onto the next (the person's limbs included), and the files
read back with OpenCV and OpenImageIO."""

from __future__ import annotations

import json

import cv2
import numpy as np
import OpenImageIO as oiio  # noqa: N813 - the alias its documentation uses
import pytest

from camgen.config import load_scene
from camgen.optics.remap import output_grid_px
from camgen.plan import PlanSettings, compile_scene
from camgen.plan.execute import execute
from tests.conftest import FIXED_PROFILE, PTZ_PROFILE, write

pytestmark = pytest.mark.opengl

W, H = 160, 120
BOX_SPEED_M_S, FPS = 5.0, 10
SCENE = f"""\
duration_s: 0.3
fps: {FPS}
environment:
  meshes:
    - {{type: plane, name: ground, size_m: [60, 60]}}
    - {{type: box, name: crate, size_m: [1, 1, 1], position_m: [1, 8, 0.5]}}
lights:
  - {{type: sun, illuminance_lux: 50000, azimuth_deg: 135, elevation_deg: 40}}
  - {{type: ambient, illuminance_lux: 5000}}
actors:
  - name: mover
    class: other
    shape: {{type: box, name: body, size_m: [1.0, 0.5, 1.0], position_m: [0, 0, 1.5],
             material: {{color_rgb: [0.9, 0.5, 0.2]}}}}
    path: {{waypoints_m: [[-1.5, 8], [6, 8]], speed_m_s: {BOX_SPEED_M_S}}}
  - name: walker
    class: person
    path: {{waypoints_m: [[0.3, 5], [3, 5]], speed_m_s: 1.4}}
outputs: {{video: false, annotations: [], flow: flo, scene_flow: true, depth: exr, radiance: exr}}
cameras:
  - {{name: fixed, profile: fixed, mount: {{position_m: [0, 0, 1.5], yaw_deg: 90, pitch_deg: 0}}}}
  - name: ptz
    profile: ptz
    mount: {{position_m: [0, 0, 3], yaw_deg: 90, pitch_deg: 0}}
    ptz: {{pan_deg: 10, tilt_deg: -10, program: {{type: keyframes, keys: [{{time_s: 2, pan_deg: -10, tilt_deg: -5}}]}}}}
  - name: virtual
    profile: wide
    mount: {{position_m: [0, 0, 3], yaw_deg: 90, pitch_deg: -15}}
    eptz:
      output_size_px: [{W}, {H}]
      zoom_x: 1.5
      program: {{type: keyframes, keys: [{{time_s: 0.5, pan_deg: 8, zoom_x: 2}}]}}
"""


def _small(profile: str) -> str:
    small = profile.replace("width_px: 640", f"width_px: {W}").replace("height_px: 480", f"height_px: {H}")
    return small.replace("pixel_pitch_um: 3.0", "pixel_pitch_um: 12.0")  # the field of view of 640×480


@pytest.fixture(scope="module")
def rendered(renderer, tmp_path_factory):
    root = tmp_path_factory.mktemp("flow")
    write(root, "profiles/fixed.yaml", _small(FIXED_PROFILE))
    barrel = "  f_number: 1.6\n  distortion: {k1: -0.2, k2: 0.05}\n"
    write(root, "profiles/ptz.yaml", _small(PTZ_PROFILE).replace("  f_number: 1.6\n", barrel))
    write(
        root,
        "profiles/wide.yaml",
        _small(FIXED_PROFILE).replace("  f_number: 2.0\n", "  f_number: 2.0\n  distortion: {k1: -0.15}\n"),
    )
    job = compile_scene(load_scene(write(root, "scenes/flow.yaml", SCENE)), PlanSettings(supersampling=1))
    results = execute(job, root / "out", renderer=renderer)
    return {result.name: result.directory for result in results}


def _exr(path) -> np.ndarray:
    return oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT)


def _states(directory) -> list[dict]:
    return [json.loads(line) for line in (directory / "camera.jsonl").read_text().splitlines()]


def test_every_frame_but_the_last_has_its_flow(rendered):
    for directory in rendered.values():
        assert sorted(p.name for p in (directory / "flow").iterdir()) == ["000000.flo", "000001.flo"]
        assert sorted(p.name for p in (directory / "scene_flow").iterdir()) == ["000000.exr", "000001.exr"]
        spec = oiio.ImageBuf(str(directory / "scene_flow" / "000000.exr")).spec()
        assert spec.channelnames == ("X", "Y", "Z") and (spec.width, spec.height) == (W, H)


@pytest.mark.parametrize("frame", [0, 1])
def test_a_pan_over_the_static_scene_gives_the_rotation_through_the_lens(rendered, frame):
    directory = rendered["ptz"]
    now, later = _states(directory)[frame : frame + 2]
    T0, T1 = np.array(now["T_world_from_cam"]), np.array(later["T_world_from_cam"])
    assert np.allclose(T0[:3, 3], T1[:3, 3])  # the head turns about the camera's centre
    rotation_deg = np.degrees(np.arccos(np.clip((np.trace(T1[:3, :3].T @ T0[:3, :3]) - 1) / 2, -1, 1)))
    assert rotation_deg > 0.5
    flow = cv2.readOpticalFlow(str(directory / "flow" / f"{frame:06d}.flo"))
    static = ~np.any(np.nan_to_num(_exr(directory / "scene_flow" / f"{frame:06d}.exr"), nan=0.0) != 0, axis=-1)
    # OpenCV's lens model: undistort each pixel to its ray, turn it into the next camera, project it.
    grid = output_grid_px(W, H)
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
    K0, K1 = np.array(now["K_px"]), np.array(later["K_px"])
    d0, d1 = np.array(now["distortion"]), np.array(later["distortion"])
    assert abs(d0[0]) > 0.1  # the lens distorts: the flow goes through it
    rays = cv2.undistortPoints(grid.reshape(-1, 1, 2), K0, d0, criteria=criteria).reshape(-1, 2)
    turned = np.column_stack([rays, np.ones(len(rays))]) @ (T1[:3, :3].T @ T0[:3, :3]).T
    expected, _ = cv2.projectPoints(turned, np.zeros(3), np.zeros(3), K1, d1)
    expected = expected.reshape(H, W, 2) - grid
    assert static.mean() > 0.8
    assert np.abs(flow - expected)[static].max() < 0.01


def test_a_box_moving_sideways_flows_by_focal_length_times_its_step_over_depth(rendered):
    directory = rendered["fixed"]
    (state,) = _states(directory)[:1]
    fx = state["K_px"][0][0]
    step_m = BOX_SPEED_M_S / FPS
    flow = cv2.readOpticalFlow(str(directory / "flow" / "000000.flo"))
    scene_flow = _exr(directory / "scene_flow" / "000000.exr")
    depth = _exr(directory / "depth" / "000000.exr")[..., 0]
    box = np.all(np.abs(scene_flow - [step_m, 0.0, 0.0]) < 1e-5, axis=-1)
    assert box.sum() > 100
    np.testing.assert_allclose(flow[box, 0], fx * step_m / depth[box], rtol=1e-4)
    assert np.abs(flow[box, 1]).max() < 1e-3
    background = np.all(np.nan_to_num(scene_flow, nan=0.0) == 0, axis=-1)
    assert np.abs(flow[background]).max() < 1e-4  # a still camera: the environment does not move
    assert np.isnan(scene_flow[0, 0]).all()  # the sky: no surface


@pytest.mark.parametrize("frame", [0, 1])
def test_the_flow_carries_the_moving_actors_onto_the_next_frame(rendered, frame):
    """Frame t + 1 sampled where the flow says each moving pixel went matches frame t (brightness
    constancy), far better than frame t + 1 where the pixel was; the person's skinned limbs included."""
    directory = rendered["fixed"]
    flow = cv2.readOpticalFlow(str(directory / "flow" / f"{frame:06d}.flo"))
    now = _exr(directory / "radiance" / f"{frame:06d}.exr") @ [0.2126, 0.7152, 0.0722]
    later = _exr(directory / "radiance" / f"{frame + 1:06d}.exr") @ [0.2126, 0.7152, 0.0722]
    moving = np.any(np.nan_to_num(_exr(directory / "scene_flow" / f"{frame:06d}.exr")) != 0, axis=-1)
    grid = output_grid_px(W, H).astype(np.float32)
    target = grid + flow
    warped = cv2.remap(later.astype(np.float32), target[..., 0], target[..., 1], cv2.INTER_LINEAR)
    inside = (target[..., 0] >= 0) & (target[..., 0] <= W - 1) & (target[..., 1] >= 0) & (target[..., 1] <= H - 1)
    chosen = moving & inside
    assert chosen.sum() > 500
    error = np.abs(warped - now)[chosen] / now[chosen]
    unmoved = np.abs(later - now)[chosen] / now[chosen]
    assert np.median(error) < 0.03 < 0.3 < np.median(unmoved)


@pytest.mark.parametrize("frame", [0, 1])
def test_a_virtual_ptz_moves_the_static_scene_by_its_crop_through_the_lens(rendered, frame):
    directory = rendered["virtual"]
    now, later = _states(directory)[frame : frame + 2]
    assert now["window_px"] != later["window_px"]  # the crop pans and zooms
    flow = cv2.readOpticalFlow(str(directory / "flow" / f"{frame:06d}.flo"))
    grid = output_grid_px(W, H)
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
    # camera.jsonl's K_px is the stream's; the sensor's distortion holds on it (a crop and scale).
    distortion = np.array(now["distortion"])
    assert abs(distortion[0]) > 0.1
    rays = cv2.undistortPoints(grid.reshape(-1, 1, 2), np.array(now["K_px"]), distortion, criteria=criteria)
    rays = np.column_stack([rays.reshape(-1, 2), np.ones(W * H)])
    expected, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), np.array(later["K_px"]), distortion)
    expected = expected.reshape(H, W, 2) - grid
    static = ~np.any(np.nan_to_num(_exr(directory / "scene_flow" / f"{frame:06d}.exr"), nan=0.0) != 0, axis=-1)
    assert static.mean() > 0.5  # the box and the walker fill the rest
    assert np.abs(flow - expected)[static].max() < 0.01
    assert np.abs(flow).mean() > 1.0
