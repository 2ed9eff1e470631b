"""Rain (camgen.world.rain, camgen.render.rain): Marshall–Palmer counts, a seeded population that falls
consistently between frames, streak lengths and areas in closed form, the depth test, and wet ground."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.spatial import cKDTree

from camgen.render.renderer import View
from camgen.world.rain import (
    DIAMETER_MAX_MM,
    DIAMETER_MIN_MM,
    WET_ALBEDO_FACTOR,
    diameter_classes,
    drop_density_per_m3,
    drops_in_box,
    rain_visibility_m,
    streak_coverage,
    terminal_speed_m_s,
)
from tests.render.conftest import camera_matrix, look_at, scene_from

WIDTH, HEIGHT = 160, 120
F_PX = 150.0
BOX_LOW_M, BOX_HIGH_M = (-6.0, -5.0, 0.0), (6.0, 5.0, 8.0)


def test_marshall_palmer_counts_and_terminal_speed_closed_forms():
    """Drops per m³ against a numerical integral of N0 e^−ΛD; Gunn–Kinzer speeds from Atlas et al.'s fit;
    the classes add up to the whole range; the rain's visual range from its extinction."""
    for rate in (1.0, 5.0, 30.0):
        lam = 4.1 * rate**-0.21
        expected, _ = quad(lambda d, lam=lam: 8000.0 * math.exp(-lam * d), DIAMETER_MIN_MM, DIAMETER_MAX_MM)
        assert drop_density_per_m3(rate, DIAMETER_MIN_MM, DIAMETER_MAX_MM) == pytest.approx(expected, rel=1e-9)
        diameters, densities = diameter_classes(rate)
        assert densities.sum() == pytest.approx(expected, rel=1e-9)
        assert np.all(np.diff(diameters) > 0) and DIAMETER_MIN_MM < diameters[0] < diameters[-1] < DIAMETER_MAX_MM
        # β = (π/2)·∫D² N(D) dD over all sizes (extinction efficiency 2), mm² m⁻³ → m⁻¹.
        beta, _ = quad(lambda d, lam=lam: math.pi / 2 * d * d * 8000.0 * math.exp(-lam * d), 0, 50)
        assert rain_visibility_m(rate) == pytest.approx(3.912023 / (beta * 1e-6), rel=1e-6)
    # Gunn & Kinzer (1949) measured 4.03 m/s at 1 mm, 6.49 at 2 mm, 8.06 at 3 mm, 9.09 at 5 mm.
    np.testing.assert_allclose(terminal_speed_m_s([1.0, 2.0, 3.0, 5.0]), [4.03, 6.49, 8.06, 9.09], atol=0.12)


@pytest.fixture(scope="module")
def population():
    return drops_in_box(BOX_LOW_M, BOX_HIGH_M, 7.3, 8.0, 11)


def test_drop_count_matches_marshall_palmer(population):
    """Drops in a 960 m³ box match N0/Λ (e^−Λ·1 − e^−Λ·6) per m³ within 4 Poisson σ, in total and per class."""
    positions, diameters_mm, _ = population
    volume_m3 = float(np.prod(np.subtract(BOX_HIGH_M, BOX_LOW_M)))
    expected = drop_density_per_m3(8.0, DIAMETER_MIN_MM, DIAMETER_MAX_MM) * volume_m3
    assert abs(len(positions) - expected) < 4 * math.sqrt(expected)
    assert np.all((positions >= BOX_LOW_M) & (positions <= BOX_HIGH_M))
    classes, densities = diameter_classes(8.0)
    for diameter, density in zip(classes, densities, strict=True):
        n = int(np.sum(diameters_mm == diameter))
        assert abs(n - density * volume_m3) < 4 * math.sqrt(density * volume_m3) + 1


