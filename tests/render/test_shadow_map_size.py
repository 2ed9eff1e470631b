"""A sun's shadow maps follow the size of the render (`shadow_map_size_texels`): a small render's shadow edge
lies where the sun puts it and is as sharp, in its own pixels, as a large render's."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.render.renderer import View, shadow_map_size_texels
from tests.render.conftest import camera_matrix, look_at, scene_from

pytestmark = pytest.mark.opengl

ELEVATION_DEG = 40.0
WALL_HEIGHT_M = 3.0
WALL_THICKNESS_M = 0.2
VIEW_WIDTH_M = 8.0
"""The overhead views see 8 m × 4 m of ground, the shadow's edge in the middle."""
EDGE_X_M = -(WALL_THICKNESS_M / 2 + WALL_HEIGHT_M / math.tan(math.radians(ELEVATION_DEG)))
"""The closed form: the sun (azimuth 0, towards +x) casts the wall's top far edge to x = −(t/2 + h / tan e)."""


def _overhead(width_px: int) -> View:
    """Straight down from 20 m onto (EDGE_X_M, 0), image x along world x, VIEW_WIDTH_M across `width_px`."""
    f_px = 20.0 * width_px / VIEW_WIDTH_M
    T = look_at((EDGE_X_M, 0.0, 20.0), (EDGE_X_M, 0.0, 0.0))
    return View(camera_matrix(f_px, f_px, (width_px - 1) / 2, (width_px / 2 - 1) / 2), T, width_px, width_px // 2)


@pytest.fixture(scope="module")
def edges(renderer) -> dict[int, tuple[float, float]]:
    """Per render width (px): the shadow edge's mean column (its 50 % crossing, rows averaged) and its
    10-90 % ramp width, both in that render's pixels."""
    from camgen.render.scene_graph import build_scene_graph

    graph = build_scene_graph(
        scene_from(
            environment={
                "meshes": [
                    {"type": "plane", "name": "ground", "size_m": [60.0, 60.0]},
                    {
                        "type": "box",
                        "name": "wall",
                        "size_m": [WALL_THICKNESS_M, 30.0, WALL_HEIGHT_M],
                        "position_m": [0.0, 0.0, WALL_HEIGHT_M / 2],
                    },
                ]
            },
            lights=[
                {"type": "sun", "illuminance_lux": 50000, "azimuth_deg": 0.0, "elevation_deg": ELEVATION_DEG},
                {"type": "ambient", "illuminance_lux": 5000},
            ],
        )
    )
    found = {}
    for width_px in (400, 1600):
        radiance = renderer.draw(graph, _overhead(width_px), ("radiance",)).radiance
        luminance = radiance @ np.array([0.2126, 0.7152, 0.0722])
        shaded, lit = np.percentile(luminance, 5), np.percentile(luminance, 95)
        level = (luminance - shaded) / (lit - shaded)  # 0 in the shadow, 1 on the lit ground beyond its edge
        crossings, ramps = [], []
        for row in level:  # lit ground (left, −x) falls into the shadow between the edge and the wall (right)
            down = np.flatnonzero((row[:-1] >= 0.5) & (row[1:] < 0.5))[0]  # the first: the edge, not the wall
            crossings.append(down + (row[down] - 0.5) / (row[down] - row[down + 1]))
            ramps.append(down + np.flatnonzero(row[down:] < 0.1).min() - np.flatnonzero(row[: down + 1] > 0.9).max())
        found[width_px] = (float(np.mean(crossings)), float(np.median(ramps)))
    return found


def test_small_renders_take_small_maps_and_large_ones_pyrenders_own():
    """Sizes follow the larger side; any view over 1024 px across (1080p and up) keeps 2048 texels."""
    from pyrender.constants import SHADOW_TEX_SZ

    assert shadow_map_size_texels(_overhead(160)) == 512  # the least
    assert shadow_map_size_texels(_overhead(400)) == 512
    assert shadow_map_size_texels(_overhead(640)) == 1024
    for width, height in ((1280, 720), (1920, 1080), (1080, 1920), (3840, 2160)):
        view = View(camera_matrix(1000.0, 1000.0, width / 2, height / 2), np.eye(4), width, height)
        assert shadow_map_size_texels(view) == SHADOW_TEX_SZ


def test_a_small_renders_shadow_edge_is_where_and_as_sharp_as_a_large_renders(edges):
    """A 3 m wall, 20 cm thick, under a sun 40° high: its shadow's edge is a straight line 3.675 m behind its
    axis. Seen from 20 m straight down, 400 px across (512-texel maps) and 1600 px across (2048 texels), each
    render's edge lies within a pixel of the closed form, the small one within a pixel of the large one's
    scaled down, and its ramp is no wider in its pixels than the large one's in its own, plus one."""
    columns = {width_px: (width_px - 1) / 2 for width_px in edges}  # the closed form's edge: the image centre
    for width_px, (column, _) in edges.items():
        print(f"{width_px} px: edge at column {column:.2f} (closed form {columns[width_px]:.2f})")
        assert column == pytest.approx(columns[width_px], abs=1.0)
    (small, small_ramp), (large, large_ramp) = edges[400], edges[1600]
    scale = 400 / 1600
    assert small == pytest.approx((large + 0.5) * scale - 0.5, abs=1.0)
    print(f"10-90 % ramp: {small_ramp:.0f} px at 400 px, {large_ramp:.0f} px at 1600 px")
    assert small_ramp <= large_ramp + 1
