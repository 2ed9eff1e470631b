"""What the scene graph and the renderer keep between calls follows every change: `OrderedScene`'s world poses
and ordered lists, a placed vehicle's primitive bounds (`_pose_vehicle_mesh`), the renderer's skipped context
update (`_PassRenderer._update_context`) and the vertex rows it keeps per deformed primitive (`_upload_deformed`)."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.render.gl import pyrender
from camgen.render.renderer import View
from camgen.render.scene_graph import OrderedScene, build_scene_graph
from tests.render.conftest import camera_matrix, look_at, scene_from


def _turned(angle_rad: float, translation_m) -> np.ndarray:
    c, s = np.cos(angle_rad), np.sin(angle_rad)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    T[:3, 3] = translation_m
    return T


def _box_node(name: str, pose: np.ndarray) -> pyrender.Node:
    import trimesh

    return pyrender.Node(name=name, mesh=pyrender.Mesh.from_trimesh(trimesh.creation.box((1, 1, 1))), matrix=pose)


def test_a_pose_set_again_is_the_pose_handed_out():
    scene = OrderedScene()
    first, second = _turned(0.3, (1, 2, 3)), _turned(-1.1, (4, 5, 6))
    node = _box_node("a", first)
    scene.add_node(node)
    assert np.array_equal(scene.get_pose(node), pyrender.Scene.get_pose(scene, node))  # pyrender's, walked anew
    assert np.allclose(scene.get_pose(node), first)
    scene.get_pose(node)
    scene.set_pose(node, second)
    assert np.array_equal(scene.get_pose(node), second)
    handed = scene.get_pose(node)
    handed[:] = 0.0  # a caller writing into what it was given changes nothing kept
    assert np.array_equal(scene.get_pose(node), second)


def test_a_child_moves_with_its_parent():
    scene = OrderedScene()
    parent, child = _box_node("parent", _turned(0.2, (1, 0, 0))), _box_node("child", _turned(0.5, (0, 2, 0)))
    parent.children.append(child)
    scene.add_node(parent)
    assert np.allclose(scene.get_pose(child), _turned(0.2, (1, 0, 0)) @ _turned(0.5, (0, 2, 0)))
    moved = _turned(-0.7, (3, 3, 1))
    scene.set_pose(parent, moved)
    assert np.allclose(scene.get_pose(child), moved @ _turned(0.5, (0, 2, 0)))


def test_lists_follow_nodes_added_and_removed():
    scene = OrderedScene()
    a, b = _box_node("a", np.eye(4)), _box_node("b", np.eye(4))
    sun = pyrender.Node(light=pyrender.DirectionalLight(), matrix=np.eye(4))
    scene.add_node(a)
    scene.add_node(sun)
    assert scene.mesh_nodes == [a] and scene.light_nodes == [sun] and scene.directional_light_nodes == [sun]
    scene.add_node(b)
    assert scene.mesh_nodes == [a, b]
    scene.remove_node(a)
    scene.remove_node(sun)
    assert scene.mesh_nodes == [b] and scene.light_nodes == [] and scene.directional_light_nodes == []
    listed = scene.mesh_nodes
    listed.append(a)  # a caller's list is its own
    assert scene.mesh_nodes == [b]


def test_a_placed_vehicles_bounds_are_its_vertices_bounds_at_each_time():
    graph = build_scene_graph(
        scene_from(
            duration_s=4.0,
            environment={"meshes": [{"type": "plane", "name": "ground", "size_m": [60, 60]}]},
            lights=[{"type": "sun", "illuminance_lux": 1000, "azimuth_deg": 30, "elevation_deg": 40}],
            actors=[
                {"name": "car", "class": "car", "path": {"waypoints_m": [[-8, 0], [0, 0], [6, 12]], "speed_m_s": 6}}
            ],
        )
    )
    (node,) = graph.actor_nodes
    seen = []
    for time_s in (0.4, 2.6, 0.4):
        graph.place_actors(time_s)
        for primitive in node.mesh.primitives:
            positions = np.asarray(primitive.positions)
            expected = np.array([positions.min(axis=0), positions.max(axis=0)])
            assert primitive.bounds.dtype == expected.dtype and np.array_equal(primitive.bounds, expected)
        everything = np.concatenate([np.asarray(p.positions, np.float64) for p in node.mesh.primitives])
        assert np.array_equal(node.mesh.bounds, [everything.min(axis=0), everything.max(axis=0)])
        seen.append(node.mesh.bounds.copy())
    assert not np.array_equal(seen[0], seen[1])  # the car drove on: old bounds would not do
    assert np.array_equal(seen[0], seen[2])


@pytest.mark.opengl
def test_a_mesh_added_after_a_draw_is_drawn(renderer):
    graph = build_scene_graph(
        scene_from(
            environment={"meshes": [{"type": "plane", "name": "ground", "size_m": [40, 40]}]},
            lights=[{"type": "ambient", "illuminance_lux": 100}],
        )
    )
    view = View(camera_matrix(300.0, 300.0, 159.5, 119.5), look_at((0.0, -8.0, 4.0), (0.0, 0.0, 0.5)), 320, 240)
    before = renderer.draw(graph, view, ("radiance", "instance_id"))
    box = _box_node("box", _turned(0.4, (0.0, 0.0, 0.5)))
    graph.scene.add_node(box)
    graph.instance_ids[box] = 9
    after = renderer.draw(graph, view, ("radiance", "instance_id"), nodes=[*graph.environment_nodes, box])
    assert not (before.instance_id == 9).any()
    covered = after.instance_id == 9
    assert covered.sum() > 500
    assert not np.array_equal(before.radiance[covered], after.radiance[covered])
    graph.scene.remove_node(box)
    again = renderer.draw(graph, view, ("radiance", "instance_id"))
    assert np.array_equal(again.instance_id, before.instance_id)
    assert np.array_equal(again.radiance, before.radiance)


def _street(**actors):
    return scene_from(
        duration_s=4.0,
        environment={"meshes": [{"type": "plane", "name": "ground", "size_m": [60, 60]}]},
        lights=[{"type": "sun", "illuminance_lux": 20000, "azimuth_deg": 30, "elevation_deg": 40}],
        actors=[
            {"name": "car", "class": "car", "path": {"waypoints_m": [[-8, 0], [0, 0], [6, 12]], "speed_m_s": 6}},
            {"name": "walker", "class": "person", "path": {"waypoints_m": [[2, -3], [2, 5]], "speed_m_s": 1.3}},
        ],
    )


@pytest.mark.opengl
def test_vertices_uploaded_again_are_a_fresh_graphs(renderer):
    """A graph placed and drawn at one time, then another, draws the second as a graph placed there first does:
    the vertex rows kept per primitive (`_upload_deformed`) take each placement's positions and normals."""
    view = View(camera_matrix(300.0, 300.0, 159.5, 119.5), look_at((0.0, -12.0, 5.0), (0.0, 0.0, 0.5)), 320, 240)
    graph = build_scene_graph(_street())
    graph.place_actors(0.5)
    first = renderer.draw(graph, view, ("radiance", "instance_id"))  # uploaded whole, into the context
    graph.place_actors(1.1)
    renderer.draw(graph, view, ("radiance",))  # uploaded again: its rows kept
    graph.place_actors(1.7)
    second = renderer.draw(graph, view, ("radiance", "instance_id"))  # through the kept rows
    fresh = build_scene_graph(_street())
    fresh.place_actors(1.7)
    expected = renderer.draw(fresh, view, ("radiance", "instance_id"))
    assert not np.array_equal(first.instance_id, second.instance_id)  # the actors moved in view
    assert np.array_equal(second.instance_id, expected.instance_id)
    assert np.array_equal(second.radiance, expected.radiance)


