"""Walking, running and standing, as poses of a person's skeleton at any time along its route.

Footsteps are placed along the route by distance, so the gait is phase-locked to the distance walked:
foot k of side s ∈ {left 0, right 1} has its mid-stance where the pelvis has walked (k + s/2)·S, and
stands on the ground while the pelvis is within ±β·S/2 of it (stride S, duty factor β); it lands
`STANCE_AHEAD_FRACTION` of that travel ahead of the pelvis. A stance foot is pinned to the ground:
first flat, then turning about its ball (heel-off) until toe-off, so its contact point does not move.
A swinging foot travels to its next footprint along a smooth arc. The pelvis follows the route, its
heading rounded over turns; walking, its height over a stride is the smooth lower envelope (bounded
vertical acceleration) of the highest point from which the planted legs reach their feet, which gives
the rise and fall of walking without kinks; running, it bounces as a spring-mass body does
(`running_bounce_m`: free fall in flight, lowest at mid-stance, `RUN_DROP_M` below standing there).
Legs are solved by two-bone inverse kinematics with the knee towards the foot's heading; arms swing
opposite to the legs.

Parameters and sources:

- Stride S = c·h·(v²/(g·h))^0.3 with h the hip height (Alexander 1984, "The gaits of bipedal and
  quadrupedal animals", Int. J. Robotics Res. 3: c = 2.3); c = 2.5 matches Perry 1992's normal adult
  gait (1.41 m stride at 1.37 m/s) and Nilsson & Thorstensson 1987's running (≈ 2.3 m at 3 m/s).
- Walk–run transition at Froude number v²/(g·h) = 0.5 (≈ 2.1 m/s for h = 0.9 m).
- Duty factor: walking 0.62 at 1.3 m/s falling to 0.58 near the transition; running 0.40 at 3 m/s
  and 0.35 at 5 m/s (Perry 1992; Nilsson & Thorstensson 1987).
- Step width 0.10 m (0.08–0.12 m); toe clearance 3 cm walking, the heel lifted 22 cm running;
  heel-off at 45 % of stance, the foot at 50° (walking) or 55° (running) to the ground at toe-off;
  arm swing ±15–25° walking with 15–30° elbow flexion, ±35° running with the elbow at 90°; pelvic
  rotation ±4°; trunk lean 7° running (Winter 1991, Perry 1992). The pelvis rises and falls by about
  5 cm at 1.4 m/s (4–5 cm measured in adults: Saunders, Inman & Eberhart 1953).
- Standing: feet a hip's width apart, weight shifting from foot to foot with a 5 s period;
  arriving and leaving blend between the gait and the stance over 0.5 s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from camgen.actors.actions import (
    ARM_BLEND_S,
    ARMS_RELAX_S,
    FALL_DIRECTIONS,
    HIP_ABOVE_SEAT_M,
    KNEE_BUCKLE_RAD,
    RISE_S,
    SEATED_RECLINE_RAD,
    SIT_S,
    TRANSITION_LEAN_RAD,
    arm_rotations,
    blend_rotation,
    bracing_arm,
    fall_angle_rad,
    fall_duration_s,
    phone_arm,
    seated_arm,
    wave_arm,
    window_weight,
)
from camgen.actors.person import PersonModel
from camgen.actors.skeleton import INDEX, JOINTS, Pose, cross, global_transforms, rot_axis, rotation_between
from camgen.motion.trajectory import Route

G_M_S2 = 9.81
STRIDE_COEFFICIENT = 2.5
WALK_RUN_FROUDE = 0.5
STEP_WIDTH_M = 0.10
HEEL_OFF_FRACTION = 0.45
STANCE_AHEAD_FRACTION = 0.35
"""Where the planted ankle is when the foot lands: this fraction of the stance's travel ahead of the
pelvis (the rest is behind it at toe-off, where the heel is up and the ankle raised)."""
BLEND_S = 0.5
HEADING_LOOKAHEAD_M = 0.4
"""The body faces along the route between this distance behind and ahead: turns are rounded."""
LEG_REACH_FRACTION = 0.99
"""A stance leg never straightens beyond this fraction of its length (a knee kept soft)."""
FOOTPRINT_CACHE = 64
"""Footprints a walker remembers (each is reused by every frame of its stance and swing)."""
HEIGHT_SAMPLES = 96
PELVIS_ACCELERATION_M_S2 = 3.0
"""Largest upward acceleration of the pelvis in walking and running, m/s² (the centre of mass's
vertical acceleration peaks at about 0.3 g in walking: Cavagna et al. 1976)."""
RUN_DROP_M = 0.07
"""How much lower than standing a runner's pelvis passes at mid-stance: the stance knee flexes to about
45° (Novacheck 1998, "The biomechanics of running", Gait & Posture 7: 77; 44° measured on a 1.78 m body
at 3 m/s). Where the bounce then lifts the pelvis beyond a planted leg's reach, near touchdown and
toe-off, that foot leaves the ground a little early."""
WALK_KNEE_DROP_M = 0.02
"""How much lower than standing the pelvis passes over a planted foot when walking: the stance knee
flexes 15–20° after loading (Saunders, Inman & Eberhart 1953, a determinant of gait)."""


@dataclass(frozen=True)
class GaitParameters:
    speed_m_s: float
    stride_m: float
    duty: float
    running: bool
    clearance_m: float
    toe_off_pitch_rad: float
    arm_swing_rad: float
    elbow_rad: float
    lean_rad: float


def gait_parameters(speed_m_s: float, hip_height_m: float) -> GaitParameters:
    """Stride, duty factor and the style of the gait at a speed, for a body with this hip height."""
    froude = speed_m_s**2 / (G_M_S2 * hip_height_m)
    stride = STRIDE_COEFFICIENT * hip_height_m * froude**0.3
    running = froude > WALK_RUN_FROUDE
    if running:
        duty = float(np.clip(0.40 - 0.025 * (speed_m_s - 3.0), 0.28, 0.45))
        return GaitParameters(speed_m_s, stride, duty, True, 0.22, math.radians(55), math.radians(35),
                              math.radians(90), math.radians(7))  # fmt: skip
    duty = float(np.clip(0.62 - 0.06 * (speed_m_s - 1.3) / 0.7, 0.58, 0.66))
    swing = math.radians(min(25.0, 15.0 * speed_m_s / 1.4))
    return GaitParameters(speed_m_s, stride, duty, False, 0.03, math.radians(50), swing, math.radians(20), 0.0)


@dataclass(frozen=True)
class FootState:
    ball_m: np.ndarray
    """(3,) where the ball of the foot is, world."""
    yaw_rad: float
    pitch_rad: float
    """Heel raised about the ball, rad (0 flat)."""
    swing: float = -1.0
    """How far through its swing the foot is, 0…1; −1 while planted."""


class Walker:
    """The pose of one person along one route at any time (pure: same time, same pose)."""

    def __init__(self, model: PersonModel, route: Route, phase_seed: float = 0.0, actions: tuple = ()):
        """`actions`: the person's `camgen.config.scene.PersonAction`s (`camgen.actors.actions`)."""
        self.model, self.route = model, route
        self.actions = tuple(sorted(actions, key=lambda a: a.start_s))
        J = model.joints_m
        self.hip_height_m = float(J[INDEX["thigh_l"], 2])
        self.gait = gait_parameters(route.speed_m_s, self.hip_height_m)
        self.thigh_m = float(np.linalg.norm(J[INDEX["calf_l"]] - J[INDEX["thigh_l"]]))
        self.shin_m = float(np.linalg.norm(J[INDEX["foot_l"]] - J[INDEX["calf_l"]]))
        # Foot geometry: the ankle relative to the ball in the foot frame (x forward, z up).
        self.ankle_from_ball = {side: J[INDEX[f"foot_{side}"]] - J[INDEX[f"ball_{side}"]] for side in ("l", "r")}
        self.ball_height_m = float(J[INDEX["ball_l"], 2])
        self.stand_height_m = float(J[INDEX["pelvis"], 2]) - 0.005
        self.phase_seed = phase_seed
        self._footprints: dict = {}
        self._phases, self._heights = self._height_table()

    # Where the route takes the body ------------------------------------------------------------
    def _yaw_at_distance(self, distance_m: float, route: Route | None = None) -> float:
        route = route or self.route
        ahead = route.at_distance(distance_m + HEADING_LOOKAHEAD_M)
        behind = route.at_distance(distance_m - HEADING_LOOKAHEAD_M)
        delta = ahead - behind
        if np.hypot(*delta) < 1e-6:
            if not route.moves:  # someone standing still faces a direction of their own
                return 2 * math.pi * ((self.phase_seed * 7.31) % 1.0) - math.pi
            return float(route.at(route.start_s)[1])
        return math.atan2(delta[1], delta[0])

    def _footprint(self, distance_m: float, side: int, route: Route | None = None) -> tuple[np.ndarray, float]:
        """Ball position and yaw of a foot planted when the pelvis has walked `distance_m`."""
        key = (distance_m, side, route)
        if key not in self._footprints:
            if len(self._footprints) > FOOTPRINT_CACHE:
                self._footprints.clear()
            self._footprints[key] = self._place_foot(distance_m, side, route or self.route)
        return self._footprints[key]

    def _place_foot(
        self, distance_m: float, side: int, route: Route, lateral_m: float = STEP_WIDTH_M / 2
    ) -> tuple[np.ndarray, float]:
        """Ball position and yaw of a flat foot whose ankle stands `lateral_m` beside the route's point
        at `distance_m`, facing along the route there."""
        yaw = self._yaw_at_distance(distance_m, route)
        centre = route.at_distance(distance_m)
        left = np.array([-math.sin(yaw), math.cos(yaw)])
        lateral = lateral_m * (1 if side == 0 else -1)
        offset = self.ankle_from_ball["l" if side == 0 else "r"]
        # The ankle's ground point lies on the footprint line; the ball is ahead of it.
        forward = np.array([math.cos(yaw), math.sin(yaw)])
        ball_xy = centre + lateral * left - offset[0] * forward - offset[1] * left
        return np.array([ball_xy[0], ball_xy[1], self.ball_height_m]), yaw

    def _walking_foot(self, distance_m: float, side: int, route: Route | None = None) -> FootState:
        gait = self.gait
        S, beta = gait.stride_m, gait.duty
        shift = (side / 2 + self.phase_seed) * S
        k = math.floor((distance_m - shift + beta * S / 2) / S)
        mid = k * S + shift
        start, end = mid - beta * S / 2, mid + beta * S / 2
        plant = start + STANCE_AHEAD_FRACTION * beta * S
        if distance_m <= end:  # stance: pinned, heel rising in its last part
            ball, yaw = self._footprint(plant, side, route)
            heel = (distance_m - start) / (end - start)
            rise = max(0.0, (heel - HEEL_OFF_FRACTION) / (1 - HEEL_OFF_FRACTION))
            return FootState(ball, yaw, gait.toe_off_pitch_rad * _smooth(rise))
        u = (distance_m - end) / ((1 - beta) * S)
        ball0, yaw0 = self._footprint(plant, side, route)
        ball1, yaw1 = self._footprint(plant + S, side, route)
        w = _smooth(u)
        ball = ball0 + (ball1 - ball0) * w
        ball[2] = self.ball_height_m + gait.clearance_m * math.sin(math.pi * u)
        yaw = yaw0 + _angle_diff(yaw1, yaw0) * w
        pitch = gait.toe_off_pitch_rad * (1 - _smooth(min(1.0, u / 0.6)))
        return FootState(ball, yaw, pitch, swing=u)

    def _standing_foot(self, distance_m: float, side: int) -> FootState:
        """A foot of someone standing at `distance_m`: the feet a hip's width apart."""
        hips_m = abs(self.model.joints_m[INDEX["thigh_l"], 1])
        ball, yaw = self._place_foot(distance_m, side, self.route, lateral_m=hips_m)
        return FootState(ball, yaw, 0.0)

    # The pose -----------------------------------------------------------------------------------
    def pose(self, time_s: float) -> Pose:
        """The skeleton's pose at `time_s`."""
        route, gait = self.route, self.gait
        distance = route.distance_at(time_s)
        standing = route.standing(time_s)
        b = 0.0 if standing is None else float(np.clip(min(standing) / BLEND_S, 0.0, 1.0))
        feet = []
        for side in (0, 1):
            walk = self._walking_foot(distance, side)
            if b > 0:
                stand = self._standing_foot(distance, side)
                lift = 0.05 * math.sin(math.pi * b) if np.hypot(*(walk.ball_m - stand.ball_m)[:2]) > 0.02 else 0.0
                ball = walk.ball_m + (stand.ball_m - walk.ball_m) * _smooth(b)
                ball[2] += lift
                yaw = walk.yaw_rad + _angle_diff(stand.yaw_rad, walk.yaw_rad) * _smooth(b)
                walk = FootState(ball, yaw, walk.pitch_rad * (1 - _smooth(b)), -1.0 if b == 1.0 else walk.swing)
            feet.append(walk)
        yaw = self._yaw_at_distance(distance)
        cycle = (distance / gait.stride_m - self.phase_seed) * 2 * math.pi  # left mid-stance at 0
        amp = 1 - _smooth(b)
        pelvis_xy = route.at_distance(distance)
        sway = 0.015 * b * math.sin(2 * math.pi * time_s / 5.0 + 7 * self.phase_seed)
        pelvis_xy = pelvis_xy + sway * np.array([-math.sin(yaw), math.cos(yaw)])
        pelvic_rotation = math.radians(4) * amp * math.sin(cycle)
        R_pelvis = rot_axis("z", yaw + pelvic_rotation)
        J = self.model.joints_m
        ankles = [self._ankle(foot, "l" if side == 0 else "r") for side, foot in enumerate(feet)]
        walking_height = float(np.interp((distance / gait.stride_m) % 1.0, self._phases, self._heights, period=1.0))
        height = amp * walking_height + (1 - amp) * self.stand_height_m
        action = self._action_at(time_s)
        seated = 0.0
        if action is not None and action.type == "sit":  # the pelvis lowers and moves back onto the seat
            seated = window_weight(time_s, action.start_s, action.duration_s, SIT_S)
            seat_xy = pelvis_xy - 0.9 * self.thigh_m * np.array([math.cos(yaw), math.sin(yaw)])
            pelvis_xy = pelvis_xy + (seat_xy - pelvis_xy) * seated
            height += (action.seat_height_m + HIP_ABOVE_SEAT_M - height) * seated
        T_pelvis = np.eye(4)
        T_pelvis[:3, :3] = R_pelvis
        T_pelvis[:3, 3] = (pelvis_xy[0], pelvis_xy[1], height)
        local = np.tile(np.eye(3), (len(JOINTS), 1, 1))
        lean = gait.lean_rad * amp + TRANSITION_LEAN_RAD * math.sin(math.pi * seated) + SEATED_RECLINE_RAD * seated
        local[INDEX["spine_01"]] = rot_axis("y", lean)
        local[INDEX["spine_03"]] = rot_axis("z", -1.5 * pelvic_rotation)
        local[INDEX["neck_01"]] = rot_axis("y", -lean * 0.7) @ rot_axis("z", 0.5 * pelvic_rotation)
        pose = Pose(T_pelvis, local)
        G = global_transforms(J, pose)
        for side, sign, foot, ankle in zip(("l", "r"), (1, -1), feet, ankles, strict=True):
            self._solve_leg(local, G, side, ankle, foot)
            # Arms: the left arm swings forward with the right leg.
            swing = gait.arm_swing_rad * math.sin(cycle) * sign * amp - math.radians(4)
            elbow = gait.elbow_rad * (0.75 + 0.25 * math.sin(cycle) * sign) * amp + math.radians(12) * (1 - amp)
            self._pose_arm(local, side, sign, swing, elbow)
        if action is not None:
            T_pelvis = self._act(action, time_s, local, T_pelvis, feet, seated)
        return Pose(T_pelvis, local)

    # Named actions (camgen.actors.actions) ------------------------------------------------------
    def _action_at(self, time_s: float):
        """The action under way at `time_s` (a fall's rise after its window included), or None."""
        for action in self.actions:
            end = action.start_s + action.duration_s + (RISE_S if action.type == "fall" else 0.0)
            if action.start_s <= time_s <= end:
                return action
        return None

    def falling(self, time_s: float) -> bool:
        """Whether a fall (or the rise after it) is under way at `time_s`."""
        action = self._action_at(time_s)
        return action is not None and action.type == "fall" and time_s > action.start_s

    def _act(self, action, time_s: float, local, T_pelvis: np.ndarray, feet, seated: float) -> np.ndarray:
        """Pose the arms and head for `action` over the gait's pose in `local`; a fall also tips the
        whole body (the returned pelvis transform)."""
        if action.type in ("wave", "phone"):
            w = window_weight(time_s, action.start_s, action.duration_s, ARM_BLEND_S)
            side, sign = ("l", 1) if action.side == "left" else ("r", -1)
            upper, fore = wave_arm(time_s, sign) if action.type == "wave" else phone_arm(sign)
            self._blend_arm(local, side, upper, fore, w)
            if action.type == "phone":  # the head bends over the phone (45° in all)
                local[INDEX["neck_01"]] = local[INDEX["neck_01"]] @ rot_axis("y", math.radians(25) * w)
                local[INDEX["head"]] = local[INDEX["head"]] @ rot_axis("y", math.radians(20) * w)
            return T_pelvis
        if action.type == "sit":
            for side, sign in (("l", 1), ("r", -1)):
                self._blend_arm(local, side, *seated_arm(sign), seated)
            return T_pelvis
        # A fall: the tilt of a toppling body, then lying, then rising over RISE_S.
        end = action.start_s + action.duration_s
        if time_s <= end:
            theta = fall_angle_rad(time_s - action.start_s, self.stand_height_m)
        else:
            theta = fall_angle_rad(end - action.start_s, self.stand_height_m) * (1 - _smooth((time_s - end) / RISE_S))
        tilt = theta / (math.pi / 2)
        # The arms reach out while the body falls and relax once it lies (else they would prop it up).
        since_impact_s = time_s - action.start_s - fall_duration_s(self.stand_height_m)
        brace = min(1.0, 2 * tilt) * (1 - _smooth(since_impact_s / ARMS_RELAX_S))
        for side, sign in (("l", 1), ("r", -1)):
            self._blend_arm(local, side, *bracing_arm(sign, action.direction), brace)
            i_thigh, i_calf = INDEX[f"thigh_{side}"], INDEX[f"calf_{side}"]
            local[i_calf] = local[i_calf] @ rot_axis("y", KNEE_BUCKLE_RAD * tilt)
            local[i_thigh] = local[i_thigh] @ rot_axis("y", -0.5 * KNEE_BUCKLE_RAD * tilt)
        heading = math.atan2(T_pelvis[1, 0], T_pelvis[0, 0]) + FALL_DIRECTIONS[action.direction]
        towards = np.array([math.cos(heading), math.sin(heading), 0.0])
        # The body tips over the edge of its feet on the side it falls to: the balls or the heels.
        edges = [max((foot.ball_m, self._ankle(foot, name)), key=lambda p: p[:2] @ towards[:2])
                 for foot, name in zip(feet, ("l", "r"), strict=True)]  # fmt: skip
        pivot = np.mean(edges, axis=0)
        pivot[2] = 0.0
        R = Rotation.from_rotvec(theta * cross(np.array([0.0, 0.0, 1.0]), towards)).as_matrix()
        # What of the tipped body goes below the ground is lifted onto it after skinning (`PersonRig.settle`).
        T = np.eye(4)
        T[:3, :3] = R
        T[:3, 3] = pivot - R @ pivot
        return T @ T_pelvis

    def _blend_arm(self, local, side: str, upper_dir: np.ndarray, fore_dir: np.ndarray, w: float) -> None:
        if w <= 0:
            return
        R_upper, R_fore = arm_rotations(self.model.joints_m, side, upper_dir, fore_dir)
        i_upper, i_lower = INDEX[f"upperarm_{side}"], INDEX[f"lowerarm_{side}"]
        local[i_upper] = blend_rotation(local[i_upper], R_upper, w)
        local[i_lower] = blend_rotation(local[i_lower], R_fore, w)

    def _raw_height(self, route: Route, distance_m: float) -> float:
        """The highest pelvis from which every planted leg reaches its foot, walking along `route`."""
        gait = self.gait
        yaw = self._yaw_at_distance(distance_m, route)
        cycle = (distance_m / gait.stride_m - self.phase_seed) * 2 * math.pi
        R_pelvis = rot_axis("z", yaw + math.radians(4) * math.sin(cycle))
        pelvis_xy = route.at_distance(distance_m)
        height = self.stand_height_m - WALK_KNEE_DROP_M
        for side, name in ((0, "l"), (1, "r")):
            foot = self._walking_foot(distance_m, side, route)
            if foot.swing < 0:
                height = min(height, self._reach_height(self._ankle(foot, name), R_pelvis, pelvis_xy, name))
        return height

    def _height_table(self) -> tuple[np.ndarray, np.ndarray]:
        """The walking pelvis height over one stride (phase 0…1 of the distance walked), from a straight
        walk: the lower envelope of parabolas hung from the planted legs' limit at every phase, so the
        pelvis never rises above what a planted leg reaches and its vertical acceleration stays within
        `PELVIS_ACCELERATION_M_S2` (a smooth rise and fall, not the limit's corners)."""
        straight = Route(np.array([[0.0, 0.0], [1e4, 0.0]]), np.zeros(2), self.route.speed_m_s)
        S = self.gait.stride_m
        phases = np.arange(HEIGHT_SAMPLES) / HEIGHT_SAMPLES
        if self.gait.running:
            return phases, self.stand_height_m - RUN_DROP_M + running_bounce_m(phases, self.gait, self.phase_seed)
        limit = np.array([self._raw_height(straight, 10 * S + p * S) for p in phases])
        # Height against phase: d²h/dφ² = a·(S / v)², so a parabola of that curvature in φ.
        curvature = 0.5 * PELVIS_ACCELERATION_M_S2 * (S / self.route.speed_m_s) ** 2
        gap = np.abs(phases[:, None] - phases[None, :])
        gap = np.minimum(gap, 1.0 - gap)
        return phases, np.min(limit[None, :] + curvature * gap**2, axis=1)

    def _reach_height(self, ankle: np.ndarray, R_pelvis: np.ndarray, pelvis_xy: np.ndarray, side: str) -> float:
        """The highest pelvis from which this leg still reaches `ankle` (its knee kept soft)."""
        J = self.model.joints_m
        reach = LEG_REACH_FRACTION * (self.thigh_m + self.shin_m)
        hip_offset = R_pelvis @ (J[INDEX[f"thigh_{side}"]] - J[INDEX["pelvis"]])
        horizontal = float(np.hypot(*(pelvis_xy + hip_offset[:2] - ankle[:2])))
        if horizontal >= reach:
            return ankle[2] - hip_offset[2]
        return ankle[2] - hip_offset[2] + math.sqrt(reach**2 - horizontal**2)

    def _ankle(self, foot: FootState, side: str) -> np.ndarray:
        R = rot_axis("z", foot.yaw_rad) @ rot_axis("y", foot.pitch_rad)
        return foot.ball_m + R @ self.ankle_from_ball[side]

    def _solve_leg(self, local, G, side: str, ankle: np.ndarray, foot: FootState) -> None:
        """Two-bone IK: thigh and calf put the ankle on its target, the knee towards the foot's heading;
        the foot takes its yaw and pitch, the toes stay flat on the ground."""
        J = self.model.joints_m
        i_thigh, i_calf, i_foot, i_ball = (INDEX[f"{n}_{side}"] for n in ("thigh", "calf", "foot", "ball"))
        hip = G[INDEX["pelvis"]] @ np.append(J[i_thigh] - J[INDEX["pelvis"]], 1.0)
        hip = hip[:3]
        l1, l2 = self.thigh_m, self.shin_m
        to_ankle = ankle - hip
        d = float(np.clip(np.linalg.norm(to_ankle), abs(l1 - l2) + 1e-4, (l1 + l2) * 0.9999))
        u = to_ankle / max(np.linalg.norm(to_ankle), 1e-9)
        pole = np.array([math.cos(foot.yaw_rad), math.sin(foot.yaw_rad), 0.0])
        v = pole - np.dot(pole, u) * u
        v /= max(np.linalg.norm(v), 1e-9)
        alpha = math.acos(float(np.clip((l1**2 + d**2 - l2**2) / (2 * l1 * d), -1.0, 1.0)))
        knee = hip + l1 * (math.cos(alpha) * u + math.sin(alpha) * v)
        ankle_reached = hip + d * u
        R_pelvis = G[INDEX["pelvis"], :3, :3]
        R_thigh = _aim(J[i_calf] - J[i_thigh], knee - hip, pole)
        R_calf = _aim(J[i_foot] - J[i_calf], ankle_reached - knee, pole)
        R_foot = rot_axis("z", foot.yaw_rad) @ rot_axis("y", foot.pitch_rad)
        R_ball = rot_axis("z", foot.yaw_rad)
        local[i_thigh] = R_pelvis.T @ R_thigh
        local[i_calf] = R_thigh.T @ R_calf
        local[i_foot] = R_calf.T @ R_foot
        local[i_ball] = R_foot.T @ R_ball

    def _pose_arm(self, local, side: str, sign: int, swing_rad: float, elbow_rad: float) -> None:
        """Upper arm hanging 7° out from the trunk, swung forward by `swing_rad`; forearm flexed."""
        J = self.model.joints_m
        i_upper, i_lower = INDEX[f"upperarm_{side}"], INDEX[f"lowerarm_{side}"]
        abduction = math.radians(7)
        hang = np.array([0.0, sign * math.sin(abduction), -math.cos(abduction)])
        upper_dir = rot_axis("y", -swing_rad) @ hang
        fore_dir = rot_axis("y", -(swing_rad + elbow_rad)) @ hang
        R_upper = rotation_between(J[i_lower] - J[i_upper], upper_dir)
        R_fore = rotation_between(J[INDEX[f"hand_{side}"]] - J[i_lower], fore_dir)
        local[i_upper] = R_upper  # the clavicle keeps the trunk's axes: directions above are in them
        local[i_lower] = R_upper.T @ R_fore


