"""The backgrounds a renderer keeps (`camgen.render.renderer.BackgroundCache`): the sky, the far ground and
fog's airlight of a view drawn again (motion blur's sub-frames of one crop, a still camera's next frame) are
the values computed afresh, bit for bit; a change of what they depend on (the sun, the sky's luminance, the
view) computes them again; the kept bytes stay under the budget; and a draw that covers every pixel
(most crops of moving regions) composites nothing."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.render.renderer import (
    BackgroundCache,
    View,
    composite_background,
    far_ground_depth_m,
    far_ground_radiance,
    horizon_airlight,
    sky_view,
)
from camgen.render.scene_graph import build_scene_graph
from tests.render.conftest import camera_matrix, look_at, scene_from

pytestmark = pytest.mark.opengl

WIDTH_PX, HEIGHT_PX, F_PX = 160, 96, 200.0


def _graph(*, sun_azimuth_deg: float = 200.0, sky_cd_m2: float = 4000.0, fog: bool = True):
    environment = {
        "sky": "clear",
        "sky_luminance_cd_m2": sky_cd_m2,
        "shadows": False,
        "ground_to_horizon": True,
        "meshes": [{"type": "plane", "name": "ground", "size_m": [10, 10], "material": {"color_rgb": [0.2] * 3}}],
    }
    if fog:
        environment["fog"] = {"visibility_m": 60.0}
    vehicle = {"seed": 3, "body_type": "hatchback", "colour": "white", "driver": False}
    return build_scene_graph(
        scene_from(
            environment=environment,
            lights=[
                {"type": "ambient", "illuminance_lux": 15000},
                {"type": "sun", "illuminance_lux": 60000, "elevation_deg": 12, "azimuth_deg": sun_azimuth_deg},
            ],
            actors=[{"name": "car", "class": "car", "vehicle": vehicle, "path": {"waypoints_m": [[0, 0]]}}],
        )
    )


# Over the car, through its windows, at the sky above the horizon and the far ground beyond the 10 m plane.
VIEW = View(
    camera_matrix(F_PX, F_PX, (WIDTH_PX - 1) / 2, (HEIGHT_PX - 1) / 2 - 20),
    look_at((0.5, -7.0, 1.6), (0.5, 0.0, 1.0)),
    WIDTH_PX,
    HEIGHT_PX,
)


def test_a_view_drawn_again_gets_the_background_computed_afresh_bit_for_bit(renderer):
    graph = _graph()
    kept = renderer.backgrounds
    try:
        renderer.backgrounds = BackgroundCache(max_bytes=0)  # keeps nothing: every draw computes afresh
        fresh = renderer.draw(graph, VIEW, ("radiance", "depth_m")).radiance
        renderer.backgrounds = cache = BackgroundCache()
        first = renderer.draw(graph, VIEW, ("radiance", "depth_m")).radiance
        misses = cache.misses
        again = renderer.draw(graph, VIEW, ("radiance", "depth_m")).radiance
    finally:
        renderer.backgrounds = kept
    coverage_open = np.isinf(renderer.draw(graph, VIEW, ("depth_m",)).depth_m)
    assert coverage_open.mean() > 0.2  # the view shows sky and far ground
    assert misses >= 4 and cache.misses == misses and cache.hits >= misses  # sky, ground, its depth, fog's
    np.testing.assert_array_equal(first, fresh)
    np.testing.assert_array_equal(again, fresh)


def test_kept_arrays_equal_the_functions_they_stand_for():
    graph, cache = _graph(), BackgroundCache()
    depth_m = far_ground_depth_m(graph.far_ground, VIEW)
    np.testing.assert_array_equal(cache.ground_depth_m(graph, VIEW), depth_m)
    np.testing.assert_array_equal(cache.sky(graph, VIEW), sky_view(graph, VIEW))
    np.testing.assert_array_equal(cache.airlight(graph, VIEW), horizon_airlight(graph, VIEW))
    # The ground is kept at every pixel whose ray meets it; a draw asks for some of them (those it leaves
    # open): each pixel's value is its own.
    below = np.isfinite(depth_m)
    some = below & (np.indices(below.shape).sum(axis=0) % 3 == 0)
    assert some.sum() > 500
    np.testing.assert_array_equal(
        cache.ground_radiance(graph, VIEW, below)[some], far_ground_radiance(graph, VIEW, some)[some]
    )
    with pytest.raises(ValueError, match="read-only"):
        cache.sky(graph, VIEW)[0, 0] = 0.0


def test_what_a_background_depends_on_computes_it_again():
    cache = BackgroundCache()
    base = _graph()
    below = np.isfinite(far_ground_depth_m(base.far_ground, VIEW))
    ground, sky = cache.ground_radiance(base, VIEW, below), cache.sky(base, VIEW)
    misses = cache.misses
    turned = _graph(sun_azimuth_deg=120.0)  # another sun: another ground and sky
    assert not np.array_equal(cache.ground_radiance(turned, VIEW, below), ground)
    assert not np.array_equal(cache.sky(turned, VIEW), sky)
    brighter = _graph(sky_cd_m2=8000.0)
    assert not np.array_equal(cache.sky(brighter, VIEW), sky)
    moved = View(VIEW.K_px, look_at((0.5, -7.0, 1.7), (0.5, 0.0, 1.0)), WIDTH_PX, HEIGHT_PX)
    assert not np.array_equal(cache.sky(base, moved), sky)
    # Each a grid and its pixels (the turned sun's ground took the kept depth: the same level and view).
    assert cache.misses == misses + 8
    assert cache.hits >= 1
    np.testing.assert_array_equal(cache.sky(base, VIEW), sky)  # the first is still kept


def test_the_kept_bytes_stay_under_the_budget():
    graph = _graph(fog=False)
    probe = BackgroundCache()
    probe.sky(graph, VIEW)
    one = probe.nbytes  # a view's sky: its grid and its pixels
    assert len(probe) == 2 and one > sky_view(graph, VIEW).nbytes
    cache = BackgroundCache(max_bytes=3 * one)
    views = [
        View(VIEW.K_px, look_at((0.5, -7.0, 1.6 + 0.01 * k), (0.5, 0.0, 1.0)), WIDTH_PX, HEIGHT_PX) for k in range(6)
    ]
    for view in views:
        cache.sky(graph, view)
        assert cache.nbytes <= cache.max_bytes
    assert len(cache) == 2 * 3
    misses = cache.misses
    cache.sky(graph, views[-1])  # the latest is kept
    cache.sky(graph, views[0])  # the oldest went first, grid and pixels
    assert cache.misses == misses + 2
    small = BackgroundCache(max_bytes=one - 1)  # an array over the budget is returned, not kept (its grid is)
    assert small.sky(graph, VIEW).shape == (HEIGHT_PX, WIDTH_PX, 3) and len(small) == 1


def test_a_draw_that_covers_every_pixel_composites_nothing():
    graph = _graph()
    radiance = np.full((HEIGHT_PX, WIDTH_PX, 3), 7.0, np.float32)
    cache = BackgroundCache()
    behind = composite_background(graph, VIEW, radiance, np.ones((HEIGHT_PX, WIDTH_PX), np.float32), cache)
    assert (radiance == 7.0).all() and behind.open_depth_m is None
    assert len(behind.rows) == len(behind.cols) == len(behind.transmittance) == len(behind.depth_m) == 0
    assert behind.radiance.shape == (0, 3) and cache.misses == 0
    # One open pixel: the sky or ground goes there, and nowhere else.
    coverage = np.ones((HEIGHT_PX, WIDTH_PX), np.float32)
    coverage[5, 7] = 0.0
    composite_background(graph, VIEW, radiance, coverage, cache)
    changed = (radiance != 7.0).any(axis=-1)
    assert changed[5, 7] and changed.sum() == 1


def test_a_smooth_ground_is_evaluated_at_the_asked_pixels_only_and_not_kept():
    # A wet road's far ground is evaluated pixel by pixel (far_ground_step_px <= 2): keeping it would mean
    # evaluating every pixel under the horizon, most of them hidden by the site.
    from camgen.render.renderer import far_ground_step_px
    from camgen.render.scene_graph import FarGround

    graph = _graph()
    graph.far_ground = FarGround(graph.far_ground.height_m, graph.far_ground.reflectance_rgb, roughness=0.1)
    assert far_ground_step_px(graph.far_ground, VIEW) <= 2
    cache = BackgroundCache()
    below = np.isfinite(far_ground_depth_m(graph.far_ground, VIEW))
    some = below & (np.indices(below.shape)[0] % 2 == 0)
    got = cache.ground_radiance(graph, VIEW, some)
    np.testing.assert_array_equal(got[some], far_ground_radiance(graph, VIEW, some)[some])
    assert cache.nbytes == 0  # no pixels kept (only the grid's place: a smooth ground has none)
    nothing = BackgroundCache(max_bytes=0)  # keeps nothing at all, not even an empty grid
    nothing.ground_radiance(graph, VIEW, some)
    nothing.sky(graph, VIEW)
    assert len(nothing) == 0 and nothing.nbytes == 0


@pytest.mark.parametrize("roughness", [None, 0.1])
def test_regions_and_pixels_are_the_whole_views_values(roughness):
    """The sky and the far ground made over a region, or at scattered pixels (those behind glass), are the
    whole view's values there bit for bit, for a rough ground whose grid has nodes evaluated exactly (a low
    sun) and for a smooth one evaluated pixel by pixel; and a composite of a frame with open pixels and glass
    equals one made from the whole view's arrays."""
    from camgen.render.renderer import Behind, _bounding_rect, far_ground_step_px
    from camgen.render.scene_graph import FarGround

    graph = _graph(fog=False)
    if roughness is not None:
        graph.far_ground = FarGround(graph.far_ground.height_m, graph.far_ground.reflectance_rgb, roughness=roughness)
    assert (far_ground_step_px(graph.far_ground, VIEW) <= 2) == (roughness is not None)
    cache = BackgroundCache()
    depth_m = far_ground_depth_m(graph.far_ground, VIEW)
    below = np.isfinite(depth_m)
    sky, ground = sky_view(graph, VIEW), far_ground_radiance(graph, VIEW, below)
    if roughness is None:  # some pixels are evaluated exactly (the grid's rows are evaluated as pixels ask)
        whole = BackgroundCache().ground_nodes(graph, VIEW)
        whole.region(graph, VIEW, below, None)
        assert whole.far_off.any()
    region = (13, 5, 131, 77)
    x0, y0, x1, y1 = region
    np.testing.assert_array_equal(cache.sky(graph, VIEW, region), sky[y0:y1, x0:x1])
    np.testing.assert_array_equal(cache.ground_depth_m(graph, VIEW, region), depth_m[y0:y1, x0:x1])
    part = cache.ground_radiance(graph, VIEW, below[y0:y1, x0:x1], region)
    np.testing.assert_array_equal(part[below[y0:y1, x0:x1]], ground[y0:y1, x0:x1][below[y0:y1, x0:x1]])
    rng = np.random.default_rng(5)
    rows, cols = rng.integers(0, HEIGHT_PX, 300), rng.integers(0, WIDTH_PX, 300)
    np.testing.assert_array_equal(cache.sky_points(graph, VIEW, rows, cols), sky[rows, cols])
    under = below[rows, cols]
    np.testing.assert_array_equal(
        cache.ground_points(graph, VIEW, rows[under], cols[under]), ground[rows[under], cols[under]]
    )

    # A frame: an opaque block, open pixels around it, glass over part of both.
    coverage = np.ones((HEIGHT_PX, WIDTH_PX), np.float32)
    coverage[:40, 20:150] = 0.0
    coverage[30:60, 60:90] = 0.3
    radiance = rng.uniform(0.0, 50.0, (HEIGHT_PX, WIDTH_PX, 3)).astype(np.float32)
    expected = radiance.copy()
    behind = composite_background(graph, VIEW, radiance, coverage, BackgroundCache())
    assert _bounding_rect(coverage == 0.0) == (20, 0, 150, 40)
    # The same composite from the whole view's sky and ground (as it was made before regions).
    open_sky = coverage == 0.0
    glass_rows, glass_cols = np.nonzero((coverage > 0.0) & (coverage < 1.0))
    expected[open_sky] = sky[open_sky]
    open_below = below & open_sky
    expected[open_below] = ground[open_below]
    reference = sky[glass_rows, glass_cols]
    reference[below[glass_rows, glass_cols]] = ground[glass_rows, glass_cols][below[glass_rows, glass_cols]]
    clear = np.float32(graph.sky_luminance_cd_m2)
    t = 1.0 - coverage[glass_rows, glass_cols]
    expected[glass_rows, glass_cols] += t[:, None] * (reference - clear)
    np.testing.assert_array_equal(radiance, expected)
    assert isinstance(behind, Behind)
    np.testing.assert_array_equal(behind.open_depth_m, np.where(open_sky, depth_m, np.float32(np.inf)))
    np.testing.assert_array_equal(behind.depth_m, depth_m[glass_rows, glass_cols])
