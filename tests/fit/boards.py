"""Views of calibration boards through a distorting lens, for calibration tests.

Shared by tests/render/test_lens_calibration.py and tests/fit/test_lens.py. The checkerboard views are
rendered (OpenGL); the ChArUco views are synthesised from OpenCV's printed board (no OpenGL).

Poses are generated here rather than added to scenes/checkerboard.yaml. To constrain distortion the
board must reach into the image corners, and which pinhole ray an image corner sees depends on the
lens (normalised radius 1.47 behind the barrel lens, 0.94 behind the pincushion one), so each
profile gets its own poses: a view pushes the board into an image corner (two tilts per corner) or
edge (one view per edge) until its inner corners, projected through that profile's lens
(`camgen.optics.projection.project_points`), lie `BOARD_GAP_PX` from the border.
`write_board_scene_like` renders the same poses through another profile.

Sharpness, as a person calibrating would get it: the profiles stop the lens down from f/1.2 to
f/4 and each scene camera focuses on the board centre (`focus_distance_m`). The scene keeps the
example's board, sky and lights but not its floor, which reaches 13 m away and would keep the
depth-of-field stage in every view.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import cv2
import numpy as np
import yaml

from camgen.config import load_profile, load_scene
from camgen.config.scene import CheckerboardMesh
from camgen.fit.checkerboard import gray8_from_radiance, inner_corners
from camgen.fit.lens import BoardSpec
from camgen.motion.pose import R_HEAD_FROM_CV, R_world_from_cam, rot_z, rotation_xyz_deg
from camgen.optics.intrinsics import camera_matrix_px
from camgen.optics.projection import project_points, undistort_points
from camgen.optics.remap import LensMapCache
from camgen.plan import Job, PlanSettings, compile_scene
from camgen.plan.lens_stages import LensStages
from camgen.render.sequence import render_camera
from tests.conftest import REPO, write

PROFILE = REPO / "profiles/lowlight_2mp_1p2in.yaml"
EXAMPLE_SCENE = REPO / "scenes/checkerboard.yaml"
SUPERSAMPLING = 2
"""PlanSettings' default; BENCHMARKS.md gives an fx bias of 0.016 % at 2× (measured here: ≤ 0.01 %)."""
F_NUMBER = 4.0
BOARD_GAP_PX = 40.0
"""Gap between the board's outermost inner corners and the image border: the detector needs the
edges of the outer squares, so a little of each must stay in the frame."""

DISTORTIONS = {
    "barrel": {"k1": -0.3, "k2": 0.08, "p1": 0.001, "p2": -0.0008},
    "pincushion": {"k1": 0.2, "k2": -0.05, "p1": -0.0006, "p2": 0.0005},
    "mustache": {"k1": -0.3, "k2": 0.4},
}

UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 100, 1e-12)
"""`cv2.undistortPoints` to convergence (its default, 5 iterations, leaves 0.03 px)."""

IMAGE_CORNERS = [(-1, -1), (1, -1), (-1, 1), (1, 1)]
# One entry per view: where the board is pushed (−1 left/top, +1 right/bottom, 0 centred), the
# camera's direction seen from the board centre (azimuth towards +X, elevation; degrees), its distance
# from the board centre (m) and its roll (degrees). Two tilts per image corner, one per edge.
CALIBRATION_VIEWS = [
    *[((sx, sy), (-20 * sx, 15 * sy), 1.25, 10 * sx * sy) for sx, sy in IMAGE_CORNERS],
    *[((sx, sy), (30 * sx, -10 * sy), 1.4, -15 * sx * sy) for sx, sy in IMAGE_CORNERS],
    ((-1, 0), (30, 15), 1.4, -20),
    ((1, 0), (-20, 15), 1.4, 20),
    ((0, -1), (5, -10), 1.4, -20),
    ((0, 1), (5, 10), 1.4, 20),
]


def flow_yaml(mapping: dict[str, float]) -> str:
    return yaml.safe_dump(mapping, default_flow_style=True).strip()


