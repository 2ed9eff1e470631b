"""PTZ and camera networks through the renderer.

1. Zoom: a PTZ camera calibrated from checkerboard renders at two zoom steps (1× and 2.5×) recovers
   each step's focal length f_wide·zoom within 0.2 % (measured: see the test's printout, -s).
2. Camera network: an actor seen by both cameras of scenes/intersection_two_cameras.yaml carries the
   same global instance id in both instance passes, the id of the scene's instance table.
3. A moving PTZ sequence (tour with a zoom change) runs end to end: the video is written and
   camera.jsonl records the head's pan, tilt and zoom moving under its limits.
"""

from __future__ import annotations

import json

import av
import cv2
import numpy as np
import pytest
import yaml

from camgen.config import load_scene
from camgen.fit.checkerboard import RECTILINEAR, calibrate, find_corners, gray8_from_radiance, inner_corners
from camgen.motion.trajectory import actor_routes
from camgen.optics.projection import project_points
from camgen.plan import PlanSettings, compile_scene
from camgen.plan.execute import execute
from camgen.plan.ptz import actor_centre
from camgen.render.scene_graph import instance_table
from camgen.render.sequence import crop_to_output, render_camera
from tests.conftest import REPO

pytestmark = pytest.mark.opengl

# Same field of view as the checkerboard example's profile at zoom 1 (1920 px × 5.8 µm behind 6 mm),
# no distortion and f/4 so that the focal length alone is measured.
ZOOM_PROFILE = """\
description: test PTZ camera for zoom calibration
sensor: {width_px: 1920, height_px: 1080, pixel_pitch_um: 5.8, full_well_e: 20000, conversion_gain_dn_per_e: 0.2}
lens: {focal_length_range_mm: [6.0, 60.0], f_number: 4.0, min_focus_distance_m: 0.3}
ptz: {tilt_range_deg: [-90, 90]}
"""
ZOOM_STEPS = (1.0, 2.5)
RENDERED_ZOOM_X = 2.5
"""The zoom step rendered and calibrated. Zoom 1 (6 mm) is the field of view that
tests/render/test_calibration.py already calibrates from the same 14 poses (the example's own profile), so
at zoom 1 only the planned camera is checked here: 30 s of rendering and corner finding would repeat it."""


