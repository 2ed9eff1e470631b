"""Driving: a procedural person seated at a steering wheel, posed once in the vehicle's frame.

A car's, van's, truck's or bus's driver sits still relative to its vehicle (the body is rigid with the
shell; the vehicle's rig moves it), so the pose is solved once, from where the vehicle's package puts
the seat's H-point, the pedals and the steering wheel (`camgen.vehicles.cabin`):

- the hip joints' centre is the H-point (SAE J1100: the pivot of the torso and thigh, the hip joint of
  the seated manikin), the trunk reclined by the seat back's angle (`Driver.back_angle_rad`), the pelvis
  taking `camgen.actors.riding.PELVIS_SHARE` of it, the neck and head bent forward against it so that
  the eyes look ahead (as a rider's, `camgen.actors.riding.Rider`);
- the hands on the steering wheel's rim at ten to two, the elbows bent outwards and down; the balls of
  the feet on the pedals, the feet level, the knees forward; arms and legs are the rider's closed-form
  two-bone chains.

`pedal_x_m` says where the pedals are for legs reaching them with the knees bent (`LEG_REACH` of the
leg's length from hip to ankle), as a driver sets the seat; `steering_wheel_m` puts the wheel where the
hands reach it with the elbows bent (`ARM_REACH` of the arm's length). Pure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from camgen.actors.person import PersonModel
from camgen.actors.riding import HIP_ABOVE_SEAT_M, Rider
from camgen.actors.skeleton import INDEX, Pose, global_transforms, skin, skinning_matrices, weight_matrix

LEG_REACH = 0.88
"""Hip-to-ankle distance over the leg's length (thigh + shin) with the feet on the pedals: a knee angle
of about 120° (drivers' preferred knee angles span about 100–135°: Park, Kim & Kim 2000, "Comfortable
driving postures for Koreans", Int. J. Ind. Ergon. 26: 489)."""
ARM_REACH = 0.80
"""Shoulder-to-wrist distance over the arm's length with the hands on the wheel (elbows bent about
110–130°, the same study's comfortable elbow angles)."""
WHEEL_RADIUS_M = 0.19
"""A steering wheel's rim radius (passenger cars 360–390 mm across; buses' and trucks' wheels are larger,
the hands' positions hardly differ)."""
WHEEL_BELOW_SHOULDERS_M = 0.30
"""How far the wheel's centre sits under the shoulders, m (the rim's top near the shoulders' height
less a hand's length)."""
GRIP_ANGLE_RAD = math.radians(60.0)
"""The hands at ten to two: 60° from the wheel's top."""


@dataclass(frozen=True)
class Controls:
    """Where a seated driver's body meets the vehicle, in the vehicle's frame (x forward, z up), m."""

    h_point_m: np.ndarray
    """(3,) the seat's H-point: the hip joints' centre."""
    grips_m: np.ndarray
    """(2, 3) the hands' places on the steering wheel's rim, left then right."""
    feet_m: np.ndarray
    """(2, 3) the pedals' treads under the balls of the left and right foot."""


class Driver(Rider):
    """A seated driver's pose: a rider whose trunk reclines by the seat back instead of leaning to the
    bar, its targets fixed in the vehicle's frame, its knees raised towards the dashboard (`knee_pole`:
    the thighs rise from the seat to pedals below it, and a knee pushed forward would meet the footwell's
    front, the wheel arch)."""

    knee_pole = np.array([0.5, 0.15, 1.0])

    def __init__(self, model: PersonModel, controls: Controls, back_angle_rad: float):
        from camgen.vehicles import RiderTargets  # the shared target record (vehicles import actors, lazily)

        seat = controls.h_point_m - np.array([0.0, 0.0, HIP_ABOVE_SEAT_M])  # the rider's seat is under its hips
        targets = RiderTargets(np.eye(4), seat, controls.grips_m, controls.feet_m)
        super().__init__(model, lambda time_s: targets, route=None)
        self.back_angle_rad = back_angle_rad

    def lean_rad(self, targets) -> float:
        """A reclined back: a negative lean."""
        return -self.back_angle_rad


def leg_lengths_m(model: PersonModel) -> tuple[float, float]:
    """(thigh, shin) lengths of a person's rest skeleton, m."""
    J = model.joints_m
    thigh = float(np.linalg.norm(J[INDEX["calf_l"]] - J[INDEX["thigh_l"]]))
    shin = float(np.linalg.norm(J[INDEX["foot_l"]] - J[INDEX["calf_l"]]))
    return thigh, shin


def pedal_x_m(model: PersonModel, h_point_m: np.ndarray, pedal_z_m: float) -> float:
    """The x of a pedal's tread at height `pedal_z_m` under the ball of a foot whose ankle is `LEG_REACH`
    of the leg's length from the hips at `h_point_m` (x, y, z), the foot level."""
    J = model.joints_m
    ankle_from_ball = J[INDEX["foot_l"]] - J[INDEX["ball_l"]]
    ankle_z = pedal_z_m + float(J[INDEX["ball_l"], 2]) + float(ankle_from_ball[2])
    reach = LEG_REACH * sum(leg_lengths_m(model))
    ahead = math.sqrt(max(reach**2 - (float(h_point_m[2]) - ankle_z) ** 2, 0.0))
    return float(h_point_m[0]) + ahead - float(ankle_from_ball[0])


def seated_joints_m(model: PersonModel, h_point_m: np.ndarray, back_angle_rad: float) -> np.ndarray:
    """(J, 3) the joints of the driver's trunk, head and (unposed) limbs seated at `h_point_m`, reclined."""
    rider = Driver(model, Controls(h_point_m, np.zeros((2, 3)), np.zeros((2, 3))), back_angle_rad)
    T_pelvis, local = rider._trunk(np.eye(4), h_point_m - np.array([0.0, 0.0, HIP_ABOVE_SEAT_M]), -back_angle_rad)
    return global_transforms(model.joints_m, Pose(T_pelvis, local))[:, :3, 3]


def shoulders_m(model: PersonModel, h_point_m: np.ndarray, back_angle_rad: float) -> np.ndarray:
    """(2, 3) the shoulder joints (left, right) of the driver seated at `h_point_m`, reclined."""
    return seated_joints_m(model, h_point_m, back_angle_rad)[[INDEX["upperarm_l"], INDEX["upperarm_r"]]]


def steering_wheel_m(model: PersonModel, h_point_m: np.ndarray, back_angle_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """(centre (3,), grips (2, 3) left then right) of a steering wheel in front of the seated driver, its
    rim's ten-to-two points `ARM_REACH` of the arm's length from the shoulders (wrists a hand behind
    the rim, `camgen.actors.riding.WRIST_FROM_GRIP_M`)."""
    from camgen.actors.riding import WRIST_FROM_GRIP_M

    shoulders = shoulders_m(model, h_point_m, back_angle_rad)
    J = model.joints_m
    arm = min(
        float(np.linalg.norm(J[INDEX[f"lowerarm_{s}"]] - J[INDEX[f"upperarm_{s}"]]))
        + float(np.linalg.norm(J[INDEX[f"hand_{s}"]] - J[INDEX[f"lowerarm_{s}"]]))
        for s in ("l", "r")
    )
    middle = shoulders.mean(axis=0)
    offsets = np.array([[0.0, WHEEL_RADIUS_M * math.sin(GRIP_ANGLE_RAD) * s, WHEEL_RADIUS_M * math.cos(GRIP_ANGLE_RAD)]
                        for s in (1, -1)])  # fmt: skip
    centre = np.array([middle[0], h_point_m[1], middle[2] - WHEEL_BELOW_SHOULDERS_M])
    wrist = centre + offsets[0] + WRIST_FROM_GRIP_M
    across = wrist - shoulders[0]
    ahead = math.sqrt(max((ARM_REACH * arm) ** 2 - across[1] ** 2 - across[2] ** 2, 0.0))
    centre[0] = shoulders[0, 0] + ahead - WRIST_FROM_GRIP_M[0]
    return centre, centre + offsets


def seated_vertices(model: PersonModel, controls: Controls, back_angle_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (V, 3), normals (V, 3)) of the person seated with `controls`, in the vehicle's frame."""
    pose = Driver(model, controls, back_angle_rad).pose(0.0)
    M = skinning_matrices(model.joints_m, global_transforms(model.joints_m, pose))
    weights = weight_matrix(model.joint_index, model.joint_weight, len(model.joints_m))
    return skin(model.vertices_m, model.normals, weights, M)