def lens_profile(*, distortion: dict[str, float] | None = None, lateral_ca: dict[str, float] | None = None) -> str:
    """The low-light profile's YAML stopped down to F_NUMBER, with its `distortion:` line replaced
    and/or a `chromatic_aberration:` line added."""
    text = PROFILE.read_text(encoding="utf-8")
    edits = [(r"^  f_number: .*$", f"  f_number: {F_NUMBER}")]
    if distortion is not None:
        edits.append((r"^  distortion: .*$", f"  distortion: {flow_yaml(distortion)}"))
    if lateral_ca is not None:
        edits.append((r"^(  vignetting: .*)$", f"  chromatic_aberration: {flow_yaml(lateral_ca)}\n\\1"))
    for pattern, replacement in edits:
        text, count = re.subn(pattern, replacement, text, flags=re.MULTILINE)
        assert count == 1, f"{PROFILE.name} no longer has one line matching {pattern!r}"
    return text


def board_corners_world_m(board: CheckerboardMesh) -> np.ndarray:
    """Inner corners (N, 3) of a board in the world, m (the scene graph centres the squares on position_m)."""
    nx, ny = inner_corners(board)
    x, y = np.meshgrid((np.arange(nx) - (nx - 1) / 2), (np.arange(ny) - (ny - 1) / 2))
    local = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=-1) * board.square_size_m
    return local @ rotation_xyz_deg(board.rotation_deg).T + np.asarray(board.position_m)


def aimed_rotation(position_m: np.ndarray, target_m: np.ndarray, ray: np.ndarray, roll_deg: float) -> np.ndarray:
    """R_world_from_cam of a camera at `position_m` that sees `target_m` along the camera-frame
    direction `ray` (x, y, 1), rolled by `roll_deg` about that ray (image up ≈ world up at roll 0)."""
    z = (target_m - position_m) / np.linalg.norm(target_m - position_m)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    look_at = np.column_stack([x, np.cross(z, x), z])
    ray = ray / np.linalg.norm(ray)
    axis = np.cross([0.0, 0.0, 1.0], ray)  # |axis| = sin of the angle between the optical axis and the ray
    sin_angle = np.linalg.norm(axis)
    onto_ray = cv2.Rodrigues(axis / sin_angle * math.asin(sin_angle))[0] if sin_angle > 0 else np.eye(3)
    return look_at @ rot_z(math.radians(roll_deg)) @ onto_ray.T


def mount_angles_deg(R_world_from_cam_: np.ndarray) -> tuple[float, float, float]:
    """(yaw, pitch, roll) of a scene mount with this camera rotation (inverse of `R_world_from_cam`)."""
    M = R_world_from_cam_ @ R_HEAD_FROM_CV.T
    yaw, pitch, roll = math.atan2(M[1, 0], M[0, 0]), math.asin(M[2, 0]), math.atan2(M[2, 1], M[2, 2])
    angles = tuple(math.degrees(a) for a in (yaw, pitch, roll))
    np.testing.assert_allclose(R_world_from_cam(*angles), R_world_from_cam_, atol=1e-12)
    return angles


def board_view(board: CheckerboardMesh, K: np.ndarray, distortion: np.ndarray, size_px, view) -> dict:
    """A scene camera for one `*_VIEWS` entry: the board pushed into its image corner or edge until its
    inner corners, projected through the lens, lie `BOARD_GAP_PX` from the border there; focused on
    the board centre."""
    (sx, sy), (azimuth_deg, elevation_deg), distance_m, roll_deg = view
    centre = np.asarray(board.position_m, dtype=np.float64)
    corners = board_corners_world_m(board)
    az, el = math.radians(azimuth_deg), math.radians(elevation_deg)
    position = centre + distance_m * np.array([math.sin(az) * math.cos(el), -math.cos(az) * math.cos(el), math.sin(el)])
    width, height = size_px
    # Where the board centre should appear (distorted px), corrected until the border gap is right.
    target = K[:2, 2] + np.array([sx * 0.3 * width, sy * 0.3 * height])
    for _ in range(50):
        ray = np.append((undistort_points(target, K, distortion) - K[:2, 2]) / np.diag(K)[:2], 1.0)
        R = aimed_rotation(position, centre, ray, roll_deg)
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R, position
        uv, _ = project_points(corners, T, K, distortion)
        gap = np.array(
            [
                uv[:, axis].min() if side < 0 else limit - 1 - uv[:, axis].max()
                for axis, side, limit in ((0, sx, width), (1, sy, height))
            ]
        )
        shift = np.where(np.array([sx, sy]) != 0, (gap - BOARD_GAP_PX) * np.array([sx, sy]), 0.0)
        if np.abs(shift).max() < 0.1:
            break
        target = target + 0.8 * shift
    yaw, pitch, roll = mount_angles_deg(R)
    depth_m = float((R.T @ (centre - position))[2])
    return {
        "mount": {"position_m": position.tolist(), "yaw_deg": yaw, "pitch_deg": pitch, "roll_deg": roll},
        "focus_distance_m": depth_m,  # the board centre is in focus
    }


