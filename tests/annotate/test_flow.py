"""Optical flow from known motion (camgen.annotate.flow) against closed forms and OpenCV, and the .flo
file against OpenCV's reader."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
import trimesh

from camgen.annotate.flow import (
    UNKNOWN_FLOW_PX,
    forward_flow_px,
    mesh_displacement_m,
    rigid_displacement_m,
    surface_points_m,
)
from camgen.io.flow import write_flo
from camgen.optics.remap import output_grid_px

W, H = 160, 120
K = np.array([[150.0, 0.0, 79.5], [0.0, 150.0, 59.5], [0.0, 0.0, 1.0]])


def _pose(R: np.ndarray, t=(0.0, 0.0, 0.0)) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    return T


def _rays(K_px: np.ndarray, distortion) -> np.ndarray:
    """Undistorted normalised rays of every pixel, by OpenCV's own inverse (independent of camgen's)."""
    grid = output_grid_px(W, H).reshape(-1, 1, 2)
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
    return cv2.undistortPoints(grid, K_px, np.array(distortion, float), criteria=criteria).reshape(H, W, 2)


@pytest.mark.parametrize("distortion", [(0.0,) * 5, (-0.25, 0.08, 0.001, -0.0005, 0.0)])
def test_a_pan_over_a_static_scene_gives_the_rotation_homography(distortion):
    rng = np.random.default_rng(3)
    T0 = _pose(np.eye(3), (1.0, -2.0, 3.0))
    R_pan = cv2.Rodrigues(np.array([0.0, np.radians(2.0), np.radians(0.3)]))[0]  # pan 2°, a little roll
    T1 = _pose(R_pan, (1.0, -2.0, 3.0))
    depth = rng.uniform(2.0, 50.0, (H, W))
    depth[:20] = np.inf  # sky: points at infinity
    rays = _rays(K, distortion)
    flow = forward_flow_px(output_grid_px(W, H), rays, depth, np.zeros((H, W, 3)), T0, T1, K, distortion)
    # Closed form: the ray rotates into the next camera (R1ᵀ·R0) and goes through the lens (OpenCV).
    rotated = np.concatenate([rays, np.ones((H, W, 1))], -1).reshape(-1, 3) @ (R_pan.T @ np.eye(3)).T
    expected, _ = cv2.projectPoints(rotated, np.zeros(3), np.zeros(3), K, np.array(distortion, float))
    expected = expected.reshape(H, W, 2) - output_grid_px(W, H)
    assert np.abs(flow - expected).max() < 1e-3
    assert 3.0 < np.abs(flow[..., 0]).mean() < 8.0  # 2° at f = 150 px is about 5 px


def test_a_box_moving_sideways_flows_by_focal_length_times_speed_over_depth():
    T = _pose(np.eye(3))
    depth = np.full((H, W), 10.0)
    depth[40:80, 60:100] = 5.0  # the box's front face, 5 m away, parallel to the image
    box_before = _pose(np.eye(3), (0.0, 0.0, 5.0))
    box_after = _pose(np.eye(3), (0.2, 0.0, 5.0))  # 0.2 m to the right (camera x) in one frame
    points = surface_points_m(_rays(K, (0.0,) * 5), depth, T)
    displacement = np.zeros((H, W, 3))
    displacement[40:80, 60:100] = rigid_displacement_m(points[40:80, 60:100], box_before, box_after)
    flow = forward_flow_px(output_grid_px(W, H), _rays(K, (0.0,) * 5), depth, displacement, T, T, K, (0.0,) * 5)
    np.testing.assert_allclose(flow[40:80, 60:100, 0], 150.0 * 0.2 / 5.0, atol=1e-4)  # 6 px
    np.testing.assert_allclose(flow[40:80, 60:100, 1], 0.0, atol=1e-4)
    assert np.abs(flow[:40]).max() < 1e-4  # the static background stays


def test_a_rotating_body_moves_its_points_about_its_own_axis():
    before = _pose(np.eye(3), (2.0, 0.0, 0.0))
    after = _pose(cv2.Rodrigues(np.array([0.0, 0.0, np.pi / 2]))[0], (2.0, 0.0, 0.0))  # a quarter turn about z
    moved = np.array([[3.0, 0.0, 0.5]]) + rigid_displacement_m(np.array([[3.0, 0.0, 0.5]]), before, after)
    np.testing.assert_allclose(moved, [[2.0, 1.0, 0.5]], atol=1e-12)


def _deforming_sphere():
    """A triangulated sphere (trimesh, independent of camgen) and its vertices after a smooth bend and
    some noise: a limb's skin between two frames."""
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.3)
    vertices = np.asarray(sphere.vertices) + np.array([1.0, 2.0, 1.0])
    rng = np.random.default_rng(4)
    bent = vertices + 0.05 * np.sin(3 * vertices[:, [2, 0, 1]]) + rng.normal(0, 0.005, vertices.shape)
    return vertices, bent, sphere.faces