def test_same_seed_same_rain_and_drops_fall_between_frames(population):
    positions, _, speeds = population
    again = drops_in_box(BOX_LOW_M, BOX_HIGH_M, 7.3, 8.0, 11)
    assert all(np.array_equal(a, b) for a, b in zip(population, again, strict=True))
    other = drops_in_box(BOX_LOW_M, BOX_HIGH_M, 7.3, 8.0, 12)
    assert len(other[0]) != len(positions) or not np.array_equal(other[0], positions)
    # 40 ms later every drop is v·0.04 m lower, and no new drop appears except at the box's top.
    dt_s = 0.04
    later, _, _ = drops_in_box(BOX_LOW_M, BOX_HIGH_M, 7.3 + dt_s, 8.0, 11)
    moved = positions - np.column_stack([np.zeros((len(speeds), 2)), speeds * dt_s])
    stayed = moved[:, 2] >= BOX_LOW_M[2]
    tree = cKDTree(later)
    distance_m, _ = tree.query(moved[stayed])
    assert distance_m.max() < 1e-9
    distance_m, _ = cKDTree(moved[stayed]).query(later)
    new = later[distance_m > 1e-9]
    assert len(new) > 0 and np.all(new[:, 2] > BOX_HIGH_M[2] - terminal_speed_m_s(DIAMETER_MAX_MM) * dt_s)


def test_streak_length_and_area_closed_form():
    """A drop d m straight ahead falling v·T images as a vertical streak v·T·f/d px long (its second
    moment: ℓ²/12) carrying the drop's image area π/4 (D f/d)² px². A long lens (f = 600 px) makes these
    drops bright enough to be sampled at least every 1.2 px (a fainter one is sampled more sparsely)."""
    f_px = 600.0
    K = camera_matrix(f_px, f_px, (WIDTH - 1) / 2, (HEIGHT - 1) / 2)
    depth = np.full((HEIGHT, WIDTH), np.inf, np.float32)
    for distance_m, exposure_s in ((1.5, 0.01), (3.0, 0.02), (2.0, 0.005)):
        diameter_mm = np.array([3.0])
        v = float(terminal_speed_m_s(3.0))
        fall = np.array([[0.0, v * exposure_s, 0.0]])  # down the image
        coverage = streak_coverage(np.array([[0.01, 0.02, distance_m]]), diameter_mm, fall, K, depth)
        length_px = v * exposure_s * f_px / distance_m
        rows = coverage.sum(axis=1).astype(np.float64)
        y = np.arange(HEIGHT)
        mean = (rows * y).sum() / rows.sum()
        variance = (rows * (y - mean) ** 2).sum() / rows.sum()
        # Splatting each sample bilinearly adds the variance f(1 − f) averaged over fractions: 1/6 px².
        measured_px = math.sqrt(max(12 * (variance - 1 / 6), 0.0))
        assert measured_px == pytest.approx(length_px, abs=1.0)
        assert mean == pytest.approx(0.02 * f_px / distance_m + (HEIGHT - 1) / 2, abs=0.5)
        area_px2 = math.pi / 4 * (3e-3 * f_px / distance_m) ** 2
        assert coverage.sum() == pytest.approx(area_px2, rel=0.05)  # the streak's ends change depth by ±v·T/2


