"""The plan's bound on an actor's image motion within one exposure (`camgen.plan.compile._actor_motion_px`)
covers the actor's whole box, not only its route's point.

- A truck passing 4.4 m in front of a camera, its route's point (the rear axle) out of the view, its corners
  above and below it, and only its front in the view: the bound is the front's displacement, f·Δx/d for its
  side's depth d (a translation parallel to the image), where the route's point alone gave 0.
- A car 50 m away crossing the view, wholly in it: the bound is its route point's (what the plan measured
  before), projected at both ends with OpenCV, within the few percent its nearer corners move faster.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from camgen.config.scene import VEHICLE_ENVELOPE_M
from camgen.motion.trajectory import actor_routes
from camgen.plan.compile import _actor_motion_px
from tests.render.conftest import camera_matrix, look_at, scene_from

K = camera_matrix(300.0, 300.0, 79.5, 59.5)
WIDTH_PX, HEIGHT_PX = 160, 120
EXPOSURE_S = 0.02
CAMERA_M = np.array([0.0, -6.0, 2.0])
T_WORLD_FROM_CAM = look_at(CAMERA_M, CAMERA_M + np.array([0.0, 10.0, 0.0]))  # facing +y, level


@pytest.fixture(scope="module")
def passing():
    scene = scene_from(
        duration_s=12.0,
        lights=[{"type": "ambient", "illuminance_lux": 1000.0}],
        actors=[
            {"name": "truck", "class": "truck", "path": {"waypoints_m": [[-60, 0], [60, 0]], "speed_m_s": 15}},
            {"name": "car", "class": "car", "path": {"waypoints_m": [[-60, 50], [60, 50]], "speed_m_s": 15}},
        ],
    )
    routes = actor_routes(scene)
    return {actor.name: actor for actor in scene.actors}, routes


def _time_at(route, x_m: float) -> float:
    """When the route's point passes x = `x_m` (it drives along +x)."""
    times = np.linspace(0.0, 12.0, 120_001)
    return float(np.interp(x_m, route.at(times)[0][:, 0], times))


def _bound_px(actor, routes, time_s: float) -> float:
    return _actor_motion_px(
        [actor], routes, np.array([time_s]), EXPOSURE_S, T_WORLD_FROM_CAM, K, WIDTH_PX, HEIGHT_PX, None
    )


def test_a_truck_whose_front_alone_is_in_view_is_blurred(passing):
    actors, routes = passing
    truck, route = actors["truck"], routes["truck"]
    time_s = _time_at(route, -6.0)  # rear axle 6 m left of the camera's axis; the front (6.5 m ahead) 0.5 m
    (start, end), _ = route.at(np.array([time_s, time_s + EXPOSURE_S]))
    rvec, _ = cv2.Rodrigues(T_WORLD_FROM_CAM[:3, :3].T)
    tvec = -T_WORLD_FROM_CAM[:3, :3].T @ T_WORLD_FROM_CAM[:3, 3]

    def pixel(point_m):
        return cv2.projectPoints(np.array([point_m], float), rvec, tvec, K, None)[0].reshape(2)

    # The setting: the route's point out of the view at any height, and the front's corners too (above and
    # below the image), while the front's edge at the camera's height is in it.
    (_, low_y_m, _), (front_m, _, top_m) = VEHICLE_ENVELOPE_M["truck"]
    front_x_m, side_y_m = start[0] + front_m, low_y_m
    for height_m in (0.0, top_m):
        assert pixel([start[0], start[1], height_m])[0] < 0
        assert not 0 <= pixel([front_x_m, side_y_m, height_m])[1] < HEIGHT_PX
    assert 0 <= pixel([front_x_m, side_y_m, CAMERA_M[2]])[0] < WIDTH_PX
    # The side 4.4 m from the camera slides parallel to the image: every point of it by f·Δx/d.
    expected_px = 300.0 * (end[0] - start[0]) / (side_y_m - CAMERA_M[1])
    assert expected_px > 10.0
    assert _bound_px(truck, routes, time_s) == pytest.approx(expected_px, rel=0.01)


def test_a_far_car_wholly_in_view_keeps_its_route_points_bound(passing):
    actors, routes = passing
    car, route = actors["car"], routes["car"]
    time_s = _time_at(route, -2.0)
    (start, end), _ = route.at(np.array([time_s, time_s + EXPOSURE_S]))
    rvec, _ = cv2.Rodrigues(T_WORLD_FROM_CAM[:3, :3].T)
    tvec = -T_WORLD_FROM_CAM[:3, :3].T @ T_WORLD_FROM_CAM[:3, 3]
    route_point_px = 0.0
    for height_m in (
        0.0,
        VEHICLE_ENVELOPE_M["car"][1][2],
    ):  # the route's point at ground and top height, as the plan measured before
        a, b = (
            cv2.projectPoints(np.array([[*xy, height_m]], float), rvec, tvec, K, None)[0].reshape(2)
            for xy in (start, end)
        )
        assert 0 <= a[0] < WIDTH_PX and 0 <= a[1] < HEIGHT_PX
        route_point_px = max(route_point_px, float(np.hypot(*(b - a))))
    bound_px = _bound_px(car, routes, time_s)
    assert route_point_px > 1.0
    assert route_point_px <= bound_px <= 1.05 * route_point_px
