"""Riding: a procedural person seated on a bicycle or motorcycle, as poses of its skeleton at any time.

The two-wheeler says where its seat, grips and pedals (or footpegs) are at each time
(`camgen.vehicles.TwoWheelerRig.rider_targets`); the rider's pose follows from them:

- the hip joints' centre sits `HIP_ABOVE_SEAT_M` over the seat (the sitting bones under it), the pelvis
  facing along the vehicle and tipped forward by `PELVIS_SHARE` of the trunk's lean;
- the trunk leans forward, at each time, until the hands reach the grips with the elbows a little bent
  (the wrists at `ARM_REACH` of the arm's length from the shoulders), within `LEAN_LIMITS_RAD`: on the
  standard motorcycle the rider sits at the lower limit, upright; on the hybrid bicycle riders of 1.55,
  1.75 and 1.95 m lean 37°, 47° and 47° (measured; the bar rises with a tall rider's saddle); a turned
  bar takes one grip forward and the rider leans on to reach it; the neck and head lift back against the
  lean so that the eyes look ahead;
- arms and legs are two-bone chains solved in closed form (as the gait's legs, `camgen.actors.gait`):
  the wrists on the grips (`WRIST_FROM_GRIP_M`: the hand's width behind and over the bar), the hands
  over the bar (`HAND_DIRECTION`, thumbs inwards), the elbows bent outwards and down; the ball of each
  foot on its pedal's tread or footpeg, the foot level along the vehicle, the knees forwards and a
  little outwards.

A bicycle's saddle is set for its rider (`camgen.vehicles.two_wheeler.saddle_height_for`); a leg that
cannot reach its pedal (a motorcycle's pegs are fixed) stretches as far as it goes.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from camgen.actors.gait import _aim
from camgen.actors.person import PersonModel
from camgen.actors.skeleton import INDEX, JOINTS, PARENT_INDEX, Pose, global_transforms, joint_transforms, rot_axis
from camgen.motion.trajectory import Route

HIP_ABOVE_SEAT_M = 0.09
"""The hip joints' centres over the seat, m (Reed, Manary & Schneider 1999, SAE 1999-01-0959)."""
PELVIS_SHARE = 0.4
"""Share of the trunk's forward lean taken by the pelvis's tilt (the rest bends the lumbar spine)."""
ARM_REACH = 0.93
"""Shoulder-to-wrist distance over the arm's length with the hands on the grips (elbows slightly bent)."""
LEAN_LIMITS_RAD = (math.radians(5.0), math.radians(70.0))
WRIST_FROM_GRIP_M = np.array([-0.04, 0.0, 0.03])
"""The wrist joint from the grip's axis, in the vehicle's frame, m (a hand wrapped over the bar)."""
HAND_DIRECTION = np.array([0.86, 0.0, -0.51])
"""Which way the hands point from the wrists, in the vehicle's frame: forward and 30° down, over the bar
(the fingers, which the skeleton lacks, would wrap round it)."""
ELBOW_POLE = np.array([-0.3, 0.8, -0.5])
"""Which way the left elbow points, in the vehicle's frame (mirrored in y for the right): outwards,
back and down."""
KNEE_POLE = np.array([1.0, 0.15, 0.0])
"""Which way the left knee points, in the vehicle's frame (mirrored for the right)."""
SHOULDERS = (INDEX["upperarm_l"], INDEX["upperarm_r"])
"""The joints whose reach `Rider.lean_rad` tries (the shoulders: the upper arms' roots)."""


