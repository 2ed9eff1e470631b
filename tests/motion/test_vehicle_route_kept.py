"""A `VehicleRoute` keeps its state (distance, speed) and pose at each single time it is asked for: asked at
times in any order, again and by every method, it answers bit for bit what a fresh route (nothing kept)
answers at that time; what it hands out may be changed by the caller without changing later answers."""

from __future__ import annotations

import numpy as np

from camgen.motion.vehicle_route import STATE_MEMO_TIMES, VEHICLE_DYNAMICS, VehicleRoute

WAYPOINTS_M = np.array([[0.0, 0.0], [30.0, 0.0], [30.0, 25.0], [5.0, 30.0]])
PAUSES_S = np.array([0.0, 2.0, 0.0, 1.0])


def _route(loop=False):
    return VehicleRoute(WAYPOINTS_M, PAUSES_S, 8.0, VEHICLE_DYNAMICS["car"], start_s=1.5, loop=loop)


def _answers(route, time_s):
    """Every per-time answer of `route` at `time_s`, as arrays."""
    point, heading = route.at(time_s)
    standing = route.standing(time_s)
    return [
        point,
        heading,
        np.asarray(route.distance_at(time_s)),
        route.curvature_at(time_s),
        route.steer_rad_at(time_s),
        route.speed_at(time_s),
        np.asarray([np.nan, np.nan] if standing is None else standing),
        *route.legs_until(time_s),
    ]


def _same_bits(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def test_kept_states_at_interleaved_times_equal_a_fresh_routes():
    for loop in (False, True):
        route = _route(loop)
        rng = np.random.default_rng(4)
        times = rng.uniform(-2.0, route.duration_s + 3.0, 40)
        asked = np.concatenate([times, times[::-1], rng.choice(times, 40), [0.0, 1.5, route.duration_s + 1.5]])
        answers = {}
        for t in asked:
            t = float(t)
            got = _answers(route, t)
            fresh = _answers(_route(loop), t)
            assert all(_same_bits(a, b) for a, b in zip(got, fresh, strict=True)), t
            # An array of times is not kept: the same numbers from the whole computation.
            one = np.array([t])
            point, heading = route.at(one)
            unkept = [
                point[0],
                heading[0],
                route.distance_at(one)[0],
                route.curvature_at(one)[0],
                route.speed_at(one)[0],
            ]
            kept = [got[0], got[1], got[2], got[3], got[5]]
            assert all(_same_bits(a, b) for a, b in zip(kept, unkept, strict=True)), t
            answers.setdefault(t, got)
        distances = {float(a[2]) for a in answers.values()}
        assert len(distances) > 20  # the times differ in where the vehicle is (a frozen state would not)


def test_a_callers_change_to_an_answer_is_not_kept():
    route = _route()
    point, heading = route.at(9.0)
    expected = point.copy(), heading.copy()
    point += 100.0
    heading += 1.0
    again = route.at(9.0)
    assert _same_bits(again[0], expected[0]) and _same_bits(again[1], expected[1])
    points, _ = route.at(np.array([9.0, 9.0]))  # an array of times is not kept, its answer the caller's too
    points[:] = -1.0
    assert _same_bits(route.at(9.0)[0], expected[0])


def test_more_times_than_kept_still_answer_alike_and_arrays_of_times_too():
    route = _route(loop=True)
    times = np.linspace(0.0, 2 * route.duration_s, 2 * STATE_MEMO_TIMES + 7)
    for t in times:
        route.at(float(t))
    assert len(route._kept) == STATE_MEMO_TIMES
    fresh = _route(loop=True)
    for t in times[:5]:
        assert all(_same_bits(a, b) for a, b in zip(_answers(route, float(t)), _answers(fresh, float(t)), strict=True))
    point, heading = route.at(times)
    assert point.shape == (len(times), 2) and heading.shape == (len(times),)
    for k in (0, 100, len(times) - 1):
        assert np.array_equal(point[k], fresh.at(float(times[k]))[0])
