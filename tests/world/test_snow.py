"""Snow (camgen.world.snow): the Gunn–Marshall spectrum in closed form, flakes from melted drops, Locatelli–
Hobbs speeds, the visibility relation of Rasmussen et al. (1999) at the source's own values, a seeded
population that falls and drifts consistently between frames, and streaks whose length, area and spread
follow from the flake's speed, size and defocus."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.spatial import cKDTree

from camgen.world.rain import drops_in_box, rain_visibility_m, streak_layers
from camgen.world.snow import (
    MELTED_MAX_MM,
    MELTED_MIN_MM,
    fall_speed_m_s,
    flake_classes,
    flake_density_per_m3,
    flake_diameter_mm,
    flake_extinction_per_m,
    flake_radiance,
    flakes_in_box,
    illuminated_flake_radiance,
    melted_classes,
    melted_rate_mm_h,
    snow_visibility_m,
    wind_drift_m_s,
)
from tests.render.conftest import camera_matrix

WIDTH, HEIGHT = 160, 120
BOX_LOW_M, BOX_HIGH_M = (-5.0, -4.0, 0.0), (5.0, 4.0, 6.0)


def _n0(rate):  # Gunn & Marshall (1958), m⁻³ mm⁻¹ of melted diameter
    return 3800.0 * rate**-0.87


def _lam(rate):  # mm⁻¹
    return 2.55 * rate**-0.48


def test_gunn_marshall_counts_and_mean_diameter_closed_forms():
    """Flakes per m³ against a numerical integral of 3800 R^−0.87 e^{−2.55 R^−0.48 d}; the classes add up to
    the drawn range and their density-weighted mean melted diameter is the truncated exponential's; over
    all sizes the count is N0/Λ."""
    for rate in (0.3, 1.0, 5.0):
        n0, lam = _n0(rate), _lam(rate)
        expected, _ = quad(lambda d, n0=n0, lam=lam: n0 * math.exp(-lam * d), MELTED_MIN_MM, MELTED_MAX_MM)
        assert flake_density_per_m3(rate, MELTED_MIN_MM, MELTED_MAX_MM) == pytest.approx(expected, rel=1e-9)
        assert flake_density_per_m3(rate, 0.0, 1e3) == pytest.approx(n0 / lam, rel=1e-12)
        melted, densities = melted_classes(rate)
        assert densities.sum() == pytest.approx(expected, rel=1e-9)
        first, _ = quad(lambda d, n0=n0, lam=lam: d * n0 * math.exp(-lam * d), MELTED_MIN_MM, MELTED_MAX_MM)
        assert (melted * densities).sum() / densities.sum() == pytest.approx(first / expected, rel=1e-9)
    # Wet snow of the same rate falls twice as fast on half as many flakes (the estimate the module states).
    assert flake_density_per_m3(1.0, 0.5, 4.0, "wet") == pytest.approx(flake_density_per_m3(1.0, 0.5, 4.0) / 2)


def test_flakes_hold_their_drops_water_and_fall_at_about_a_metre_a_second():
    """D = √(d³/c): a flake of bulk density C3/D (0.017 g cm⁻² dry, 0.072 wet) holds the water of a drop of d.
    Locatelli & Hobbs's unrimed dendrite aggregates: 0.8 D^0.16 m/s (0.89 m/s at 2 mm, 1.16 at 10 mm); every
    drawn class falls at 0.8–1.3 m/s, wet ones at 2 m/s."""
    melted = np.array([0.5, 1.0, 2.0, 3.5])
    for kind, c3 in (("dry", 0.017), ("wet", 0.072)):
        D = flake_diameter_mm(melted, kind)
        density_g_cm3 = c3 / (D * 0.1)
        np.testing.assert_allclose(density_g_cm3 * (D * 0.1) ** 3, (melted * 0.1) ** 3, rtol=1e-12)
    np.testing.assert_allclose(flake_diameter_mm([1.0, 2.0]), [2.425, 6.860], atol=1e-3)
    np.testing.assert_allclose(fall_speed_m_s([2.0, 5.0, 10.0]), [0.894, 1.035, 1.156], atol=1e-3)
    speeds = flake_classes(1.0)[2]
    assert np.all(np.diff(speeds) > 0) and 0.8 <= speeds.min() and speeds.max() <= 1.3
    np.testing.assert_array_equal(flake_classes(1.0, "wet")[2], 2.0)


def test_the_spectrum_carries_its_own_rate():
    """The published N0 and Λ with the flakes' own speeds carry the rate they are a function of: within 5 % at
    1 mm/h (a check of the coefficients that needs no source; 0.84–1.33 R over 0.3–5 mm/h)."""
    assert melted_rate_mm_h(1.0) == pytest.approx(1.0, rel=0.05)
    assert melted_rate_mm_h(1.0, "wet") == pytest.approx(1.0, rel=0.05)
    for rate in (0.3, 2.0, 5.0):
        assert 0.8 < melted_rate_mm_h(rate) / rate < 1.4


def test_visibility_is_rasmussens_relation():
    """Rasmussen et al. (1999) eq. 13, V = 1.3 C3 V_t / (ρ_w S) (cgs), gives 0.40 km of dry snow and 3.4 km of
    wet at 2 mm/h; the visibility goes as 1/S; snow of 1 mm/h is over ten times thicker than rain of 1 mm/h;
    and the drawn flakes' own geometric extinction (efficiency 2, integrated numerically) agrees within 5 %
    at 1 mm/h, 12 % at 5 mm/h."""
    assert snow_visibility_m(2.0) == pytest.approx(1.3 * 0.017 * 100 / (0.2 / 3600) / 100, rel=0.01)
    assert snow_visibility_m(2.0) == pytest.approx(400.0, rel=0.02)
    assert snow_visibility_m(2.0, "wet") == pytest.approx(3400.0, rel=0.02)
    assert snow_visibility_m(0.5) == pytest.approx(4 * snow_visibility_m(2.0), rel=1e-12)
    assert rain_visibility_m(1.0) > 10 * snow_visibility_m(1.0)
    for rate, tolerance in ((1.0, 0.05), (5.0, 0.12)):
        n0, lam = _n0(rate), _lam(rate)
        # β = (π/2) ∫ D(d)² N(d) dd, D² = d³ / 0.17 mm (dry), mm² m⁻³ → m⁻¹.
        beta, _ = quad(lambda d, n0=n0, lam=lam: math.pi / 2 * d**3 / 0.17 * n0 * math.exp(-lam * d), 0, np.inf)
        assert flake_extinction_per_m(rate) == pytest.approx(beta * 1e-6, rel=1e-6)
        assert 3.912023 / (beta * 1e-6) == pytest.approx(snow_visibility_m(rate), rel=tolerance)


def test_flake_light():
    """An isotropic scatterer of albedo ω: ω (L_sky + L_ground)/2 under a sky and a ground, plus ω E/(4π) in a
    sun; in a light from behind the camera, (2/3) ω E/π (a Lambertian sphere's geometric albedo)."""
    np.testing.assert_allclose(flake_radiance([100.0] * 3, [20.0] * 3), 0.9 * 60.0, rtol=1e-6)
    np.testing.assert_allclose(flake_radiance([0.0] * 3, [0.0] * 3, 4 * math.pi * 1000.0), 900.0, rtol=1e-6)
    assert illuminated_flake_radiance(math.pi) == pytest.approx(0.9 * 2 / 3)


@pytest.fixture(scope="module")
def population():
    return flakes_in_box(BOX_LOW_M, BOX_HIGH_M, 3.7, 2.0, 11, "dry", (1.5, -0.5))


def test_flake_count_matches_gunn_marshall(population):
    """Flakes in a 480 m³ box match the class densities within 4 Poisson σ, in total and per class."""
    positions, diameters_mm, _ = population
    volume_m3 = float(np.prod(np.subtract(BOX_HIGH_M, BOX_LOW_M)))
    diameters, densities, _ = flake_classes(2.0)
    expected = densities.sum() * volume_m3
    assert abs(len(positions) - expected) < 4 * math.sqrt(expected)
    assert np.all((positions >= BOX_LOW_M) & (positions <= BOX_HIGH_M))
    for diameter, density in zip(diameters, densities, strict=True):
        n = int(np.sum(diameters_mm == diameter))
        assert abs(n - density * volume_m3) < 4 * math.sqrt(density * volume_m3) + 1


def test_same_seed_same_snow_and_flakes_fall_and_drift_between_frames(population):
    """The same seed gives the same flakes, another seed others, and rain's drops of the same seed are not
    snow's; 40 ms later every flake has moved by (u, w, −v)·0.04 s."""
    positions, _, speeds = population
    again = flakes_in_box(BOX_LOW_M, BOX_HIGH_M, 3.7, 2.0, 11, "dry", (1.5, -0.5))
    assert all(np.array_equal(a, b) for a, b in zip(population, again, strict=True))
    other = flakes_in_box(BOX_LOW_M, BOX_HIGH_M, 3.7, 2.0, 12, "dry", (1.5, -0.5))[0]
    assert len(other) != len(positions) or not np.array_equal(other, positions)
    drops = drops_in_box(BOX_LOW_M, BOX_HIGH_M, 3.7, 2.0, 11)[0]
    assert cKDTree(drops).query(positions[:200])[0].min() > 1e-9
    dt_s = 0.04
    later = flakes_in_box(BOX_LOW_M, BOX_HIGH_M, 3.7 + dt_s, 2.0, 11, "dry", (1.5, -0.5))[0]
    moved = positions + np.column_stack(
        [np.full(len(speeds), 1.5 * dt_s), np.full(len(speeds), -0.5 * dt_s), -speeds * dt_s]
    )
    stayed = np.all((moved >= BOX_LOW_M) & (moved <= BOX_HIGH_M), axis=1)
    distance_m, _ = cKDTree(later).query(moved[stayed])
    assert stayed.mean() > 0.9 and distance_m.max() < 1e-9


def test_wind_drift_follows_the_scene_direction():
    class Wind:
        speed_m_s, direction_deg = 2.0, 90.0

    np.testing.assert_allclose(wind_drift_m_s(Wind), (0.0, 2.0), atol=1e-12)
    assert wind_drift_m_s(None) == (0.0, 0.0)


def _moments(coverage: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centroid (x, y) and covariance (2, 2) of a coverage image, px."""
    y, x = np.mgrid[: coverage.shape[0], : coverage.shape[1]]
    w = coverage.astype(np.float64) / coverage.sum()
    mean = np.array([(w * x).sum(), (w * y).sum()])
    dx, dy = x - mean[0], y - mean[1]
    return mean, np.array([[(w * dx * dx).sum(), (w * dx * dy).sum()], [(w * dx * dy).sum(), (w * dy * dy).sum()]])


def test_flake_streak_length_area_drift_and_defocus():
    """A 6.9 mm flake (2 mm of water) d metres ahead falling at its speed v in a side wind u images as a streak
    √(u² + v²)·T·f/d px long along (u, v) in the image (its second moment ℓ²/12, plus σ² of its footprint and
    the bilinear splat's 1/6 px²), carrying its image area π/4 (D f/d)²; a footprint spread by defocus keeps
    the area and widens the streak across by σ² exactly."""
    f_px = 600.0
    K = camera_matrix(f_px, f_px, (WIDTH - 1) / 2, (HEIGHT - 1) / 2)
    depth = np.full((HEIGHT, WIDTH), np.inf, np.float32)
    diameter_mm = float(flake_diameter_mm(2.0))
    v = float(fall_speed_m_s(diameter_mm))
    for distance_m, exposure_s, u, blur_px in ((2.0, 0.02, 0.0, 0.0), (1.5, 0.04, 1.0, 0.0), (3.0, 0.04, 0.5, 3.0)):
        fall = np.array([[u * exposure_s, v * exposure_s, 0.0]])  # right and down the image
        image_px = diameter_mm * 1e-3 * f_px / distance_m
        sigma_px = math.hypot(image_px, blur_px) / 4
        coverage, _ = streak_layers(
            np.array([[0.01, 0.02, distance_m]]),
            np.array([diameter_mm]),
            fall,
            K,
            depth,
            image_max_px=100.0,
            spread_px=np.array([sigma_px]),
        )
        length_px = math.hypot(u, v) * exposure_s * f_px / distance_m
        mean, covariance = _moments(coverage)
        eigenvalues, eigenvectors = np.linalg.eigh(covariance)
        along = eigenvectors[:, 1] * np.sign(eigenvectors[1, 1])
        # The Gaussian layer's σ is the nearest of SPREAD_SHARP_PX·√2^k (within 19 %).
        layer_sigma = 0.5 * math.sqrt(2) ** round(math.log(sigma_px / 0.5) / math.log(math.sqrt(2)))
        across_px2 = (layer_sigma**2 if sigma_px >= 0.5 else 0.0) + 1 / 6
        assert math.sqrt(max(12 * (eigenvalues[1] - across_px2), 0.0)) == pytest.approx(length_px, abs=1.0)
        assert eigenvalues[0] == pytest.approx(across_px2, abs=0.1)
        np.testing.assert_allclose(along, np.array([u, v]) / math.hypot(u, v), atol=0.03)
        np.testing.assert_allclose(mean, np.array([0.01, 0.02]) * f_px / distance_m + (np.array(K[:2, 2])), atol=0.5)
        assert coverage.sum() == pytest.approx(math.pi / 4 * image_px**2, rel=0.05)


def test_values_are_summed_by_coverage():
    """Σ α·value over two overlapping flakes of values 1 and 3 lies between α·1 and α·3 everywhere and sums to
    area₁·1 + area₂·3."""
    K = camera_matrix(600.0, 600.0, (WIDTH - 1) / 2, (HEIGHT - 1) / 2)
    depth = np.full((HEIGHT, WIDTH), np.inf, np.float32)
    positions = np.array([[0.0, 0.0, 2.0], [0.003, 0.0, 2.0]])
    diameters = np.array([5.0, 5.0])
    fall = np.array([[0.0, 0.02, 0.0]] * 2)
    coverage, valued = streak_layers(
        positions, diameters, fall, K, depth, image_max_px=100.0, spread_px=np.array([0.4, 2.0]), values=[1.0, 3.0]
    )
    area_px2 = math.pi / 4 * (5e-3 * 600 / 2.0) ** 2
    assert valued.sum() == pytest.approx(4 * area_px2, rel=0.05)
    assert np.all(valued <= 3 * coverage + 1e-6) and np.all(valued >= coverage - 1e-6)


def test_blurring_tile_by_tile_is_blurring_the_frame():
    """A sparse layer blurred over the tiles holding its splats (found by scanning, or named by the caller)
    equals OpenCV's blur of the whole frame with zeros beyond it, at narrow and wide σ and at the edges."""
    import cv2

    from camgen.world.rain import BLUR_TILE_PX, _add_blurred

    rng = np.random.default_rng(1)
    image = np.zeros((600, 900))
    rows, columns = rng.integers(0, 600, 40), rng.integers(0, 900, 40)
    rows[:2], columns[:2] = (0, 599), (899, 0)  # corners
    image[rows, columns] = rng.random(40)
    tiles = np.unique(np.column_stack([rows, columns]) // BLUR_TILE_PX * BLUR_TILE_PX, axis=0)
    for sigma_px in (0.5, 2.0, 11.3):
        expected = cv2.GaussianBlur(image, (0, 0), sigma_px, borderType=cv2.BORDER_CONSTANT)
        for named in (None, tiles):
            total = np.zeros_like(image)
            _add_blurred(total, image, sigma_px, named)
            np.testing.assert_allclose(total, expected, atol=1e-15)