def test_points_on_a_deforming_mesh_move_with_their_triangles_corners():
    vertices, later, faces = _deforming_sphere()
    rng = np.random.default_rng(5)
    chosen = rng.integers(0, len(faces), 400)
    weights = rng.dirichlet([1.0, 1.0, 1.0], 400)
    points = np.einsum("nj,njk->nk", weights, vertices[faces[chosen]])
    expected = np.einsum("nj,njk->nk", weights, (later - vertices)[faces[chosen]])
    np.testing.assert_allclose(mesh_displacement_m(points, vertices, later, faces), expected, atol=1e-9)
    # The corners themselves, and a point 1 mm off the surface (a neighbouring pixel's depth): its
    # closest point's motion, within what 1 mm along the surface changes.
    np.testing.assert_allclose(mesh_displacement_m(vertices, vertices, later, faces), later - vertices, atol=1e-9)
    outward = points + 0.001 * (points - [1.0, 2.0, 1.0]) / np.linalg.norm(points - [1.0, 2.0, 1.0], axis=1)[:, None]
    assert np.abs(mesh_displacement_m(outward, vertices, later, faces) - expected).max() < 1e-3


def test_a_point_that_passes_behind_the_next_camera_has_unknown_flow():
    T0 = _pose(np.eye(3))
    depth = np.full((H, W), 1.0)
    displacement = np.zeros((H, W, 3))
    displacement[..., 2] = -2.0  # moves from 1 m in front to 1 m behind
    flow = forward_flow_px(output_grid_px(W, H), _rays(K, (0.0,) * 5), depth, displacement, T0, T0, K, (0.0,) * 5)
    assert (flow == np.float32(UNKNOWN_FLOW_PX)).all()


def test_flo_files_read_back_with_opencv(tmp_path):
    flow = np.random.default_rng(1).normal(0, 20, (H, W, 2)).astype(np.float32)
    flow[0, 0] = UNKNOWN_FLOW_PX
    write_flo(tmp_path / "f.flo", flow)
    np.testing.assert_array_equal(cv2.readOpticalFlow(str(tmp_path / "f.flo")), flow)
    raw = (tmp_path / "f.flo").read_bytes()
    assert raw[:4] == b"PIEH" and len(raw) == 12 + 8 * W * H  # Middlebury's header and layout


@pytest.mark.parametrize(
    ("name", "flow", "message"),
    [
        ("f.png", np.zeros((2, 2, 2), np.float32), "named *.flo"),
        ("f.flo", np.zeros((2, 2, 3), np.float32), "shape (H, W, 2)"),
        ("f.flo", np.full((2, 2, 2), np.nan, np.float32), "UNKNOWN_FLOW_PX"),
    ],
)
def test_write_flo_refuses_what_it_cannot_store(tmp_path, name, flow, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)").replace("*", r"\*")):
        write_flo(tmp_path / name, flow)
    assert not list(tmp_path.iterdir())
