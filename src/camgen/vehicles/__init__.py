"""Procedural vehicles as pure geometry: cars (sedan, hatchback, estate, SUV, pickup), vans, box
trucks, buses, bicycles and motorcycles.

`vehicle_rig` turns a scene's car, truck, bus, bicycle or motorcycle actor without a shape into what
the renderer draws and the annotations read: a `VehicleModel` (`camgen.vehicles.body`: shell, glass,
cabin and driver (`camgen.vehicles.cabin`), wheels, lamps, plates) of a `VehicleLook` drawn from the
actor's identity seed (`camgen.vehicles.look`), posed along its route at any time — the wheels turned
by the distance travelled (angle = distance / wheel radius) and the front wheels steered by the route's
steering angle where the route has one (`steer_rad_at`; straight ahead otherwise). A two-wheeler
(`camgen.vehicles.two_wheeler`, `TwoWheelerRig`) leans into turns by the balance angle, turns its fork
and handlebar about its raked steering axis and a bicycle its crank and pedals with the rear wheel
through its gearing; it tells its rider (`camgen.actors.riding`) where the seat, the grips and the
pedals or footpegs are at any time. Nothing here touches OpenGL or files.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from camgen.config.scene import Actor, Scene, is_procedural_vehicle
from camgen.motion.memo import TimeMemo, frozen
from camgen.motion.trajectory import Route
from camgen.vehicles.body import Part, VehicleModel, build_vehicle
from camgen.vehicles.headlamps import HEADLAMP_AHEAD_M, AutoHeadlamps, daylight_horizontal_lux, lit_at
from camgen.vehicles.look import TWO_WHEELERS, VehicleLook, draw_look
from camgen.vehicles.plate import motorcycle_plate_image, plate_image
from camgen.vehicles.two_wheeler import (
    CRANK,
    CRANK_M,
    DEFAULT_SADDLE_M,
    FRONT,
    PEDAL_LEFT,
    PEDAL_RIGHT,
    PEDAL_TOP_M,
    PEDAL_Y_M,
    REAR,
    STEERING,
    TwoWheelerModel,
    build_bicycle,
    build_motorcycle,
    chain_ratio,
    saddle_height_for,
)

VEHICLE_SPAWN_KEY = 0x7665_6869
"""First spawn key of an identity seed derived from the scene's seed (ASCII "vehi")."""

LAMP_LUMINANCE_CD_M2 = {
    "head": 20_000.0,
    "tail": 600.0,
    "brake": 5_000.0,
    "indicator": 4_000.0,
    "cycle_head": 7_500.0,
    "cycle_tail": 2_500.0,
}
"""Luminance of a lit lamp's lens as a camera off its axis sees it, cd/m²: a low beam's 10–20 kcd
peak (UN ECE R112) falls to a few hundred cd away from the beam over its ~0.02 m² lens; a rear
position lamp gives 4–17 cd, a stop lamp 60–185 cd and a rear indicator 50–350 cd (UN ECE R7 and
R6) over 0.02–0.04 m². A bicycle's lamps (the Road Vehicles Lighting Regulations 1989, as amended in
2005: a white front and a red rear lamp when ridden between sunset and sunrise, a flashing one of at
least 4 cd): about 10 cd over the front lamp's 13.5 cm² lens and 4 cd over the rear lamp's 17.5 cm²
(estimates at the regulations' minimum; LED cycle lamps are often brighter on their axis). A bus's LED
destination display has no fixed luminance: it dims with the illuminance at the bus
(`camgen.vehicles.sign.display_luminance_cd_m2`)."""
LAMP_COLOUR_RGB = {
    "head": (1.0, 1.0, 1.0),
    "tail": (4.7, 0.0, 0.0),
    "brake": (4.7, 0.0, 0.0),
    "indicator": (1.6, 0.75, 0.0),
    "cycle_head": (1.0, 1.0, 1.0),
    "cycle_tail": (4.7, 0.0, 0.0),
    "destination": (1.6, 0.75, 0.0),
}
"""Linear colour of each lamp's light scaled to unit luminance (Y = 0.2126 R + 0.7152 G + 0.0722 B):
white, red (ECE R48's red: sRGB red) and amber."""
INDICATOR_HZ = 1.5
"""Indicator flashes per second (UN ECE R48: 90 ± 30 per minute), lit half of each period."""
INDICATOR_STEER_RAD = 0.05
"""Steering angle beyond which the indicator of that side flashes, rad."""
GRAVITY_M_S2 = 9.80665
ROLL_WINDOW_S = 0.6
"""A two-wheeler's lean is the balance angle averaged over this window centred on the time (`lean_rad`):
a rider rolls into a turn over about half a second (Cossalter, *Motorcycle Dynamics*, 2006, ch. 7: roll
rates of 20–60°/s when entering a bend), where the route's curvature steps at an arc's ends."""
ROLL_SAMPLES = 7


