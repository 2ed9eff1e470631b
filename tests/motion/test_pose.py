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


def test_projection_follows_the_hand_derived_convention():
    # A camera looking north (+Y), level: image right is east (+X), image down is world down (−Z).
    R_cam_from_world = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])
    np.testing.assert_allclose(R_world_from_cam(90, 0, 0).T, R_cam_from_world, atol=1e-15)
    K = np.array([[1000.0, 0, 959.5], [0, 1000.0, 539.5], [0, 0, 1]])
    t = np.array([2.0, -3.0, 5.0])
    points = t + np.array([[0, 10, 0], [1, 10, 0], [0, 10, 1]])  # ahead, east of it, above it
    rvec, _ = cv2.Rodrigues(R_cam_from_world)
    uv, _ = cv2.projectPoints(points, rvec, -R_cam_from_world @ t, K, None)
    uv = uv.reshape(-1, 2)
    np.testing.assert_allclose(uv[0], [959.5, 539.5], atol=1e-9)
    assert uv[1, 0] > 959.5 and uv[2, 1] < 539.5


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