@pytest.mark.opengl
def test_a_deformed_primitive_with_new_colours_is_drawn_with_them(renderer):
    """Kept vertex rows are used only while a primitive's other attributes are the arrays they were made with."""
    view = View(camera_matrix(300.0, 300.0, 159.5, 119.5), look_at((0.0, -12.0, 5.0), (0.0, 0.0, 0.5)), 320, 240)
    graph = build_scene_graph(_street())
    for time_s in (0.5, 0.7, 0.9):  # into the context, uploaded whole, then through the kept rows
        graph.place_actors(time_s)
        renderer.draw(graph, view, ("radiance",))
    car = graph.actor_nodes[0]
    coloured = [p for p in car.mesh.primitives if p.color_0 is not None]
    assert coloured, "the car's primitives carry vertex colours"
    for primitive in coloured:
        colours = np.array(primitive.color_0)
        colours[:, :3] = colours[:, :3] * 0.25
        primitive.color_0 = colours
        graph.deformed.add(primitive)
    darker = renderer.draw(graph, view, ("radiance", "instance_id"))
    fresh = build_scene_graph(_street())
    fresh.place_actors(0.9)
    for primitive, changed in zip(fresh.actor_nodes[0].mesh.primitives, car.mesh.primitives, strict=True):
        primitive.color_0 = changed.color_0
    expected = renderer.draw(fresh, view, ("radiance", "instance_id"))
    assert np.array_equal(darker.radiance, expected.radiance)


@pytest.mark.opengl
def test_lights_bound_once_per_program_light_every_primitive_as_bound_each_time(renderer, monkeypatch):
    """A lit draw binds the lights at the first primitive of each program only (`_PassRenderer._bind_lit`); the same
    pixels as binding them for every primitive: textured and plain materials (two programs, the textures on units
    after the lights'), a sun's cascades and a spot light's map."""
    from camgen.render.renderer import _PassRenderer

    scene = scene_from(
        environment={
            "meshes": [
                {"type": "plane", "name": "road", "size_m": [30, 30], "material": {"texture": {"type": "asphalt"}}},
                {"type": "box", "name": "a", "size_m": [1, 1, 2], "position_m": [-1.5, 2, 1]},
                {"type": "box", "name": "b", "size_m": [1, 2, 1], "position_m": [1.5, 0, 0.5],
                 "material": {"texture": {"type": "brick"}}},
                {"type": "box", "name": "c", "size_m": [2, 1, 1], "position_m": [0, -2, 0.5]},
            ]
        },
        lights=[
            {"type": "sun", "illuminance_lux": 20000, "azimuth_deg": 200, "elevation_deg": 35},
            {"type": "spot", "position_m": [0.5, 0.5, 5], "target_m": [0, 0, 0], "intensity_cd": 20000},
            {"type": "ambient", "illuminance_lux": 2000},
        ],
    )  # fmt: skip
    view = View(camera_matrix(320.0, 320.0, 159.5, 119.5), look_at((2.0, -9.0, 6.0), (0.0, 0.0, 0.5)), 320, 240)
    once = renderer.draw(build_scene_graph(scene), view, ("radiance",)).radiance
    full = _PassRenderer._bind_lit

    def every_time(self, scene, program, node, flags, lit_programs):
        lit_programs.clear()
        return full(self, scene, program, node, flags, lit_programs)

    monkeypatch.setattr(_PassRenderer, "_bind_lit", every_time)
    each = renderer.draw(build_scene_graph(scene), view, ("radiance",)).radiance
    assert np.isfinite(once).all() and once.max() > 0.0
    assert np.array_equal(once, each)
