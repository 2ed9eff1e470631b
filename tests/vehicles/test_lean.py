"""Two-wheelers lean into turns (`camgen.vehicles.TwoWheelerRig.lean_rad`) and a bicycle lights its lamps.

- On a circle of radius R at speed v a bicycle and a motorcycle lean by φ = atan(v² / (g R)) (the
  steady-turn balance of gravity and the centrifugal force through the contact line; Cossalter,
  *Motorcycle Dynamics*), into the turn, rolling about the line through the tyres' contact points (the
  wheels stay on the ground); on a straight they stay upright; the rider leans with the machine, hands on
  the grips and feet on the pedals or pegs.
- A bicycle with its lights on, seen at night from behind and from the front: the difference from the
  same frame with its lights off is its red rear or white front lamp's emission, exactly, and nothing else.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.actors import person_model, rider_rig
from camgen.actors.skeleton import INDEX
from camgen.config.scene import Actor
from camgen.motion.trajectory import Route
from camgen.vehicles import (
    GRAVITY_M_S2,
    LAMP_COLOUR_RGB,
    LAMP_LUMINANCE_CD_M2,
    TwoWheelerRig,
    saddle_for_rider,
    vehicle_rig,
)

SPEED_M_S = 6.0
RADIUS_M = 12.0


class _Circle(Route):
    """A left-hand circle of radius `RADIUS_M` driven at `SPEED_M_S` (what a vehicle route offers: speed and
    curvature at any time)."""

    def at(self, time_s):
        angle = SPEED_M_S * np.asarray(time_s, np.float64) / RADIUS_M
        xy = RADIUS_M * np.stack([np.sin(angle), 1.0 - np.cos(angle)], axis=-1)
        return xy, angle

    def distance_at(self, time_s):
        return SPEED_M_S * float(time_s)

    def speed_at(self, time_s):
        return np.full(np.shape(time_s), SPEED_M_S)

    def curvature_at(self, time_s):
        return np.full(np.shape(time_s), 1.0 / RADIUS_M)


def _circle() -> _Circle:
    return _Circle(np.array([[0.0, 0.0], [30.0, 0.0]]), np.zeros(2), 5.0)


def _straight() -> Route:
    return Route(np.array([[0.0, 0.0], [40.0, 0.0]]), np.zeros(2), 8.0)


def _rigs(route: Route, cls: str) -> tuple[TwoWheelerRig, object]:
    vehicle_actor = Actor.model_validate(
        {"name": "bike", "class": cls, "vehicle": {"seed": 7}, "path": {"waypoints_m": [[0, 0]]}}
    )
    rider_actor = Actor.model_validate(
        {"name": "rider", "class": "person", "rides": "bike", "appearance": {"seed": 8, "age_group": "adult"}}
    )
    saddle = saddle_for_rider(person_model(rider_actor, scene_seed=0, actor_index=1).joints_m, INDEX)
    vehicle = vehicle_rig(vehicle_actor, route, scene_seed=0, actor_index=0, saddle_m=saddle)
    return vehicle, rider_rig(rider_actor, vehicle, scene_seed=0, actor_index=1)


def _tilt_rad(T: np.ndarray, v: np.ndarray) -> float:
    """How far `v` tilts from the vertical towards the vehicle's left (its heading's left on the ground),
    rad."""
    left = np.cross([0.0, 0.0, 1.0], T[:3, 0])
    return math.atan2(float(v @ left), float(v[2]))


def _roll_rad(T: np.ndarray) -> float:
    """The vehicle's roll: its up axis's tilt towards its left, rad."""
    return _tilt_rad(T, T[:3, 2])


@pytest.mark.parametrize("cls", ["bicycle", "motorcycle"])
def test_a_two_wheeler_leans_by_the_balance_angle_in_a_steady_turn_and_not_on_a_straight(cls):
    expected = math.atan(SPEED_M_S**2 / (GRAVITY_M_S2 * RADIUS_M))  # 17.0°
    vehicle, rider = _rigs(_circle(), cls)
    for time_s in (1.0, 2.5, 4.0):
        T, _ = vehicle.pose(time_s)
        assert abs(_roll_rad(T) - expected) < math.radians(1.0), (cls, math.degrees(_roll_rad(T)))
        # It rolls about its contact line: both tyres still touch the ground under their wheels.
        for centre in vehicle.model.wheel_centres_m:
            lowest = (T[:3, :3] @ (centre - [0.0, 0.0, vehicle.look.wheel_radius_m]) + T[:3, 3])[2]
            assert abs(lowest) < 1e-9
        # The rider leans with it, hands on the grips, feet on the pedals or pegs.
        rider.place(time_s)
        targets = vehicle.rider_targets(time_s)
        J = rider.joints_m
        grip = np.linalg.norm(J[[INDEX["hand_l"], INDEX["hand_r"]]] - rider.walker._wrist_targets(targets), axis=1)
        balls = J[[INDEX["ball_l"], INDEX["ball_r"]]] - np.array([0.0, 0.0, rider.walker.ball_height_m])
        feet = np.linalg.norm(balls - targets.feet_m, axis=1)
        assert grip.max() < 0.01 and feet.max() < 0.01, (grip, feet)
        trunk_roll = _tilt_rad(T, J[INDEX["head"]] - J[INDEX["pelvis"]])
        assert abs(trunk_roll - expected) < math.radians(3.0), math.degrees(trunk_roll)
    straight, _ = _rigs(_straight(), cls)
    assert straight.lean_rad(2.0) == 0.0
    assert np.allclose(straight.pose(2.0)[0][:3, 2], [0.0, 0.0, 1.0])


def test_a_vehicle_route_leans_into_its_bend_within_the_balance_angle():
    """A bicycle turning left at a corner of its route: leans left in the bend, no more than the balance
    angle of the route's tightest curvature at its speed, and is upright on the straights."""
    from camgen.motion.trajectory import vehicle_route_from_path

    path = Actor.model_validate(
        {"name": "b", "class": "bicycle", "path": {"waypoints_m": [[0, 0], [20, 0], [20, 20]], "speed_m_s": 5.0}}
    ).path
    route = vehicle_route_from_path(path, "bicycle")
    vehicle, _ = _rigs(route, "bicycle")
    times = np.linspace(0.0, route.duration_s, 200)
    lean = np.array([vehicle.lean_rad(float(t)) for t in times])
    bound = np.arctan(
        np.asarray(route.speed_at(times)) ** 2 * np.abs(np.asarray(route.curvature_at(times))).max() / GRAVITY_M_S2
    )
    assert lean.max() > math.radians(5.0) and lean.min() > -1e-9
    assert np.all(lean <= bound.max() + 1e-9)
    assert abs(lean[0]) < 1e-9 and abs(lean[-1]) < 1e-9


