"""Occlusion and pixel density of camgen.coverage against a render of the same scene: the depth pass says
which grid points the camera sees, and a rendered 1 m target's image length gives the density."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.coverage.density import densities
from camgen.coverage.grid import make_grid
from camgen.coverage.network import camera_coverage
from camgen.coverage.occlusion import inside_solids, scene_occluders
from camgen.optics.projection import project_points
from camgen.render.renderer import View
from camgen.render.scene_graph import build_scene_graph
from tests.coverage.conftest import F_PX, HEIGHT_PX, WIDTH_PX, look_at_pitch_deg, pinhole_view, scene_with

pytestmark = pytest.mark.opengl

GROUND = {"type": "plane", "name": "ground", "size_m": [40, 40]}
BOX = {"type": "box", "name": "van", "size_m": [1.0, 3.0, 1.5], "position_m": [0, 0, 0.75], "rotation_deg": [0, 0, 20]}
POST = {"type": "cylinder", "name": "post", "radius_m": 0.3, "height_m": 3.0, "position_m": [4, -2, 1.5]}


def test_occlusion_agrees_with_the_rendered_depth(renderer):
    scene = scene_with([GROUND, BOX, POST])
    occluders = scene_occluders(scene)
    view = pinhole_view((-10.0, 0.5, 3.0), pitch_deg=look_at_pitch_deg(3.0, 12.0))
    grid = make_grid((-2.0, 12.0, -6.0, 6.0), 0.25, 0.0)
    coverage = camera_coverage(grid, view, occluders)
    depth_m = renderer.draw(
        build_scene_graph(scene), View(view.K_px, view.T_world_from_cam, WIDTH_PX, HEIGHT_PX), ("depth_m",)
    ).depth_m
    points = grid.points_m()
    considered = coverage.in_view.ravel() & ~inside_solids(points, occluders)
    uv, depth = project_points(points[considered], view.T_world_from_cam, view.K_px, view.distortion)
    u = np.clip(np.round(uv[:, 0]).astype(int), 0, WIDTH_PX - 1)
    v = np.clip(np.round(uv[:, 1]).astype(int), 0, HEIGHT_PX - 1)
    seen_by_render = depth_m[v, u] >= depth * 0.99 - 0.02
    seen = coverage.visible.ravel()[considered]
    assert (~seen).sum() > 50  # the van and the post hide real areas
    assert np.mean(seen == seen_by_render) >= 0.99


def test_vertical_density_matches_a_rendered_one_metre_target(renderer):
    # A 1 m tall, thin vertical board 4 m in front of a level camera: its rendered height in pixels
    # (100 px, so one pixel of rasterisation is 1 %).
    target = {"type": "box", "name": "target", "size_m": [0.02, 0.3, 1.0], "position_m": [4.0, 0.0, 1.6]}
    scene = scene_with([target])
    view = pinhole_view((0.0, 0.0, 1.6))
    _, dens = densities(np.array([[4.0 - 0.01, 0.0, 1.6]]), 1.6, view)
    depth_m = renderer.draw(
        build_scene_graph(scene), View(view.K_px, view.T_world_from_cam, WIDTH_PX, HEIGHT_PX), ("depth_m",)
    ).depth_m
    column = np.isfinite(depth_m[:, WIDTH_PX // 2])
    rendered_px_m = column.sum() / 1.0
    assert dens.vertical_px_m[0] == pytest.approx(F_PX / 3.99, rel=1e-6)
    assert rendered_px_m == pytest.approx(dens.vertical_px_m[0], rel=0.02)