def zoom_scene(directory, zoom_x: float):
    """The checkerboard example's 14 poses, each moved away from the board by the zoom factor."""
    data = yaml.safe_load((REPO / "scenes/checkerboard.yaml").read_text())
    (directory / "zoom_ptz.yaml").write_text(ZOOM_PROFILE)
    board = next(m for m in data["environment"]["meshes"] if m["name"] == "board")
    centre = np.array(board["position_m"])
    data["environment"]["meshes"] = [board]  # the floor would keep depth of field in (see test_lens_calibration)
    for camera in data["cameras"]:
        camera["profile"] = "zoom_ptz.yaml"
        position = centre + (np.array(camera["mount"]["position_m"]) - centre) * zoom_x
        camera["mount"]["position_m"] = position.round(4).tolist()
        camera["ptz"] = {"zoom_x": zoom_x}
        camera["focus_distance_m"] = float(np.linalg.norm(position - centre))
    path = directory / f"zoom_{zoom_x:g}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def find_corners_on_the_board(gray8: np.ndarray, inner: tuple[int, int]) -> np.ndarray | None:
    """`find_corners` on the part of a view that holds the board, with a margin of 2.5 squares: the board is
    located by OpenCV's detector on the view at half size (no sub-pixel step), then its corners are found at
    full size in that part only. Nothing of the plan's camera is used.

    At zoom 2.5 the board covers 12–59 % of these views: detection took 19 s instead of 34 s for the 14
    views (loaded machine), and its corners calibrate as well: fx −0.075 %, fy −0.080 %, RMS 0.049 px
    against −0.066 %, −0.072 %, 0.049 px from the whole views (3× supersampling; single corners move by
    up to 0.08 px, as the detector's result depends on the image it is given). tests/render/test_calibration.py
    keeps whole views: there, with the distortion free too, its cy moved from +0.31 to +0.42 px (bound 0.5)."""
    height, width = gray8.shape
    half = cv2.resize(gray8, (width // 2, height // 2), interpolation=cv2.INTER_AREA)
    found, coarse = cv2.findChessboardCornersSB(half, inner)
    if not found:
        return None
    corners = coarse.reshape(inner[1], inner[0], 2) * 2 + 0.5  # half-size pixel centres at full size
    margin_px = 2.5 * float(np.hypot(*np.diff(corners, axis=1).reshape(-1, 2).T).max())
    (x0, y0), (x1, y1) = corners.reshape(-1, 2).min(axis=0) - margin_px, corners.reshape(-1, 2).max(axis=0) + margin_px
    x0, y0 = max(0, int(x0)), max(0, int(y0))
    x1, y1 = min(width, int(np.ceil(x1))), min(height, int(np.ceil(y1)))
    fine = find_corners(np.ascontiguousarray(gray8[y0:y1, x0:x1]), inner)
    return None if fine is None else fine + np.float32([x0, y0])


@pytest.mark.parametrize("zoom_x", ZOOM_STEPS)
def test_a_zoom_step_plans_the_focal_length_and_its_camera_matrix(tmp_path, zoom_x):
    """focal length = wide end × zoom_x, and fx, fy = f / pitch: what the rendered zoom step is calibrated against."""
    job = compile_scene(load_scene(zoom_scene(tmp_path, zoom_x)))
    for camera in job.cameras:
        state = camera.states[0]
        assert state.focal_length_mm == pytest.approx(6.0 * zoom_x)
        f_px = 6.0 * zoom_x / 5.8e-3
        np.testing.assert_allclose(np.array(state.K_px)[[0, 1], [0, 1]], [f_px, f_px], rtol=1e-9)
        np.testing.assert_allclose(np.array(state.K_px)[:2, 2], [959.5, 539.5], atol=1e-9)


def test_calibration_at_a_zoom_step_recovers_its_focal_length(renderer, tmp_path):
    zoom_x = RENDERED_ZOOM_X
    # 3× supersampling: at 2× (the default) the farther board's edges gave fx +0.17 %, near the bound; 3× −0.07 %.
    job = compile_scene(load_scene(zoom_scene(tmp_path, zoom_x)), PlanSettings(supersampling=3))
    board = next(m for m in job.scene.environment.meshes if m.name == "board")
    found = []
    for camera in job.cameras:
        frame = next(render_camera(renderer, job, camera))
        radiance = crop_to_output(frame.passes.radiance, camera.render)
        found.append(find_corners_on_the_board(gray8_from_radiance(radiance), inner_corners(board)))
    views = [c for c in found if c is not None]
    assert len(views) >= 12
    camera = job.cameras[0]
    # the profile's lens is rectilinear: fit the intrinsics alone (k free would trade f against k1)
    result = calibrate(board, views, (camera.width_px, camera.height_px), flags=RECTILINEAR)
    K_plan = np.array(camera.states[0].K_px)
    assert camera.states[0].focal_length_mm == pytest.approx(6.0 * zoom_x)
    error_fx, error_fy = result.K_px[0, 0] / K_plan[0, 0] - 1, result.K_px[1, 1] / K_plan[1, 1] - 1
    print(f"zoom {zoom_x:g}×: fx {error_fx:+.4%}, fy {error_fy:+.4%}, RMS {result.rms_px:.3f} px, {len(views)} views")
    assert result.rms_px < 0.1
    assert abs(error_fx) < 2e-3 and abs(error_fy) < 2e-3


def test_an_actor_has_one_global_id_in_both_cameras(renderer, tmp_path):
    data = yaml.safe_load((REPO / "scenes/intersection_two_cameras.yaml").read_text())
    data["outputs"] = {"video": False, "annotations": ["coco"]}  # instance ids only (mot would draw img1 frames)
    path = tmp_path / "intersection.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    job = compile_scene(load_scene(path))
    ids = {instance.name: instance.instance_id for instance in instance_table(job.scene)}
    routes = actor_routes(job.scene)
    frame = 50  # t = 2 s: car_east near the middle of the crossing
    seen = {}
    for camera in job.cameras:
        state = camera.states[frame]
        passes = next(render_camera(renderer, job, camera, frames=[frame])).passes
        instance = crop_to_output(passes.instance_id, camera.render)
        for actor in job.scene.actors:
            centre_at, _ = actor_centre(actor, routes[actor.name])
            # A person's box centre is at the crotch, between the legs: look at the chest instead.
            chest_m = np.array([0.0, 0.0, 0.35 if actor.cls == "person" else 0.0])
            # the pinhole render (no lens stage has run yet): project without distortion
            uv, depth = project_points(
                (centre_at(state.time_s) + chest_m)[None],
                np.array(state.T_world_from_cam),
                np.array(state.K_px),
                np.zeros(8),
            )
            u, v = np.round(uv[0]).astype(int) if np.all(np.isfinite(uv[0])) else (-1, -1)
            if depth[0] > 0 and 0 <= u < camera.width_px and 0 <= v < camera.height_px:
                seen.setdefault(actor.name, {})[camera.name] = int(instance[v, u])
    both = {name: by_camera for name, by_camera in seen.items() if len(by_camera) == 2}
    assert both, f"no actor centre in both views at frame {frame}: {seen}"
    for name, by_camera in both.items():
        assert set(by_camera.values()) == {ids[name]}, (name, by_camera)


PTZ_TOUR_PROFILE = """\
description: small PTZ camera for an end-to-end tour
sensor: {width_px: 320, height_px: 180, pixel_pitch_um: 3.0, full_well_e: 10000, conversion_gain_dn_per_e: 0.4}
lens: {focal_length_range_mm: [2.0, 20.0], f_number: 1.6, distortion: {k1: -0.05}}
codec: {name: h264, bitrate_kbps: 500}
ptz: {pan_max_deg_s: 120, pan_accel_deg_s2: 300, tilt_range_deg: [-90, 10]}
"""


def test_a_ptz_tour_renders_end_to_end(renderer, tmp_path):
    data = yaml.safe_load((REPO / "scenes/ptz_patrol.yaml").read_text())
    (tmp_path / "small_ptz.yaml").write_text(PTZ_TOUR_PROFILE)
    data["duration_s"] = 1.2
    camera = data["cameras"][0]
    camera["profile"] = "small_ptz.yaml"
    camera["ptz"]["program"]["stops"][0]["dwell_s"] = 0.1
    (tmp_path / "tour.yaml").write_text(yaml.safe_dump(data, sort_keys=False))
    job = compile_scene(load_scene(tmp_path / "tour.yaml"), PlanSettings(supersampling=1))
    results = execute(job, tmp_path / "out", renderer=renderer)
    directory = results[0].directory
    assert (directory / "video.mp4").stat().st_size > 0
    records = [json.loads(line) for line in (directory / "camera.jsonl").read_text().splitlines()]
    assert len(records) == job.frame_count
    pan = np.array([r["pan_deg"] for r in records])
    zoom = np.array([r["zoom_x"] for r in records])
    assert pan[-1] > pan[0] + 5 and zoom[-1] > 1.5  # on its way to the zoomed entrance preset
    assert {r["ptz_mode"] for r in records} >= {"dwell", "move"}
    speed = np.abs(np.diff(pan)) * job.fps
    assert speed.max() <= 120 * (1 + 1e-9) + 0.01 * job.fps  # plus one pan step of quantisation
    for record in records:
        K = np.array(record["K_px"])
        assert K[0, 0] == pytest.approx(record["focal_length_mm"] / 3.0e-3)


EPTZ_PROFILE = """\
description: small fixed camera for a virtual PTZ
sensor: {width_px: 640, height_px: 360, pixel_pitch_um: 3.0, full_well_e: 10000, conversion_gain_dn_per_e: 0.4}
lens: {focal_length_mm: 2.4, f_number: 2.0, distortion: {k1: -0.08, k2: 0.01}}
codec: {name: h264, bitrate_kbps: 500}
"""


def test_a_virtual_ptz_stream_and_its_metadata_agree(renderer, tmp_path):
    """ePTZ following a walker: the stream has the output size, and the walker's centre projected with
    camera.jsonl's K_px and distortion lands on the walker's ids in the stream's instance pass."""
    data = yaml.safe_load((REPO / "scenes/ptz_follow.yaml").read_text())
    (tmp_path / "small_box.yaml").write_text(EPTZ_PROFILE)
    data["duration_s"] = 1.0
    data["cameras"] = [
        {
            "name": "box_eptz",
            "profile": "small_box.yaml",
            "mount": {"position_m": [-24, -16, 6], "yaw_deg": 62, "pitch_deg": -14},
            "eptz": {
                "output_size_px": [320, 180],
                "zoom_max_x": 4,
                "program": {"type": "follow", "target": "walker_1", "target_height_frac": 0.4},
            },
        }
    ]
    (tmp_path / "eptz.yaml").write_text(yaml.safe_dump(data, sort_keys=False))
    job = compile_scene(load_scene(tmp_path / "eptz.yaml"), PlanSettings(supersampling=1))
    directory = execute(job, tmp_path / "out", renderer=renderer, save_passes=True)[0].directory
    records = [json.loads(line) for line in (directory / "camera.jsonl").read_text().splitlines()]
    walker_id = next(i.instance_id for i in instance_table(job.scene) if i.name == "walker_1")
    centre_at, _ = actor_centre(job.scene.actors[0], actor_routes(job.scene)["walker_1"])
    zooms, hits = [], 0
    for record in records:
        instance = np.load(directory / "passes" / f"{record['frame']:06d}.npz")["instance_id"]
        assert instance.shape == (180, 320)
        uv, _ = project_points(
            centre_at(record["time_s"])[None],
            np.array(record["T_world_from_cam"]),
            np.array(record["K_px"]),
            np.array(record["distortion"]),
        )
        u, v = np.round(uv[0]).astype(int)
        hits += bool(0 <= u < 320 and 0 <= v < 180 and instance[v, u] == walker_id)
        zooms.append(record["zoom_x"])
        x0, y0, w, h = record["window_px"]
        assert 0 <= x0 and x0 + w <= 640 and 0 <= y0 and y0 + h <= 360
    assert hits == len(records)
    assert max(zooms) > 1.2  # it zoomed in on the walker
    with av.open(str(directory / "video.mp4")) as container:
        stream = container.streams.video[0]
        assert (stream.codec_context.width, stream.codec_context.height) == (320, 180)
