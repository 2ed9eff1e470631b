"""Camera orientation conventions: world Z up, OpenCV camera axes; projection equals cv2.projectPoints."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from camgen.motion.pose import R_world_from_cam
from camgen.motion.trajectory import position_on_path


def test_zero_pose_looks_along_world_x_with_image_down_as_world_down():
    R = R_world_from_cam(0, 0, 0)
    np.testing.assert_allclose(R[:, 2], [1, 0, 0], atol=1e-15)  # optical axis
    np.testing.assert_allclose(R[:, 0], [0, -1, 0], atol=1e-15)  # image right
    np.testing.assert_allclose(R[:, 1], [0, 0, -1], atol=1e-15)  # image down
    assert np.linalg.det(R) == pytest.approx(1.0)


@pytest.mark.parametrize(("yaw", "pitch", "axis"), [(90, 0, [0, 1, 0]), (0, -90, [0, 0, -1]), (180, 30, None)])
def test_yaw_and_pitch_aim_the_axis(yaw, pitch, axis):
    R = R_world_from_cam(yaw, pitch, 0)
    if axis is None:
        c = np.cos(np.radians(pitch))
        axis = [-c, 0, np.sin(np.radians(pitch))]
    np.testing.assert_allclose(R[:, 2], axis, atol=1e-12)


def test_pan_and_tilt_compose_like_yaw_and_pitch_on_a_level_mount():
    np.testing.assert_allclose(
        R_world_from_cam(30, 0, 0, pan_deg=20, tilt_deg=-10), R_world_from_cam(50, -10, 0), atol=1e-12
    )


def test_roll_turns_the_image_clockwise():
    R = R_world_from_cam(0, 0, 90)
    # Rolled 90° clockwise (as seen in the image), image right points to world down.
    np.testing.assert_allclose(R[:, 0], [0, 0, -1], atol=1e-12)


def test_projection_matches_cv2():
    rng = np.random.default_rng(0)
    R = R_world_from_cam(37, -21, 4, pan_deg=12, tilt_deg=-5)
    t_world = np.array([3.0, -2.0, 6.0])
    K = np.array([[1500.0, 0, 959.5], [0, 1498.0, 539.5], [0, 0, 1]])
    in_camera = np.column_stack([rng.uniform(-3, 3, (200, 2)), rng.uniform(5, 40, 200)])
    points = in_camera @ R.T + t_world
    cam = (points - t_world) @ R  # R_cam_from_world = Rᵀ
    ours = (cam[:, :2] / cam[:, 2:]) @ K[:2, :2].T + K[:2, 2]
    rvec, _ = cv2.Rodrigues(R.T)
    theirs, _ = cv2.projectPoints(points, rvec, -R.T @ t_world, K, None)
    np.testing.assert_allclose(ours, theirs.reshape(-1, 2), atol=1e-6)


def test_path_moves_at_constant_speed_and_stops():
    waypoints = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]])
    t = np.array([0.0, 1.0, 3.0, 5.0, 100.0])
    xy, heading = position_on_path(waypoints, speed_m_s=1.0, start_s=1.0, loop=False, time_s=t)
    np.testing.assert_allclose(xy, [[0, 0], [0, 0], [2, 0], [3, 1], [3, 4]], atol=1e-12)
    np.testing.assert_allclose(heading[2:], [0, np.pi / 2, np.pi / 2])


def test_looping_path_returns_to_start():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    xy, _ = position_on_path(square, 2.0, 0.0, True, np.array([2.0, 2.25]))
    np.testing.assert_allclose(xy, [[0, 0], [0.5, 0]], atol=1e-12)


def test_single_waypoint_stands_still():
    xy, heading = position_on_path(np.array([[4.0, 5.0]]), 1.0, 0.0, False, np.linspace(0, 9, 4))
    np.testing.assert_allclose(xy, [[4, 5]] * 4)
    assert np.all(heading == 0)
