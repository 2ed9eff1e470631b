"""The ground continued to the horizon (`camgen.render.scene_graph.FarGround`): a camera looking over the
edge of a 20 × 20 m ground plane sees, under the horizon, a uniform ground of the plane's reflectance lit
as the plane is (Lambert: ρ/π·(E_sky + E_sun·sin h)), and the sky only above the geometric horizon; fog
thins it by its own distance (Koschmieder); it is a backdrop, with no depth and no instance id."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.render.renderer import View
from camgen.render.scene_graph import build_scene_graph
from tests.render.conftest import camera_matrix, look_at, scene_from

pytestmark = pytest.mark.opengl

WIDTH_PX, HEIGHT_PX = 160, 120
F_PX = 100.0
CAMERA_HEIGHT_M = 3.0
REFLECTANCE = 0.2
SKY_CD_M2 = 3000.0
E_SKY_LUX, E_SUN_LUX, SUN_ELEVATION_DEG = 10_000.0, 50_000.0, 30.0


def draw(renderer, *, ground_to_horizon: bool = True, fog_visibility_m: float | None = None):
    environment = {
        "meshes": [
            {"type": "plane", "name": "ground", "size_m": [20, 20], "material": {"color_rgb": [REFLECTANCE] * 3}}
        ],
        "sky_luminance_cd_m2": SKY_CD_M2,
        "shadows": False,
        "ground_to_horizon": ground_to_horizon,
    }
    if fog_visibility_m is not None:
        environment["fog"] = {"visibility_m": fog_visibility_m}
    scene = scene_from(
        environment=environment,
        lights=[
            {"type": "ambient", "illuminance_lux": E_SKY_LUX},
            {"type": "sun", "illuminance_lux": E_SUN_LUX, "elevation_deg": SUN_ELEVATION_DEG, "azimuth_deg": 90},
        ],
    )
    # Looking level along +X from 3 m: the horizon is the middle row; the plane ends 10 m ahead, 30 px
    # under it (3 m / 10 m · 100 px), so the rows between show the far ground.
    view = View(
        camera_matrix(F_PX, F_PX, (WIDTH_PX - 1) / 2, (HEIGHT_PX - 1) / 2),
        look_at((0, 0, CAMERA_HEIGHT_M), (1, 0, CAMERA_HEIGHT_M)),
        WIDTH_PX,
        HEIGHT_PX,
    )
    return renderer.draw(build_scene_graph(scene), view, ("radiance", "depth_m", "instance_id"))


def row_below_horizon_px(distance_m: float) -> float:
    """Image row of the ground at `distance_m` ahead."""
    return (HEIGHT_PX - 1) / 2 + F_PX * CAMERA_HEIGHT_M / distance_m


def test_the_far_ground_is_lit_as_the_plane_is_and_meets_the_sky_at_the_horizon(renderer):
    passes = draw(renderer)
    lambert = REFLECTANCE / math.pi * (E_SKY_LUX + E_SUN_LUX * math.sin(math.radians(SUN_ELEVATION_DEG)))
    far = passes.radiance[int(row_below_horizon_px(40.0)), WIDTH_PX // 2]
    np.testing.assert_allclose(far, lambert, rtol=1e-5)
    # Under the horizon down to the plane's edge: far ground; above it: the sky.
    edge_row = row_below_horizon_px(10.0)
    column = passes.radiance[:, WIDTH_PX // 2, 1]
    sky_rows = np.flatnonzero(column == SKY_CD_M2)
    assert sky_rows.max() == HEIGHT_PX // 2 - 1  # rows 0…59: rays at or above the horizon
    far_rows = np.flatnonzero(np.isclose(column, lambert, rtol=1e-5))
    assert far_rows.min() == HEIGHT_PX // 2 and far_rows.max() < edge_row
    # The plane itself, just inside its edge, is within the rough dielectric's specular of the same value.
    assert lambert <= column[int(edge_row) + 2] <= 1.15 * lambert
    # A backdrop: no depth, no id.
    behind = slice(HEIGHT_PX // 2, int(edge_row) - 1)
    assert np.isinf(passes.depth_m[behind, WIDTH_PX // 2]).all()
    assert (passes.instance_id[behind, WIDTH_PX // 2] == 0).all()


def test_without_ground_to_horizon_the_sky_shows_under_the_horizon(renderer):
    column = draw(renderer, ground_to_horizon=False).radiance[:, WIDTH_PX // 2, 1]
    assert column[int(row_below_horizon_px(40.0))] == SKY_CD_M2


def test_fog_thins_the_far_ground_by_its_own_distance(renderer):
    visibility_m = 60.0
    passes = draw(renderer, fog_visibility_m=visibility_m)
    row = int(row_below_horizon_px(40.0))
    distance_m = math.hypot(CAMERA_HEIGHT_M / ((row - (HEIGHT_PX - 1) / 2) / F_PX), CAMERA_HEIGHT_M)
    distance_m *= math.hypot(1.0, ((WIDTH_PX // 2) - (WIDTH_PX - 1) / 2) / F_PX)
    lambert = REFLECTANCE / math.pi * (E_SKY_LUX + E_SUN_LUX * math.sin(math.radians(SUN_ELEVATION_DEG)))
    t = math.exp(-3.912 * distance_m / visibility_m)
    np.testing.assert_allclose(passes.radiance[row, WIDTH_PX // 2], lambert * t + SKY_CD_M2 * (1 - t), rtol=1e-3)
