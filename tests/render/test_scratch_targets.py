"""Draws taking turns at two sizes or sets of passes keep a target each (`Renderer._framebuffer`'s scratch
targets) instead of making it again at every turn, and draw the same pixels; at most `SCRATCH_FRAMEBUFFERS`
are kept."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.render.renderer import SCRATCH_FRAMEBUFFERS, View, _Framebuffer
from camgen.render.scene_graph import build_scene_graph
from tests.render.conftest import camera_matrix, look_at, scene_from

pytestmark = pytest.mark.opengl


def _view(width_px: int, height_px: int) -> View:
    f_px = 0.9 * width_px
    K = camera_matrix(f_px, f_px, (width_px - 1) / 2, (height_px - 1) / 2)
    return View(K, look_at((0.0, -6.0, 2.0), (0.0, 2.0, 0.5)), width_px, height_px)


def test_alternating_draws_keep_their_targets_and_pixels(renderer, monkeypatch):
    graph = build_scene_graph(
        scene_from(
            environment={"meshes": [
                {"type": "plane", "name": "ground", "size_m": [30, 30]},
                {"type": "box", "name": "block", "size_m": [1, 1, 2], "position_m": [0, 2, 1]},
            ]},
            lights=[{"type": "sun", "illuminance_lux": 50000, "elevation_deg": 40},
                    {"type": "ambient", "illuminance_lux": 5000}],
        )
    )  # fmt: skip
    fine, coarse = _view(320, 240), _view(160, 120)
    made: list[tuple] = []
    making = _Framebuffer.__init__

    def counted(self, width_px, height_px, passes):
        made.append((width_px, height_px, passes))
        making(self, width_px, height_px, passes)

    monkeypatch.setattr(_Framebuffer, "__init__", counted)
    first = None
    after_first = None
    for _ in range(3):  # a frame's supersampled radiance, then its depth and ids, then an actor's ids
        if first is not None and after_first is None:
            after_first = len(made)
        radiance = renderer.draw(graph, fine, ("radiance",)).radiance
        geometry = renderer.draw(graph, coarse, ("depth_m", "instance_id"))
        ids = renderer.draw(graph, coarse, ("instance_id",), crop_px=(40, 30, 120, 90)).instance_id
        drawn = (radiance, geometry.depth_m, geometry.instance_id, ids)
        if first is None:
            first = drawn
        for now, then in zip(drawn, first, strict=True):
            np.testing.assert_array_equal(now, then)
    # One target each, made once: at most three in the first round (fewer where an earlier test of this session's
    # shared renderer left one of these sizes), none after it.
    assert len(made) == len(set(made)) <= 3 and len(made) == after_first, made
    assert np.ptp(first[0]) > 0 and (first[2] > 0).any()
    for size in range(6):  # more sizes than are kept: the oldest go
        renderer.draw(graph, _view(64 + 16 * size, 48), ("instance_id",))
    assert len(renderer._scratch) == SCRATCH_FRAMEBUFFERS
