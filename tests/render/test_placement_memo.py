"""`SceneGraph.place_actors` at times asked for in any order, again and again (as a frame's sub-frames ask
for them), places every actor as a fresh placement at that time does: the poses each rig keeps per time
(`camgen.motion.memo`) and the vertices a vehicle keeps turned (`VehicleRig._turn`) change nothing."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.actors import Crowd, PersonRig
from camgen.actors.gait import Walker
from camgen.actors.riding import Rider
from tests.render.conftest import scene_from

TIMES_S = [0.8, 1.8, 0.8, 0.2, 1.8, 0.8 + 1e-4, 3.4, 0.2, 2.1, 0.8, 3.4, 1.8, 2.1]
"""Interleaved, repeated and nearly equal times: the car and the bicycle on their first straights (up to 0.9 s
and 1.3 s), in their turns (the bicycle leaning) and on their second straights; the faller before it falls and
falling (from 2 s)."""


@pytest.fixture(scope="module")
def graph():
    from camgen.render.scene_graph import build_scene_graph

    return build_scene_graph(
        scene_from(
            duration_s=5.0,
            environment={"meshes": [{"type": "plane", "name": "ground", "size_m": [80, 80]}]},
            lights=[{"type": "sun", "illuminance_lux": 1000, "azimuth_deg": 30, "elevation_deg": 40}],
            actors=[
                {"name": "car", "class": "car", "path": {"waypoints_m": [[-4, -2], [0, -2], [4, 20]], "speed_m_s": 8}},
                {"name": "parked", "class": "car", "path": {"waypoints_m": [[5, 8]], "heading_deg": 30}},
                {"name": "bicycle", "class": "bicycle", "path": {"waypoints_m": [[-2, 4], [0, 4], [5, 14]], "speed_m_s": 5}},  # noqa: E501
                {"name": "cyclist", "class": "person", "rides": "bicycle"},
                {"name": "walker", "class": "person", "path": {"waypoints_m": [[3, -6], [3, 6]], "speed_m_s": 1.3}},
                {
                    "name": "faller",
                    "class": "person",
                    "path": {"waypoints_m": [[-4, -6]]},
                    "actions": [{"type": "fall", "start_s": 2.0, "duration_s": 3.0, "direction": "left"}],
                },
            ],
        )
    )  # fmt: skip


def _fresh_vehicle(rig):
    """The same vehicle, newly made: nothing kept from other times but its first placement's (at 0 s)."""
    return type(rig)(rig.model, rig.route, lights_on=rig.lights_on)


def _whole_turn(rig, time_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(T_world_from_vehicle, vertices, normals) at `time_s` as the vehicle's placement turned every vertex by
    its bone's transform before it kept any (one product over every vertex, from a new rig's pose)."""
    T, bones = _fresh_vehicle(rig).pose(time_s)
    M = np.concatenate([T[None], T @ bones])
    chosen = M[np.concatenate([part.wheel for part in rig.model.parts]).astype(np.int64) + 1]
    rest = np.concatenate([part.vertices_m for part in rig.model.parts])
    rest_normals = np.concatenate([part.normals for part in rig.model.parts])
    vertices = np.einsum("vij,vj->vi", chosen[:, :3, :3], rest) + chosen[:, :3, 3]
    return T, vertices, np.einsum("vij,vj->vi", chosen[:, :3, :3], rest_normals)


def _fresh_crowd(graph) -> Crowd:
    """The graph's people newly made (their vehicles too): no pose kept from any time."""
    rigs = []
    for rig in graph.crowd.rigs:
        walker = rig.walker
        if isinstance(walker, Rider):
            fresh = Rider(rig.model, _fresh_vehicle(walker.targets.__self__).rider_targets, walker.route)
        else:
            fresh = Walker(rig.model, walker.route, phase_seed=walker.phase_seed, actions=walker.actions)
        rigs.append(PersonRig(rig.model, fresh))
    return Crowd(rigs)


def test_placements_at_interleaved_and_repeated_times_equal_fresh_placements(graph):
    vehicles = [(node, rig) for node, rig in zip(graph.actor_nodes, graph.vehicles, strict=True) if rig is not None]
    for time_s in TIMES_S:
        graph.place_actors(time_s)
        for node, rig in vehicles:
            T, vertices, normals = _whole_turn(rig, time_s)
            np.testing.assert_array_equal(rig.T_world_from_vehicle, T)
            np.testing.assert_array_equal(rig.vertices_m, vertices)
            np.testing.assert_array_equal(rig.normals, normals)
            assert rig.lit == _fresh_vehicle(rig).lamps(time_s)
            for primitive, piece in zip(node.mesh.primitives, rig.parts, strict=True):
                np.testing.assert_array_equal(primitive.positions, vertices[piece].astype(np.float32))
                np.testing.assert_array_equal(primitive.normals, normals[piece].astype(np.float32))
        fresh = _fresh_crowd(graph)
        fresh.place(time_s)
        for rig, reference in zip(graph.crowd.rigs, fresh.rigs, strict=True):
            for name in ("vertices_m", "normals", "joints_m", "keypoints_m", "T_world_from_pelvis"):
                np.testing.assert_array_equal(
                    getattr(rig, name), getattr(reference, name), err_msg=f"{name}, {time_s} s"
                )


