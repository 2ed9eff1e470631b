"""Coverage's vertical pixel density against renders through every example profile's lens (OpenGL).

A 1 m tall board is placed where its centre images at the frame's centre, 25 px from its left and right
edges (where a barrel lens squeezes a vertical element most: there it is tangential, scaled by the
radial function g(r)) and near its top and bottom edges (where it is radial, scaled by d(r·g)/dr). The
scene goes through the real camera path: `camgen.plan.compile_scene`, `camgen.render.sequence.
render_camera` and the plan's lens stages, whose remap distorts the instance-id pass by nearest pixel.
The board's rendered height (its run of ids in the column through its centre) is compared with
`camgen.coverage.density.densities`' vertical px/m for the same point and camera (the camera's home
view, `camgen.coverage.views.home_view`): within 2 %, as issue 22 accepts. At the side edges a pinhole's
f_y / depth is off by 6.2–6.8 % (bullet), 9.0 % (box camera), 5.1 % (low-light), 4.3 % (30× PTZ) and
3.1 % (20× PTZ), so the check sees the lens.

Measured (rendered against predicted, centre / left / right / top / bottom): the 2.8 mm bullet (−19 %
barrel at the corner, the strongest of profiles/) +0.67 / −0.11 / −0.52 / +0.85 / +0.47 %; the 4K box
camera at its 3.8 mm wide end (k1 −0.08) +0.42 / +0.07 / +0.07 / +0.66 / +0.66 %; the low-light camera
−0.24 / −0.55 / −0.55 / −0.68 / −0.68 %; the 30× PTZ at 1× +0.53 / −0.05 / −0.05 / +1.37 / +1.37 %; the
20× PTZ at 1× +0.70 / +0.37 / +0.37 / +1.32 / +1.32 %: a pixel of rasterisation, and at the top and
bottom the board's 1 m against the derivative at its middle.

The profiles are the example ones with the sensor scaled down (fewer, larger pixels: same sensor size,
so the same field of view and distortion in normalised coordinates) to keep the renders small: 2× (3× for
the 4K box camera), 960 × 540 to 1344 × 760.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
import yaml

from camgen.config import load_scene
from camgen.coverage.density import densities
from camgen.coverage.views import home_view
from camgen.optics.projection import project_points, undistort_points
from camgen.plan import PlanSettings, compile_scene
from camgen.plan.lens_stages import LensStages
from camgen.render.sequence import render_camera
from tests.conftest import REPO, write

pytestmark = pytest.mark.opengl

CAMERA_HEIGHT_M = 2.5
TARGET_DEPTH_M = 3.0
"""Depth of every board's centre: about 160 (bullet) and 210 px (box) tall, so a pixel is < 0.7 %."""
EDGE_GAP_PX = 25
# (profile, sensor scale-down factor, focal length the scene sets (None: a fixed lens or a PTZ at 1×)).
PROFILES = [
    ("bullet_4mp_2p8mm", 2, None),
    ("box_4k_varifocal", 3, 3.8),
    ("lowlight_2mp_1p2in", 2, None),
    ("ptz_2mp_30x", 2, None),
    ("ptz_2mp_20x", 2, None),
]
EXTENDS = {"ptz_2mp_20x": "ptz_2mp_30x"}
"""A profile that extends another takes its (scaled) sensor from it."""


