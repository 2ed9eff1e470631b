"""Actor routes: waypoint paths with pauses and random walks never teleport or speed, and are reproducible.

Reference values are closed forms: a leg of length L takes L/v, so the actor reaches waypoint k at
start_s + Σ_{j<k} L_j/v + Σ_{0<j<k} pause_j, and a loop's lap takes Σ L/v (closing leg included) + Σ pause.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from camgen.config.scene import ActorPath, RandomWalk, Scene
from camgen.motion.trajectory import (
    RANDOM_WALK_SPAWN_KEY,
    Route,
    actor_routes,
    position_on_path,
    random_walk_rng,
    random_walk_route,
    route_from_path,
)
from tests.stress import stress_settings

DT_S = 0.01
TOL_M = 1e-9
SETTINGS = stress_settings(60)

coordinate = st.floats(-20, 20, allow_nan=False).map(lambda v: round(v, 3))
point = st.tuples(coordinate, coordinate)


@st.composite
def waypoints(draw, max_size=6):
    points = draw(st.lists(point, min_size=1, max_size=max_size))
    # Consecutive waypoints must differ (the scene rejects repeats); keep a visible gap.
    kept = [points[0]]
    for p in points[1:]:
        if math.dist(p, kept[-1]) > 0.05:
            kept.append(p)
    if len(kept) > 2 and math.dist(kept[-1], kept[0]) <= 0.05:
        kept.pop()  # a loop's closing leg would have no length (see the dedicated test)
    return kept


@st.composite
def routes(draw):
    points = draw(waypoints())
    pauses = draw(st.lists(st.floats(0, 3), min_size=len(points), max_size=len(points)))
    if draw(st.booleans()):
        pauses = [pauses[0]] * len(points)
    return Route(
        np.array(points, dtype=np.float64),
        np.array(pauses),
        speed_m_s=draw(st.floats(0.2, 5)),
        start_s=draw(st.floats(0, 3)),
        loop=draw(st.booleans()),
    )


@st.composite
def random_walks(draw):
    x_min, y_min = draw(coordinate), draw(coordinate)
    width, height = draw(st.floats(0.5, 30)), draw(st.floats(0.5, 30))
    region = ((x_min, y_min), (x_min + width, y_min + height))
    start = None
    if draw(st.booleans()):
        u, v = draw(st.floats(0, 1)), draw(st.floats(0, 1))
        start = (x_min + u * width, y_min + v * height)
    leg_min = draw(st.floats(0.2, 8))
    pause_min = draw(st.floats(0, 2))
    return RandomWalk(
        region_m=region,
        start_m=start,
        speed_m_s=draw(st.floats(0.3, 5)),
        leg_length_m=(leg_min, leg_min + draw(st.floats(0, 8))),
        pause_s=(pause_min, pause_min + draw(st.floats(0, 2))),
        start_s=draw(st.floats(0, 3)),
        seed=draw(st.integers(0, 2**32)),
    )


def walk_route(walk: RandomWalk, horizon_s: float = 30.0) -> Route:
    return random_walk_route(walk, horizon_s, rng=random_walk_rng(walk, scene_seed=0, actor_index=0))


def sample_times(route: Route) -> np.ndarray:
    end_s = route.start_s + min(2 * route.duration_s, 80.0) + 1.0
    return np.arange(-1.0, end_s, DT_S)


def assert_no_teleport(route: Route, times_s: np.ndarray) -> None:
    xy, _ = route.at(times_s)
    step_m = np.hypot(*np.diff(xy, axis=0).T)
    allowed_m = route.speed_m_s * np.diff(times_s) * (1 + 1e-9) + TOL_M
    assert np.all(step_m <= allowed_m), float(np.max(step_m - allowed_m))


def arrivals_s(route: Route) -> np.ndarray:
    """Closed-form arrival time at each waypoint after the first (and, for a loop, back at the first)."""
    points = route.waypoints_m
    if route.loop:
        points = np.vstack([points, points[:1]])
    legs_s = np.hypot(*np.diff(points, axis=0).T) / route.speed_m_s
    pauses = np.append(route.pauses_s[1:], route.pauses_s[0])[: len(legs_s)]
    waits_s = np.concatenate([[0.0], np.cumsum(pauses)[:-1]])
    return route.start_s + np.cumsum(legs_s) + waits_s


@SETTINGS
@given(routes())
def test_path_never_exceeds_its_speed(route):
    assert_no_teleport(route, sample_times(route))


@SETTINGS
@given(routes(), st.lists(st.floats(-2, 100), min_size=2, max_size=40))
def test_path_moves_no_farther_than_speed_times_elapsed(route, times):
    # Lipschitz at any pair of times, across pauses and loop laps: the position never jumps.
    t = np.array(times)
    xy, _ = route.at(t)
    apart_m = np.hypot(*(xy[:, None] - xy[None, :]).transpose(2, 0, 1))
    assert np.all(apart_m <= route.speed_m_s * np.abs(t[:, None] - t[None, :]) * (1 + 1e-9) + 1e-8)


@SETTINGS
@given(routes())
def test_pauses_last_their_stated_time(route):
    points, pauses, v = route.waypoints_m, route.pauses_s, route.speed_m_s
    arrivals = arrivals_s(route)
    targets = list(range(1, len(points))) + ([0] if route.loop else [])
    eps = 1e-6
    for k, arrival in zip(targets, arrivals, strict=True):
        last = not route.loop and k == len(points) - 1
        pause = np.inf if last else pauses[k]
        ends = [arrival] + ([arrival + pause] if np.isfinite(pause) else [arrival + 5.0])
        xy, _ = route.at(np.array(ends))
        np.testing.assert_allclose(xy, [points[k]] * 2, atol=1e-7)
        if not last and len(points) > 1:
            inside = np.linspace(arrival, arrival + pause, 7)
            xy, _ = route.at(inside)
            np.testing.assert_allclose(xy, np.broadcast_to(points[k], xy.shape), atol=1e-7)
            # Just after the pause it is walking again, at full speed.
            after, _ = route.at(arrival + pause + eps)
            assert math.dist(after, points[k]) == pytest.approx(v * eps, rel=1e-3, abs=1e-9)


@SETTINGS
@given(routes())
def test_heading_is_continuous_through_pauses(route):
    points = route.waypoints_m
    if len(points) < 2:
        return
    arrivals = arrivals_s(route)
    closed = np.vstack([points, points[:1]]) if route.loop else points
    for i, arrival in enumerate(arrivals):
        k = (i + 1) % len(points)
        pause = route.pauses_s[k] if (route.loop or k != len(points) - 1) else 3.0
        arrived = closed[i + 1] - closed[i]
        expected = math.atan2(arrived[1], arrived[0])
        _, heading = route.at(np.linspace(arrival - 1e-6, arrival + pause - 1e-6, 9))
        np.testing.assert_allclose(np.angle(np.exp(1j * (heading - expected))), 0.0, atol=1e-9)


@SETTINGS
@given(routes())
def test_before_start_the_actor_waits_at_the_first_waypoint_facing_its_first_leg(route):
    xy, heading = route.at(np.linspace(-5.0, route.start_s, 11))
    np.testing.assert_allclose(xy, np.broadcast_to(route.waypoints_m[0], xy.shape), atol=1e-12)
    if len(route.waypoints_m) > 1:
        first = route.waypoints_m[1] - route.waypoints_m[0]
        np.testing.assert_allclose(heading, math.atan2(first[1], first[0]))


@SETTINGS
@given(routes(), st.integers(1, 4))
def test_loop_returns_to_the_start_every_lap(route, laps):
    if not route.loop:
        return
    points, v = route.waypoints_m, route.speed_m_s
    closed = np.vstack([points, points[:1]])
    lap_s = np.hypot(*np.diff(closed, axis=0).T).sum() / v + route.pauses_s.sum()
    if len(points) > 1:
        assert route.duration_s == pytest.approx(lap_s)
    xy, _ = route.at(route.start_s + laps * lap_s)
    np.testing.assert_allclose(xy, points[0], atol=1e-7)
    # A lap later, everything repeats.
    t = route.start_s + np.linspace(0, lap_s, 13)
    np.testing.assert_allclose(route.at(t + laps * lap_s)[0], route.at(t)[0], atol=1e-7)


@SETTINGS
@given(routes())
def test_open_path_stops_at_its_last_waypoint(route):
    if route.loop:
        return
    end_s = route.start_s + route.duration_s
    xy, _ = route.at(np.array([end_s, end_s + 1.0, end_s + 1e4]))
    np.testing.assert_allclose(xy, np.broadcast_to(route.waypoints_m[-1], xy.shape), atol=1e-7)


@SETTINGS
@given(routes(), st.floats(-1, 60))
def test_every_position_until_a_time_lies_on_a_covered_leg_with_its_heading(route, until_s):
    starts, headings, lengths = route.legs_until(until_s)
    t = np.linspace(-1.0, until_s, 400)
    xy, heading = route.at(t)
    direction = np.stack([np.cos(headings), np.sin(headings)], -1)
    along = np.einsum("lk,tlk->tl", direction, xy[:, None] - starts[None])
    offset = xy[:, None] - starts[None]
    across = np.abs(direction[None, :, 0] * offset[..., 1] - direction[None, :, 1] * offset[..., 0])
    on_leg = (along >= -1e-7) & (along <= lengths + 1e-7) & (across <= 1e-7)
    same_heading = np.abs(np.angle(np.exp(1j * (heading[:, None] - headings[None])))) <= 1e-9
    assert np.all(np.any(on_leg & same_heading, axis=1))


def test_pause_on_a_known_path():
    # 3 m east at 1 m/s from t = 1 s, 2 s pause, 4 m north: arrivals at 4 s and 10 s.
    route = Route(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]]), np.array([9.0, 2.0, 9.0]), 1.0, 1.0, False)
    xy, heading = route.at(np.array([0.0, 2.5, 4.0, 5.0, 6.0, 7.0, 10.0, 50.0]))
    np.testing.assert_allclose(xy, [[0, 0], [1.5, 0], [3, 0], [3, 0], [3, 0], [3, 1], [3, 4], [3, 4]], atol=1e-12)
    np.testing.assert_allclose(heading, [0, 0, 0, 0, np.pi / 2, np.pi / 2, np.pi / 2, np.pi / 2])
    assert route.duration_s == pytest.approx(9.0)


def test_single_waypoint_stands_still_facing_x():
    route = Route(np.array([[4.0, 5.0]]), np.array([1.0]), 1.0, 0.0, True)
    xy, heading = route.at(np.linspace(0, 9, 4))
    np.testing.assert_allclose(xy, [[4, 5]] * 4)
    assert np.all(heading == 0) and not route.moves


def test_at_keeps_the_shape_of_time():
    route = Route(np.array([[0.0, 0.0], [1.0, 1.0]]), np.zeros(2), 1.0)
    xy, heading = route.at(np.zeros((3, 4, 5)))
    assert xy.shape == (3, 4, 5, 2) and heading.shape == (3, 4, 5)
    xy, heading = route.at(0.5)
    assert xy.shape == (2,) and heading.shape == ()


@pytest.mark.parametrize(
    ("waypoints", "pauses", "speed", "start"),
    [
        (np.zeros((0, 2)), np.zeros(0), 1.0, 0.0),
        (np.zeros((2, 3)), np.zeros(2), 1.0, 0.0),
        (np.zeros((2, 2)), np.zeros(3), 1.0, 0.0),
        (np.zeros((2, 2)), np.array([0.0, -1.0]), 1.0, 0.0),
        (np.zeros((2, 2)), np.zeros(2), 0.0, 0.0),
        (np.zeros((2, 2)), np.zeros(2), 1.0, -1.0),
    ],
)
def test_route_rejects_bad_arrays(waypoints, pauses, speed, start):
    with pytest.raises(ValueError):
        Route(waypoints, pauses, speed, start)


def test_position_on_path_takes_pauses():
    waypoints = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]])
    xy, _ = position_on_path(waypoints, 1.0, 0.0, False, np.array([2.0, 3.0, 4.0]), pauses_s=1.5)
    np.testing.assert_allclose(xy, [[2, 0], [2, 0], [2, 0.5]])


def test_path_model_pauses_become_route_pauses():
    path = ActorPath(waypoints_m=[(0, 0), (1, 0), (1, 1)], pause_s=2.0, loop=True)
    np.testing.assert_array_equal(route_from_path(path).pauses_s, [2.0, 2.0, 2.0])
    path = ActorPath(waypoints_m=[(0, 0), (1, 0), (1, 1)], pause_s=[0, 1, 3])
    np.testing.assert_array_equal(route_from_path(path).pauses_s, [0.0, 1.0, 3.0])


@SETTINGS
@given(random_walks())
def test_random_walk_stays_inside_its_region(walk):
    route = walk_route(walk)
    (x_min, y_min), (x_max, y_max) = walk.region_m
    xy, _ = route.at(sample_times(route))
    for points in (route.points_m, xy):
        assert np.all(points >= np.array([x_min, y_min]) - TOL_M)
        assert np.all(points <= np.array([x_max, y_max]) + TOL_M)


@SETTINGS
@given(random_walks())
def test_random_walk_never_exceeds_its_speed(walk):
    route = walk_route(walk)
    assert_no_teleport(route, sample_times(route))
    assert route.speed_m_s == walk.speed_m_s and route.start_s == walk.start_s and not route.loop


@SETTINGS
@given(random_walks(), st.floats(0, 60))
def test_random_walk_covers_its_horizon_with_drawn_legs_and_pauses(walk, horizon_s):
    route = walk_route(walk, horizon_s)
    points = route.points_m
    start = np.mean(walk.region_m, axis=0) if walk.start_m is None else np.array(walk.start_m)
    np.testing.assert_allclose(points[0], start)
    lengths = np.hypot(*np.diff(points, axis=0).T)
    # Legs are drawn until the walk reaches the horizon, and no further.
    end_s = walk.start_s + lengths.sum() / walk.speed_m_s + route.pauses_s[1:].sum()
    assert end_s >= horizon_s - 1e-9
    if len(points) > 1:
        assert end_s - lengths[-1] / walk.speed_m_s - route.pauses_s[-1] < horizon_s + 1e-9
    else:
        assert walk.start_s >= horizon_s
    low, high = np.array(walk.region_m[0]), np.array(walk.region_m[1])
    on_edge = np.any((points[1:] <= low + TOL_M) | (points[1:] >= high - TOL_M), axis=1)
    assert np.all(lengths <= walk.leg_length_m[1] + 1e-9)
    assert np.all((lengths >= walk.leg_length_m[0] - 1e-9) | on_edge)  # only the edge shortens a leg
    assert np.all(lengths > 0)
    assert np.all((route.pauses_s[1:] >= walk.pause_s[0]) & (route.pauses_s[1:] <= walk.pause_s[1]))


@SETTINGS
@given(random_walks(), st.floats(1, 30), st.floats(0, 30))
def test_random_walk_is_reproducible_and_a_longer_horizon_only_extends_it(walk, horizon_s, more_s):
    first, again = walk_route(walk, horizon_s), walk_route(walk, horizon_s)
    np.testing.assert_array_equal(first.waypoints_m, again.waypoints_m)
    np.testing.assert_array_equal(first.pauses_s, again.pauses_s)
    longer = walk_route(walk, horizon_s + more_s)
    n = len(first.waypoints_m)
    np.testing.assert_array_equal(longer.waypoints_m[:n], first.waypoints_m)
    np.testing.assert_array_equal(longer.pauses_s[:n], first.pauses_s)


def test_random_walk_in_a_tiny_region_still_moves():
    walk = RandomWalk(region_m=((0, 0), (0.1, 0.2)), leg_length_m=(5, 10), pause_s=(0, 0), seed=3)
    route = walk_route(walk, horizon_s=20.0)
    assert route.moves and len(route.points_m) > 20
    assert np.all(np.hypot(*np.diff(route.points_m, axis=0).T) > 0)


def _scene(actors, seed=1):
    return Scene.model_validate(
        {
            "duration_s": 20,
            "seed": seed,
            "lights": [{"type": "ambient", "illuminance_lux": 1000}],
            "actors": actors,
            "cameras": [{"name": "cam", "profile": "fixed", "mount": {"position_m": [0, -5, 3]}}],
        }
    )


def _walker(name, **walk):
    return {"name": name, "class": "person", "random_walk": {"region_m": [[-10, -10], [10, 10]], **walk}}


def test_scene_routes_differ_by_actor_and_repeat_by_seed():
    scene = _scene([_walker("a"), _walker("b"), {"name": "c", "class": "car", "path": {"waypoints_m": [[0, 0]]}}])
    routes = actor_routes(scene)
    assert list(routes) == ["a", "b", "c"]
    assert not np.array_equal(routes["a"].waypoints_m[1:3], routes["b"].waypoints_m[1:3])
    again = actor_routes(scene)
    np.testing.assert_array_equal(routes["a"].waypoints_m, again["a"].waypoints_m)
    np.testing.assert_array_equal(routes["b"].pauses_s, again["b"].pauses_s)
    # The horizon covers the scene and the motion-blur margin after it.
    for name in "ab":
        route = routes[name]
        assert route.start_s + route.duration_s >= scene.duration_s + 1.0
    # Another scene seed, another walk; the same explicit seed, the same walk for any actor.
    other = actor_routes(_scene([_walker("a"), _walker("b")], seed=2))
    assert not np.array_equal(other["a"].waypoints_m[1:3], routes["a"].waypoints_m[1:3])
    seeded = actor_routes(_scene([_walker("a", seed=7), _walker("b", seed=7)]))
    np.testing.assert_array_equal(seeded["a"].waypoints_m, seeded["b"].waypoints_m)


def test_unseeded_walk_draws_from_the_documented_seed_sequence():
    scene = _scene([_walker("a"), _walker("b")], seed=5)
    walk = scene.actors[1].random_walk
    rng = np.random.default_rng(np.random.SeedSequence(5, spawn_key=(RANDOM_WALK_SPAWN_KEY, 1)))
    expected = random_walk_route(walk, scene.duration_s + 1.0, rng=rng)
    np.testing.assert_array_equal(actor_routes(scene)["b"].waypoints_m, expected.waypoints_m)


def test_loop_whose_last_waypoint_is_its_first_pauses_there_once_per_waypoint():
    # The closing leg has no length: arriving at the repeated point ends the lap's walking.
    points = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 0.0]])
    route = Route(points, np.array([1.0, 0.5, 0.25]), 1.0, 0.0, True)
    assert route.duration_s == pytest.approx(4.0 + 0.5 + 0.25 + 1.0)
    xy, heading = route.at(np.array([2.2, 4.5, 4.7, 5.6, 5.75]))
    np.testing.assert_allclose(xy, [[2, 0], [0, 0], [0, 0], [0, 0], [0, 0]], atol=1e-12)
    np.testing.assert_allclose(heading, [0, np.pi, np.pi, np.pi, 0])


@SETTINGS
@given(routes())
def test_distance_walked_is_where_the_route_puts_the_actor(route):
    """`at_distance(distance_at(t))` is `at(t)`: the walked distance locates the actor; it never falls
    and grows at most at the speed (the gait's phase is locked to it)."""
    times = sample_times(route)
    distance = np.array([route.distance_at(float(t)) for t in times])
    assert np.all(np.diff(distance) >= -1e-9)
    assert np.all(np.diff(distance) <= route.speed_m_s * np.diff(times) * (1 + 1e-9) + 1e-9)
    xy, _ = route.at(times)
    np.testing.assert_allclose(route.at_distance(distance), xy, atol=1e-6)


@SETTINGS
@given(routes())
def test_standing_reports_the_pauses(route):
    """While the actor moves, `standing` is None; while it stands, since + until span the pause."""
    for t in sample_times(route)[::7]:
        state = route.standing(float(t))
        xy0, _ = route.at(float(t))
        xy1, _ = route.at(float(t) + 1e-4)
        if state is None:
            assert np.hypot(*(xy1 - xy0)) > 0
            continue
        since, until = state
        assert since >= 0 and until >= 0
        if math.isfinite(until) and until > 2e-4:
            assert np.hypot(*(xy1 - xy0)) == 0


def test_standing_on_a_known_path():
    route = Route(np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 3.0]]), np.array([0.0, 1.5, 0.0]), 1.0, 0.5)
    assert route.standing(0.2) == (math.inf, pytest.approx(0.3))
    assert route.standing(1.0) is None
    assert route.standing(3.0) == (pytest.approx(0.5), pytest.approx(1.0))
    assert route.standing(10.0)[1] == math.inf
    assert route.distance_at(3.0) == pytest.approx(2.0) and route.distance_at(5.0) == pytest.approx(3.0)