class Rider:
    """The pose of one person riding a two-wheeler at any time (pure: same time, same pose).

    `targets(time_s)` gives a `camgen.vehicles.RiderTargets` (the vehicle's frame, seat, grips, feet)."""

    knee_pole = KNEE_POLE
    """Which way the left knee points, in the vehicle's frame (mirrored for the right)."""

    def __init__(self, model: PersonModel, targets: Callable, route: Route):
        self.model, self.targets, self.route = model, targets, route
        J = model.joints_m
        self.actions = ()
        self.hip_centre_from_pelvis = (J[INDEX["thigh_l"]] + J[INDEX["thigh_r"]]) / 2 - J[INDEX["pelvis"]]
        self.ankle_from_ball = {side: J[INDEX[f"foot_{side}"]] - J[INDEX[f"ball_{side}"]] for side in ("l", "r")}
        self.ball_height_m = float(J[INDEX["ball_l"], 2])
        self.arm_m = min(
            float(np.linalg.norm(J[INDEX[f"lowerarm_{s}"]] - J[INDEX[f"upperarm_{s}"]]))
            + float(np.linalg.norm(J[INDEX[f"hand_{s}"]] - J[INDEX[f"lowerarm_{s}"]]))
            for s in ("l", "r")
        )

    def falling(self, time_s: float) -> bool:
        return False

    def _trunk(self, T_vehicle: np.ndarray, seat_m: np.ndarray, lean_rad: float) -> tuple[np.ndarray, np.ndarray]:
        """(T_world_from_pelvis, local rotations) of a trunk leaning `lean_rad` on the seat."""
        R = T_vehicle[:3, :3]
        tilt = PELVIS_SHARE * lean_rad
        R_pelvis = R @ rot_axis("y", tilt)
        T_pelvis = np.eye(4)
        T_pelvis[:3, :3] = R_pelvis
        T_pelvis[:3, 3] = seat_m + R @ np.array([0.0, 0.0, HIP_ABOVE_SEAT_M]) - R_pelvis @ self.hip_centre_from_pelvis
        local = np.tile(np.eye(3), (len(JOINTS), 1, 1))
        bend = lean_rad - tilt
        local[INDEX["spine_01"]] = rot_axis("y", 0.5 * bend)
        local[INDEX["spine_02"]] = rot_axis("y", 0.3 * bend)
        local[INDEX["spine_03"]] = rot_axis("y", 0.2 * bend)
        local[INDEX["neck_01"]] = rot_axis("y", -0.6 * lean_rad)
        local[INDEX["head"]] = rot_axis("y", -0.3 * lean_rad)
        return T_pelvis, local

    def _wrist_targets(self, targets) -> np.ndarray:
        R = targets.T_world_from_vehicle[:3, :3]
        return targets.grips_m + R @ WRIST_FROM_GRIP_M

    def lean_rad(self, targets) -> float:
        """The smallest forward lean (within `LEAN_LIMITS_RAD`, to 0.1°) at which both wrists are within
        `ARM_REACH` of the arm's length: the shoulders come nearer the grips as the trunk leans (over
        the range of a rider's reach), so it is found by bisection. A turned handlebar takes one grip
        forward, and the rider leans on to reach it."""
        J = self.model.joints_m
        wrists = self._wrist_targets(targets)

        def short_m(lean: float) -> float:  # how much farther the farther grip is than the arm reaches
            T_pelvis, local = self._trunk(targets.T_world_from_vehicle, targets.seat_m, lean)
            shoulders = joint_transforms(J, Pose(T_pelvis, local), SHOULDERS)[:, :3, 3]
            return float(np.linalg.norm(wrists - shoulders, axis=1).max()) - ARM_REACH * self.arm_m

        low, high = LEAN_LIMITS_RAD
        if short_m(low) <= 0:
            return low
        if short_m(high) > 0:
            return high
        while high - low > math.radians(0.1):
            mid = (low + high) / 2
            low, high = (low, mid) if short_m(mid) <= 0 else (mid, high)
        return high

    def pose(self, time_s: float) -> Pose:
        """The skeleton's pose at `time_s`."""
        targets = self.targets(time_s)
        T_vehicle = targets.T_world_from_vehicle
        R = T_vehicle[:3, :3]
        T_pelvis, local = self._trunk(T_vehicle, targets.seat_m, self.lean_rad(targets))
        J = self.model.joints_m
        G = global_transforms(J, Pose(T_pelvis, local))
        wrists = self._wrist_targets(targets)
        for k, (side, sign) in enumerate((("l", 1), ("r", -1))):
            mirror = np.array([1.0, sign, 1.0])
            pole = R @ (ELBOW_POLE * mirror)
            arm = (f"upperarm_{side}", f"lowerarm_{side}", f"hand_{side}")
            # The hand over the grip: pointing forward and down, the thumb towards the stem.
            R_hand = _aim(J[INDEX[f"hand_{side}"]] - J[INDEX[f"lowerarm_{side}"]], R @ HAND_DIRECTION,
                          R @ np.array([0.0, -sign, 0.0]))  # fmt: skip
            self._chain(local, G, arm, wrists[k], pole, R_hand, front_sign=-1.0)
            # The foot level along the vehicle, the ball on the tread.
            ball = targets.feet_m[k] + np.array([0.0, 0.0, self.ball_height_m])
            ankle = ball + R @ self.ankle_from_ball[side]
            knee_pole = R @ (self.knee_pole * mirror)
            self._chain(local, G, (f"thigh_{side}", f"calf_{side}", f"foot_{side}"), ankle, knee_pole, R)
        return Pose(T_pelvis, local)

    def _chain(self, local, G, names: tuple[str, str, str], target: np.ndarray, pole: np.ndarray, R_end=None,
               front_sign: float = 1.0):  # fmt: skip
        """Two-bone IK: the chain's root, middle and end joints `names`, the end joint put on `target`
        (as near as the chain reaches), the middle joint bent towards `pole`; each bone's front (its rest
        +x) turned towards `front_sign` × `pole` (a knee's front is its point, an elbow's its crease). The
        bones' local rotations are written into `local`; `R_end`: the end joint's global rotation (else it
        follows its parent)."""
        J = self.model.joints_m
        i0, i1, i2 = (INDEX[n] for n in names)
        parent = int(PARENT_INDEX[i0])
        root = G[parent] @ np.append(J[i0] - J[parent], 1.0)
        root = root[:3]
        l1, l2 = float(np.linalg.norm(J[i1] - J[i0])), float(np.linalg.norm(J[i2] - J[i1]))
        to_target = target - root
        d = float(np.clip(np.linalg.norm(to_target), abs(l1 - l2) + 1e-4, (l1 + l2) * 0.9999))
        u = to_target / max(float(np.linalg.norm(to_target)), 1e-9)
        v = pole - float(np.dot(pole, u)) * u
        v /= max(float(np.linalg.norm(v)), 1e-9)
        alpha = math.acos(float(np.clip((l1**2 + d**2 - l2**2) / (2 * l1 * d), -1.0, 1.0)))
        middle = root + l1 * (math.cos(alpha) * u + math.sin(alpha) * v)
        end = root + d * u
        R_parent = G[parent, :3, :3]
        R0 = _aim(J[i1] - J[i0], middle - root, front_sign * pole)
        R1 = _aim(J[i2] - J[i1], end - middle, front_sign * pole)
        local[i0] = R_parent.T @ R0
        local[i1] = R0.T @ R1
        if R_end is not None:
            local[i2] = R1.T @ R_end
        # Keep G's rows of the chain current for later chains that hang from them (none do today).
        G[i0, :3, :3], G[i0, :3, 3] = R0, root
        G[i1, :3, :3], G[i1, :3, 3] = R1, middle