def scaled_profile(name: str, factor: int) -> str:
    """The example profile's YAML with width and height divided by `factor` and the pixel pitch times it."""
    text = (REPO / f"profiles/{name}.yaml").read_text(encoding="utf-8")

    def scale(key: str, new) -> None:
        nonlocal text
        match = re.search(rf"^(\s*{key}:\s*)([0-9.]+)", text, re.M)
        text = text[: match.start(2)] + str(new(match.group(2))) + text[match.end(2) :]

    scale("width_px", lambda v: int(v) // factor)
    scale("height_px", lambda v: int(v) // factor)
    scale("pixel_pitch_um", lambda v: float(v) * factor)
    return text


def scene_dict(name: str, focal_length_mm: float | None, meshes: list[dict]) -> dict:
    camera = {"name": "cam", "profile": name, "mount": {"position_m": [0, 0, CAMERA_HEIGHT_M]}}
    if focal_length_mm is not None:
        camera["focal_length_mm"] = focal_length_mm
    if name.startswith("ptz_"):  # the dome's head at home, the lens at its wide end
        camera["ptz"] = {"pan_deg": 0, "tilt_deg": 0, "zoom_x": 1}
    return {
        "duration_s": 0.04,
        "fps": 25,
        "environment": {"meshes": meshes},
        "lights": [{"type": "ambient", "illuminance_lux": 300}],
        # coco asks for the instance pass, which the plan distorts with the lens (no image is rendered).
        "outputs": {"video": False, "annotations": ["coco"]},
        "cameras": [camera],
    }


def board_centres_m(view) -> dict[str, np.ndarray]:
    """World centres of the boards: the undistorted ray of each aimed pixel at TARGET_DEPTH_M, the top and
    bottom boards moved 0.6 m towards the middle so that they stay inside the frame."""
    W, H = view.width_px, view.height_px
    aims_px = {
        "centre": ((W - 1) / 2, (H - 1) / 2, 0.0),
        "left": (EDGE_GAP_PX, (H - 1) / 2, 0.0),
        "right": (W - 1 - EDGE_GAP_PX, (H - 1) / 2, 0.0),
        "top": ((W - 1) / 2, 0.0, -0.6),
        "bottom": ((W - 1) / 2, H - 1.0, 0.6),
    }
    centres = {}
    for key, (u, v, dz) in aims_px.items():
        pinhole = undistort_points(np.array([[u, v]]), view.K_px, view.distortion)[0]
        ray_cam = np.linalg.solve(view.K_px, [pinhole[0], pinhole[1], 1.0])
        centres[key] = view.centre_m + TARGET_DEPTH_M * (view.T_world_from_cam[:3, :3] @ ray_cam) + [0, 0, dz]
    return centres


@pytest.fixture(scope="module", params=PROFILES, ids=[p[0] for p in PROFILES])
def rendered_boards(request, renderer, tmp_path_factory):
    """(coverage's view, board centres, the instance-id pass through the lens) for one profile."""
    name, factor, focal_length_mm = request.param
    directory = tmp_path_factory.mktemp(name)
    if name in EXTENDS:
        write(directory, f"profiles/{EXTENDS[name]}.yaml", scaled_profile(EXTENDS[name], factor))
        write(directory, f"profiles/{name}.yaml", (REPO / f"profiles/{name}.yaml").read_text(encoding="utf-8"))
    else:
        write(directory, f"profiles/{name}.yaml", scaled_profile(name, factor))
    path = write(directory, "scenes/boards.yaml", yaml.safe_dump(scene_dict(name, focal_length_mm, [])))
    loaded = load_scene(path)
    view = home_view(loaded.scene.cameras[0], loaded.profiles["cam"].profile)
    centres = board_centres_m(view)
    boards = [
        {
            "type": "box",
            "name": key,
            "size_m": [0.02, 0.3, 1.0],  # thin, facing the camera
            "position_m": [float(x) for x in centre],
            "rotation_deg": [0, 0, math.degrees(math.atan2(centre[1], centre[0]))],
        }
        for key, centre in centres.items()
    ]
    path.write_text(yaml.safe_dump(scene_dict(name, focal_length_mm, boards)), encoding="utf-8")
    job = compile_scene(load_scene(path), PlanSettings())
    (camera,) = job.cameras
    (frame,) = render_camera(renderer, job, camera, frames=[0])
    state = camera.states[frame.index]
    out = LensStages(camera).apply(state, frame.passes)
    return view, state, camera, centres, out.instance_id


def test_the_render_goes_through_the_same_camera(rendered_boards):
    view, state, camera, _, ids = rendered_boards
    assert "optics.remap" in {stage.name for stage in camera.stages}
    assert ids.shape == (view.height_px, view.width_px)
    np.testing.assert_allclose(state.K_px, view.K_px, rtol=1e-12)
    np.testing.assert_allclose(state.distortion, view.distortion, atol=1e-15)
    np.testing.assert_allclose(state.T_world_from_cam, view.T_world_from_cam, atol=1e-12)


def run_length_px(column: np.ndarray, row: int) -> int:
    """Length of the run of `column[row]`'s value through `row`."""
    same = column == column[row]
    top = row
    while top > 0 and same[top - 1]:
        top -= 1
    bottom = row
    while bottom < len(column) - 1 and same[bottom + 1]:
        bottom += 1
    return bottom - top + 1


@pytest.mark.parametrize("board", ["centre", "left", "right", "top", "bottom"])
def test_a_one_metre_board_measures_the_predicted_vertical_density(rendered_boards, board):
    view, _, _, centres, ids = rendered_boards
    centre = centres[board]
    (uv,), _ = project_points(centre[None], view.T_world_from_cam, view.K_px, view.distortion)
    u, v = (round(float(x)) for x in uv)
    assert ids[v, u] != 0  # the board is where the lens model puts it
    rendered_px_m = np.median([run_length_px(ids[:, column], v) for column in (u - 1, u, u + 1)]) / 1.0
    # The board's centre is the probe point of a plane at its height (a face-height plane's semantics).
    _, predicted = densities(centre[None], centre[2], view)
    predicted_px_m = predicted.vertical_px_m[0]
    assert rendered_px_m == pytest.approx(predicted_px_m, rel=0.02)
    if board in ("left", "right"):  # the lens matters there: a pinhole's f_y / depth is ≥ 3 % off, 3× worse
        pinhole_px_m = view.K_px[1, 1] / TARGET_DEPTH_M
        assert abs(pinhole_px_m - rendered_px_m) > max(0.03 * rendered_px_m, 3 * abs(predicted_px_m - rendered_px_m))
