"""Headless OpenGL works where the suite runs: pyrender over EGL (llvmpipe on CPU-only machines)."""

from __future__ import annotations

import os

import numpy as np
import pytest


@pytest.mark.opengl
def test_pyrender_renders_headless_over_egl():
    from camgen.render.gl import pyrender

    assert os.environ["PYOPENGL_PLATFORM"] == "egl"
    import trimesh

    scene = pyrender.Scene(bg_color=(0, 0, 0, 0), ambient_light=(1.0, 1.0, 1.0))
    scene.add(pyrender.Mesh.from_trimesh(trimesh.creation.box((1.0, 1.0, 1.0))))
    pose = np.eye(4)
    pose[2, 3] = 3.0  # OpenGL camera looks down −z; the unit box sits 2.5 m in front
    scene.add(pyrender.PerspectiveCamera(yfov=0.8), pose=pose)
    renderer = pyrender.OffscreenRenderer(64, 48)
    try:
        _, depth = renderer.render(scene)
    finally:
        renderer.delete()
    assert depth[24, 32] == pytest.approx(2.5, rel=1e-3)
    assert depth[0, 0] == 0.0
