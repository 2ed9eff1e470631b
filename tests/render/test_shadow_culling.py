"""A shadow map's pass leaves out the meshes whose box lies beyond its view (`meshes_reach_clip_volume`): the
maps, and the frames shaded from them, are the same bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.render.renderer import SUN_CASCADES, View, gl_projection, meshes_reach_clip_volume
from tests.render.conftest import camera_matrix, look_at, scene_from


class _Primitive:
    def __init__(self, low, high, poses=None):
        self.bounds, self.poses = np.array([low, high], float), poses


class _Mesh:
    def __init__(self, *primitives):
        self.primitives = primitives

    @property
    def bounds(self) -> np.ndarray:
        """pyrender's `Mesh.bounds`: the least and greatest of its primitives' bounds."""
        bounds = np.array([primitive.bounds for primitive in self.primitives])
        return np.array([bounds[:, 0].min(axis=0), bounds[:, 1].max(axis=0)])


def _projections() -> dict[str, np.ndarray]:
    """P·V of an orthographic map (a sun's: 20 m × 10 m, depth 0-30 m) and of a perspective one (a lamp's)."""
    ortho = np.diag([2 / 20.0, 2 / 10.0, -2 / 30.0, 1.0])
    ortho[2, 3] = -1.0
    V = np.linalg.inv(look_at((0.0, -5.0, 6.0), (1.0, 3.0, 0.0)) @ np.diag([1.0, -1.0, -1.0, 1.0]))
    perspective = gl_projection(camera_matrix(300.0, 300.0, 319.5, 239.5), 640, 480, 0.5, 40.0) @ V
    return {"orthographic": ortho, "perspective": perspective}


@pytest.mark.parametrize("kind", ["orthographic", "perspective"])
def test_a_box_is_left_out_only_when_none_of_it_is_in_the_view(kind):
    """Against a dense sampling of each box (11³ points, corners included): a box said to be out has no
    sampled point inside −w ≤ x, y, z ≤ w, and a box with one inside is said to reach it; both kinds occur."""
    P_V = _projections()[kind]
    rng = np.random.default_rng(11)
    grid = np.stack(np.meshgrid(*[np.linspace(0.0, 1.0, 11)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    meshes, poses, inside = [], [], []
    for _ in range(300):
        low = rng.uniform([-20.0, -20.0, -25.0], [15.0, 15.0, 5.0])
        high = low + rng.uniform(0.1, 8.0, 3)
        a = rng.uniform(0.0, 2 * math.pi)
        pose = np.eye(4)
        pose[:3, :3] = [[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]]
        pose[:3, 3] = rng.uniform(-5.0, 5.0, 3)
        points = (low + grid * (high - low)) @ pose[:3, :3].T + pose[:3, 3]
        clip = np.c_[points, np.ones(len(points))] @ P_V.T
        inside.append(np.all(np.abs(clip[:, :3]) <= clip[:, 3:], axis=1).any())
        split = low + rng.uniform(0.0, 1.0, 3) * (high - low)  # two primitives sharing the box
        meshes.append(
            _Mesh(_Primitive(low, np.maximum(split, low + 0.05)), _Primitive(np.minimum(split, high - 0.05), high))
        )
        poses.append(pose)
    reaches = meshes_reach_clip_volume(meshes, np.array(poses), P_V)
    assert np.all(reaches | ~np.array(inside))
    assert 30 < reaches.sum() < 270, reaches.sum()


def test_instanced_primitives_are_always_drawn():
    """pyrender's bounds of instances add their translations only (not their rotations or scales)."""
    far_away = _Primitive([1000.0, 1000.0, 1000.0], [1001.0, 1001.0, 1001.0])
    instanced = _Primitive([1000.0, 1000.0, 1000.0], [1001.0, 1001.0, 1001.0], poses=np.eye(4)[None])
    meshes = [_Mesh(far_away), _Mesh(far_away, instanced)]
    reaching = meshes_reach_clip_volume(meshes, np.array([np.eye(4)] * 2), _projections()["orthographic"])
    assert reaching.tolist() == [False, True]