def test_streaks_never_cross_nearer_surfaces():
    """Depth map: a surface 2 m away on the left half. A drop 5 m away whose streak crosses both halves
    shows only on the right; a drop 1 m away shows on the left, over the surface."""
    K = camera_matrix(600.0, 600.0, (WIDTH - 1) / 2, (HEIGHT - 1) / 2)
    depth = np.full((HEIGHT, WIDTH), np.inf, np.float32)
    depth[:, : WIDTH // 2] = 2.0
    far = streak_coverage(np.array([[0.0, 0.0, 5.0]]), np.array([3.0]), np.array([[0.4, 0.1, 0.0]]), K, depth)
    assert far[:, : WIDTH // 2 - 1].max() == 0.0 and far[:, WIDTH // 2 + 1 :].sum() > 0
    near = streak_coverage(np.array([[-0.05, 0.0, 1.0]]), np.array([1.0]), np.array([[0.0, 0.1, 0.0]]), K, depth)
    assert near[:, : WIDTH // 2].sum() > 0


def _graph(environment: dict, lights: list[dict]):
    from camgen.render.scene_graph import build_scene_graph

    return build_scene_graph(scene_from(environment=environment, lights=lights))


ROAD = {
    "type": "plane",
    "name": "road",
    "size_m": [40, 60],
    "position_m": [0, 20, 0],
    "material": {"color_rgb": [0.12, 0.12, 0.12], "texture": {"type": "asphalt", "seed": 3}},
}
WALL = {  # 0.25 m ahead, on the left half of the view: nearer than NEAR_M, so every drawn drop is behind it
    "type": "box",
    "name": "wall",
    "size_m": [2.0, 0.01, 2.0],
    "position_m": [-1.0, 0.255, 1.5],
    "material": {"color_rgb": [0.5, 0.5, 0.5]},
}


def _view() -> View:
    K = camera_matrix(F_PX, F_PX, (WIDTH - 1) / 2, (HEIGHT - 1) / 2)
    return View(K, look_at((0.0, 0.0, 1.5), (0.0, 10.0, 1.0)), WIDTH, HEIGHT)


@pytest.mark.opengl
def test_rainy_frame_is_seeded_and_depth_tested(renderer):
    """The same seed gives the same frame; rain shows over the open street and the sky, never over a
    wall nearer than any drop (its pixels stay exactly as rendered: no haze within 15 m either)."""
    from camgen.render.rain import rainy_radiance

    environment = {
        "sky_luminance_cd_m2": 2000.0,
        "meshes": [ROAD, WALL],
        "rain": {"rate_mm_h": 10.0, "seed": 3},
    }
    graph = _graph(environment, [{"type": "ambient", "illuminance_lux": 5000.0}])
    view = _view()
    drawn = renderer.draw(graph, view, ("radiance", "depth_m", "instance_id"))
    wall = drawn.instance_id == 2
    assert 0.3 < wall.mean() < 0.6
    rainy = rainy_radiance(graph, view, drawn.radiance, drawn.depth_m, 1.0, 1 / 50)
    again = rainy_radiance(graph, view, drawn.radiance, drawn.depth_m, 1.0, 1 / 50)
    assert np.array_equal(rainy, again)
    np.testing.assert_allclose(rainy[wall], drawn.radiance[wall], rtol=1e-5)  # haze starts at 15 m
    changed = np.abs(rainy - drawn.radiance).max(axis=-1) > 1e-3 * drawn.radiance.max(axis=-1)
    assert changed[~wall].mean() > 0.05
    later = rainy_radiance(graph, view, drawn.radiance, drawn.depth_m, 1.04, 1 / 50)
    assert not np.array_equal(later, rainy)


@pytest.mark.opengl
def test_rain_haze_is_koschmieder_beyond_the_streaks(renderer, monkeypatch):
    """Without streaks, rain is a haze of its visual range over each pixel's distance beyond 15 m: the
    far ground (no mesh, depth +inf) over its own distance, as fog; the sky becomes the horizon's."""
    import camgen.render.rain as rain_module
    from camgen.render.renderer import far_ground_depth_m, ray_lengths

    monkeypatch.setattr(rain_module, "rain_coverage", lambda view, depth_m, *args: np.zeros(depth_m.shape, np.float32))
    environment = {"sky_luminance_cd_m2": 2000.0, "meshes": [ROAD], "rain": {"rate_mm_h": 40.0}}
    graph = _graph(environment, [{"type": "ambient", "illuminance_lux": 5000.0}])
    view = _view()
    drawn = renderer.draw(graph, view, ("radiance", "depth_m"))
    hazy = rain_module.rainy_radiance(graph, view, drawn.radiance, drawn.depth_m, 1.0, 1 / 50)
    distance_m = np.where(
        np.isinf(drawn.depth_m), far_ground_depth_m(graph.far_ground, view), drawn.depth_m
    ) * ray_lengths(view)
    t = np.exp(-3.912023 * np.maximum(distance_m - 15.0, 0.0) / rain_visibility_m(40.0))[..., None]
    expected = 2000.0 + (drawn.radiance - 2000.0) * t
    assert np.isinf(drawn.depth_m).sum() > 0 and (np.isinf(drawn.depth_m) & np.isfinite(distance_m)).sum() > 50
    np.testing.assert_allclose(hazy, expected, rtol=1e-4)


@pytest.mark.opengl
def test_wet_asphalt_is_darker_by_the_documented_factor(renderer):
    """Under the ambient light alone (diffuse), wet asphalt's radiance is WET_ALBEDO_FACTOR of the dry;
    rain wets the ground unless `wet: false`."""
    lights = [{"type": "ambient", "illuminance_lux": 5000.0}]
    view = _view()
    base = {"sky_luminance_cd_m2": 1000.0, "meshes": [ROAD], "ground_to_horizon": False}

    def road_mean(extra: dict) -> float:
        drawn = renderer.draw(_graph({**base, **extra}, lights), view, ("radiance", "instance_id"))
        return float(drawn.radiance[drawn.instance_id == 1].mean())

    dry, wet = road_mean({}), road_mean({"wet": True})
    assert wet / dry == pytest.approx(WET_ALBEDO_FACTOR, rel=0.02)
    graph = _graph({**base, "rain": {"rate_mm_h": 3.0}}, lights)
    raining = renderer.draw(graph, view, ("radiance", "instance_id"))
    assert float(raining.radiance[raining.instance_id == 1].mean()) == pytest.approx(wet, rel=1e-6)
    assert road_mean({"rain": {"rate_mm_h": 3.0}, "wet": False}) == pytest.approx(dry, rel=1e-6)


def test_plan_draws_depth_for_rain_and_says_why():
    """Rain consumes a depth pass (its depth test) even when no output asks for depth; the plan says so."""
    from pathlib import Path

    from camgen.config import load_scene
    from camgen.plan import PlanSettings, compile_scene

    loaded = load_scene(Path(__file__).parents[2] / "scenes/rainy_street.yaml")
    camera = compile_scene(loaded, PlanSettings()).cameras[0]
    assert "depth_m" in camera.render.passes
    decisions = {decision.stage: decision for decision in camera.decisions}
    assert decisions["render.rain"].included and "6 mm/h" in decisions["render.rain"].reason
    assert "rain's depth test" in decisions["pass.depth_m"].reason


@pytest.mark.opengl
def test_wet_road_shows_a_sharper_sun_glint(renderer):
    """The sun low ahead (20°): a wet, smoother road's specular glint peaks far brighter than the dry one's,
    though the wet road is darker on average (`WET_ROUGHNESS_FACTOR`: most of the wet look here)."""
    lights = [{"type": "sun", "illuminance_lux": 50000.0, "azimuth_deg": 90.0, "elevation_deg": 20.0}]
    road = {**ROAD, "material": {"color_rgb": [0.12, 0.12, 0.12], "roughness": 0.9}}
    base = {"sky_luminance_cd_m2": 1000.0, "meshes": [road], "ground_to_horizon": False, "shadows": False}
    view = _view()
    peak, mean = {}, {}
    for wet in (False, True):
        drawn = renderer.draw(_graph({**base, "wet": wet}, lights), view, ("radiance", "instance_id"))
        road_px = drawn.radiance[drawn.instance_id == 1].mean(axis=-1)
        peak[wet], mean[wet] = float(road_px.max()), float(np.median(road_px))
    assert peak[True] > 5.0 * peak[False]  # 33x on llvmpipe
    assert mean[True] < mean[False]


def test_the_far_ground_is_wet_too():
    from camgen.render.scene_graph import far_ground

    road = {**ROAD, "material": {"color_rgb": [0.2, 0.1, 0.05]}}
    dry = far_ground(scene_from(environment={"sky_luminance_cd_m2": 100.0, "meshes": [road]}, lights=[]))
    wet = far_ground(
        scene_from(environment={"sky_luminance_cd_m2": 100.0, "meshes": [road], "rain": {"rate_mm_h": 1.0}}, lights=[])
    )
    np.testing.assert_allclose(wet.reflectance_rgb, np.multiply(WET_ALBEDO_FACTOR, dry.reflectance_rgb), rtol=1e-12)
