"""A sun's cascade starts from the kept depths of the casters that held still since its last draw with the same
matrices (`_StillCasters`, `_PassRenderer._sun_shadow_pass`): the maps and the frames are those of passes
that draw every caster, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

import camgen.render.renderer as renderer_module
from camgen.render.renderer import ShadowFit, View, _StillCasters, _texel_rects, caster_versions
from tests.render.conftest import camera_matrix, look_at, scene_from
from tests.render.test_shadow_culling import _shadow_maps


class _Node:
    pass


def test_the_kept_set_is_what_held_still_under_the_same_matrices():
    """First pass: nothing to compare with. Second, same light, size and matrix: the nodes whose counts held are
    drawn and kept. Third: a hit, the kept ones copied. A kept node's count rising ends the hit (and keeps the
    rest, which held); another matrix, another size, another scene or an uncounted node keep nothing."""
    still, parked, walker, uncounted = _Node(), _Node(), _Node(), _Node()
    scene, light = _Node(), _Node()
    nodes = [still, parked, walker, uncounted]
    matrix = np.eye(4)
    casters = _StillCasters()

    def plan(counts, *, matrix=matrix, size=2048, scene=scene, layer=0):
        versions = {id(node): count for node, count in zip(nodes, counts, strict=True) if count is not None}
        mode, kept, drawn = casters.plan(scene, light, layer, size, matrix, nodes, versions)
        assert sorted(map(id, kept + drawn)) == sorted(map(id, nodes))  # a split of the nodes
        return mode, {nodes.index(n) for n in kept}

    assert plan([0, 0, 1, None]) == ("none", set())
    assert plan([0, 0, 2, None]) == ("keep", {0, 1})
    assert plan([0, 0, 3, None]) == ("hit", {0, 1})
    assert plan([0, 0, 4, None], layer=1) == ("none", set())  # each cascade its own
    assert plan([0, 1, 4, None]) == ("keep", {0})  # the parked car moved: only the still one is kept
    assert plan([0, 1, 5, None]) == ("hit", {0})
    assert plan([0, 1, 6, None], matrix=2 * matrix) == ("none", set())  # the light or the fit moved
    assert plan([0, 1, 7, None], matrix=2 * matrix) == ("keep", {0, 1})
    assert plan([0, 1, 8, None], size=1024, matrix=2 * matrix) == ("none", set())
    assert plan([0, 1, 9, None], scene=_Node(), matrix=2 * matrix) == ("none", set())


@pytest.mark.opengl
def test_kept_casters_shade_the_same_frames(renderer, monkeypatch):
    """Posts on a street under a low sun, a box walking between them and a car that waits, then drives off,
    seen by a held 160×120 view whose shadows are fitted to a fixed box (as a sequence's are): over six times the
    passes keep the still casters' depths (the car's while it waits: hits), and every map and frame equals, bit
    for bit, the draw of every caster."""
    from camgen.render.renderer import _PassRenderer
    from camgen.render.scene_graph import build_scene_graph

    posts = [
        {"type": "box", "name": f"post{i}", "size_m": [0.3, 0.3, 3.0], "position_m": [x, 2.0, 1.5]}
        for i, x in enumerate(range(-12, 13, 3))
    ]
    box = {"type": "box", "size_m": [0.5, 0.5, 1.8], "position_m": [0.0, 0.0, 0.9]}
    graph = build_scene_graph(
        scene_from(
            environment={"meshes": [{"type": "plane", "name": "ground", "size_m": [60.0, 60.0]}, *posts]},
            lights=[
                {"type": "sun", "illuminance_lux": 50000, "azimuth_deg": 200.0, "elevation_deg": 25.0},
                {"type": "ambient", "illuminance_lux": 5000},
            ],
            actors=[
                {"name": "walker", "class": "person", "shape": {**box, "name": "walker_body"},
                 "path": {"waypoints_m": [[-6.0, 4.0], [6.0, 4.0]], "speed_m_s": 4.0}},
                {"name": "car", "class": "car", "vehicle": {"seed": 3, "body_type": "hatchback"},
                 "path": {"waypoints_m": [[-8.0, 8.0], [8.0, 8.0]], "speed_m_s": 8.0, "start_s": 0.5}},
            ],
        )
    )  # fmt: skip
    view = View(camera_matrix(110.0, 110.0, 79.5, 59.5), look_at((0.0, -6.0, 3.0), (0.0, 3.0, 0.5)), 160, 120)
    fit = ShadowFit(view, np.array([-30.0, -30.0, 0.0]), np.array([30.0, 30.0, 3.0]))
    plans: list[str] = []
    planning = _StillCasters.plan

    def counted(self, *args):
        result = planning(self, *args)
        plans.append(result[0])
        return result

    monkeypatch.setattr(_StillCasters, "plan", counted)
    copied: list[tuple[int, int]] = []  # (width, height) of each copy of texels between the layers
    copy = renderer_module.GL.glCopyImageSubData

    def counted_copy(*args):
        copied.append((args[-3], args[-2]))
        return copy(*args)

    monkeypatch.setattr(renderer_module.GL, "glCopyImageSubData", counted_copy)

    def frames(keep: bool) -> list[tuple[np.ndarray, list[np.ndarray]]]:
        monkeypatch.setattr(renderer._renderer, "keep_still_casters", keep)
        out = []
        for time_s in np.linspace(0.0, 1.0, 6):
            graph.place_actors(float(time_s))
            radiance = renderer.draw(graph, view, ("radiance",), shadow_fit=fit).radiance
            out.append((radiance, _shadow_maps(renderer, graph)))
        return out

    kept, every = frames(True), frames(False)
    assert plans.count("hit") >= 3 * 3, plans  # each cascade at 0.4 s and, once the car drove off, again
    size = renderer._renderer.shadow_map_texels
    partial = [(w, h) for w, h in copied if w * h < size * size]
    assert len(partial) >= 3, copied  # hits after a pass of the same kept set restored only what it drew over
    assert len(caster_versions(graph)) == len(posts) + 3  # the ground, the posts, the walker and the car
    for (kept_radiance, kept_maps), (radiance, maps) in zip(kept, every, strict=True):
        assert len(maps) == 3
        for kept_map, every_map in zip(kept_maps, maps, strict=True):
            assert np.array_equal(kept_map, every_map)
        assert np.array_equal(kept_radiance, radiance)
    assert not np.array_equal(kept[0][0], kept[-1][0])  # the walker and its shadow moved
    assert not all(np.array_equal(a, b) for a, b in zip(kept[0][1], kept[-1][1], strict=True))
    assert _PassRenderer is type(renderer._renderer)


@pytest.mark.opengl
def test_a_casters_texels_lie_in_its_texel_rectangle(renderer, monkeypatch):
    """`_texel_rects` bounds what a depth-only draw of a node writes to each cascade: a walker and a car drawn
    alone (every other mesh hidden) into the maps of a held view write texels, and every one of them lies in
    the node's rectangle of that cascade, which is not much larger than the texels written."""
    from pyrender.light import DirectionalLight

    from camgen.render.scene_graph import build_scene_graph

    graph = build_scene_graph(
        scene_from(
            environment={"meshes": [{"type": "plane", "name": "ground", "size_m": [60.0, 60.0]}]},
            lights=[{"type": "sun", "illuminance_lux": 50000, "azimuth_deg": 150.0, "elevation_deg": 40.0}],
            actors=[
                {"name": "walker", "class": "person",
                 "path": {"waypoints_m": [[-2.0, 3.0], [4.0, 5.0]], "speed_m_s": 1.4}},
                {"name": "car", "class": "car", "vehicle": {"seed": 4, "body_type": "sedan"},
                 "path": {"waypoints_m": [[-6.0, 9.0], [8.0, 9.0]], "speed_m_s": 6.0}},
            ],
        )
    )  # fmt: skip
    view = View(camera_matrix(150.0, 150.0, 79.5, 59.5), look_at((0.0, -6.0, 4.0), (0.0, 6.0, 0.5)), 160, 120)
    fit = ShadowFit(view, np.array([-30.0, -30.0, 0.0]), np.array([30.0, 30.0, 3.0]))
    monkeypatch.setattr(renderer._renderer, "keep_still_casters", False)
    graph.place_actors(1.0)
    sun = next(node for node in graph.scene.light_nodes if isinstance(node.light, DirectionalLight))
    for alone in graph.actor_nodes:
        hidden = [node for node in graph.scene.mesh_nodes if node is not alone]
        for node in hidden:
            node.mesh.is_visible = False
        try:
            renderer.draw(graph, view, ("radiance",), shadow_fit=fit)
            maps = _shadow_maps(renderer, graph)
        finally:
            for node in hidden:
                node.mesh.is_visible = True
        size = renderer._renderer.shadow_map_texels
        written_somewhere = False
        for cascade, depths in enumerate(maps):
            V, P = renderer._renderer._sun_cascades[id(sun)][cascade]
            rows, cols = np.nonzero(depths.reshape(size, size) < 1.0)
            rects = _texel_rects(graph.scene, [alone], P @ V, size)
            if not len(rows):
                continue
            written_somewhere = True
            assert len(rects) == 1, (alone.name, cascade, rects)
            x0, y0, x1, y1 = rects[0]
            assert np.all((cols >= x0) & (cols < x1) & (rows >= y0) & (rows < y1)), (alone.name, cascade, rects)
            written = (cols.max() - cols.min() + 1) * (rows.max() - rows.min() + 1)
            assert (x1 - x0) * (y1 - y0) < 2 * written + 4 * (x1 - x0 + y1 - y0), (alone.name, cascade, rects)
        assert written_somewhere, alone.name