def identity_seed(actor: Actor, *, scene_seed: int, actor_index: int) -> int:
    """The vehicle's identity seed: its own, or one derived from the scene's seed and its index."""
    if actor.vehicle is not None and actor.vehicle.seed is not None:
        return actor.vehicle.seed
    sequence = np.random.SeedSequence(scene_seed, spawn_key=(VEHICLE_SPAWN_KEY, actor_index))
    return int(sequence.generate_state(1, dtype=np.uint32)[0])


def vehicle_look(actor: Actor, *, scene_seed: int, actor_index: int) -> VehicleLook:
    block = actor.vehicle
    return draw_look(
        identity_seed(actor, scene_seed=scene_seed, actor_index=actor_index),
        actor.cls,
        pinned=block.pinned() if block is not None else None,
    )


@lru_cache(maxsize=64)
def _model(look: VehicleLook, driver: bool = False) -> VehicleModel:
    return build_vehicle(look, driver=driver)


def has_driver(actor: Actor, route: Route) -> bool:
    """Whether a car, truck or bus actor has a driver at its wheel: as its `vehicle.driver` says, else
    when its route moves it (a parked vehicle is empty)."""
    block = actor.vehicle
    if block is not None and block.driver is not None:
        return block.driver
    return bool(route.moves)


def wheel_spin_rad(distance_m: float, wheel_radius_m: float) -> float:
    """How far a wheel rolling without slip has turned after `distance_m`, rad (about its axle, +y:
    forward travel turns the top of the wheel forward)."""
    return distance_m / wheel_radius_m


def ackermann_rad(steer_rad: float, wheelbase_m: float, track_m: float) -> tuple[float, float]:
    """(left, right) front-wheel angles for a bicycle-model steering angle `steer_rad` (positive turns
    left): each wheel aims at the turn's centre on the rear axle's line (Ackermann geometry), so
    the inner wheel turns more: tan δ = wheelbase / (R ∓ track/2), R = wheelbase / tan δ."""
    if abs(steer_rad) < 1e-9:
        return 0.0, 0.0
    radius = wheelbase_m / math.tan(steer_rad)
    return math.atan(wheelbase_m / (radius - track_m / 2)), math.atan(wheelbase_m / (radius + track_m / 2))


