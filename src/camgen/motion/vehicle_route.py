"""Vehicle routes: a kinematic bicycle model along waypoints, with a turning circle and eased speed.

A `Route` (`camgen.motion.trajectory`) walks straight legs at constant speed and snaps its heading at each
waypoint. A vehicle cannot: its heading follows the kinematic bicycle model (Rajamani, *Vehicle Dynamics
and Control*, 2nd ed., Springer 2012, §2.2)::

    ẋ = v·cos ψ,   ẏ = v·sin ψ,   ψ̇ = v·tan δ / L            (reference point: the rear axle's middle)

so the path's curvature is κ = tan δ / L and never exceeds 1/R_min with R_min = L / tan δ_max. A
`VehicleRoute` therefore rounds every corner of the waypoint polygon with a circular arc of radius R_min
tangent to both legs (a Dubins-like fillet): the heading is continuous, |κ| ≤ 1/R_min, and the corner is
cut as a driver cuts it. The arc passes the waypoint at

    d = R_min·(1/cos(θ/2) − 1)                                                        (θ: the turn angle)

(0.41·R_min for a right angle, `waypoint_miss_m`), the tolerance to which the curve meets each
interior waypoint. It starts exactly at the first waypoint and ends exactly at the last. Where the legs
are too short to hold the fillets of their two ends (each needs R_min·tan(θ/2) of the leg), or a path
turns straight back, the route is refused (`RouteTooTightError`): no vehicle could drive it.

Speed follows the usual two-pass profile over the arc length s: the cruise speed (the path's
speed_m_s) on straights, v ≤ √(a_lat·R) on arcs (lateral acceleration bound), a start from rest, a stop
at every waypoint with a pause (at the middle of its arc, the point nearest the waypoint) and at the
end, accelerating at most at a_acc and braking at most at a_dec. With limits constant between
breakpoints, v² is piecewise linear in s, so the motion is a sequence of constant-acceleration pieces
and t(s) and its inverse s(t) are closed forms: every frame time has an exact position.

The route point is the middle of the rear axle (where the model's velocity is along the heading):
a body drawn around it sits its rear axle there. Front-wheel steering `steer_rad_at` is δ = atan(L·κ).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from camgen.motion.memo import POSE_MEMO_TIMES, TimeMemo, frozen
from camgen.motion.route_fields import freeze_route_fields

LEG_ARC_STEP_RAD = math.radians(5.0)
"""Largest turn of one straight piece that `VehicleRoute.legs_until` gives for an arc, rad."""

TOUCH_TOLERANCE_M = 1e-9
"""Legs may be this much shorter than their fillets need (rounding), m."""

STATE_MEMO_TIMES = POSE_MEMO_TIMES
"""How many single times' states (distance, speed, pose) a route keeps: a vehicle's pose at a time asks for its
position, distance and curvature there, and a frame asks for the same few tens of times again; as many as an
actor keeps poses (`camgen.motion.memo.POSE_MEMO_TIMES`, whose docstring counts a frame's times)."""


def rear_axle_radius_m(outer_radius_m: float, forward_m: float, outward_m: float) -> float:
    """Turning radius of the rear axle's middle, m, from the radius a point of the vehicle sweeps.

    In a steady low-speed turn every point of a rigid vehicle circles the centre on the rear axle's
    line; a point `forward_m` ahead of the rear axle and `outward_m` outboard of the centre line sweeps
    ``R_outer² = (R + outward)² + forward²``. For the kerb-to-kerb turning circle of a car the point is
    the outer front tyre (forward = wheelbase, outward = half the track); for a bus's swept circle it is
    the body's outer front corner.
    """
    return math.sqrt(outer_radius_m**2 - forward_m**2) - outward_m


@dataclass(frozen=True)
class VehicleDynamics:
    """Limits of one vehicle class (kinematic bicycle model and the driver's comfort).

    Parameters
    ----------
    wheelbase_m : float
        L, between front and rear axles, m.
    min_turn_radius_m : float
        R_min, of the rear axle's middle, m (= L / tan δ_max).
    lateral_accel_m_s2 : float
        a_lat: largest lateral acceleration the driver takes in a curve, m/s².
    accel_m_s2 : float
        a_acc: largest longitudinal acceleration, m/s².
    decel_m_s2 : float
        a_dec: largest braking deceleration (positive), m/s².
    """

    wheelbase_m: float
    min_turn_radius_m: float
    lateral_accel_m_s2: float
    accel_m_s2: float
    decel_m_s2: float

    def __post_init__(self) -> None:
        for name in ("wheelbase_m", "min_turn_radius_m", "lateral_accel_m_s2", "accel_m_s2", "decel_m_s2"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be > 0, got {value}")

    @property
    def max_steer_rad(self) -> float:
        """δ_max = atan(L / R_min), rad."""
        return math.atan(self.wheelbase_m / self.min_turn_radius_m)


# Turning radii, from published turning circles through `rear_axle_radius_m`:
# - car: VW Golf VII (a typical C-segment car), wheelbase 2.637 m, front track 1.549 m, kerb-to-kerb turning
#   circle 10.9 m (manufacturer data) → R_min = 4.0 m, δ_max = 33°. Typical cars: 10–11.5 m circles.
# - truck: AASHTO "A Policy on Geometric Design of Highways and Streets" (Green Book, 2011), Table 2-2b,
#   single-unit truck SU-9: wheelbase 6.1 m, centreline (front axle) turning radius 11.6 m → R_min = 9.9 m.
# - bus: UN ECE Regulation No. 107, Annex 3 §7.5: a bus must turn within a ring of outer radius 12.5 m
#   (inner 5.3 m). A 12 m city bus (wheelbase 5.9 m, front overhang 2.7 m, width 2.55 m — the EU maximum,
#   Directive 96/53/EC) whose outer front corner runs on 12.5 m → R_min = 7.8 m.
# - motorcycle: manufacturers list 2.5–3.0 m minimum turning radii for mid-size motorcycles (e.g. Honda
#   CB500F, 2.7 m); wheelbase 1.41 m → R_min = 2.3 m.
# - bicycle: an adult bicycle (wheelbase 1.02 m) turned at walking pace by about 27° of handlebar → 2.0 m;
#   an estimate, no table found.
# Lateral acceleration: AASHTO Green Book (2011) §3.3.6 lets low-speed urban curves use side friction
# f ≈ 0.3 (≈ 3 m/s²); drivers in normal traffic stay mostly below 3–4 m/s² at low speed (Bosetti, Da Lio
# and Saroldi, "On the human control of vehicles: an experimental study of acceleration", Eur. Transp. Res.
# Rev. 6, 2014); cars and motorcycles take 2.5 m/s². Buses and trucks take 1.5 m/s², the comfort limit
# for standing passengers and loads (Hoberock, "A survey of longitudinal acceleration comfort studies in
# ground transportation vehicles", J. Dyn. Sys. Meas. Control 99, 1977: 0.11–0.15 g).
# Longitudinal: cars accelerate from a stop at about 1.5–2.5 m/s² (Long, "Acceleration characteristics of
# starting vehicles", TRR 1737, 2000) and brake comfortably at up to 3.4 m/s² (AASHTO Green Book §3.2.2,
# the rate most drivers exceed only when surprised); buses keep both at ≈ 0.12 g (Hoberock 1977); trucks
# accelerate at ≈ 1 m/s² (Long 2000, heavy vehicles); a cyclist accelerates at ≈ 1 m/s² and brakes at ≈
# 1.5 m/s² (estimates for calm riding).
VEHICLE_DYNAMICS: dict[str, VehicleDynamics] = {
    "car": VehicleDynamics(2.637, rear_axle_radius_m(10.9 / 2, 2.637, 1.549 / 2), 2.5, 2.0, 3.0),
    "truck": VehicleDynamics(6.1, rear_axle_radius_m(11.6, 6.1, 0.0), 1.5, 1.0, 2.0),
    "bus": VehicleDynamics(5.9, rear_axle_radius_m(12.5, 5.9 + 2.7, 2.55 / 2), 1.5, 1.2, 1.2),
    "motorcycle": VehicleDynamics(1.41, rear_axle_radius_m(2.7, 1.41, 0.0), 2.5, 2.5, 3.0),
    "bicycle": VehicleDynamics(1.02, 1.02 / math.tan(math.radians(27.0)), 2.0, 1.0, 1.5),
}
"""Actor class → its vehicle's limits (sources in the comment above)."""

VEHICLE_CLASSES = frozenset(VEHICLE_DYNAMICS)
"""Actor classes that drive (`VehicleRoute`) by default."""


class RouteTooTightError(ValueError):
    """The waypoints ask for a turn the vehicle cannot make; `waypoint` is the index to move."""

    def __init__(self, message: str, waypoint: int):
        super().__init__(message)
        self.waypoint = waypoint


def waypoint_miss_m(turn_rad: float, radius_m: float) -> float:
    """How far the fillet of a turn by `turn_rad` with `radius_m` passes from its corner, m:
    R·(1/cos(θ/2) − 1)."""
    return radius_m * (1.0 / math.cos(abs(turn_rad) / 2.0) - 1.0)


@dataclass(frozen=True, eq=False)
class VehicleRoute:
    """Where a vehicle is at any time: straights and arcs of radius ≥ R_min, speed eased into turns and stops.

    Offers what `camgen.motion.trajectory.Route` offers (`at`, `distance_at`, `at_distance`, `standing`,
    `legs_until`, `duration_s`, `moves`, `points_m`) and `speed_at`, `curvature_at`, `steer_rad_at`.
    Until `start_s` the vehicle stands at the start of its curve (the first waypoint), facing along it.
    It stops for its pause at each waypoint with a pause > 0 and at the end for good. A loop stops at
    the first waypoint's fillet at the end of every lap (for ``pauses_s[0]``, possibly 0 s) and leaves
    from rest again, so every lap is the same.

    Parameters
    ----------
    waypoints_m : ndarray, shape (N, 2)
        Ground points (x, y), m; N ≥ 1.
    pauses_s : ndarray, shape (N,)
        Dwell at each waypoint, s, ≥ 0.
    speed_m_s : float
        Cruise speed on straights, m/s, > 0.
    dynamics : VehicleDynamics
        Turning radius and acceleration limits.
    start_s : float
        When the vehicle leaves, s, ≥ 0.
    loop : bool
        Drive back to the first waypoint and repeat.
    """

    waypoints_m: np.ndarray
    pauses_s: np.ndarray
    speed_m_s: float
    dynamics: VehicleDynamics
    start_s: float = 0.0
    loop: bool = False

    def __post_init__(self) -> None:
        freeze_route_fields(self)
        self._path  # noqa: B018 — refuse a route the vehicle cannot drive when it is made

    @property
    def points_m(self) -> np.ndarray:
        """The waypoints, (N, 2) m: every fillet lies in the triangle of its corner and its two tangent
        points, so the waypoints' convex hull contains every position the vehicle takes."""
        return self.waypoints_m

    # --- geometry -------------------------------------------------------------------------------------

    @cached_property
    def _path(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, list[tuple[float, float]], float]:
        """The curve as primitives: start distance (P+1,) m, start point (P, 2) m, start heading (P,) rad,
        curvature (P,) 1/m; then the stops (distance m, dwell s) along one lap (the last one is the end,
        or the loop's return), and the heading to face before any primitive."""
        points, pauses = self.waypoints_m, self.pauses_s
        # Drop repeated waypoints (a repeat's pause adds to its twin's).
        kept, dwell = [0], [float(pauses[0])]
        for k in range(1, len(points)):
            if np.array_equal(points[k], points[kept[-1]]):
                dwell[-1] += float(pauses[k])
            else:
                kept.append(k)
                dwell.append(float(pauses[k]))
        if self.loop and len(kept) > 1 and np.array_equal(points[kept[-1]], points[kept[0]]):
            dwell[0] += dwell.pop()
            kept.pop()
        vertices = points[kept]
        n = len(vertices)
        if n == 1:
            return np.zeros(1), np.zeros((0, 2)), np.zeros(0), np.zeros(0), [], 0.0
        radius = self.dynamics.min_turn_radius_m
        legs = n if self.loop else n - 1
        ends = [(vertices[j], vertices[(j + 1) % n]) for j in range(legs)]
        length = np.array([math.dist(a, b) for a, b in ends])
        heading = np.array([math.atan2(b[1] - a[1], b[0] - a[0]) for a, b in ends])
        # Turn at each vertex (between the leg arriving and the leg leaving), 0 at an open route's ends.
        turn = np.zeros(n)
        for k in range(n):
            if self.loop or 0 < k < n - 1:
                turn[k] = math.remainder(heading[k % legs] - heading[k - 1], 2 * math.pi)
                if abs(abs(turn[k]) - math.pi) < 1e-9:
                    raise RouteTooTightError(
                        f"turns straight back at waypoint {kept[k]} {_point(vertices[k])}; a vehicle cannot reverse "
                        "its heading on the spot: add waypoints that lead it round a turn of radius "
                        f"≥ {radius:.1f} m",
                        kept[k],
                    )
        tangent = radius * np.tan(np.abs(turn) / 2)
        for j in range(legs):
            need = tangent[j] + tangent[(j + 1) % n]
            if need > length[j] + TOUCH_TOLERANCE_M:
                a, b = kept[j], kept[(j + 1) % n]
                raise RouteTooTightError(
                    f"the leg from waypoint {a} {_point(vertices[j])} to waypoint {b} "
                    f"{_point(vertices[(j + 1) % n])} is "
                    f"{length[j]:.2f} m long, but rounding its turns ({math.degrees(abs(turn[j])):.0f}° and "
                    f"{math.degrees(abs(turn[(j + 1) % n])):.0f}°) with this vehicle's minimum turning radius "
                    f"{radius:.1f} m needs {tangent[j]:.2f} + {tangent[(j + 1) % n]:.2f} m of it; move the waypoints "
                    "apart or make the turns gentler",
                    b,
                )
        starts, headings, curvatures, lengths = [], [], [], []

        def add(point: np.ndarray, psi: float, kappa: float, size: float) -> None:
            if size > 0:
                starts.append(np.asarray(point, dtype=np.float64))
                headings.append(psi)
                curvatures.append(kappa)
                lengths.append(size)

        def arc(k: int, part: str) -> float:
            """Add the fillet at vertex k (its first half, second half or whole); return the arc length
            from the primitive's start to the fillet's middle (where a stop at k falls)."""
            if turn[k] == 0:
                return 0.0
            into = heading[k - 1]
            begin = vertices[k] - tangent[k] * np.array([math.cos(into), math.sin(into)])
            kappa = math.copysign(1.0 / radius, turn[k])
            full = radius * abs(turn[k])
            if part == "second":
                middle = _advance(begin, into, kappa, full / 2)
                add(middle, into + turn[k] / 2, kappa, full / 2)
                return 0.0
            add(begin, into, kappa, full if part == "whole" else full / 2)
            return full / 2

        stops: list = []  # (primitives before, distance into the next, dwell)
        if self.loop:
            arc(0, "second")
        for j in range(legs):
            k = (j + 1) % n
            direction = np.array([math.cos(heading[j]), math.sin(heading[j])])
            add(vertices[j] + tangent[j] * direction, heading[j], 0.0, length[j] - tangent[j] - tangent[k])
            if k == 0:  # a loop's lap ends at the middle of its first fillet
                arc(0, "first")
                stops.append((len(lengths), 0.0, dwell[0]))
                continue
            if k == n - 1 and not self.loop:  # the route's end
                stops.append((len(lengths), 0.0, math.inf))
                continue
            before = len(lengths)
            to_middle = arc(k, "whole")
            if dwell[k] > 0:
                stops.append((before, to_middle, dwell[k]))
        distance = np.concatenate([[0.0], np.cumsum(lengths)])
        # A stop's distance from the same sums as the primitives' (an end stop is exactly the end).
        stops = [(float(distance[i] + offset), pause) for i, offset, pause in stops]
        first_heading = float(headings[0]) if headings else float(heading[0])
        return (
            distance,
            np.array(starts).reshape(-1, 2),
            np.array(headings, dtype=np.float64),
            np.array(curvatures, dtype=np.float64),
            stops,
            first_heading,
        )

    @property
    def length_m(self) -> float:
        """Length of the curve (of one lap for a loop), m."""
        return float(self._path[0][-1])

    @property
    def moves(self) -> bool:
        """Whether the vehicle ever changes position."""
        return self.length_m > 0

    def _primitive(self, s: np.ndarray) -> np.ndarray:
        distance = self._path[0]
        return np.clip(np.searchsorted(distance, s, side="right") - 1, 0, len(distance) - 2)

    def _pose_at_distance(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Point (…, 2) m, heading (…) rad and curvature (…) 1/m at arc length `s` (…) m within one lap."""
        distance, starts, headings, curvatures, _, first_heading = self._path
        s = np.asarray(s, dtype=np.float64)
        if len(starts) == 0:
            point = np.broadcast_to(self.waypoints_m[0], (*s.shape, 2)).copy()
            return point, np.full(s.shape, first_heading), np.zeros(s.shape)
        i = self._primitive(s)
        along = np.clip(s - distance[i], 0.0, distance[i + 1] - distance[i])
        point = _advance(starts[i], headings[i], curvatures[i], along)
        psi = headings[i] + curvatures[i] * along
        return point, np.angle(np.exp(1j * psi)), curvatures[i]

    # --- speed profile ---------------------------------------------------------------------------------

    @cached_property
    def _motion(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """One lap as pieces of constant acceleration (dwells included): start time (M+1,) s after
        leaving, start distance (M,) m, start speed (M,) m/s, acceleration (M,) m/s², and whether each
        piece is a dwell (M,)."""
        distance, _, _, curvatures, stops, _ = self._path
        dyn = self.dynamics
        if len(curvatures) == 0:
            return np.zeros(1), np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0, dtype=bool)
        # Breakpoints: primitive ends and stops; the limit between two is constant.
        stop_at = {s: dwell for s, dwell in stops}
        nodes = np.unique(np.concatenate([distance, [s for s, _ in stops]]))
        lap = distance[-1]
        cap = np.minimum(self.speed_m_s, np.sqrt(dyn.lateral_accel_m_s2 / np.maximum(np.abs(curvatures), 1e-300)))
        mids = (nodes[:-1] + nodes[1:]) / 2
        limit2 = cap[self._primitive(mids)] ** 2  # per interval
        node2 = np.minimum(np.concatenate([limit2[:1], limit2]), np.concatenate([limit2, limit2[-1:]]))
        node2[0] = node2[-1] = 0.0  # from rest, to rest
        for k, s in enumerate(nodes):
            if s in stop_at:
                node2[k] = 0.0
        gaps = np.diff(nodes)
        forward = node2.copy()
        for k in range(1, len(nodes)):
            forward[k] = min(forward[k], forward[k - 1] + 2 * dyn.accel_m_s2 * gaps[k - 1])
        v2 = forward.copy()
        for k in range(len(nodes) - 2, -1, -1):
            v2[k] = min(v2[k], v2[k + 1] + 2 * dyn.decel_m_s2 * gaps[k])
        times, s0s, v0s, accs, dwells = [0.0], [], [], [], []

        def piece(s0: float, s1: float, u: float, acc: float) -> None:
            """A piece from s0 to s1 entered at v² = u with acceleration acc."""
            if s1 - s0 <= 0:
                return
            v0 = math.sqrt(max(u, 0.0))
            if acc == 0:
                duration = (s1 - s0) / v0
            else:
                v1 = math.sqrt(max(u + 2 * acc * (s1 - s0), 0.0))
                duration = (v1 - v0) / acc
            times.append(times[-1] + duration)
            s0s.append(s0)
            v0s.append(v0)
            accs.append(acc)
            dwells.append(False)

        for k in range(len(gaps)):
            a, b, u, w, c2 = nodes[k], nodes[k + 1], v2[k], v2[k + 1], limit2[k]
            s1 = a + (c2 - u) / (2 * dyn.accel_m_s2)
            s2 = b - (c2 - w) / (2 * dyn.decel_m_s2)
            if s1 <= s2:
                piece(a, s1, u, dyn.accel_m_s2)
                piece(s1, s2, c2, 0.0)
                piece(s2, b, c2, -dyn.decel_m_s2)
            else:
                # Where accelerating from u meets braking to w: u + 2·a_acc·(s − a) = w + 2·a_dec·(b − s).
                both = 2 * (dyn.accel_m_s2 + dyn.decel_m_s2)
                peak = (w - u + 2 * dyn.decel_m_s2 * b + 2 * dyn.accel_m_s2 * a) / both
                peak = min(max(peak, a), b)
                piece(a, peak, u, dyn.accel_m_s2)
                piece(peak, b, u + 2 * dyn.accel_m_s2 * (peak - a), -dyn.decel_m_s2)
            dwell = stop_at.get(b, 0.0)
            if dwell > 0 and (b < lap or self.loop):
                times.append(times[-1] + dwell)
                s0s.append(b)
                v0s.append(0.0)
                accs.append(0.0)
                dwells.append(True)
        return np.array(times), np.array(s0s), np.array(v0s), np.array(accs), np.array(dwells, dtype=bool)

    @property
    def duration_s(self) -> float:
        """Time from leaving to the stop at the last waypoint, or, for a loop, one lap with its pauses, s."""
        return float(self._motion[0][-1])

    def _local(self, time_s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Laps completed (…), time into the lap (…) s and whether the vehicle has not left yet (…)."""
        since = np.asarray(time_s, dtype=np.float64) - self.start_s
        total = self.duration_s
        before = since < 0
        since = np.maximum(since, 0.0)
        if total == 0:
            return np.zeros(since.shape), np.zeros(since.shape), before
        if self.loop:
            laps = np.floor(since / total)
            return laps, since - laps * total, before
        return np.zeros(since.shape), np.minimum(since, total), before

    def _state_at(self, time_s) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Laps (…), distance into the lap (…) m and speed (…) m/s at `time_s`."""
        times, s0s, v0s, accs, _ = self._motion
        laps, local, before = self._local(time_s)
        if len(s0s) == 0:
            return laps, np.zeros(local.shape), np.zeros(local.shape)
        i = np.clip(np.searchsorted(times, local, side="right") - 1, 0, len(s0s) - 1)
        tau = np.clip(local - times[i], 0.0, times[i + 1] - times[i])
        arrived = np.zeros(local.shape, dtype=bool) if self.loop else local >= times[-1]
        speed = np.where(before | arrived, 0.0, np.maximum(v0s[i] + accs[i] * tau, 0.0))
        s = s0s[i] + v0s[i] * tau + 0.5 * accs[i] * tau**2
        ends = np.append(s0s[1:], self.length_m)
        s = np.clip(s, s0s[i], np.maximum(ends[i], s0s[i]))
        return laps, s, speed

    @cached_property
    def _kept(self) -> TimeMemo[list]:
        """Per time (s), its `_state_at` and, once asked for, its `_pose_at_distance` (None until then), the
        arrays read-only; the oldest forgotten beyond `STATE_MEMO_TIMES` (first in, first out)."""
        return TimeMemo(STATE_MEMO_TIMES)

    def _kept_at(self, time_s) -> list | None:
        """The kept [laps, distance, speed, pose] of a single time `time_s` (made when new); None for an array
        of times or −0.0 (a key equal to 0.0)."""
        if isinstance(time_s, np.ndarray) or not isinstance(time_s, (float, int, np.floating, np.integer)):
            return None
        key = float(time_s)
        if key == 0.0 and math.copysign(1.0, key) < 0:
            return None
        kept = self._kept.get(key)
        if kept is None:
            kept = self._kept.put(key, [*frozen(*self._state_at(time_s)), None])
        return kept

    def _state(self, time_s) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Laps (…), distance into the lap (…) m and speed (…) m/s at `time_s` (kept for a single time,
        read-only then: `_kept_at`)."""
        kept = self._kept_at(time_s)
        return self._state_at(time_s) if kept is None else (kept[0], kept[1], kept[2])

    def _pose_at(self, time_s) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """`_pose_at_distance` at the distance into the lap at `time_s` (kept for a single time, read-only)."""
        kept = self._kept_at(time_s)
        if kept is None:
            return self._pose_at_distance(self._state_at(time_s)[1])
        if kept[3] is None:
            kept[3] = frozen(*self._pose_at_distance(kept[1]))
        return kept[3]

    # --- the Route interface ---------------------------------------------------------------------------

    def at(self, time_s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Ground position (…, 2) m and heading (…) rad (counter-clockwise from +X, in (−π, π]) at `time_s` (…)."""
        point, heading, _ = self._pose_at(time_s)
        return _copy(point), _copy(heading)

    def speed_at(self, time_s: np.ndarray | float) -> np.ndarray:
        """Speed along the curve at `time_s` (…), m/s (0 before the start and while standing)."""
        return _copy(self._state(time_s)[2])

    def curvature_at(self, time_s: np.ndarray | float) -> np.ndarray:
        """Signed curvature of the path at `time_s` (…), 1/m (positive: turning left)."""
        return _copy(self._pose_at(time_s)[2])

    def steer_rad_at(self, time_s: np.ndarray | float) -> np.ndarray:
        """Front-wheel steering angle of the bicycle model at `time_s` (…), rad, positive left: atan(L·κ)."""
        return np.arctan(self.dynamics.wheelbase_m * self.curvature_at(time_s))

    def distance_at(self, time_s: np.ndarray | float) -> np.ndarray | float:
        """Distance driven by `time_s` (a float, or an array for an array) since the beginning, m
        (continuous, never falls)."""
        laps, s, _ = self._state(time_s)
        driven = laps * self.length_m + s
        return float(driven) if driven.ndim == 0 else driven

    def at_distance(self, distance_m: float | np.ndarray) -> np.ndarray:
        """Ground point (…, 2) m at a distance driven along the curve (a loop repeats; an open route stays
        at its ends)."""
        d = np.asarray(distance_m, dtype=np.float64)
        lap = self.length_m
        if lap == 0:
            return np.broadcast_to(self.waypoints_m[0], (*d.shape, 2)).copy()
        d = np.mod(d, lap) if self.loop else np.clip(d, 0.0, lap)
        return self._pose_at_distance(d)[0]

    def standing(self, time_s: float) -> tuple[float, float] | None:
        """(seconds since the vehicle stopped, seconds until it drives on) while it stands at `time_s` (inf
        where it never started or never leaves); None while it drives (passing a stop at speed 0 included)."""
        times, _, _, _, dwells = self._motion
        if not self.moves:
            return math.inf, math.inf
        since = time_s - self.start_s
        if since < 0:
            return math.inf, -since
        total = times[-1]
        if not self.loop and since >= total:
            return since - total, math.inf
        local = since % total if self.loop else since
        i = int(np.clip(np.searchsorted(times, local, side="right") - 1, 0, len(dwells) - 1))
        if not dwells[i]:
            return None
        return local - times[i], times[i + 1] - local

    def leg_pad_m(self, reach_m: float) -> float:
        """Margin, m, by which a footprint reaching `reach_m` from the route point must grow so that, slid
        along `legs_until`'s straight pieces, it contains the vehicle on the arcs they stand for: the
        arc's sagitta R·(1 − cos(Δ/2)) plus reach·Δ/2 (the heading differs from the chord's by ≤ Δ/2)."""
        _, _, _, curvatures, _, _ = self._path
        bent = curvatures[curvatures != 0]
        if len(bent) == 0:
            return 0.0
        radius = 1.0 / float(np.min(np.abs(bent)))
        half = LEG_ARC_STEP_RAD / 2
        return radius * (1 - math.cos(half)) + reach_m * half

    def legs_until(self, time_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Straight pieces along which the footprint, grown by `leg_pad_m`, covers the vehicle until `time_s`.

        Straights are themselves; an arc becomes chords turning ≤ `LEG_ARC_STEP_RAD` each, whole once
        begun. A loop contributes each piece once.

        Returns
        -------
        start_m : ndarray, shape (K, 2)
        heading_rad : ndarray, shape (K,)
        length_m : ndarray, shape (K,)
            How much of each piece is covered by `time_s`, m (0 for a vehicle that has not left).
        """
        distance, starts, headings, curvatures, _, first_heading = self._path
        if not self.moves:
            return self.waypoints_m[:1].copy(), np.array([first_heading]), np.zeros(1)
        laps, s, _ = self._state(time_s)
        reached = self.length_m if laps > 0 else float(s)
        out_start, out_heading, out_length = [], [], []
        for i in range(len(starts)):
            size = distance[i + 1] - distance[i]
            if curvatures[i] == 0:
                cuts = np.array([0.0, size])
            else:
                count = max(1, math.ceil(abs(curvatures[i]) * size / LEG_ARC_STEP_RAD))
                cuts = np.linspace(0.0, size, count + 1)
            ends = _advance(starts[i], headings[i], curvatures[i], cuts)
            for a, b, begin in zip(ends[:-1], ends[1:], distance[i] + cuts[:-1], strict=True):
                if begin >= reached and out_start:
                    break
                chord = b - a
                full = float(np.hypot(*chord))
                out_start.append(a)
                out_heading.append(math.atan2(chord[1], chord[0]))
                covered = full if curvatures[i] != 0 else min(max(reached - begin, 0.0), full)
                out_length.append(covered)
        return np.array(out_start), np.array(out_heading), np.array(out_length)


def _copy(value):
    """A writable copy of a kept array (a numpy scalar as it is), so a caller may change what it gets."""
    return value.copy() if isinstance(value, np.ndarray) else value


def _point(point_m: np.ndarray) -> str:
    return "[" + ", ".join(f"{float(c):g}" for c in point_m) + "]"


def _advance(start_m: np.ndarray, heading_rad, curvature, along_m) -> np.ndarray:
    """Point (…, 2) m after `along_m` (…) along a curve of constant `curvature` (…) 1/m from `start_m`
    (…, 2) with `heading_rad` (…): a straight where the curvature is 0, else a circular arc."""
    start = np.asarray(start_m, dtype=np.float64)
    psi = np.asarray(heading_rad, dtype=np.float64)
    kappa = np.asarray(curvature, dtype=np.float64)
    d = np.asarray(along_m, dtype=np.float64)
    turn = kappa * d
    # sin(x)/x and (1 − cos x)/x written to stay exact near x = 0.
    sinc = np.sinc(turn / (2 * np.pi))  # sin(turn/2)/(turn/2)
    chord = d * sinc
    mid = psi + turn / 2
    return start + np.stack([chord * np.cos(mid), chord * np.sin(mid)], axis=-1)
