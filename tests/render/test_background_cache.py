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
    assert cache.misses == misses + 4  # the turned sun's ground took the kept depth (same level and view)
    assert cache.hits >= 1
    np.testing.assert_array_equal(cache.sky(base, VIEW), sky)  # the first is still kept


def test_the_kept_bytes_stay_under_the_budget():
    graph = _graph(fog=False)
    one = sky_view(graph, VIEW).nbytes
    cache = BackgroundCache(max_bytes=3 * one)
    views = [
        View(VIEW.K_px, look_at((0.5, -7.0, 1.6 + 0.01 * k), (0.5, 0.0, 1.0)), WIDTH_PX, HEIGHT_PX) for k in range(6)
    ]
    for view in views:
        cache.sky(graph, view)
        assert cache.nbytes <= cache.max_bytes
    assert len(cache) == 3
    misses = cache.misses
    cache.sky(graph, views[-1])  # the latest is kept
    cache.sky(graph, views[0])  # the oldest went first
    assert cache.misses == misses + 1
    small = BackgroundCache(max_bytes=one - 1)  # an array over the budget is returned, not kept
    assert small.sky(graph, VIEW).shape == (HEIGHT_PX, WIDTH_PX, 3) and len(small) == 0


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
    assert len(cache) == 0 and cache.misses == 0