def write_board_scene(directory: Path, name: str, profile_text: str, views) -> Job:
    """Write profiles/<name>.yaml and scenes/board_<name>.yaml (the example's board, sky and lights, no
    floor, seen from `views` through that profile's lens) and plan the scene."""
    profile = load_profile(write(directory, f"profiles/{name}.yaml", profile_text)).profile
    sensor = profile.sensor
    K = camera_matrix_px(
        profile.lens.focal_length_mm,
        sensor.pixel_pitch_um,
        sensor.pitch_y_um,
        sensor.width_px,
        sensor.height_px,
        sensor.principal_point_offset_px,
    )
    scene = yaml.safe_load(EXAMPLE_SCENE.read_text(encoding="utf-8"))
    boards = [mesh for mesh in scene["environment"]["meshes"] if mesh["type"] == "checkerboard"]
    board = CheckerboardMesh.model_validate(boards[0])
    size_px = (sensor.width_px, sensor.height_px)
    scene["description"] = f"the checkerboard example's board through the {name} lens"
    scene["environment"]["meshes"] = boards
    scene["cameras"] = [
        {
            "name": f"view_{i:02d}",
            "profile": name,
            **board_view(board, K, profile.lens.distortion.as_array(), size_px, v),
        }
        for i, v in enumerate(views)
    ]
    path = write(directory, f"scenes/board_{name}.yaml", yaml.safe_dump(scene, sort_keys=False))
    return compile_scene(load_scene(path), PlanSettings(supersampling=SUPERSAMPLING))


def lens_output(renderer, job: Job):
    """(camera, radiance (H, W, 3) after the lens stages) for the first frame of every camera."""
    cache = LensMapCache()  # the cameras of one profile share the lens maps
    for camera in job.cameras:
        (frame,) = render_camera(renderer, job, camera, frames=[0])
        yield camera, LensStages(camera, cache).apply(camera.states[frame.index], frame.passes).radiance


def the_board(job: Job) -> CheckerboardMesh:
    return next(mesh for mesh in job.scene.environment.meshes if isinstance(mesh, CheckerboardMesh))


def write_board_scene_like(directory: Path, name: str, profile_text: str, like: str) -> Job:
    """Write profiles/<name>.yaml and scenes/board_<name>.yaml: the scene `write_board_scene` wrote
    for `like` in `directory`, same poses and focus, seen through this profile; plan it."""
    load_profile(write(directory, f"profiles/{name}.yaml", profile_text))
    scene = yaml.safe_load((directory / f"scenes/board_{like}.yaml").read_text(encoding="utf-8"))
    scene["description"] = f"the {like} scene's views through the {name} lens"
    for camera in scene["cameras"]:
        camera["profile"] = name
    path = write(directory, f"scenes/board_{name}.yaml", yaml.safe_dump(scene, sort_keys=False))
    return compile_scene(load_scene(path), PlanSettings(supersampling=SUPERSAMPLING))


# --- synthetic ChArUco views -----------------------------------------------------------------------