def _rot_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rot_x(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rot_y(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


class VehicleRig:
    """A vehicle's model and route, and its posed state at the last `place` time.

    After `place`: `vertices_m` and `normals` hold every part's vertices in the world, one slice of
    them per part (`parts`, in the model's order), `T_world_from_vehicle` its frame (read-only: a pose is
    kept for its time, `pose`), and `lit` which lamps shine.

    `lights_on`: True or False, or a function of the time (`camgen.vehicles.headlamps.AutoHeadlamps`)."""

    keypoints_m = None
    """Vehicles carry no skeleton (the annotations read keypoints of people only)."""

    def __init__(self, model: VehicleModel, route: Route, *, lights_on: bool | Callable[[float], bool] = False):
        self.model, self.route, self.lights_on = model, route, lights_on
        sizes = [len(part.vertices_m) for part in model.parts]
        ends = np.cumsum(sizes)
        self.parts = [slice(int(e - n), int(e)) for n, e in zip(sizes, ends, strict=True)]
        self._rest = np.concatenate([part.vertices_m for part in model.parts])
        self._rest_normals = np.concatenate([part.normals for part in model.parts])
        self._wheel = np.concatenate([part.wheel for part in model.parts]).astype(np.int64)
        self._bone = self._wheel + 1
        """Each vertex's row of the transforms `place` builds: 0 the body's, 1 + b bone (wheel) b's."""
        starts = np.flatnonzero(np.diff(self._bone, prepend=-1))
        ends = [*starts[1:], len(self._bone)]
        self._runs = [(slice(int(i), int(j)), int(self._bone[i])) for i, j in zip(starts, ends, strict=True)]
        """The vertices in runs of one bone each (the body's, each wheel's or other bone's): a few tens."""
        self._turned: tuple[list[bytes], np.ndarray, np.ndarray] | None = None
        """(each bone's rotation as bytes, the rest vertices and normals turned by them), kept from the last
        placement: the runs of a bone whose rotation holds (the body's on a straight) are not turned again."""
        self._state: tuple | None = None
        signs = [piece for part, piece in zip(model.parts, self.parts, strict=True) if part.surface == "destination"]
        self._sign = signs[0] if signs else None
        self._boxed = np.concatenate([np.full(len(part.vertices_m), part.surface != "shade") for part in model.parts])
        self.lit: dict[str, bool] = {}
        self._poses: TimeMemo[tuple] = TimeMemo()
        self.place(0.0)

    @property
    def look(self) -> VehicleLook:
        return self.model.look

    def steer_rad(self, time_s: float) -> float:
        """The bicycle-model steering angle at `time_s`, rad, positive to the left: atan(wheelbase ×
        curvature) of this vehicle's own wheelbase where the route gives its curvature, else the route's
        `steer_rad_at`, else 0 (a route of straight legs)."""
        curvature = getattr(self.route, "curvature_at", None)
        if curvature is not None:
            return math.atan(self.look.wheelbase_m * float(curvature(time_s)))
        steer = getattr(self.route, "steer_rad_at", None)
        return 0.0 if steer is None else float(steer(time_s))

    def pose(self, time_s: float) -> tuple[np.ndarray, np.ndarray]:
        """(T_world_from_vehicle (4, 4), T_vehicle_from_bone (B, 4, 4)) at `time_s`, read-only: a pure function
        of the time, kept for it (`TimeMemo`) with the lamps (`place` and the rider ask for the same times)."""
        T, bones, _, _ = self._posed(time_s)
        return T, bones

    def _posed(self, time_s: float) -> tuple[np.ndarray, np.ndarray, dict[str, bool], tuple[bytes, bytes]]:
        """(T_world_from_vehicle, T_vehicle_from_bone, lamps, the two as bytes) at `time_s`: the pose kept for
        the time with its steering angle, the lamps worked out each call (they follow `lights_on` too, which
        a caller may change between two calls at one time)."""
        kept = self._poses.get(time_s)
        if kept is None:
            steering = self.steer_rad(time_s)  # the pose's and the indicators' (one look-up on the route)
            T, bones = frozen(*self._pose_at(time_s, steering))
            kept = self._poses.put(time_s, (T, bones, steering, (T.tobytes(), bones.tobytes())))
        T, bones, steering, as_bytes = kept
        return T, bones, self._lamps_at(time_s, steering), as_bytes

    def _pose_at(self, time_s: float, steering_rad: float) -> tuple[np.ndarray, np.ndarray]:
        """(T_world_from_vehicle (4, 4), T_vehicle_from_wheel (4, 4, 4)) at `time_s`, the front wheels steered
        `steering_rad` (`steer_rad` at that time). The route's point is the rear axle's middle (the kinematic
        bicycle model's reference point, `camgen.motion.vehicle_route`); the vehicle's frame is centred on its
        footprint ahead of it."""
        xy, heading = self.route.at(time_s)
        look = self.look
        T = np.eye(4)
        T[:3, :3] = _rot_z(float(heading))
        T[:2, 3] = np.asarray(xy, dtype=np.float64) - look.rear_axle_x_m * T[:2, 0]
        spin = _rot_y(wheel_spin_rad(self.route.distance_at(time_s), look.wheel_radius_m))
        left, right = ackermann_rad(steering_rad, look.wheelbase_m, look.track_m)
        wheels = np.tile(np.eye(4), (4, 1, 1))
        for w, steer in enumerate((left, right, 0.0, 0.0)):
            wheels[w, :3, :3] = _rot_z(steer) @ spin
            wheels[w, :3, 3] = self.model.wheel_centres_m[w]
        return T, wheels

    def place(self, time_s: float) -> bool:
        """Pose the vehicle at `time_s`; whether anything drawn changed since the last call."""
        T, wheels, lit, state = self._posed(time_s)
        self.T_world_from_vehicle = T
        moved = state != self._state
        changed = moved or lit != self.lit
        self.lit = dict(lit)
        if not moved:
            return changed
        self._state = state
        # Each vertex's transform to the world: the body's, or the body's after its wheel's (bone's).
        M = np.empty((len(wheels) + 1, 4, 4))
        M[0] = T
        M[1:] = T @ wheels
        turned, normals = self._turn(M)
        self.vertices_m = np.empty_like(turned)
        for rows, bone in self._runs:
            np.add(turned[rows], M[bone, :3, 3], out=self.vertices_m[rows])
        self.normals = normals.copy()
        return True

    def _turn(self, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The rest vertices and normals turned by their bone's rotation in `M` (B + 1, 4, 4; the body's first),
        kept for the next placement: only the runs of a bone whose rotation changed are turned again, each row
        by the product of its own matrix and vector (the rows kept are what turning them all again would give,
        bit for bit)."""
        keys = [M[b, :3, :3].tobytes() for b in range(len(M))]
        if self._turned is None or len(self._turned[0]) != len(keys):
            turned, normals = np.empty_like(self._rest), np.empty_like(self._rest_normals)
            stale = [True] * len(keys)
        else:
            kept, turned, normals = self._turned
            stale = [key != before for key, before in zip(keys, kept, strict=True)]
        self._turned = (keys, turned, normals)
        changed = [rows for rows, bone in self._runs if stale[bone]]
        while changed:  # each stretch of consecutive changed runs in one product
            first = changed.pop(0)
            stop = first.stop
            while changed and changed[0].start == stop:
                stop = changed.pop(0).stop
            rows = slice(first.start, stop)
            chosen = np.take(M, self._bone[rows], axis=0)
            turned[rows] = np.einsum("vij,vj->vi", chosen[:, :3, :3], self._rest[rows])
            normals[rows] = np.einsum("vij,vj->vi", chosen[:, :3, :3], self._rest_normals[rows])
        return turned, normals

    def lamps(self, time_s: float) -> dict[str, bool]:
        """Which lamps shine at `time_s`: head and tail lamps when the scene turns them on; brake
        lamps while a vehicle that drives stands at a stop; an indicator flashes on the side the
        front wheels turn to; a bus's destination display always."""
        return self._lamps_at(time_s, self.steer_rad(time_s))

    def _lamps_at(self, time_s: float, steering_rad: float) -> dict[str, bool]:
        """`lamps` at `time_s`, the front wheels steered `steering_rad` (`steer_rad` at that time)."""
        standing = self.route.standing(time_s) if self.route.moves else None
        flash = (time_s * INDICATOR_HZ) % 1.0 < 0.5
        lit = lit_at(self.lights_on, time_s)
        return {
            "head": lit,
            "tail": lit,
            "brake": standing is not None and math.isfinite(standing[1]),
            "indicator_left": bool(steering_rad > INDICATOR_STEER_RAD and flash),
            "indicator_right": bool(steering_rad < -INDICATOR_STEER_RAD and flash),
            "destination": self._sign is not None,  # a bus in service shows its route (`camgen.vehicles.sign`)
        }

    @property
    def headlamp(self) -> tuple[np.ndarray, int] | None:
        """(point (3,) in the vehicle's frame, m; how many lamps) of the light its lit low beams cast
        (`camgen.vehicles.headlamps`): midway between the head lamps' lenses, `HEADLAMP_AHEAD_M` ahead of
        them; None for a vehicle without head lamps (a bicycle's lamp glows only)."""
        heads = [part for part in self.model.parts if part.surface == "head"]
        if not heads:
            return None
        vertices = np.concatenate([part.vertices_m for part in heads])
        centre = (vertices.min(axis=0) + vertices.max(axis=0)) / 2
        centre[0] = vertices[:, 0].max() + HEADLAMP_AHEAD_M
        return centre, 1 if self.look.body_type == "motorcycle" else 2

    @property
    def sign_centre_m(self) -> np.ndarray | None:
        """(3,) world point in the middle of the posed destination display's lit dots, m (where its light
        sensor reads the ambient light, `camgen.vehicles.sign.display_luminance_cd_m2`); None without one."""
        if self._sign is None:
            return None
        dots = self.vertices_m[self._sign]
        return (dots.min(axis=0) + dots.max(axis=0)) / 2

    @property
    def box_vertices_m(self) -> np.ndarray:
        """The posed vertices that bound the vehicle in an image: all but the shaded ground under it
        (`camgen.vehicles.body.ground_shade`), which shows below a bumper seen from behind but is not the
        vehicle."""
        return self.vertices_m[self._boxed]

    def heading_box(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(low (3,), high (3,), T_world_from_box (4, 4)): the box around the posed vehicle in its own
        frame (wheels steered and turned included)."""
        T = self.T_world_from_vehicle
        local = (self.vertices_m - T[:3, 3]) @ T[:3, :3]
        # each axis reduced on its own: the same values, ~20× faster than over axis 0 of (N, 3) (50k: 2.7 ms)
        low = np.array([local[:, axis].min() for axis in range(3)])
        high = np.array([local[:, axis].max() for axis in range(3)])
        return low, high, T

    def plate_corners_world(self) -> dict[str, np.ndarray]:
        """ "front" / "rear" → (4, 3) corners of each plate in the world (top left, top right, bottom
        right, bottom left as one reads it)."""
        T = self.T_world_from_vehicle
        return {side: quad @ T[:3, :3].T + T[:3, 3] for side, quad in self.model.plate_corners_m.items()}


def handlebar_rad(steer_rad: float, rake_rad: float) -> float:
    """How far a two-wheeler's handlebar turns about its steering axis, raked `rake_rad` from the
    vertical, for the kinematic steering angle `steer_rad` on the ground: tan δ = tan θ · cos(rake)
    (the front wheel's plane turned by θ about the tilted axis, seen from above; Cossalter, *Motorcycle
    Dynamics*, 2006, §1.3, neglecting the roll a rider leans into a turn)."""
    return math.atan2(math.tan(steer_rad), math.cos(rake_rad))


def _rotation_about(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' rotation matrix about the unit `axis`."""
    x, y, z = axis
    K = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def _translation(offset: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = offset
    return T


class TwoWheelerRig(VehicleRig):
    """A bicycle or motorcycle driving its route: its bones (front and rear wheel, steering, and a
    bicycle's crank and pedals) posed at any time, and where its rider's hands, feet and seat go."""

    model: TwoWheelerModel

    def crank_rad(self, time_s: float) -> float:
        """The bicycle's crank angle at `time_s`, rad: the rear wheel's turn over the gearing (0 with
        the right crank forward and level; growing as the pedals are pushed forward over the top)."""
        spin = wheel_spin_rad(self.route.distance_at(time_s), self.look.wheel_radius_m)
        return spin / chain_ratio(self.look)

    def lean_rad(self, time_s: float) -> float:
        """The roll angle at `time_s`, rad, positive leaning left (into a left turn): the steady-turn
        balance angle φ = atan(v² κ / g) of the route's speed v and curvature κ (Cossalter, *Motorcycle
        Dynamics*, 2006, §4.1, thin tyres: gravity and the centrifugal force resultant through the
        contact line), averaged over `ROLL_WINDOW_S` centred on the time; 0 on a route without speeds
        and curvatures (straight legs)."""
        speed = getattr(self.route, "speed_at", None)
        curvature = getattr(self.route, "curvature_at", None)
        if speed is None or curvature is None:
            return 0.0
        times = time_s + ROLL_WINDOW_S * np.linspace(-0.5, 0.5, ROLL_SAMPLES)
        v, kappa = np.asarray(speed(times), np.float64), np.asarray(curvature(times), np.float64)
        return float(np.mean(np.arctan(v**2 * kappa / GRAVITY_M_S2)))

    def _pose_at(self, time_s: float, steering_rad: float) -> tuple[np.ndarray, np.ndarray]:
        """(T_world_from_vehicle (4, 4), T_vehicle_from_bone (B, 4, 4)) at `time_s`, steered `steering_rad`
        (`steer_rad` at that time), bones as `camgen.vehicles.two_wheeler.BONES` (a motorcycle has the first
        three). The vehicle rolls by `lean_rad` about its contact line (its frame's x axis, on the ground)."""
        xy, heading = self.route.at(time_s)
        look, model = self.look, self.model
        T = np.eye(4)
        T[:3, :3] = _rot_z(float(heading)) @ _rot_x(-self.lean_rad(time_s))
        T[:2, 3] = np.asarray(xy, dtype=np.float64) - look.rear_axle_x_m * T[:2, 0]
        spin = _rot_y(wheel_spin_rad(self.route.distance_at(time_s), look.wheel_radius_m))
        steer = np.eye(4)  # about the steering axis through the head tube
        steer[:3, :3] = _rotation_about(model.steer_axis, handlebar_rad(steering_rad, model.rake_rad))
        steer[:3, 3] = model.steer_point_m - steer[:3, :3] @ model.steer_point_m
        bones = np.tile(np.eye(4), (3 if model.bottom_bracket_m is None else 6, 1, 1))
        front, rear = model.wheel_centres_m
        bones[FRONT] = steer @ _translation(front)
        bones[FRONT, :3, :3] = bones[FRONT, :3, :3] @ spin
        bones[REAR, :3, :3], bones[REAR, :3, 3] = spin, rear
        bones[STEERING] = steer
        if model.bottom_bracket_m is not None:
            crank = self.crank_rad(time_s)
            bones[CRANK, :3, :3], bones[CRANK, :3, 3] = _rot_y(crank), model.bottom_bracket_m
            for bone, angle, side in ((PEDAL_RIGHT, crank, -1), (PEDAL_LEFT, crank + math.pi, 1)):
                bones[bone, :3, 3] = model.bottom_bracket_m + _rot_y(angle) @ (CRANK_M, 0.0, 0.0)
                bones[bone, 1, 3] += side * PEDAL_Y_M
        return T, bones

    def _lamps_at(self, time_s: float, steering_rad: float) -> dict[str, bool]:
        """A motorcycle's head, tail and brake lamps as a car's (no indicators); a bicycle's front and
        rear lamps when its lights are on."""
        lit = super()._lamps_at(time_s, steering_rad)
        lit = {key: value for key, value in lit.items() if not key.startswith("indicator")}
        return lit | {"cycle_head": lit["head"], "cycle_tail": lit["head"]}

    def rider_targets(self, time_s: float) -> RiderTargets:
        """Where the rider's body meets the two-wheeler at `time_s`, in the world."""
        T, bones = self.pose(time_s)
        model = self.model

        def world(points: np.ndarray, M: np.ndarray) -> np.ndarray:
            A = T @ M
            return points @ A[:3, :3].T + A[:3, 3]

        grips = world(model.grips_m, bones[STEERING])
        if model.bottom_bracket_m is not None:
            top = np.array([0.0, 0.0, PEDAL_TOP_M])
            feet = np.array([world(top, bones[PEDAL_LEFT]), world(top, bones[PEDAL_RIGHT])])
        else:
            feet = world(model.pegs_m, np.eye(4))
        return RiderTargets(T, world(model.seat_m, np.eye(4)), grips, feet)


@dataclass(frozen=True)
class RiderTargets:
    """Where a rider sits, holds and stands on a two-wheeler at one time, world coordinates, m."""

    T_world_from_vehicle: np.ndarray
    """(4, 4) the vehicle's frame (x forward, z up)."""
    seat_m: np.ndarray
    """(3,) where the sitting bones rest."""
    grips_m: np.ndarray
    """(2, 3) the handlebar's grips, left then right."""
    feet_m: np.ndarray
    """(2, 3) the tread of the left and right pedal, or the footpegs, where the ball of each foot rests."""


@lru_cache(maxsize=64)
def _two_wheeler(look: VehicleLook, saddle_mm: int) -> TwoWheelerModel:
    return build_bicycle(look, saddle_mm / 1000) if look.body_type == "bicycle" else build_motorcycle(look)


def saddle_for_rider(joints_m: np.ndarray, joint_index: dict[str, int]) -> float:
    """The saddle height (m up the seat tube from the bottom bracket) that fits a rider of these rest
    joints (`camgen.actors.skeleton.JOINTS` order, `joint_index` their rows)."""
    J, i = joints_m, joint_index
    thigh = float(np.linalg.norm(J[i["calf_l"]] - J[i["thigh_l"]]))
    shin = float(np.linalg.norm(J[i["foot_l"]] - J[i["calf_l"]]))
    behind = J[i["foot_l"], 0] - J[i["ball_l"], 0]  # the rest foot stands level on its sole at z = 0
    return saddle_height_for(thigh, shin, np.array([behind, J[i["foot_l"], 2]]), float(abs(J[i["thigh_l"], 1])))


def vehicle_rig(
    actor: Actor,
    route: Route,
    *,
    scene_seed: int,
    actor_index: int,
    saddle_m: float | None = None,
    daylight_lux: Callable[[float], float] | None = None,
) -> VehicleRig:
    """The procedural vehicle of a car, truck, bus, bicycle or motorcycle actor without a shape, driving
    its route; `saddle_m`: a bicycle's saddle height for its rider (`saddle_for_rider`); `daylight_lux`:
    the scene's daylight on the ground over time (`camgen.vehicles.headlamps.daylight_horizontal_lux`), which
    switches `auto` lamps (none given: `auto` lamps stay dark)."""
    look = vehicle_look(actor, scene_seed=scene_seed, actor_index=actor_index)
    switch = "auto" if actor.vehicle is None else actor.vehicle.lights_on
    lights_on: bool | Callable[[float], bool] = switch
    if switch == "auto":
        driven = route.moves if look.body_type in TWO_WHEELERS else has_driver(actor, route)
        lights_on = AutoHeadlamps(daylight_lux, driven) if daylight_lux is not None else False
    if look.body_type in TWO_WHEELERS:
        saddle_mm = round(1000 * (DEFAULT_SADDLE_M if saddle_m is None else saddle_m))
        return TwoWheelerRig(_two_wheeler(look, saddle_mm), route, lights_on=lights_on)
    return VehicleRig(_model(look, has_driver(actor, route)), route, lights_on=lights_on)


def vehicle_rigs(scene: Scene, routes: dict[str, Route]) -> dict[str, VehicleRig]:
    """Actor name → the procedural vehicle of every such actor of `scene`; a ridden bicycle's saddle is
    set for its rider (`camgen.config.scene.Actor.rides`)."""
    from camgen.actors import person_model  # the riders' bodies
    from camgen.actors.skeleton import INDEX

    riders = {actor.rides: (index, actor) for index, actor in enumerate(scene.actors) if actor.rides is not None}
    daylight = daylight_horizontal_lux(scene)
    rigs = {}
    for index, actor in enumerate(scene.actors):
        if not is_procedural_vehicle(actor):
            continue
        saddle = None
        if actor.name in riders and actor.cls == "bicycle":
            rider_index, rider = riders[actor.name]
            model = person_model(rider, scene_seed=scene.seed, actor_index=rider_index)
            saddle = saddle_for_rider(model.joints_m, INDEX)
        rigs[actor.name] = vehicle_rig(
            actor, routes[actor.name], scene_seed=scene.seed, actor_index=index, saddle_m=saddle, daylight_lux=daylight
        )
    return rigs


def plate_texture(look: VehicleLook) -> np.ndarray:
    """The linear albedo image of a vehicle's `plates` part: a car's front plate over its rear plate, or
    a motorcycle's one two-line rear plate."""
    if look.body_type == "motorcycle":
        return motorcycle_plate_image(look.plate_text)
    return np.concatenate([plate_image(look.plate_text, rear=rear) for rear in (False, True)])


__all__ = [
    "LAMP_COLOUR_RGB",
    "LAMP_LUMINANCE_CD_M2",
    "Part",
    "RiderTargets",
    "TwoWheelerRig",
    "VehicleLook",
    "VehicleModel",
    "VehicleRig",
    "ackermann_rad",
    "handlebar_rad",
    "has_driver",
    "identity_seed",
    "plate_texture",
    "saddle_for_rider",
    "vehicle_look",
    "vehicle_rig",
    "vehicle_rigs",
    "wheel_spin_rad",
]