def test_what_moves_differs_between_times_and_what_stands_keeps_its_look(graph):
    """The placements compared above move (so equal arrays are no accident of a frozen rig), the car's body turns
    between the straight and the turn (so the rows kept and the rows turned again are both exercised), and a
    parked car's look version holds while the others' rise."""
    names = [actor.name for actor in graph.actors]
    car, parked = graph.vehicles[names.index("car")], names.index("parked")
    walker, faller = graph.people[names.index("walker")], graph.people[names.index("faller")]
    looks = {}
    for time_s in (0.2, 0.8, 1.8, 3.4):
        graph.place_actors(time_s)
        looks[time_s] = (
            car.T_world_from_vehicle.copy(), car.vertices_m.copy(), walker.joints_m.copy(), faller.joints_m.copy(),
            list(graph.look_versions),
        )  # fmt: skip
    assert np.array_equal(looks[0.2][0][:3, :3], looks[0.8][0][:3, :3])  # on the straight: the body only moves
    assert not np.array_equal(looks[0.8][0][:3, :3], looks[1.8][0][:3, :3])  # in the turn it turns
    for a, b in ((0.2, 0.8), (0.8, 1.8), (1.8, 3.4)):
        assert not np.array_equal(looks[a][1], looks[b][1])
        assert not np.array_equal(looks[a][2], looks[b][2])
        assert looks[a][4][parked] == looks[b][4][parked]
        assert looks[a][4][names.index("car")] != looks[b][4][names.index("car")]
    assert looks[3.4][3][:, 2].max() < looks[0.2][3][:, 2].max() - 0.5  # fallen


def test_a_kept_pose_cannot_be_changed_in_place(graph):
    graph.place_actors(1.5)
    person = graph.people[[actor.name for actor in graph.actors].index("walker")]
    with pytest.raises(ValueError, match="read-only"):
        person.joints_m[0, 0] = 0.0
    with pytest.raises(ValueError, match="read-only"):
        graph.vehicles[0].T_world_from_vehicle[0, 3] = 0.0


def test_a_vehicles_lamps_follow_lights_on_at_a_time_already_placed():
    # The pose is kept per time; the lamps also follow `lights_on`, which a caller may switch between two
    # placements at one time (review: the kept lamps stayed off).
    from camgen.motion.trajectory import actor_routes
    from camgen.vehicles import vehicle_rigs
    from tests.render.conftest import scene_from

    scene = scene_from(
        lights=[{"type": "ambient", "illuminance_lux": 100}],
        actors=[
            {
                "name": "car",
                "class": "car",
                "vehicle": {"lights_on": False},  # (auto would light them: a driven car in 100 lx)
                "path": {"waypoints_m": [[0, 0], [20, 0]], "speed_m_s": 5},
            }
        ],
    )
    rig = vehicle_rigs(scene, actor_routes(scene))["car"]
    rig.place(1.0)
    assert not rig.lit["head"]
    rig.lights_on = True
    rig.place(1.0)
    assert rig.lit["head"] and rig.lit == rig.lamps(1.0)


def test_props_left_at_another_time_are_bent_when_the_actors_time_is_asked_for_again():
    """`place_actors(props=False)` (the blur test's exposure ends) leaves the swaying trees bent as they were, so
    the graph no longer stands at one time: placing at any time again, that one too, bends them; `bend_prop` bends
    one tree alone, and the graph stands at one time again once every tree is back at the actors' time."""
    from camgen.render.scene_graph import build_scene_graph

    graph = build_scene_graph(
        scene_from(
            environment={
                "meshes": [{"type": "plane", "name": "ground", "size_m": [40, 40]}],
                "props": [
                    {"type": "bush", "position_m": [3, 4], "seed": 1},
                    {"type": "bush", "position_m": [-3, 4], "seed": 2},
                ],
                "wind": {"speed_m_s": 6.0},
            },
            lights=[{"type": "sun", "illuminance_lux": 1000, "azimuth_deg": 30, "elevation_deg": 40}],
            actors=[{"name": "walker", "class": "person", "path": {"waypoints_m": [[3, -6], [3, 6]]}}],
        )
    )
    props = graph.swaying
    assert len(props) == 2

    def positions():
        return [np.array(prop.node.mesh.primitives[0].positions) for prop in props]

    graph.place_actors(0.5)
    at_half = positions()
    graph.place_actors(0.7, props=False)
    assert graph.placed_time_s is None and all(prop.placed_at_s == 0.5 for prop in props)
    np.testing.assert_array_equal(np.concatenate(positions()), np.concatenate(at_half))
    graph.place_actors(0.7)
    assert graph.placed_time_s == 0.7 and all(prop.placed_at_s == 0.7 for prop in props)
    versions = list(graph.look_versions)
    graph.bend_prop(0, 0.5)
    assert graph.placed_time_s is None and graph.look_versions[1] == versions[1] + 1
    np.testing.assert_array_equal(positions()[0], at_half[0])
    graph.bend_prop(0, 0.7)
    assert graph.placed_time_s == 0.7
    graph.place_actors(0.5, props=False)
    graph.place_actors(0.5)  # the actors stand there, the trees do not yet
    np.testing.assert_array_equal(np.concatenate(positions()), np.concatenate(at_half))
