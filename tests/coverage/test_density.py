"""Pixel density through the lens model against closed forms, and the in-view edge against OpenCV."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from camgen.coverage.density import densities
from camgen.coverage.grid import make_grid
from camgen.coverage.network import camera_coverage, reach_coverage
from camgen.coverage.views import PtzReach
from camgen.motion.pose import R_world_from_mount
from tests.coverage.conftest import F_PX, HEIGHT_PX, WIDTH_PX, look_at_pitch_deg, pinhole_view


@pytest.mark.parametrize("distance_m", [2.0, 7.5, 30.0])
def test_fronto_parallel_density_is_f_over_distance(distance_m):
    # A camera looking level along +x at a vertical target: f/d px per metre across and up.
    view = pinhole_view((0.0, 0.0, 1.6))
    point = np.array([[distance_m, 0.0, 1.6]])
    _, dens = densities(point, 1.6, view)
    assert dens.vertical_px_m[0] == pytest.approx(F_PX / distance_m, rel=1e-4)
    assert dens.across_px_m[0] == pytest.approx(F_PX / distance_m, rel=1e-4)


@pytest.mark.parametrize(("height_m", "ground_m"), [(3.0, 4.0), (6.0, 25.0), (10.0, 10.0)])
def test_ground_density_is_f_sin_elevation_over_distance(height_m, ground_m):
    # The optical axis meets the ground at the point: px/m along the ground (least resolved direction).
    view = pinhole_view((0.0, 0.0, height_m), pitch_deg=look_at_pitch_deg(height_m, ground_m))
    distance = math.hypot(height_m, ground_m)
    _, dens = densities(np.array([[ground_m, 0.0, 0.0]]), 0.0, view)
    assert dens.ground_px_m[0] == pytest.approx(F_PX * (height_m / distance) / distance, rel=1e-4)


def test_in_view_edge_with_distortion_matches_opencv():
    distortion = (-0.12, 0.03, 0.001, -0.002, 0.0)  # strong barrel, as the 30x PTZ's wide end
    view = pinhole_view((0.0, 0.0, 4.0), pitch_deg=-30.0, distortion=distortion, f_px=180.0)
    grid = make_grid((-2.0, 30.0, -25.0, 25.0), 0.5, 0.0)
    coverage = camera_coverage(grid, view, [])
    points = grid.points_m()
    T_cam_from_world = np.linalg.inv(view.T_world_from_cam)
    rvec, _ = cv2.Rodrigues(T_cam_from_world[:3, :3])
    uv, _ = cv2.projectPoints(points, rvec, T_cam_from_world[:3, 3], view.K_px, view.distortion[:5])
    uv = uv.reshape(-1, 2)
    in_front = (points - view.centre_m) @ view.T_world_from_cam[:3, 2] > 0
    inside = in_front & (uv[:, 0] >= -0.5) & (uv[:, 0] <= WIDTH_PX - 0.5) & (uv[:, 1] >= -0.5)
    inside &= uv[:, 1] <= HEIGHT_PX - 0.5
    assert np.array_equal(coverage.in_view.ravel(), inside)
    # The distortion moves the edge: a pinhole of the same matrix sees a different set of cells.
    pinhole = camera_coverage(grid, pinhole_view((0.0, 0.0, 4.0), pitch_deg=-30.0, f_px=180.0), [])
    assert (pinhole.in_view != coverage.in_view).sum() > 20


def test_ptz_reach_centres_the_point_at_wide_and_tele():
    reach = PtzReach(
        "ptz", np.array([0.0, 0.0, 6.0]), R_world_from_mount(0, 0, 0), None, (-90.0, 10.0), 500.0, 500.0, 20.0
    )
    grid = make_grid((9.5, 10.5, -0.5, 0.5), 1.0, 0.0)  # one cell at (10, 0)
    covered = reach_coverage(grid, reach, [])
    probe = np.array([10.0, 0.0, 0.9])  # the middle of a 1.8 m person standing there
    distance = np.linalg.norm(probe - reach.position_m)
    elevation_cos = math.hypot(10.0, 0.0) / distance
    vertical = 500.0 * elevation_cos / distance  # centred: f·cos(elevation)/d
    assert covered.reached[0, 0]
    assert covered.person_wide_px_m[0, 0] == pytest.approx(min(vertical, 500.0 / distance), rel=1e-9)
    assert covered.person_tele_px_m[0, 0] == pytest.approx(20 * covered.person_wide_px_m[0, 0], rel=1e-12)
    assert covered.zoom_needed_x[1, 0, 0] == pytest.approx(62.0 / covered.person_wide_px_m[0, 0], rel=1e-12)
    out_of_tilt = PtzReach("ptz", reach.position_m, reach.R_world_from_mount, None, (-10.0, 10.0), 500.0, 500.0, 20.0)
    assert not reach_coverage(grid, out_of_tilt, []).reached[0, 0]  # 31° below the horizon


def test_jacobian_through_distortion_matches_differences_of_the_projection():
    from camgen.coverage.density import projection_jacobian
    from camgen.optics.projection import project_points

    view = pinhole_view((0.0, 0.0, 4.0), pitch_deg=-30.0, distortion=(-0.12, 0.03, 0.001, -0.002), f_px=180.0)
    points = np.array([[5.0, -6.0, 0.0], [12.0, 8.0, 0.9], [3.0, 0.5, 1.6]])
    _, J = projection_jacobian(points, view)
    for axis in range(3):
        step = np.zeros(3)
        step[axis] = 1e-4
        plus, _ = project_points(points + step, view.T_world_from_cam, view.K_px, view.distortion)
        minus, _ = project_points(points - step, view.T_world_from_cam, view.K_px, view.distortion)
        assert np.allclose(J[:, :, axis], (plus - minus) / 2e-4, rtol=1e-6, atol=1e-6)
