"""Procedural vehicles as pure geometry: cars (sedan, hatchback, estate, SUV, pickup), vans, box
trucks and buses.

`vehicle_rig` turns a scene's car, truck or bus actor without a shape into what the renderer draws
and the annotations read: a `VehicleModel` (`camgen.vehicles.body`: shell, glass, wheels, lamps,
plates) of a `VehicleLook` drawn from the actor's identity seed (`camgen.vehicles.look`), posed along
its route at any time — the wheels turned by the distance travelled (angle = distance / wheel
radius) and the front wheels steered by the route's steering angle where the route has one
(`steer_rad_at`; straight ahead otherwise). Nothing here touches OpenGL or files.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from camgen.config.scene import Actor
from camgen.motion.trajectory import Route
from camgen.vehicles.body import Part, VehicleModel, build_vehicle
from camgen.vehicles.look import VehicleLook, draw_look

VEHICLE_SPAWN_KEY = 0x7665_6869
"""First spawn key of an identity seed derived from the scene's seed (ASCII "vehi")."""

LAMP_LUMINANCE_CD_M2 = {"head": 20_000.0, "tail": 600.0, "brake": 5_000.0, "indicator": 4_000.0}
"""Luminance of a lit lamp's lens as a camera off its axis sees it, cd/m²: a low beam's 10–20 kcd
peak (UN ECE R112) falls to a few hundred cd away from the beam over its ~0.02 m² lens; a rear
position lamp gives 4–17 cd, a stop lamp 60–185 cd and a rear indicator 50–350 cd (UN ECE R7 and
R6) over 0.02–0.04 m²."""
LAMP_COLOUR_RGB = {
    "head": (1.0, 1.0, 1.0),
    "tail": (4.7, 0.0, 0.0),
    "brake": (4.7, 0.0, 0.0),
    "indicator": (1.6, 0.75, 0.0),
}
"""Linear colour of each lamp's light scaled to unit luminance (Y = 0.2126 R + 0.7152 G + 0.0722 B):
white, red (ECE R48's red: sRGB red) and amber."""
INDICATOR_HZ = 1.5
"""Indicator flashes per second (UN ECE R48: 90 ± 30 per minute), lit half of each period."""
INDICATOR_STEER_RAD = 0.05
"""Steering angle beyond which the indicator of that side flashes, rad."""


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
def _model(look: VehicleLook) -> VehicleModel:
    return build_vehicle(look)


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


