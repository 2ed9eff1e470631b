"""Headless OpenGL works where the suite runs: pyrender over EGL (llvmpipe on CPU-only machines)."""

from __future__ import annotations

import os

import pytest


@pytest.mark.opengl
def test_renderer_runs_headless_over_egl(renderer):
    assert os.environ["PYOPENGL_PLATFORM"] == "egl"
    # "llvmpipe (LLVM …)" on CPU-only machines, the GPU's name where one is present.
    assert renderer.gl_renderer
