"""Named actions of a procedural person: wave, look at a phone, sit down, fall.

An action is a time window of the scene (`camgen.config.scene.PersonAction`) during which the gait's
pose (`camgen.actors.gait.Walker.pose`) is changed; each fades in and out, so the pose never jumps.

- **wave** (walking or standing): the hand raised beside the head, the upper arm about 50° above
  horizontal, and the forearm swinging ±25° about upright at 2.5 Hz (hand waving is a 2–4 Hz
  oscillation: Bobick & Davis 2001's and the KTH/Weizmann action sets' "hand waving" clips).
- **phone** (walking or standing): texting posture: the upper arm 25° forward of hanging, the elbow
  flexed so the hand is in front of the lower chest, the neck and head flexed 45° in all (people
  texting flex the head 33–46° while standing and walking: Lee et al. 2015, "Neck flexion angle of
  smartphone users", Ergonomics 58: 1779; Hansraj 2014). That arm stops swinging.
- **sit** (standing only): the pelvis lowers over 1.2 s to `seat_height_m` plus 0.09 m (the hip
  joint centre sits about 9 cm above a firm seat: Reed, Manary & Schneider 1999, SAE 1999-01-0959)
  and moves back by 90 % of the thigh's length, the feet stay where they stood, the trunk leans
  forward up to 30° while lowering (trunk flexion during stand-to-sit: Schenkman et al. 1990) and
  reclines 8° seated; hands rest on the thighs. Standing up is the same, reversed.
- **fall** (standing only): the body topples as an inverted pendulum about the edge of its feet
  (θ'' = (g / L)·sin θ with L the pelvis height, released at rest at 15°, past where a trip or slip
  can still be recovered, after 0.15 s of tipping there), reaching the ground 0.85–0.96 s after the
  fall begins for pelvis heights of 0.75–1 m (falls from standing reach the ground in 0.7–1 s:
  Hsiao & Robinovitch 1998, J. Biomech. 31: 1), the knees buckling 20° and the arms thrown forward to
  brace (the protective reach in 95 % of the falls of Hsiao & Robinovitch's subjects), relaxing once
  down; it then lies on the ground until the action ends and rises over `RISE_S`.

People sit and fall where they stand (a bench behind the person is the scene's to place); the plan
refuses a sit or a fall while the person walks.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from scipy.spatial.transform import Rotation

from camgen.actors.skeleton import INDEX, rot_axis, rotation_between

G_M_S2 = 9.81
ARM_BLEND_S = 0.4
"""A wave or a phone fades in and out over this time, s."""
SIT_S = 1.2
"""Time to sit down or stand up, s (stand-to-sit takes 1–2 s in healthy adults)."""
HIP_ABOVE_SEAT_M = 0.09
SEATED_RECLINE_RAD = math.radians(-8)
TRANSITION_LEAN_RAD = math.radians(30)
WAVE_HZ = 2.5
WAVE_SWING_RAD = math.radians(25)
FALL_START_TILT_RAD = math.radians(15)
TRIP_S = 0.15
"""The body tips smoothly from upright to `FALL_START_TILT_RAD` over this time, s, before it falls freely."""
KNEE_BUCKLE_RAD = math.radians(20)
ARMS_RELAX_S = 0.3
"""After the body reaches the ground, its bracing arms relax over this time, s, and it lies on them."""
RISE_S = 1.5
"""A fallen person gets up over this time, s (simplified: a reversed fall, not a real rise)."""
FALL_DIRECTIONS = {"forward": 0.0, "left": math.pi / 2, "backward": math.pi, "right": -math.pi / 2}
"""Direction of a fall, as an angle from the person's heading, counter-clockwise."""


def _smooth(u: float) -> float:
    u = min(max(u, 0.0), 1.0)
    return u * u * (3 - 2 * u)


def window_weight(time_s: float, start_s: float, duration_s: float, blend_s: float) -> float:
    """0 outside [start, start + duration], rising and falling smoothly over `blend_s` at each end
    (over half the window when it is shorter than two blends)."""
    blend = min(blend_s, duration_s / 2)
    return _smooth((time_s - start_s) / blend) * _smooth((start_s + duration_s - time_s) / blend)


def fall_angle_rad(time_since_s: float, pelvis_height_m: float) -> float:
    """Tilt of a toppling body `time_since_s` after its fall began (0 before, π/2 on the ground): the
    inverted pendulum θ'' = (g / L) sin θ released at rest from `FALL_START_TILT_RAD`."""
    if time_since_s <= 0:
        return 0.0
    if time_since_s < TRIP_S:  # losing balance: tipping smoothly to where the fall takes over
        return FALL_START_TILT_RAD * _smooth(time_since_s / TRIP_S)
    return float(np.interp(time_since_s - TRIP_S, *_fall_table(round(pelvis_height_m, 3))))


