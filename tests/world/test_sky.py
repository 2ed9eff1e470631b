"""The CIE standard general sky: the standard's closed forms, and the rendered background through
every pixel's direction."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.world.sky import LUMINANCE_WEIGHTS, daylight_rgb, relative_luminance, sky_radiance

SUN = np.array([math.cos(math.radians(40)), 0.0, math.sin(math.radians(40))])  # 40° high, towards +x


def direction(elevation_deg: float, azimuth_deg: float) -> np.ndarray:
    el, az = math.radians(elevation_deg), math.radians(azimuth_deg)
    return np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])


def test_overcast_sky_is_three_times_brighter_at_the_zenith():
    """CIE standard overcast sky: L(Z) / L_z = (1 + 4 exp(−0.7 / cos Z)) / (1 + 4 exp(−0.7)); the
    horizon is 1/2.99 of the zenith (Moon & Spencer's 1:3), whatever the sun."""
    assert relative_luminance(direction(90, 0), SUN, "overcast") == pytest.approx(1.0)
    assert relative_luminance(direction(0, 123), SUN, "overcast") == pytest.approx(1 / (1 + 4 * math.exp(-0.7)))
    z = math.radians(60)
    expected = (1 + 4 * math.exp(-0.7 / math.cos(z))) / (1 + 4 * math.exp(-0.7))
    assert relative_luminance(direction(30, 10), SUN, "overcast") == pytest.approx(expected)


def test_clear_sky_is_bright_round_the_sun_and_darkest_away_from_it():
    around_sun = relative_luminance(direction(45, 5), SUN, "clear")
    opposite = relative_luminance(direction(50, 180), SUN, "clear")
    assert around_sun > 3 * opposite
    # The darkest sky is about 90° from the sun, in its vertical plane on the far side of the zenith.
    elevations = np.arange(5, 90, 1.0)
    far = [relative_luminance(direction(e, 180), SUN, "clear") for e in elevations]
    darkest = elevations[int(np.argmin(far))]
    assert 180 - 40 - darkest == pytest.approx(90, abs=15)
    # It brightens again towards the horizon (gradation V).
    assert relative_luminance(direction(2, 180), SUN, "clear") > min(far)


def test_sky_radiance_has_the_cie_luminance_and_a_bluer_zenith_than_horizon():
    rays = np.array([direction(85, 180), direction(3, 180), direction(40, 5)])
    radiance = sky_radiance(rays, SUN, "clear", 5000.0)
    assert radiance @ LUMINANCE_WEIGHTS == pytest.approx(5000.0 * relative_luminance(rays, SUN, "clear"), rel=1e-4)
    blueness = radiance[:, 2] / radiance[:, 0]
    assert blueness[0] > blueness[1] and blueness[0] > blueness[2]  # high and away from the sun: bluest


def test_daylight_colours_have_unit_luminance_and_bluer_at_higher_cct():
    rgb = daylight_rgb(np.array([6500.0, 12000.0]))
    assert rgb @ LUMINANCE_WEIGHTS == pytest.approx([1.0, 1.0], abs=1e-6)
    assert np.allclose(rgb[0], 1.0, atol=0.03)  # D65 is sRGB's white
    assert rgb[1, 2] / rgb[1, 0] > 1.3  # 12 000 K: blue


@pytest.mark.opengl
def test_the_rendered_background_is_the_sky_in_each_pixels_direction(renderer):
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph
    from tests.render.conftest import camera_matrix, look_at, scene_from

    graph = build_scene_graph(
        scene_from(
            environment={"sky_luminance_cd_m2": 4000, "sky": "overcast", "meshes": []},
            lights=[{"type": "ambient", "illuminance_lux": 1000}],
        )
    )
    # Looking up at 60° elevation, towards +y.
    T = look_at((0, 0, 0), direction(60, 90))
    view = View(camera_matrix(300, 300, 159.5, 119.5), T, 320, 240)
    radiance = renderer.draw(graph, view, ("radiance",)).radiance
    luminance = radiance @ LUMINANCE_WEIGHTS
    for u, v in ((159.5, 119.5), (10.0, 10.0), (300.0, 230.0)):
        ray = T[:3, :3] @ np.linalg.solve(view.K_px, [u, v, 1.0])
        expected = 4000 * relative_luminance(ray, np.array([0.0, 0.0, 1.0]), "overcast")
        assert luminance[round(v), round(u)] == pytest.approx(expected, rel=0.01)


def test_a_sunlit_sky_without_a_sun_is_refused():
    from camgen.errors import ConfigError
    from tests.render.conftest import scene_from

    with pytest.raises((ConfigError, ValueError), match=r"sky lit by the sun.*no sun light"):
        scene_from(environment={"sky": "clear"}, lights=[{"type": "ambient", "illuminance_lux": 1000}])