@pytest.mark.opengl
@pytest.mark.parametrize(("side", "lamp"), [("rear", "cycle_tail"), ("front", "cycle_head")])
def test_a_bicycle_lights_its_lamps_at_night(renderer, side, lamp):
    """Every pixel the lamps change gains one lamp's emission exactly; the lamp facing the camera covers
    several pixels."""
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph
    from tests.render.conftest import camera_matrix, look_at, scene_from

    def draw(lights_on: bool) -> np.ndarray:
        scene = scene_from(
            lights=[{"type": "ambient", "illuminance_lux": 2}],
            actors=[
                {
                    "name": "bike",
                    "class": "bicycle",
                    "vehicle": {"seed": 3, "lights_on": lights_on},
                    "path": {"waypoints_m": [[0, 0]]},
                }
            ],
        )
        eye = [-3.0, 0.2, 1.0] if side == "rear" else [4.0, 0.3, 1.1]
        view = View(camera_matrix(400, 400, 79.5, 59.5), look_at(eye, [0.3, 0.0, 0.85]), 160, 120)
        return renderer.draw(build_scene_graph(scene), view, ("radiance",)).radiance

    added = draw(True) - draw(False)
    emission = {k: LAMP_LUMINANCE_CD_M2[k] * np.array(LAMP_COLOUR_RGB[k]) for k in ("cycle_head", "cycle_tail")}
    lit = np.any(added != 0, axis=-1)
    near = {k: np.all(np.isclose(added[lit], e, rtol=1e-4), axis=-1) for k, e in emission.items()}
    assert np.all(near["cycle_head"] | near["cycle_tail"])
    assert near[lamp].sum() >= 6, near[lamp].sum()
