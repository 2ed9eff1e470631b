"""Building pyrender meshes from scene shapes (what cannot be drawn is refused with a clear error), and the
scene's lights in a fixed order."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from camgen.config.scene import FileMesh
from camgen.errors import ConfigError
from tests.render.conftest import look_at, scene_from

pytestmark = pytest.mark.opengl


def test_a_point_cloud_file_is_refused(tmp_path):
    from camgen.render.scene_graph import build_mesh

    trimesh.PointCloud(np.random.default_rng(0).random((20, 3))).export(tmp_path / "cloud.ply")
    shape = FileMesh.model_validate({"type": "file", "name": "cloud", "path": "cloud.ply"})
    with pytest.raises(ConfigError, match="holds no triangles"):
        build_mesh(shape, tmp_path.joinpath)


def _street_of_lamps():
    """Four street lamps (spot lights, the renderer's most) and three point lights, listed in that order."""
    from camgen.render.scene_graph import build_scene_graph

    lamps = [
        {
            "type": "spot",
            "position_m": [4.0 * k - 6.0, 2.0 * (k % 2) - 1.0, 5.0],
            "target_m": [4.0 * k - 6.0, 0.0, 0.0],
            "intensity_cd": 1000.0 + 100.0 * k,
            "color_rgb": [1.0, 0.9 - 0.05 * k, 0.7],
        }
        for k in range(4)
    ]
    bulbs = [
        {"type": "point", "position_m": [3.0 * k - 3.0, 3.0, 2.5], "intensity_cd": 300.0 + 50.0 * k} for k in range(3)
    ]
    return build_scene_graph(
        scene_from(
            environment={"meshes": [{"type": "plane", "name": "road", "size_m": [30, 10]}], "shadows": False},
            lights=[{"type": "ambient", "illuminance_lux": 0.5}, *lamps, *bulbs],
        )
    )


def test_lights_are_bound_in_the_order_the_scene_lists_them_so_a_frame_is_the_same_in_every_run(renderer):
    # pyrender keeps lights in sets (ordered by memory address, different in every run) and the shader sums
    # them in that order: the night street's frames differed in their last bits between runs.
    from camgen.render.renderer import View

    first = _street_of_lamps()
    spots, points = first.scene.spot_light_nodes, first.scene.point_light_nodes
    for nodes in (spots, points):  # the order of `lights:` (intensities rising within each kind)
        intensities = [node.light.intensity for node in nodes]
        assert intensities == sorted(intensities) and len(set(intensities)) == len(intensities)
    assert list(first.scene.light_nodes) == [*spots, *points]
    junk = [bytearray(k * 37) for k in range(200)]  # other addresses for the second graph's nodes
    second = _street_of_lamps()
    del junk
    view = View(np.array([[150.0, 0, 79.5], [0, 150.0, 59.5], [0, 0, 1]]), look_at((0, -12, 6), (0, 0, 0)), 160, 120)
    a = renderer.draw(first, view, ("radiance",)).radiance
    b = renderer.draw(second, view, ("radiance",)).radiance
    assert a.max() > 0.1
    np.testing.assert_array_equal(a, b)


def test_a_draw_shades_the_still_environment_near_to_far_then_what_moves_near_to_far():
    # camgen.render.renderer.front_to_back: near first lets the depth test drop hidden fragments before they
    # are shaded; still before moving keeps a kept background's ties.
    from camgen.render.renderer import front_to_back
    from camgen.render.scene_graph import build_scene_graph

    boxes = [
        {"type": "box", "name": f"box_{k}", "size_m": [1, 1, 1], "position_m": [x, 0, 0.5]}
        for k, x in enumerate([30.0, 5.0, 15.0])
    ]
    graph = build_scene_graph(
        scene_from(
            environment={"meshes": boxes, "shadows": False},
            lights=[{"type": "ambient", "illuminance_lux": 100}],
            actors=[
                {"name": "far", "class": "other", "path": {"waypoints_m": [[40, 2]]}},
                {"name": "near", "class": "other", "path": {"waypoints_m": [[3, 2]]}},
            ],
        )
    )
    camera_m = np.zeros(3)
    names = [node.name for node in front_to_back(graph, graph.actor_nodes + graph.environment_nodes, camera_m)]
    still = [node.name for node in graph.environment_nodes]
    assert names[: len(still)] == ["environment:box_1", "environment:box_2", "environment:box_0"]
    near, far = graph.actor_nodes[1].name, graph.actor_nodes[0].name
    assert names[len(still) :] == [near, far]
