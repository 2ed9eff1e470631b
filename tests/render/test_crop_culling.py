"""A draw leaves out the meshes whose box lies wholly outside its frustum, or the frustum of the part of the
view it fills (`camgen.render.renderer._nodes_reaching_crop`); the pixels stay those of the whole draw
(tests/render/test_still_frames.py, test_moving_regions.py)."""

from __future__ import annotations

import numpy as np
import pyrender
import trimesh

from camgen.render.renderer import View, _nodes_reaching_crop, gl_camera_pose
from tests.render.conftest import look_at

WIDTH_PX, HEIGHT_PX = 200, 100


def _scene_and_view():
    scene = pyrender.Scene()
    nodes = {}
    # The camera at the origin looks along +y; x grows to the image's right.
    for name, centre in {
        "left": (-3.0, 10.0, 0.0),
        "right": (3.0, 10.0, 0.0),
        "behind": (0.0, -5.0, 0.0),
        "straddling": (-0.6, 0.0, 0.0),  # reaches from behind the camera to in front of its left half
    }.items():
        extents = (1.0, 3.0, 1.0) if name == "straddling" else (1.0, 1.0, 1.0)
        mesh = pyrender.Mesh.from_trimesh(trimesh.creation.box(extents=extents))
        nodes[name] = scene.add(mesh, pose=trimesh.transformations.translation_matrix(centre))
    K = np.array([[100.0, 0.0, WIDTH_PX / 2 - 0.5], [0.0, 100.0, HEIGHT_PX / 2 - 0.5], [0.0, 0.0, 1.0]])
    view = View(K, look_at((0.0, 0.0, 0.0), (0.0, 1.0, 0.0)), WIDTH_PX, HEIGHT_PX)
    return scene, nodes, view


def _kept(scene, nodes, view, crop):
    V = np.linalg.inv(gl_camera_pose(view.T_world_from_cam))
    kept = _nodes_reaching_crop(scene, list(nodes.values()), view, crop, V, 0.05, 100.0)
    return {name for name, node in nodes.items() if node in kept}


def test_a_crop_keeps_the_meshes_in_its_part_of_the_view_only():
    scene, nodes, view = _scene_and_view()
    assert _kept(scene, nodes, view, (0, 0, WIDTH_PX, HEIGHT_PX)) == {"left", "right", "straddling"}
    assert _kept(scene, nodes, view, (0, 0, WIDTH_PX // 2, HEIGHT_PX)) == {"left", "straddling"}
    # Conservative: a box reaching behind the camera may be kept where it cannot reach (its corners
    # behind lie on the inner side of the far-side plane); one wholly beyond a plane never is.
    assert _kept(scene, nodes, view, (WIDTH_PX // 2 + 20, 0, WIDTH_PX, HEIGHT_PX)) - {"straddling"} == {"right"}


def test_a_mesh_just_outside_a_crop_is_kept_within_the_pad():
    scene, nodes, view = _scene_and_view()
    # The right box's image starts at u = 99.5 + 100·2.5/10.5 ≈ 123.3; a crop ending at 123 is within 2 px.
    assert "right" in _kept(scene, nodes, view, (110, 0, 123, HEIGHT_PX))
    assert "right" not in _kept(scene, nodes, view, (100, 0, 118, HEIGHT_PX))
