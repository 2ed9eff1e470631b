"""Fog by Koschmieder's law (camgen.world.fog): the closed form, and rendered frames whose black targets'
contrast against the horizon is exp(−3.912 d / V)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.render.renderer import View
from camgen.world.fog import KOSCHMIEDER_CONSTANT, apply_fog, transmittance
from tests.render.conftest import camera_matrix, look_at, scene_from

VISIBILITY_M = 100.0
TARGETS_M = ((20.0, 3.0), (50.0, 0.0), (100.0, -15.0))
"""(distance along the optical axis to the target's front face, lateral offset y) of each black box, m;
each box is a tenth of its distance wide (30 px)."""
SKY_CD_M2 = 1000.0
CAMERA_M = (0.0, 0.0, 2.0)
WIDTH, HEIGHT = 160, 120


def test_koschmieder_transmittance_closed_form():
    assert KOSCHMIEDER_CONSTANT == pytest.approx(3.912, abs=5e-4)  # ln 50, Koschmieder's 2 % threshold
    assert transmittance(1000.0, 1000.0) == pytest.approx(0.02, rel=1e-12)  # the definition of V
    assert transmittance(0.0, 50.0) == 1.0
    assert transmittance(np.inf, 50.0) == 0.0
    distances = np.array([[0.0, 10.0], [100.0, np.inf]])
    np.testing.assert_allclose(transmittance(distances, 200.0), np.exp(-3.912023 * distances / 200.0), rtol=1e-6)


def test_fog_blends_towards_the_airlight_and_hides_infinity():
    radiance = np.array([[[100.0, 50.0, 10.0], [7.0, 7.0, 7.0]]], np.float32)
    distance = np.array([[40.0, np.inf]])
    airlight = np.array([500.0, 600.0, 700.0])
    out = apply_fog(radiance, distance, airlight, 80.0)
    t = math.exp(-3.912023 * 40.0 / 80.0)
    np.testing.assert_allclose(out[0, 0], radiance[0, 0] * t + airlight * (1 - t), rtol=1e-5)
    np.testing.assert_allclose(out[0, 1], airlight, rtol=1e-6)
    assert out.dtype == np.float32


def _fog_scene(visibility_m: float | None, sky: str = "uniform"):
    meshes = [
        {
            "type": "box",
            "name": f"target_{i}",
            "size_m": [0.01, d / 10, d / 10],  # thin: only its front face is seen
            "position_m": [CAMERA_M[0] + d + 0.005, y, CAMERA_M[2]],
            "material": {"color_rgb": [0.0, 0.0, 0.0], "roughness": 1.0},
        }
        for i, (d, y) in enumerate(TARGETS_M)
    ]
    environment = {"sky_luminance_cd_m2": SKY_CD_M2, "sky": sky, "meshes": meshes}
    if visibility_m is not None:
        environment["fog"] = {"visibility_m": visibility_m}
    lights = [{"type": "sun", "illuminance_lux": 50000.0, "azimuth_deg": 0.0, "elevation_deg": 20.0}]
    return scene_from(environment=environment, lights=lights if sky != "uniform" else [])


def _view() -> View:
    K = camera_matrix(300.0, 300.0, (WIDTH - 1) / 2, (HEIGHT - 1) / 2)
    return View(K, look_at(CAMERA_M, (100.0, 0.0, CAMERA_M[2])), WIDTH, HEIGHT)


@pytest.fixture(scope="module")
def foggy_frame(renderer):
    from camgen.render.scene_graph import build_scene_graph

    view = _view()
    graph = build_scene_graph(_fog_scene(VISIBILITY_M))
    return view, renderer.draw(graph, view, ("radiance", "instance_id"))


@pytest.mark.opengl
def test_black_target_contrast_is_koschmieder(foggy_frame):
    """C = (L_horizon − L_target) / L_horizon = exp(−3.912 d / V) at every pixel of each target, with d
    the distance along the pixel's ray to the target's face (a plane at known depth: d = z·|K⁻¹(u, v, 1)|)."""
    view, passes = foggy_frame
    luminance = passes.radiance @ np.array([0.2126, 0.7152, 0.0722])
    background = passes.instance_id == 0
    horizon = float(np.median(luminance[background]))
    assert horizon == pytest.approx(SKY_CD_M2, rel=1e-5)  # the sky pixels are the airlight itself
    u, v = np.meshgrid(np.arange(WIDTH), np.arange(HEIGHT))
    ray = np.linalg.norm(np.stack([u, v, np.ones_like(u)], -1) @ np.linalg.inv(view.K_px).T, axis=-1)
    errors = []
    for i, (depth_m, _) in enumerate(TARGETS_M, start=1):
        pixels = passes.instance_id == i
        assert pixels.sum() > 500
        contrast = (horizon - luminance[pixels]) / horizon
        expected = np.exp(-3.912 * depth_m * ray[pixels] / VISIBILITY_M)
        errors.append(float(np.max(np.abs(contrast / expected - 1))))
    assert max(errors) < 0.02, errors


@pytest.mark.opengl
def test_fog_draws_its_depth_without_returning_it(foggy_frame):
    _, passes = foggy_frame
    assert passes.depth_m is None


@pytest.mark.opengl
def test_clear_air_leaves_the_targets_black(renderer):
    from camgen.render.scene_graph import build_scene_graph

    passes = renderer.draw(build_scene_graph(_fog_scene(None)), _view(), ("radiance", "instance_id"))
    assert np.abs(passes.radiance[passes.instance_id > 0]).max() < 1e-6


@pytest.mark.opengl
def test_fog_under_a_cie_sky_takes_the_horizon_in_each_azimuth(renderer):
    """With the CIE clear sky, far sky pixels become the horizon's radiance below them (the airlight)."""
    from camgen.render.scene_graph import build_scene_graph
    from camgen.world.sky import sky_radiance

    view = _view()
    graph = build_scene_graph(_fog_scene(VISIBILITY_M, sky="clear"))
    passes = renderer.draw(graph, view, ("radiance", "instance_id"))
    row = 5  # above the horizon: sky, which becomes airlight
    u = np.arange(0, WIDTH, 16)
    rays = np.stack([u, np.full_like(u, row), np.ones_like(u)], -1) @ np.linalg.inv(view.K_px).T
    rays = rays @ view.T_world_from_cam[:3, :3].T
    rays[:, 2] = 0.0
    expected = sky_radiance(rays, graph.sun_direction, "clear", SKY_CD_M2)
    np.testing.assert_allclose(passes.radiance[row, u], expected, rtol=0.01)


def test_ray_lengths_are_the_norm_of_the_back_projected_pixel():
    from camgen.render.renderer import ray_lengths

    K = np.array([[300.0, 2.0, 80.3], [0.0, 310.0, 59.1], [0.0, 0.0, 1.0]])  # with skew
    u, v = np.meshgrid(np.arange(160.0), np.arange(120.0))
    expected = np.linalg.norm(np.stack([u, v, np.ones_like(u)], -1) @ np.linalg.inv(K).T, axis=-1)
    np.testing.assert_allclose(ray_lengths(View(K, np.eye(4), 160, 120)), expected, rtol=1e-6)
