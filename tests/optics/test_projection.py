"""The lens model on points: against cv2.projectPoints / cv2.undistortPointsIter, and round trips for
every example profile at every zoom position."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from camgen.config.loader import load_profile
from camgen.optics.intrinsics import camera_matrix_px
from camgen.optics.projection import (
    LensInversionError,
    distort_points,
    fold_radius_normalized,
    project_points,
    undistort_points,
)
from tests.conftest import REPO

K = np.array([[1510.0, 0.0, 957.3], [0.0, 1490.0, 541.8], [0.0, 0.0, 1.0]])
BARREL = np.array([-0.3, 0.08, 0.001, -0.0008, 0.0, 0.0, 0.0, 0.0])
PROFILES = sorted((REPO / "profiles").glob("*.yaml"))


def _image_grid(width_px: int, height_px: int, step_px: float) -> np.ndarray:
    u, v = np.meshgrid(
        np.append(np.arange(-0.5, width_px, step_px), width_px - 0.5),
        np.append(np.arange(-0.5, height_px, step_px), height_px - 0.5),
    )
    return np.stack([u, v], axis=-1).reshape(-1, 2)


def test_distort_points_equals_cv2_project_points():
    rng = np.random.default_rng(0)
    undistorted = rng.uniform([0, 0], [1920, 1080], size=(400, 2))
    rays = np.column_stack([(undistorted - K[:2, 2]) / np.diag(K)[:2], np.ones(400)])
    expected, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), K, BARREL)
    np.testing.assert_allclose(distort_points(undistorted, K, BARREL), expected.reshape(-1, 2), atol=1e-9)


def test_undistort_points_agrees_with_opencv_iterative_undistortion():
    distorted = _image_grid(1920, 1080, 37.0)
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-14)
    reference = cv2.undistortPoints(distorted.reshape(-1, 1, 2), K, BARREL, None, K, criteria=criteria).reshape(-1, 2)
    np.testing.assert_allclose(undistort_points(distorted, K, BARREL), reference, atol=1e-6)


@pytest.mark.parametrize("path", PROFILES, ids=lambda p: p.stem)
def test_round_trip_over_the_whole_image_for_every_example_profile(path):
    profile = load_profile(path).profile
    sensor, lens = profile.sensor, profile.lens
    W, H = sensor.width_px, sensor.height_px
    focal_lengths = sorted(
        {lens.focal_length_min_mm, lens.focal_length_max_mm} | {z.focal_length_mm for z in lens.zoom_table}
    )
    grid = _image_grid(W, H, 16.0)
    for focal_length_mm in focal_lengths:
        Kp = camera_matrix_px(
            focal_length_mm, sensor.pixel_pitch_um, sensor.pitch_y_um, W, H, sensor.principal_point_offset_px
        )
        dist = lens.at_focal_length(focal_length_mm)[1].as_array()
        back = undistort_points(distort_points(grid, Kp, dist), Kp, dist)
        assert np.max(np.abs(back - grid)) < 1e-6, f"{path.stem} at {focal_length_mm} mm"
        forth = distort_points(undistort_points(grid, Kp, dist), Kp, dist)
        assert np.max(np.abs(forth - grid)) < 1e-6, f"{path.stem} at {focal_length_mm} mm"


def test_project_points_equals_cv2_in_front_and_refuses_behind_and_beyond_the_fold():
    rng = np.random.default_rng(1)
    rvec, tvec = np.array([0.1, -0.2, 0.05]), np.array([0.3, -0.1, 0.5])
    R, _ = cv2.Rodrigues(rvec)
    T_cam_from_world = np.eye(4)
    T_cam_from_world[:3, :3], T_cam_from_world[:3, 3] = R, tvec
    T_world_from_cam = np.linalg.inv(T_cam_from_world)
    cam = np.column_stack([rng.uniform(-2, 2, (300, 2)), rng.uniform(3, 10, 300)])
    world = (cam - tvec) @ R  # R^T (cam − t)
    expected, _ = cv2.projectPoints(world, rvec, tvec, K, BARREL)
    points, depth = project_points(world, T_world_from_cam, K, BARREL)
    np.testing.assert_allclose(points, expected.reshape(-1, 2), atol=1e-8)
    np.testing.assert_allclose(depth, cam[:, 2], atol=1e-12)

    folding = [-0.3]
    fold = fold_radius_normalized(folding)
    behind_and_beyond = np.array([[0.0, 0.0, -5.0], [fold * 1.05 * 5.0, 0.0, 5.0], [fold * 0.95 * 5.0, 0.0, 5.0]])
    world = (behind_and_beyond - tvec) @ R
    points, _ = project_points(world, T_world_from_cam, K, folding)
    assert np.isnan(points[:2]).all() and np.isfinite(points[2]).all()


def test_fold_radius_closed_form():
    # g(r) = r(1 + k1 r²) turns back where 1 + 3 k1 r² = 0.
    assert fold_radius_normalized([-0.3]) == pytest.approx(np.sqrt(1 / 0.9), abs=2e-3)
    assert fold_radius_normalized([0.1]) == np.inf


def test_inverting_beyond_the_fold_raises_with_the_place():
    past_fold = np.array([[K[0, 2] + 1.5 * K[0, 0], K[1, 2]]])  # beyond the largest radius g can reach
    with pytest.raises(LensInversionError, match=r"cannot be inverted at pixel \(\d+\.\d+, \d+\.\d+\)"):
        undistort_points(past_fold, K, [-0.3])


def test_the_kept_fold_radius_is_each_lenss_own():
    """Kept per coefficients: a lens asked for after another gets its own radius, whatever form its
    coefficients come in (list, array, trailing zeros), and the radius limit is part of the question."""
    for k1 in (-0.3, -0.2, -0.3, -0.1):
        expected = np.sqrt(1 / (3 * -k1))  # 1 + 3 k1 r² = 0
        assert fold_radius_normalized([k1]) == pytest.approx(expected, abs=2e-3)
        assert fold_radius_normalized(np.array([k1, 0.0, 0.0, 0.0, 0.0])) == fold_radius_normalized((k1,))
    assert fold_radius_normalized([-0.1], r_max=1.0) == np.inf  # its fold (1.83) lies beyond this limit
    assert fold_radius_normalized([-0.1]) == pytest.approx(np.sqrt(1 / 0.3), abs=2e-3)