def _rot_y(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


class VehicleRig:
    """A vehicle's model and route, and its posed state at the last `place` time.

    After `place`: `vertices_m` and `normals` hold every part's vertices in the world, one slice of
    them per part (`parts`, in the model's order), and `lit` which lamps shine."""

    keypoints_m = None
    """Vehicles carry no skeleton (the annotations read keypoints of people only)."""

    def __init__(self, model: VehicleModel, route: Route, *, lights_on: bool = False):
        self.model, self.route, self.lights_on = model, route, lights_on
        sizes = [len(part.vertices_m) for part in model.parts]
        ends = np.cumsum(sizes)
        self.parts = [slice(int(e - n), int(e)) for n, e in zip(sizes, ends, strict=True)]
        self._rest = np.concatenate([part.vertices_m for part in model.parts])
        self._rest_normals = np.concatenate([part.normals for part in model.parts])
        self._wheel = np.concatenate([part.wheel for part in model.parts]).astype(np.int64)
        self._state: tuple | None = None
        self.lit: dict[str, bool] = {}
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
        """(T_world_from_vehicle (4, 4), T_vehicle_from_wheel (4, 4, 4)) at `time_s`. The route's point
        is the rear axle's middle (the kinematic bicycle model's reference point,
        `camgen.motion.vehicle_route`); the vehicle's frame is centred on its footprint ahead of it."""
        xy, heading = self.route.at(time_s)
        look = self.look
        T = np.eye(4)
        T[:3, :3] = _rot_z(float(heading))
        T[:2, 3] = np.asarray(xy, dtype=np.float64) - look.rear_axle_x_m * T[:2, 0]
        spin = _rot_y(wheel_spin_rad(self.route.distance_at(time_s), look.wheel_radius_m))
        left, right = ackermann_rad(self.steer_rad(time_s), look.wheelbase_m, look.track_m)
        wheels = np.tile(np.eye(4), (4, 1, 1))
        for w, steer in enumerate((left, right, 0.0, 0.0)):
            wheels[w, :3, :3] = _rot_z(steer) @ spin
            wheels[w, :3, 3] = self.model.wheel_centres_m[w]
        return T, wheels

    def place(self, time_s: float) -> bool:
        """Pose the vehicle at `time_s`; whether anything drawn changed since the last call."""
        T, wheels = self.pose(time_s)
        self.T_world_from_vehicle = T
        lit = self.lamps(time_s)
        state = (T.tobytes(), wheels.tobytes())
        moved = state != self._state
        changed = moved or lit != self.lit
        self.lit = lit
        if not moved:
            return changed
        self._state = state
        # Each vertex's transform to the world: the body's, or the body's after its wheel's.
        M = np.empty((5, 4, 4))
        M[0] = T
        M[1:] = T @ wheels
        chosen = M[self._wheel + 1]
        self.vertices_m = np.einsum("vij,vj->vi", chosen[:, :3, :3], self._rest) + chosen[:, :3, 3]
        self.normals = np.einsum("vij,vj->vi", chosen[:, :3, :3], self._rest_normals)
        return True

    def lamps(self, time_s: float) -> dict[str, bool]:
        """Which lamps shine at `time_s`: head and tail lamps when the scene turns them on; brake
        lamps while a vehicle that drives stands at a stop; an indicator flashes on the side the
        front wheels turn to."""
        standing = self.route.standing(time_s) if self.route.moves else None
        steer = self.steer_rad(time_s)
        flash = (time_s * INDICATOR_HZ) % 1.0 < 0.5
        return {
            "head": self.lights_on,
            "tail": self.lights_on,
            "brake": standing is not None and math.isfinite(standing[1]),
            "indicator_left": bool(steer > INDICATOR_STEER_RAD and flash),
            "indicator_right": bool(steer < -INDICATOR_STEER_RAD and flash),
        }

    def heading_box(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(low (3,), high (3,), T_world_from_box (4, 4)): the box around the posed vehicle in its own
        frame (wheels steered and turned included)."""
        T = self.T_world_from_vehicle
        local = (self.vertices_m - T[:3, 3]) @ T[:3, :3]
        return local.min(axis=0), local.max(axis=0), T

    def plate_corners_world(self) -> dict[str, np.ndarray]:
        """ "front" / "rear" → (4, 3) corners of each plate in the world (top left, top right, bottom
        right, bottom left as one reads it)."""
        T = self.T_world_from_vehicle
        return {side: quad @ T[:3, :3].T + T[:3, 3] for side, quad in self.model.plate_corners_m.items()}


def vehicle_rig(actor: Actor, route: Route, *, scene_seed: int, actor_index: int) -> VehicleRig:
    """The procedural vehicle of a car, truck or bus actor without a shape, driving its route."""
    look = vehicle_look(actor, scene_seed=scene_seed, actor_index=actor_index)
    lights_on = actor.vehicle is not None and actor.vehicle.lights_on
    return VehicleRig(_model(look), route, lights_on=lights_on)


__all__ = [
    "LAMP_COLOUR_RGB",
    "LAMP_LUMINANCE_CD_M2",
    "Part",
    "VehicleLook",
    "VehicleModel",
    "VehicleRig",
    "ackermann_rad",
    "identity_seed",
    "vehicle_look",
    "vehicle_rig",
    "wheel_spin_rad",
]