@lru_cache(maxsize=64)
def _fall_table(pelvis_height_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(times s, tilts rad) of the toppling pendulum until it reaches the ground, integrated with
    scipy's adaptive Runge–Kutta to 1e-10 (the closed form is an elliptic integral)."""
    from scipy.integrate import solve_ivp

    def on_ground(_t, y):
        return y[0] - math.pi / 2

    on_ground.terminal = True
    solution = solve_ivp(
        lambda _t, y: [y[1], G_M_S2 / pelvis_height_m * math.sin(y[0])],
        (0.0, 10.0),
        [FALL_START_TILT_RAD, 0.0],
        events=on_ground,
        dense_output=True,
        rtol=1e-10,
        atol=1e-12,
    )
    end = float(solution.t_events[0][0])
    times = np.linspace(0.0, end, 200)
    tilts = np.minimum(solution.sol(times)[0], math.pi / 2)
    tilts[-1] = math.pi / 2
    return times, tilts


def fall_duration_s(pelvis_height_m: float) -> float:
    """Time from the start of a fall to the body on the ground, s."""
    return TRIP_S + float(_fall_table(round(pelvis_height_m, 3))[0][-1])


def blend_rotation(a: np.ndarray, b: np.ndarray, w: float) -> np.ndarray:
    """The rotation a fraction `w` of the way from `a` to `b` (geodesic)."""
    if w <= 0:
        return a
    if w >= 1:
        return b
    step = Rotation.from_matrix(a.T @ b).as_rotvec() * w
    return a @ Rotation.from_rotvec(step).as_matrix()


def arm_rotations(joints_m: np.ndarray, side: str, upper_dir: np.ndarray, fore_dir: np.ndarray) -> tuple:
    """(upper arm local rotation, forearm local rotation) pointing the arm along directions given in
    the trunk's axes (x forward, y left, z up), as `Walker._pose_arm` poses it."""
    i_upper, i_lower, i_hand = INDEX[f"upperarm_{side}"], INDEX[f"lowerarm_{side}"], INDEX[f"hand_{side}"]
    R_upper = rotation_between(joints_m[i_lower] - joints_m[i_upper], upper_dir)
    R_fore = rotation_between(joints_m[i_hand] - joints_m[i_lower], fore_dir)
    return R_upper, R_upper.T @ R_fore


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def wave_arm(time_s: float, sign: int) -> tuple[np.ndarray, np.ndarray]:
    """Upper-arm and forearm directions of a waving arm (sign +1 left, −1 right), trunk axes."""
    upper = _unit([0.15, sign * 0.62, 0.77])  # about 50° above horizontal, out to the side
    swing = WAVE_SWING_RAD * math.sin(2 * math.pi * WAVE_HZ * time_s)
    fore = _unit([0.1, sign * math.sin(swing), math.cos(swing)])
    return upper, fore


def phone_arm(sign: int) -> tuple[np.ndarray, np.ndarray]:
    """Upper-arm and forearm directions of a hand holding a phone before the lower chest."""
    upper = rot_axis("y", math.radians(-25)) @ _unit([0.0, sign * 0.08, -1.0])
    fore = _unit([0.8, -sign * 0.3, 0.52])
    return upper, fore


def seated_arm(sign: int) -> tuple[np.ndarray, np.ndarray]:
    """A seated person's arm, the hand resting on the thigh."""
    upper = rot_axis("y", math.radians(-20)) @ _unit([0.0, sign * 0.15, -1.0])
    fore = _unit([0.85, -sign * 0.05, -0.5])
    return upper, fore


def bracing_arm(sign: int, direction: str) -> tuple[np.ndarray, np.ndarray]:
    """An arm reaching the way the body falls, to break the fall: forward, back and down (the shoulder
    extends to about 50° behind the trunk), or out to the side."""
    if direction == "forward":
        return _unit([0.9, sign * 0.25, -0.2]), _unit([0.95, sign * 0.1, 0.0])
    if direction == "backward":
        return _unit([-0.55, sign * 0.3, -0.8]), _unit([-0.6, sign * 0.2, -0.75])
    towards = 1 if direction == "left" else -1
    return _unit([0.15, towards * 0.9, -0.35]), _unit([0.1, towards * 0.95, -0.25])