@pytest.mark.opengl
@pytest.mark.parametrize("light", ["sun", "lamp"])
def test_culled_shadow_passes_shade_the_same_frame(renderer, light, monkeypatch):
    """Posts along a 60 m street under a sun (three cascades) and under a lamp: with the meshes beyond each
    map left out, a 160×120 view of a few of them gets the same shadow maps (read back) and draws the same
    radiance, bit for bit, as with passes that draw every mesh."""
    import pyrender

    from camgen.render.renderer import _PassRenderer
    from camgen.render.scene_graph import build_scene_graph

    posts = [
        {"type": "box", "name": f"post{i}", "size_m": [0.3, 0.3, 3.0], "position_m": [x, 2.0, 1.5]}
        for i, x in enumerate(range(-30, 31, 4))
    ]
    lights = {
        "sun": {"type": "sun", "illuminance_lux": 50000, "azimuth_deg": 150.0, "elevation_deg": 35.0},
        "lamp": {"type": "lamp", "position_m": [0.0, 0.0, 6.0], "target_m": [0.0, 3.0, 0.0], "flux_lm": 6000},
    }
    graph = build_scene_graph(
        scene_from(
            environment={"meshes": [{"type": "plane", "name": "ground", "size_m": [80.0, 80.0]}, *posts]},
            lights=[lights[light], {"type": "ambient", "illuminance_lux": 50}],
        )
    )
    view = View(camera_matrix(120.0, 120.0, 79.5, 59.5), look_at((0.0, -4.0, 2.0), (0.0, 4.0, 0.5)), 160, 120)
    drawn: list[int] = []
    culling = _PassRenderer._sorted_mesh_nodes

    def counted(self, scene):
        nodes = culling(self, scene)
        drawn.append(len(nodes))
        return nodes

    monkeypatch.setattr(renderer._renderer, "keep_still_casters", False)  # every pass draws its casters
    culled = renderer.draw(graph, view, ("radiance",)).radiance
    culled_maps = _shadow_maps(renderer, graph)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(_PassRenderer, "_sorted_mesh_nodes", counted)
        renderer.draw(graph, view, ("radiance",))
        patch.setattr(_PassRenderer, "_sorted_mesh_nodes", pyrender.Renderer._sorted_mesh_nodes)
        every = renderer.draw(graph, view, ("radiance",)).radiance
        every_maps = _shadow_maps(renderer, graph)
    print(f"{light}: meshes drawn per map {drawn} of {len(posts) + 1}")
    assert min(drawn) < len(posts) + 1
    assert len(culled_maps) == (3 if light == "sun" else 1)
    for culled_map, every_map in zip(culled_maps, every_maps, strict=True):
        assert np.array_equal(culled_map, every_map)
        assert np.ptp(culled_map) > 0  # a map with something in it
    assert np.array_equal(culled, every)
    assert np.ptp(culled) > 0  # a lit, shadowed frame


def _shadow_maps(renderer, graph) -> list[np.ndarray]:
    """The depths of the last draw's shadow maps (each sun's cascades, each spot light's map)."""
    from OpenGL import GL
    from pyrender.light import DirectionalLight, SpotLight

    passes = renderer._renderer
    depths = []
    for node in graph.scene.light_nodes:
        if isinstance(node.light, DirectionalLight):  # a layer of its array per cascade
            from OpenGL.raw.GL.VERSION.GL_1_1 import glGetTexImage  # PyOpenGL's wrapper knows no 2D arrays

            size = passes.shadow_map_texels
            layers = np.zeros((SUN_CASCADES, size * size), np.float32)
            GL.glBindTexture(GL.GL_TEXTURE_2D_ARRAY, passes._sun_cascade_array(node.light))
            glGetTexImage(GL.GL_TEXTURE_2D_ARRAY, 0, GL.GL_DEPTH_COMPONENT, GL.GL_FLOAT, layers)
            depths += list(layers)
        elif isinstance(node.light, SpotLight):
            GL.glBindTexture(GL.GL_TEXTURE_2D, node.light.shadow_texture._texid)
            data = GL.glGetTexImage(GL.GL_TEXTURE_2D, 0, GL.GL_DEPTH_COMPONENT, GL.GL_FLOAT)
            depths.append(np.frombuffer(data, np.float32).copy())
    return depths