def running_bounce_m(phases: np.ndarray, gait: GaitParameters, phase_seed: float, samples: int = 512) -> np.ndarray:
    """A runner's vertical centre-of-mass excursion at `phases` of the stride, m, 0 at each mid-stance.

    The spring-mass model of running (Blickhan 1989, J. Biomech. 22: 1217) with the ground force of a
    stance taken as a half sine whose impulse equals the body's weight over the step, so the step is
    periodic (the sine approximation of Morin et al. 2005, J. Appl. Biomech. 21: 167); in flight the body
    falls freely (−g). Step period T = S/(2v), stance βS/v. For a hip height of 0.9 m this gives 7.3 cm
    of rise and fall at 3 m/s and 5.7 cm at 5 m/s, within the 5–10 cm measured over these speeds (Lee &
    Farley 1998, J. Exp. Biol. 201: 2935; Gullstrand et al. 2009, Gait & Posture 30: 71). The left
    foot's mid-stance is at phase `phase_seed` (`Walker._walking_foot`), the right's half a stride later."""
    contact = 2 * gait.duty  # stance's share of one step (two steps per stride)
    step_s = gait.stride_m / (2 * gait.speed_m_s)
    # u: time in the step from the start of stance, over the stance time; mid-stance at u = 0.5
    t = (np.arange(samples) + 0.5) / samples * step_s
    u = t / (contact * step_s)
    acceleration = np.where(
        u < 1, G_M_S2 * (np.pi / (2 * contact)) * np.sin(np.pi * np.minimum(u, 1.0)) - G_M_S2, -G_M_S2
    )
    velocity = np.cumsum(acceleration) * step_s / samples
    velocity -= velocity.mean()  # periodic: no net rise over a step
    height = np.cumsum(velocity) * step_s / samples
    height -= height.min()
    # The step's phase (0…1) of each stride phase: stance centred on the mid-stance of either foot.
    step_phase = ((2 * (phases - phase_seed)) % 1.0 + contact / 2) % 1.0
    return np.interp(step_phase, (np.arange(samples) + 0.5) / samples, height, period=1.0)


def _aim(rest_direction: np.ndarray, direction: np.ndarray, pole: np.ndarray) -> np.ndarray:
    """The rotation taking a rest bone (whose rest forward is +x) onto `direction`, turned about it so
    that its forward points as near `pole` as it can."""
    a0 = rest_direction / math.sqrt(rest_direction @ rest_direction)
    b0 = np.array([1.0, 0.0, 0.0]) - a0[0] * a0
    b0 /= math.sqrt(b0 @ b0)
    a1 = direction / math.sqrt(direction @ direction)
    b1 = pole - (pole @ a1) * a1
    norm = math.sqrt(b1 @ b1)
    b1 = b1 / norm if norm > 1e-9 else b0
    F0 = np.column_stack([a0, b0, cross(a0, b0)])
    F1 = np.column_stack([a1, b1, cross(a1, b1)])
    return F1 @ F0.T


def _smooth(u: float) -> float:
    """Smoothstep on [0, 1]: zero slope at both ends."""
    u = min(max(u, 0.0), 1.0)
    return u * u * (3 - 2 * u)


def _angle_diff(a: float, b: float) -> float:
    """a − b wrapped into (−π, π]."""
    return (a - b + math.pi) % (2 * math.pi) - math.pi
