"""Actor trajectories: constant speed along straight segments between ground waypoints, with pauses.

Every actor, whether it follows waypoints (`ActorPath`) or wanders (`RandomWalk`), is resolved once
into a `Route`: waypoints, a dwell at each one, a speed, a start time and whether it loops. A route is
a pure function of time; it never jumps (its position is continuous in time) and never moves faster
than its speed. A vehicle's path (`drives`) becomes a `camgen.motion.vehicle_route.VehicleRoute`
instead, which offers the same interface: corners rounded by its turning circle, speed eased into
turns and stops.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from camgen.config.scene import VEHICLE_CLASSES, Actor, ActorPath, RandomWalk, Scene
from camgen.errors import ConfigError, Problem
from camgen.motion.route_fields import freeze_route_fields
from camgen.motion.vehicle_route import VEHICLE_DYNAMICS, RouteTooTightError, VehicleRoute

RANDOM_WALK_SPAWN_KEY = 0x7761_6C6B
"""First spawn key of the seed sequence a random walk draws from when it gives no seed of its own
(``SeedSequence(scene_seed, spawn_key=(RANDOM_WALK_SPAWN_KEY, actor_index))``); the ASCII of "walk",
far above any camera index, so it never meets the per-frame keys ``(camera_index, frame_index)``."""

ROUTE_MARGIN_S = 1.0
"""Time a resolved random walk covers beyond the scene's end, s: motion blur samples the scene slightly
after the last frame (one frame period at most, if that is longer)."""

EDGE_TOLERANCE_M = 1e-9
"""A random walker this close to an edge of its region stands on it, m."""


@dataclass(frozen=True, eq=False)
class Route:
    """Where an actor is at any time: straight legs at constant speed, a dwell at each waypoint.

    Until `start_s` the actor stands at the first waypoint. It then walks to each waypoint in turn and
    stands there for its pause before it leaves. Without `loop` it stops at the last waypoint for good
    (its pause does not matter); with `loop` it walks back to the first waypoint, stands there for
    ``pauses_s[0]`` and repeats. (``pauses_s[0]`` is not spent before the first departure: `start_s`
    sets that.) The heading is that of the leg being walked; standing still, the actor keeps the
    heading it arrived with, and before its first leg it faces along that leg.

    Parameters
    ----------
    waypoints_m : ndarray, shape (N, 2)
        Ground points (x, y), m; N ≥ 1. One waypoint: the actor stands still, heading 0.
    pauses_s : ndarray, shape (N,)
        Dwell at each waypoint, s, ≥ 0.
    speed_m_s : float
        Walking speed, m/s, > 0.
    start_s : float
        When the actor leaves the first waypoint, s, ≥ 0.
    loop : bool
        Return to the first waypoint and repeat.
    """

    waypoints_m: np.ndarray
    pauses_s: np.ndarray
    speed_m_s: float
    start_s: float = 0.0
    loop: bool = False
    heading_rad: float = 0.0
    """Which way an actor that never moves (a single waypoint) faces, rad; one that moves faces along
    its legs."""

    def __post_init__(self) -> None:
        freeze_route_fields(self)

    @property
    def points_m(self) -> np.ndarray:
        """Every corner of the route, (N, 2) m: the actor is always on a segment between two of them,
        so their bounds (or any convex bound) contain every position it takes."""
        return self.waypoints_m

    def leg_pad_m(self, reach_m: float) -> float:
        """Margin by which a footprint must grow to cover the actor along `legs_until`'s pieces, m: none,
        the pieces are the legs themselves (`VehicleRoute.leg_pad_m` has its arcs' margin)."""
        return 0.0

    @cached_property
    def _phases(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
        """Knot times (M+1,) s after `start_s`, and for each of the M phases (walking or standing) its
        start point (M, 2), end point (M, 2) and heading (M,); then the heading before the start."""
        points, pauses = self.waypoints_m, self.pauses_s
        order = list(range(1, len(points))) + ([0] if self.loop else [])
        phases: list[tuple[float, np.ndarray, np.ndarray, float]] = []  # duration, start, end, heading
        heading, first_heading, previous = 0.0, None, 0
        for k in order:
            a, b = points[previous], points[k]
            length = math.hypot(*(b - a))
            if length > 0:
                heading = math.atan2(b[1] - a[1], b[0] - a[0])
                first_heading = heading if first_heading is None else first_heading
                phases.append((length / self.speed_m_s, a, b, heading))
            # The pause at the last waypoint of an open route would never end: it is no phase.
            if pauses[k] > 0 and (self.loop or k < len(points) - 1):
                phases.append((float(pauses[k]), b, b, heading))
            previous = k
        durations = np.array([p[0] for p in phases], dtype=np.float64)
        return (
            np.concatenate([[0.0], np.cumsum(durations)]),
            np.array([p[1] for p in phases], dtype=np.float64).reshape(-1, 2),
            np.array([p[2] for p in phases], dtype=np.float64).reshape(-1, 2),
            np.array([p[3] for p in phases], dtype=np.float64),
            self.heading_rad if first_heading is None else first_heading,
        )

    @property
    def duration_s(self) -> float:
        """Time from leaving the first waypoint to the end of the route, s: to the arrival at the last
        waypoint, or, for a loop, one lap including every pause."""
        return float(self._phases[0][-1])

    @property
    def moves(self) -> bool:
        """Whether the actor ever changes position."""
        _, starts, ends, _, _ = self._phases
        return bool(np.any(starts != ends))

    def at(self, time_s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Ground position and heading at `time_s`.

        Parameters
        ----------
        time_s : array_like, any shape (…)
            Scene time, s.

        Returns
        -------
        position_m : ndarray, shape (…, 2)
            Ground point (x, y), m.
        heading_rad : ndarray, shape (…)
            Direction the actor faces, counter-clockwise from +X, rad, in (−π, π].
        """
        t = np.asarray(time_s, dtype=np.float64)
        knots, starts, ends, headings, first_heading = self._phases
        if len(headings) == 0:
            return np.broadcast_to(self.waypoints_m[0], (*t.shape, 2)).copy(), np.full(t.shape, first_heading)
        since_start = t - self.start_s
        before = since_start < 0
        total = knots[-1]
        local = np.mod(since_start, total) if self.loop else np.minimum(since_start, total)
        local = np.where(before, 0.0, local)
        phase = np.clip(np.searchsorted(knots, local, side="right") - 1, 0, len(headings) - 1)
        span = knots[phase + 1] - knots[phase]
        fraction = np.clip((local - knots[phase]) / span, 0.0, 1.0)
        position = starts[phase] + fraction[..., None] * (ends[phase] - starts[phase])
        heading = np.where(before, first_heading, headings[phase])
        return position, heading

    @cached_property
    def _walk(self) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
        """Distance walked at each knot (M+1,) m, the walked polyline's corners (P, 2) m, the length
        of one lap (or of the whole route), m, and the distance walked at each corner (P,) m."""
        _, starts, ends, _, _ = self._phases
        lengths = np.hypot(*(ends - starts).T) if len(starts) else np.zeros(0)
        distance = np.concatenate([[0.0], np.cumsum(lengths)])
        walking = lengths > 0
        corners = np.concatenate([starts[walking][:1], ends[walking]]) if walking.any() else self.waypoints_m[:1]
        along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(corners, axis=0).T))])
        return distance, corners, float(distance[-1]), along

    def distance_at(self, time_s: float) -> float:
        """Distance the actor has walked by `time_s` since the beginning, m (continuous, never falls)."""
        knots, _, _, _, _ = self._phases
        distance, _, lap, _ = self._walk
        if len(knots) < 2 or lap == 0:
            return 0.0
        since = max(time_s - self.start_s, 0.0)
        laps = 0.0
        if self.loop:
            laps, since = divmod(since, knots[-1])
        else:
            since = min(since, knots[-1])
        return float(laps * lap + np.interp(since, knots, distance))

    def at_distance(self, distance_m: float | np.ndarray) -> np.ndarray:
        """Ground point (…, 2) m at a distance walked along the route (its corners in order; a loop
        repeats; an open route stays at its ends)."""
        _, corners, lap, along = self._walk
        d = np.asarray(distance_m, dtype=np.float64)
        if lap == 0 or len(corners) < 2:
            return np.broadcast_to(corners[0], (*d.shape, 2)).copy()
        d = np.mod(d, lap) if self.loop else np.clip(d, 0.0, lap)
        return np.stack([np.interp(d, along, corners[:, 0]), np.interp(d, along, corners[:, 1])], axis=-1)

    def standing(self, time_s: float) -> tuple[float, float] | None:
        """(seconds since the actor stopped, seconds until it walks on) while it stands at `time_s`
        (inf where it never started or never leaves); None while it walks."""
        knots, starts, ends, _, _ = self._phases
        if len(knots) < 2 or not self.moves:
            return math.inf, math.inf
        since = time_s - self.start_s
        if since < 0:
            return math.inf, -since
        total = knots[-1]
        if not self.loop and since >= total:
            return since - total, math.inf
        local = since % total if self.loop else since
        phase = int(np.clip(np.searchsorted(knots, local, side="right") - 1, 0, len(starts) - 1))
        if np.any(starts[phase] != ends[phase]):
            return None
        return local - knots[phase], knots[phase + 1] - local

    def legs_until(self, time_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The straight pieces the actor covers from the beginning of time to `time_s`.

        Everything the actor occupies until `time_s` is its footprint slid along one of these pieces
        with the piece's heading (standing still adds nothing: it stands at a piece's end, facing along
        it, or, before leaving, at the start of the first piece). A loop contributes each leg once.

        Returns
        -------
        start_m : ndarray, shape (K, 2)
            Where each piece starts, m.
        heading_rad : ndarray, shape (K,)
            Heading along it, rad.
        length_m : ndarray, shape (K,)
            How much of it is covered by `time_s`, m (0 for an actor that has not left yet).
        """
        knots, starts, ends, headings, first_heading = self._phases
        walking = np.flatnonzero(np.any(starts != ends, axis=1))
        if len(walking) == 0:
            return self.waypoints_m[:1].copy(), np.array([first_heading]), np.zeros(1)
        elapsed = min(max(time_s - self.start_s, 0.0), knots[-1])
        lengths = np.hypot(*(ends[walking] - starts[walking]).T)
        covered = np.clip((elapsed - knots[walking]) * self.speed_m_s, 0.0, lengths)
        keep = knots[walking] < elapsed
        keep[0] = True
        return starts[walking][keep], headings[walking][keep], covered[keep]


def route_from_path(path: ActorPath) -> Route:
    """The route of an actor that follows waypoints."""
    count = len(path.waypoints_m)
    pauses = np.full(count, path.pause_s) if isinstance(path.pause_s, float | int) else np.array(path.pause_s)
    heading_rad = 0.0 if path.heading_deg is None else math.radians(path.heading_deg)
    return Route(
        np.array(path.waypoints_m, dtype=np.float64), pauses, path.speed_m_s, path.start_s, path.loop, heading_rad
    )


def random_walk_route(walk: RandomWalk, horizon_s: float, *, rng: np.random.Generator) -> Route:
    """A random walk in its region, resolved into waypoints until `horizon_s`.

    From the start point, each leg draws, in this order, a heading uniform in [0, 2π), a length uniform
    in ``leg_length_m`` and a pause uniform in ``pause_s`` (taken at the leg's end). A leg that would
    leave the region is shortened to end on its edge. On an edge, a heading that points out of the
    region is mirrored back into it, so the next leg leaves the edge (its heading is then uniform over
    the directions into the region). Legs are drawn until the route reaches `horizon_s`; after that the
    actor stands at its last waypoint.

    Parameters
    ----------
    walk : RandomWalk
        Region, start, speed, leg lengths, pauses and start time.
    horizon_s : float
        Scene time the route must cover, s.
    rng : numpy.random.Generator
        Source of the headings, lengths and pauses; a generator in the same state gives the same
        route, and a longer horizon only appends legs.

    Returns
    -------
    Route
        Waypoints (the start, then each leg's end) with the drawn pauses; not looping.
    """
    low, high = np.array(walk.region_m[0], dtype=np.float64), np.array(walk.region_m[1], dtype=np.float64)
    point = (low + high) / 2 if walk.start_m is None else np.array(walk.start_m, dtype=np.float64)
    points, pauses = [point], [0.0]
    elapsed_s = walk.start_s
    while elapsed_s < horizon_s:
        angle = rng.uniform(0.0, 2.0 * math.pi)
        length = rng.uniform(*walk.leg_length_m)
        pause = rng.uniform(*walk.pause_s)
        direction = np.array([math.cos(angle), math.sin(angle)])
        outward = ((point <= low + EDGE_TOLERANCE_M) & (direction < 0)) | (
            (point >= high - EDGE_TOLERANCE_M) & (direction > 0)
        )
        direction = np.where(outward, -direction, direction)
        with np.errstate(divide="ignore"):
            to_edge = np.where(direction > 0, (high - point) / direction, (low - point) / direction)
        to_edge = np.where(direction == 0, np.inf, to_edge)
        length = min(length, float(np.min(to_edge)))
        point = np.clip(point + length * direction, low, high)
        points.append(point)
        pauses.append(pause)
        elapsed_s += length / walk.speed_m_s + pause
    return Route(np.array(points), np.array(pauses), walk.speed_m_s, walk.start_s, loop=False)


def random_walk_rng(walk: RandomWalk, *, scene_seed: int, actor_index: int) -> np.random.Generator:
    """The generator a random walk draws from: its own `seed`, or one derived from the scene's seed
    and the actor's index in the scene, so that actors of one scene walk differently."""
    if walk.seed is not None:
        return np.random.default_rng(np.random.SeedSequence(walk.seed))
    return np.random.default_rng(np.random.SeedSequence(scene_seed, spawn_key=(RANDOM_WALK_SPAWN_KEY, actor_index)))


def drives(actor: Actor) -> bool:
    """Whether an actor follows its path as a vehicle (`ActorPath.motion`; by default the VEHICLE_CLASSES)."""
    if actor.path is None or len(actor.path.waypoints_m) == 1:  # one waypoint: it stands (parked)
        return False
    if actor.path.motion is None:
        return actor.cls in VEHICLE_CLASSES
    return actor.path.motion == "vehicle"


def vehicle_route_from_path(path: ActorPath, cls: str) -> VehicleRoute:
    """The route of a vehicle of class `cls` that follows waypoints (`VEHICLE_DYNAMICS[cls]`'s limits);
    raises `RouteTooTightError` where the waypoints need turns tighter than its turning circle."""
    route = route_from_path(path)
    return VehicleRoute(
        route.waypoints_m, route.pauses_s, route.speed_m_s, VEHICLE_DYNAMICS[cls], route.start_s, route.loop
    )


def actor_route(actor: Actor, *, scene_seed: int, actor_index: int, horizon_s: float) -> Route | VehicleRoute:
    """The route of one actor of a scene; a random walk is resolved until `horizon_s`. A vehicle drives
    its path (`drives`): a path it cannot drive is a ConfigError naming the waypoint to move."""
    if actor.random_walk is not None:
        rng = random_walk_rng(actor.random_walk, scene_seed=scene_seed, actor_index=actor_index)
        return random_walk_route(actor.random_walk, horizon_s, rng=rng)
    if actor.path is None:
        raise ValueError(f"actor {actor.name!r} has neither a path nor a random_walk")
    if drives(actor):
        try:
            return vehicle_route_from_path(actor.path, actor.cls)
        except RouteTooTightError as error:
            raise ConfigError([_too_tight(actor, actor_index, error)]) from None
    return route_from_path(actor.path)


def _too_tight(actor: Actor, actor_index: int, error: RouteTooTightError) -> Problem:
    return Problem(
        ("actors", actor_index, "path", "waypoints_m", error.waypoint),
        f"cannot be driven by {actor.name} (a {actor.cls}): {error}; or give the path motion: linear",
    )


def vehicle_path_problems(scene: Scene) -> list[Problem]:
    """Every vehicle path of `scene` that needs turns tighter than its vehicle's turning circle."""
    problems = []
    for i, actor in enumerate(scene.actors):
        if drives(actor):
            try:
                vehicle_route_from_path(actor.path, actor.cls)
            except RouteTooTightError as error:
                problems.append(_too_tight(actor, i, error))
    return problems


def actor_routes(scene: Scene) -> dict[str, Route | VehicleRoute]:
    """Actor name → route for every actor of `scene`, covering the scene and a margin after it
    (`ROUTE_MARGIN_S`, or one frame period if that is longer). A rider (`Actor.rides`) shares the route of
    what it rides."""
    horizon_s = scene.duration_s + max(ROUTE_MARGIN_S, 1.0 / scene.fps)
    routes = {
        actor.name: actor_route(actor, scene_seed=scene.seed, actor_index=i, horizon_s=horizon_s)
        for i, actor in enumerate(scene.actors)
        if actor.rides is None
    }
    return {actor.name: routes[actor.rides if actor.rides is not None else actor.name] for actor in scene.actors}


def position_on_path(
    waypoints_m: np.ndarray,
    speed_m_s: float,
    start_s: float,
    loop: bool,
    time_s: np.ndarray,
    pauses_s: float | np.ndarray = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Ground position (…, 2) in metres and heading (…) in radians at `time_s` (any shape).

    The `Route` through `waypoints_m` (N, 2) with the dwell `pauses_s` (a scalar or (N,)) at each.
    """
    points = np.asarray(waypoints_m, dtype=np.float64).reshape(-1, 2)
    pauses = np.broadcast_to(np.asarray(pauses_s, dtype=np.float64), (len(points),))
    return Route(points, pauses, speed_m_s, start_s, loop).at(time_s)
