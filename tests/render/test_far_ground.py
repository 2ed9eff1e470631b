"""The ground continued to the horizon (`camgen.render.scene_graph.FarGround`): a camera looking over the
edge of a 20 × 20 m ground plane sees, under the horizon, ground of the plane's material shaded as the
plane is (Lambert ρ/π·(E_sky + E_sun·sin h) plus the specular lobe), meeting the plane's own rendered
shading at its edge, and the sky only above the geometric horizon; fog thins it by its own distance
(Koschmieder); it is a backdrop, with no depth and no instance id."""

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
    column = passes.radiance[:, WIDTH_PX // 2, 1]
    ids = passes.instance_id[:, WIDTH_PX // 2]
    # Above the horizon the sky; under it, down to the plane's edge, the far ground (no id); then the plane.
    sky_rows = np.flatnonzero(column == SKY_CD_M2)
    assert sky_rows.max() == HEIGHT_PX // 2 - 1  # rows 0…59: rays at or above the horizon
    far_rows = np.flatnonzero((ids == 0) & (column != SKY_CD_M2))
    plane_rows = np.flatnonzero(ids != 0)
    edge_row = row_below_horizon_px(10.0)
    assert far_rows.min() == HEIGHT_PX // 2 and far_rows.max() < edge_row <= plane_rows.min() + 1
    # Lambert's ρ/π·E plus the rough dielectric's specular lobe, which grows towards grazing view…
    far = column[far_rows]
    assert np.all((far >= lambert) & (far <= 1.15 * lambert))
    # …so that the far ground meets the plane's own shading (the GPU's) at its edge without a step.
    assert column[far_rows.max()] == pytest.approx(column[plane_rows.min()], rel=0.01)
    # A backdrop: no depth, no id.
    assert np.isinf(passes.depth_m[far_rows, WIDTH_PX // 2]).all()


def test_without_ground_to_horizon_the_sky_shows_under_the_horizon(renderer):
    column = draw(renderer, ground_to_horizon=False).radiance[:, WIDTH_PX // 2, 1]
    assert column[int(row_below_horizon_px(40.0))] == SKY_CD_M2


def test_fog_thins_the_far_ground_by_its_own_distance(renderer):
    visibility_m = 60.0
    row = int(row_below_horizon_px(40.0))
    clear = draw(renderer).radiance[row, WIDTH_PX // 2]
    fogged = draw(renderer, fog_visibility_m=visibility_m).radiance[row, WIDTH_PX // 2]
    distance_m = math.hypot(CAMERA_HEIGHT_M / ((row - (HEIGHT_PX - 1) / 2) / F_PX), CAMERA_HEIGHT_M)
    distance_m *= math.hypot(1.0, ((WIDTH_PX // 2) - (WIDTH_PX - 1) / 2) / F_PX)
    t = math.exp(-3.912 * distance_m / visibility_m)
    np.testing.assert_allclose(fogged, clear * t + SKY_CD_M2 * (1 - t), rtol=1e-3)


def far_ground_graph(*, roughness: float, sun_elevation_deg: float, sun_azimuth_deg: float):
    """A scene graph whose far ground is a plane of `roughness` under a sun, for the grid tests."""
    scene = scene_from(
        environment={
            "meshes": [
                {
                    "type": "plane",
                    "name": "ground",
                    "size_m": [20, 20],
                    "material": {"color_rgb": [REFLECTANCE] * 3, "roughness": roughness},
                }
            ],
            "sky_luminance_cd_m2": SKY_CD_M2,
            "shadows": False,
        },
        lights=[
            {"type": "ambient", "illuminance_lux": E_SKY_LUX},
            {
                "type": "sun",
                "illuminance_lux": E_SUN_LUX,
                "elevation_deg": sun_elevation_deg,
                "azimuth_deg": sun_azimuth_deg,
            },
        ],
    )
    return build_scene_graph(scene)


def horizon_view() -> View:
    """640 × 360 at f = 1000 px, looking level along +X from `CAMERA_HEIGHT_M`, the horizon on row 20: the far
    ground fills most of the frame, its grazing rows near the top."""
    return View(
        camera_matrix(1000.0, 1000.0, 319.5, 20.0),
        look_at((0, 0, CAMERA_HEIGHT_M), (1, 0, CAMERA_HEIGHT_M)),
        640,
        360,
    )


@pytest.mark.parametrize(
    ("roughness", "sun_elevation_deg", "sun_azimuth_deg"),
    [(0.9, 4.0, 0.0), (0.9, 30.0, 90.0), (0.5, 10.0, 10.0), (0.1, 8.0, 0.0)],
    ids=["dusk-into-the-sun", "side-light", "semi-rough-low-sun", "wet-into-the-sun"],
)
def test_the_far_ground_from_its_grid_matches_every_pixel_evaluated(roughness, sun_elevation_deg, sun_azimuth_deg):
    # Looking level along +X at f = 1000 px, the horizon across the frame: the hardest case for the grid is a
    # low sun ahead, whose glare on the ground turns fast near the horizon (Fresnel's grazing term).
    from camgen.render.renderer import far_ground_brdf_radiance, far_ground_depth_m, far_ground_radiance

    graph = far_ground_graph(roughness=roughness, sun_elevation_deg=sun_elevation_deg, sun_azimuth_deg=sun_azimuth_deg)
    view = horizon_view()
    below = np.isfinite(far_ground_depth_m(graph.far_ground, view))
    assert below.mean() > 0.9
    fast = far_ground_radiance(graph, view, below)[below]
    rows, cols = np.nonzero(below)
    rays = np.stack([cols, rows, np.ones_like(cols)], axis=-1) @ np.linalg.inv(view.K_px).T
    exact = far_ground_brdf_radiance(graph, rays @ view.T_world_from_cam[:3, :3].T)
    relative = np.abs(fast - exact).max(axis=1) / exact.max(axis=1)
    assert relative.max() < 1e-3  # FAR_GROUND_TOLERANCE; an 8-px grid alone misses by 2-12 % at dusk


def test_a_crop_on_the_sky_grid_gets_the_far_ground_of_the_whole_view_bit_for_bit():
    # The moving regions' crops must equal the whole draw's pixels (camgen.render.sequence.aligned_rect_px).
    from camgen.render.renderer import far_ground_depth_m, far_ground_radiance
    from camgen.render.sequence import aligned_rect_px

    graph = far_ground_graph(roughness=0.9, sun_elevation_deg=4.0, sun_azimuth_deg=0.0)
    view = horizon_view()
    whole = far_ground_radiance(graph, view, np.isfinite(far_ground_depth_m(graph.far_ground, view)))
    # Crops whose last column or row lies on a grid line where the whole view evaluates the cell beyond it
    # pixel by pixel (the horizon's rows; 70 of 75 such 40 x 40 crops differed there, by up to 1e-4 of the
    # value, while pixels were assigned to the cell after a grid line), and one elsewhere.
    rects = [(x0, 8, x0 + 33, 41) for x0 in range(0, 600, 40)] + [(203, 7, 415, 121)]
    for rect in rects:
        x0, y0, x1, y1 = aligned_rect_px(rect, 640, 360)
        crop = view.cropped((x0, y0, x1, y1))
        below = np.isfinite(far_ground_depth_m(graph.far_ground, crop))
        assert below.any()
        part = far_ground_radiance(graph, crop, below)
        np.testing.assert_array_equal(part[below], whole[y0:y1, x0:x1][below], err_msg=str((x0, y0, x1, y1)))


def test_the_grid_evaluates_the_rows_that_pixels_read_and_gives_the_whole_grids_values():
    """A far ground's grid evaluates its rows as pixels ask for them (`_FarGroundNodes`): a band of rows under the
    horizon, then a few scattered pixels, evaluate part of the grid, and give, bit for bit, what the same grid with
    every row evaluated gives there (under a low sun ahead, so that some nodes stray from the coarse grid's
    interpolation and their pixels are evaluated exactly)."""
    from camgen.render.renderer import _FarGroundNodes, far_ground_depth_m

    graph = far_ground_graph(roughness=0.9, sun_elevation_deg=4.0, sun_azimuth_deg=0.0)
    view = horizon_view()
    below = np.isfinite(far_ground_depth_m(graph.far_ground, view))
    every = _FarGroundNodes(graph, view)
    every._evaluate_rows(graph, view, np.arange(view.height_px))
    assert every._done.all() and every.far_off.any()
    asked = _FarGroundNodes(graph, view)
    region = (37, 20, 601, 75)
    x0, y0, x1, y1 = region
    part = asked.region(graph, view, below[y0:y1, x0:x1], region)
    assert 0 < asked._done.sum() < len(asked._done) / 4  # the band's rows, and the rows each pixel's cell reads
    np.testing.assert_array_equal(
        part[below[y0:y1, x0:x1]], every.region(graph, view, below[y0:y1, x0:x1], region)[below[y0:y1, x0:x1]]
    )
    rng = np.random.default_rng(2)
    rows, cols = rng.integers(200, 230, 50), rng.integers(0, 640, 50)  # behind a window, say
    np.testing.assert_array_equal(asked.points(graph, view, rows, cols), every.points(graph, view, rows, cols))
    assert asked._done.sum() < len(asked._done) / 2