def charuco_pose(board: BoardSpec, K: np.ndarray, distortion: np.ndarray, view) -> tuple[np.ndarray, np.ndarray]:
    """(R_cam_from_board, t_cam_from_board_m) of one `CHARUCO_VIEWS` entry: the board centre seen at
    pixel `K`'s principal point + offset (distorted px) at depth `depth_m`, tilted about the board's x
    then y axis and rolled about the optical axis (degrees)."""
    offset_px, (tilt_x_deg, tilt_y_deg, roll_deg), depth_m = view
    target = np.asarray(K[:2, 2] + np.asarray(offset_px), np.float64).reshape(1, 1, 2)
    x, y = cv2.undistortPoints(target, K, distortion, R=None, P=None, criteria=UNDISTORT_CRITERIA).ravel()
    R = (
        rot_z(math.radians(roll_deg))
        @ cv2.Rodrigues(np.array([0.0, math.radians(tilt_y_deg), 0.0]))[0]
        @ cv2.Rodrigues(np.array([math.radians(tilt_x_deg), 0.0, 0.0]))[0]
    )
    centre_board_m = np.array([*(np.array(board.squares) * board.square_size_m / 2), 0.0])
    return R, depth_m * np.array([x, y, 1.0]) - R @ centre_board_m


def charuco_views(
    board: BoardSpec,
    K: np.ndarray,
    distortion: np.ndarray,
    size_px: tuple[int, int],
    poses,
    *,
    rng: np.random.Generator,
    pixels_per_square: int = 120,
    supersampling: int = 2,
    noise_dn: float = 1.5,
) -> list[np.ndarray]:
    """8-bit grey images of `board` (printed by `generateImage`, mid-grey beyond its white margin) seen
    through the camera (`K`, OpenCV `distortion`) from each (R_cam_from_board, t_m) of `poses`.

    Each output pixel averages `supersampling`² samples; a sample's distorted pixel is undistorted
    (`cv2.undistortPoints`, converged to 1e-12), its ray is intersected with the board plane
    through the pose's homography [r1 r2 t], and the printed board is read there (bilinear). Gaussian
    noise of `noise_dn` is added before rounding.
    """
    width, height = size_px
    margin = pixels_per_square // 2
    cols, rows = board.squares
    printed = board.charuco_board().generateImage(
        (cols * pixels_per_square + 2 * margin, rows * pixels_per_square + 2 * margin), marginSize=margin
    )
    s = supersampling
    u, v = np.meshgrid((np.arange(width * s) + 0.5) / s - 0.5, (np.arange(height * s) + 0.5) / s - 0.5)
    samples = np.stack([u.ravel(), v.ravel()], axis=-1).reshape(-1, 1, 2)
    rays = cv2.undistortPoints(samples, K, distortion, R=None, P=None, criteria=UNDISTORT_CRITERIA).reshape(-1, 2)
    rays = np.column_stack([rays, np.ones(len(rays))])
    px_per_m = pixels_per_square / board.square_size_m
    images = []
    for R, t in poses:
        board_h = rays @ np.linalg.inv(np.column_stack([R[:, 0], R[:, 1], t])).T
        # Board metres → printed-image pixel indices (pixel centres at integers; the board starts at `margin`).
        map_x = (board_h[:, 0] / board_h[:, 2] * px_per_m + margin - 0.5).astype(np.float32).reshape(u.shape)
        map_y = (board_h[:, 1] / board_h[:, 2] * px_per_m + margin - 0.5).astype(np.float32).reshape(u.shape)
        fine = cv2.remap(printed, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=128)
        image = cv2.resize(fine.astype(np.float32), size_px, interpolation=cv2.INTER_AREA)
        images.append(np.clip(np.round(image + rng.normal(0.0, noise_dn, image.shape)), 0, 255).astype(np.uint8))
    return images


def write_gray8_views(renderer, job: Job, directory: Path) -> list[Path]:
    """Render every camera of `job` through its lens and write each view as an 8-bit grey PNG
    (`gray8_from_radiance`) named after the camera, as a person calibrating would save them."""
    directory.mkdir(parents=True, exist_ok=True)
    paths = []
    for camera, radiance in lens_output(renderer, job):
        paths.append(directory / f"{camera.name}.png")
        cv2.imwrite(str(paths[-1]), gray8_from_radiance(radiance))
    return paths
