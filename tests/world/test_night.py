"""Night: a lamp's flux and its pool of light on the ground (closed form and render), the night sky's
levels, and the night-mode helpers (`camgen.world.night`)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.world.night import (
    NIGHT_SKY_LUMINANCE_CD_M2,
    NIR_LM_EQUIVALENT_PER_W,
    beam_intensity_cd,
    beam_solid_angle_sr,
    ground_illuminance_lux,
    monochrome,
    peak_intensity_cd,
)


@pytest.mark.parametrize("half_angle_deg", [10.0, 45.0, 70.0, 88.0])
def test_a_lamps_flux_is_the_integral_of_its_intensity(half_angle_deg):
    """Φ = ∫ I dω = 2π ∫ I(θ) sin θ dθ by the midpoint rule on 200 000 cells equals the flux the peak
    intensity was made for, to 1e-6."""
    outer = math.radians(half_angle_deg)
    peak = peak_intensity_cd(5000.0, outer)
    n = 200_000
    theta = (np.arange(n) + 0.5) * (outer / n)
    flux = 2 * math.pi * np.sum(beam_intensity_cd(peak, theta, outer) * np.sin(theta)) * (outer / n)
    assert flux == pytest.approx(5000.0, rel=1e-6)


def test_a_narrow_beam_tends_to_a_cone_of_uniform_intensity():
    """For a small cone the beam's solid angle tends to that of the shape's equivalent flat-top cone:
    π(θᵢ² + (θₒ² − θᵢ²)/3) to second order; at 1° within 1e-4."""
    outer = math.radians(1.0)
    inner = 0.8 * outer
    assert beam_solid_angle_sr(outer) == pytest.approx(math.pi * (inner**2 + (outer**2 - inner**2) / 3), rel=1e-4)


def test_bad_cone_angles_are_refused():
    with pytest.raises(ValueError, match="half angle"):
        beam_solid_angle_sr(math.pi / 2)
    with pytest.raises(ValueError, match="half angle"):
        beam_solid_angle_sr(0.0)


def test_the_night_sky_levels_span_rural_to_urban_illuminance():
    """π·L: 0.5 mlx under a natural sky, 31 mlx under an urban one (the 0.001–0.1 lx of moonless nights)."""
    assert math.pi * NIGHT_SKY_LUMINANCE_CD_M2["natural"] == pytest.approx(5.47e-4, rel=1e-2)
    assert math.pi * NIGHT_SKY_LUMINANCE_CD_M2["urban"] == pytest.approx(0.0314, rel=1e-2)
    levels = [NIGHT_SKY_LUMINANCE_CD_M2[k] for k in ("natural", "rural", "suburban", "urban")]
    assert levels == sorted(levels)


def test_850nm_counts_as_1046_lumens_per_watt():
    """λ/(hc) / (1/(683 h·540 THz)) = 683 · 540e12 · 850e-9 / c = 1045.7 lm/W."""
    assert NIR_LM_EQUIVALENT_PER_W == pytest.approx(683 * 540e12 * 850e-9 / 299_792_458.0, rel=1e-12)
    assert NIR_LM_EQUIVALENT_PER_W == pytest.approx(1045.7, abs=0.1)
    # The same count as the sensor's photons: (λ/hc) per joule over its photons per lumen-second.
    from camgen.sensor.exposure import PHOTONS_PER_LUMEN_S, PLANCK_J_S

    assert NIR_LM_EQUIVALENT_PER_W == pytest.approx(
        850e-9 / (PLANCK_J_S * 299_792_458.0) / PHOTONS_PER_LUMEN_S, rel=1e-12
    )


def test_monochrome_is_bt601_luma_in_every_channel():
    rgb = np.array([[[255, 0, 0], [0, 255, 0], [0, 0, 255], [10, 20, 30]]], dtype=np.uint8)
    grey = monochrome(rgb)
    assert grey.dtype == np.uint8
    np.testing.assert_array_equal(grey[..., 0], [[76, 150, 29, 18]])
    assert (grey[..., 0] == grey[..., 1]).all() and (grey[..., 1] == grey[..., 2]).all()


HEIGHT_M = 6.0
ALBEDO = 0.5
CM_PER_PX = 10.0
FLUX_LM = 5000.0
HALF_ANGLE_DEG = 45.0


@pytest.fixture(scope="module")
def lamp_pool(renderer):
    """A 5000 lm lamp with a 45° beam 6 m over a grey (ρ = 0.5, roughness 1) plane, seen straight down from 30 m,
    10 cm per pixel, 160 × 120."""
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph
    from tests.render.conftest import camera_matrix, look_at, scene_from

    scene = scene_from(
        environment={
            "meshes": [
                {
                    "type": "plane",
                    "name": "ground",
                    "size_m": [100, 100],
                    "material": {"color_rgb": [ALBEDO] * 3, "roughness": 1.0},
                }
            ],
            "shadows": False,
        },
        lights=[
            {
                "type": "lamp",
                "position_m": [0.0, 0.0, HEIGHT_M],
                "flux_lm": FLUX_LM,
                "cone_half_angle_deg": HALF_ANGLE_DEG,
            }
        ],
    )
    f_px = 30.0 * 100 / CM_PER_PX
    view = View(camera_matrix(f_px, f_px, 79.5, 59.5), look_at((0.0, 0.0, 30.0), (0.0, 0.0, 0.0)), 160, 120)
    return renderer.draw(build_scene_graph(scene), view, ("radiance",)).radiance


@pytest.mark.opengl
@pytest.mark.parametrize("offset_m", [0.0, 2.0, 4.0, 5.0, 5.5, 7.0])
def test_the_lamps_pool_on_the_ground_follows_the_cosine_inverse_square_law(lamp_pool, offset_m):
    """Ground luminance along a line from under the lamp equals ρ/π · I(θ) cos θ / d² within 3 % (the
    renderer's specular lobe at roughness 1 adds 2.0–2.2 %: measured 1.020 under the lamp, 98 lx, to
    1.022 at 5.5 m), inside the full beam (θ < 36°), through the fade (5 m: 39.8°, 5.5 m: 42.5°), and
    dark beyond the 45° cone (6 m, 7 m)."""
    outer = math.radians(HALF_ANGLE_DEG)
    peak = peak_intensity_cd(FLUX_LM, outer)
    column = round(79.5 + offset_m * 100 / CM_PER_PX)
    r_m = (column - 79.5) * CM_PER_PX / 100
    measured = float(lamp_pool[59:61, column].mean())
    expected = ALBEDO / math.pi * float(ground_illuminance_lux(peak, outer, HEIGHT_M, r_m))
    under = ALBEDO / math.pi * float(ground_illuminance_lux(peak, outer, HEIGHT_M, 0.0))
    assert measured == pytest.approx(expected, abs=1e-4 * under, rel=0.03)


def test_a_night_site_fills_in_the_skyglow_and_an_ambient_light():
    """An urban night at 01:00 in Paris (the sun 26° down): sky 10 mcd/m², ambient π·L = 31.4 mlx; the
    same site without night_sky is refused (the daylight model needs the sun up)."""
    from camgen.errors import ConfigError
    from tests.render.conftest import scene_from

    site = {"latitude_deg": 48.85, "longitude_deg": 2.35, "time": "2026-06-21T01:00:00+02:00"}
    scene = scene_from(
        duration_s=600.0,
        environment={"night_sky": "urban", "site": site},
        lights=[{"type": "ambient"}, {"type": "lamp", "position_m": [0, 0, 6], "flux_lm": 4000}],
    )
    assert scene.environment.sky_luminance_cd_m2 == pytest.approx(0.01)
    assert scene.lights[0].illuminance_lux == pytest.approx(math.pi * 0.01)
    with pytest.raises((ConfigError, ValueError), match="needs the sun up"):
        scene_from(environment={"site": site}, lights=[{"type": "ambient"}])
