"""Thin-lens depth of field: CoC against closed forms, the disc against its moments, the layered blur
against cv2.filter2D (one plane), edge-spread measurements, occlusion rules and the brute-force
per-pixel reference."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from camgen.optics.depth_of_field import disc_kernel, layered_blur, reference_blur, signed_coc_px
from camgen.optics.intrinsics import blur_circle_diameter_mm

LENS = {"focal_length_mm": 50.0, "f_number": 2.0, "focus_distance_m": 5.0, "pixel_pitch_um": 5.0}


def _rms_relative_error(image: np.ndarray, reference: np.ndarray) -> float:
    relative = (image.astype(np.float64) - reference) / reference
    return float(np.sqrt(np.mean(relative * relative)))


def _edge_spread_coc_px(image: np.ndarray) -> float:
    """CoC from a vertical step edge: 4·√(σ² − 1/12), σ² the variance of the row-averaged line spread."""
    profile = image[..., 0].mean(axis=0, dtype=np.float64)
    line_spread = np.diff(profile)
    weights = line_spread / line_spread.sum()
    x = np.arange(len(line_spread))
    mean = np.sum(weights * x)
    variance = np.sum(weights * (x - mean) ** 2)
    return 4.0 * math.sqrt(variance - 1.0 / 12.0)


def _street(seed: int, width_px: int = 96, height_px: int = 72) -> tuple[np.ndarray, np.ndarray]:
    """Sky over a slanted textured ground (CoC +4 at the horizon → −12 at the bottom) and 4 boxes on it."""
    rng = np.random.default_rng(seed)
    horizon = height_px // 4
    rows = np.arange(height_px, dtype=np.float64)
    ground_coc = 4.0 - 16.0 * (rows - horizon) / (height_px - 1 - horizon)
    coc = np.repeat(np.where(rows < horizon, 5.0, ground_coc)[:, None], width_px, axis=1)
    yy, xx = np.mgrid[:height_px, :width_px]
    texture = np.sin(xx / 3.0 + 0.5 * yy)[..., None] * np.array([1.0, 0.8, 0.6])
    ground = 40.0 + 30.0 * texture + rng.uniform(0.0, 20.0, (height_px, width_px, 3))
    sky = np.array([800.0, 900.0, 1200.0]) * (1.0 + 0.2 * np.sin(xx / 7.0))[..., None]
    radiance = np.where((rows < horizon)[:, None, None], sky, ground)
    for bottom in np.sort(rng.integers(horizon + 4, height_px, 4)):  # far to near, nearer ones in front
        box_h, box_w = rng.integers(8, 30, 2)
        left = rng.integers(0, width_px - box_w)
        top = max(bottom - box_h, 0)
        coc[top:bottom, left : left + box_w] = ground_coc[bottom - 1]
        stripes = 1.0 + 0.5 * np.sign(np.sin(xx[top:bottom, left : left + box_w] / 2.0))
        radiance[top:bottom, left : left + box_w] = rng.uniform(5.0, 300.0, 3) * stripes[..., None]
    return radiance.astype(np.float32), coc.astype(np.float32)


# --- signed_coc_px ---------------------------------------------------------------------------------


def test_signed_coc_closed_form():
    # A = 25 mm, f/(s − f) = 50/4950: c = 25·(1 − 5/d)·(50/4950)/0.005 px = 50.505…·(1 − 5/d).
    full = 25.0 * (50.0 / 4950.0) / 0.005
    depth_m = np.array([2.5, 5.0, 10.0, 20.0, np.inf])
    expected = full * np.array([-1.0, 0.0, 0.5, 0.75, 1.0])
    np.testing.assert_allclose(signed_coc_px(depth_m, **LENS), expected, rtol=1e-6, atol=1e-6)


def test_signed_coc_magnitude_matches_blur_circle_diameter_mm():
    depth_m = np.random.default_rng(0).uniform(0.1, 200.0, size=(2, 3, 4))
    coc = signed_coc_px(depth_m, **LENS)
    assert coc.shape == (2, 3, 4) and coc.dtype == np.float32
    mm = blur_circle_diameter_mm(depth_m, LENS["focal_length_mm"], LENS["f_number"], LENS["focus_distance_m"])
    np.testing.assert_allclose(np.abs(coc), mm / (LENS["pixel_pitch_um"] * 1e-3), rtol=1e-6)


def test_signed_coc_is_negative_in_front_positive_behind_and_increasing():
    depth_m = np.geomspace(0.06, 1e4, 500)
    coc = signed_coc_px(depth_m, **LENS)
    assert np.all(coc[depth_m < 5.0] < 0.0) and np.all(coc[depth_m > 5.0] > 0.0)
    assert np.all(np.diff(coc) > 0.0)
    assert signed_coc_px(np.array(5.0), **LENS) == 0.0


def test_signed_coc_at_infinity_is_the_finite_limit():
    limit = signed_coc_px(np.array([np.inf]), **LENS)[0]
    assert np.isfinite(limit)
    assert limit == pytest.approx(signed_coc_px(np.array([1e9]), **LENS)[0], rel=1e-6)


@pytest.mark.parametrize("depth_m", [0.05, 0.01, -3.0, -np.inf])
def test_signed_coc_rejects_depth_not_beyond_the_focal_length(depth_m):
    with pytest.raises(ValueError, match="focal length"):
        signed_coc_px(np.array([1.0, depth_m, np.inf]), **LENS)


def test_signed_coc_rejects_nan_and_bad_parameters():
    with pytest.raises(ValueError, match="NaN"):
        signed_coc_px(np.array([1.0, np.nan]), **LENS)
    with pytest.raises(ValueError, match="f_number"):
        signed_coc_px(np.array([1.0]), **{**LENS, "f_number": 0.0})
    with pytest.raises(ValueError, match="focus_distance_m"):
        signed_coc_px(np.array([1.0]), **{**LENS, "focus_distance_m": 0.04})


# --- disc_kernel -------------------------------------------------------------------------------------


@pytest.mark.parametrize("diameter_px", [0.0, 0.5, 1.0, 1.01, 1.5, 2.0, 3.7, 4.0, 9.3, 16.0, 40.0])
def test_disc_kernel_is_normalised_odd_and_symmetric(diameter_px):
    kernel = disc_kernel(diameter_px)
    assert kernel.dtype == np.float32 and kernel.shape[0] == kernel.shape[1] and kernel.shape[0] % 2 == 1
    assert kernel.shape[0] == 2 * max(math.ceil(diameter_px / 2 - 0.5), 0) + 1
    assert kernel.sum() == pytest.approx(1.0, abs=1e-6)
    assert np.all(kernel >= 0.0)
    np.testing.assert_array_equal(kernel, kernel[::-1])
    np.testing.assert_array_equal(kernel, kernel[:, ::-1])
    np.testing.assert_allclose(kernel, kernel.T, atol=1e-9)


@pytest.mark.parametrize("diameter_px", [0.0, 0.4, 1.0])
def test_disc_inside_one_pixel_is_the_identity(diameter_px):
    np.testing.assert_array_equal(disc_kernel(diameter_px), np.ones((1, 1), np.float32))


@pytest.mark.parametrize("diameter_px", [4.0, 5.5, 8.0, 12.7, 20.0, 31.0, 40.0])
def test_disc_kernel_line_spread_variance_is_r2_over_4_plus_pixel_box(diameter_px):
    marginal = disc_kernel(diameter_px).sum(axis=0, dtype=np.float64)
    x = np.arange(len(marginal)) - len(marginal) // 2
    radius_px = diameter_px / 2
    assert np.sum(marginal * x * x) == pytest.approx(radius_px**2 / 4 + 1 / 12, rel=0.04)


@pytest.mark.parametrize("diameter_px", [2.0, 4.0, 9.3, 40.0])
def test_disc_kernel_area_is_pi_r2(diameter_px):
    # The centre pixel is fully covered (R ≥ √2/2), so its weight is 1 / area.
    kernel = disc_kernel(diameter_px)
    centre = kernel.shape[0] // 2
    area_px2 = 1.0 / kernel[centre, centre]
    assert area_px2 == pytest.approx(math.pi * diameter_px**2 / 4, rel=1e-6)


@pytest.mark.parametrize("diameter_px", [-1.0, np.nan, np.inf])
def test_disc_kernel_rejects_bad_diameters(diameter_px):
    with pytest.raises(ValueError, match="diameter_px"):
        disc_kernel(diameter_px)


# --- layered_blur: single planes and edges -----------------------------------------------------------


@pytest.mark.parametrize("coc_px", [0.8, 2.5, 7.3, -7.3, 12.0, 31.4])
def test_plane_at_one_depth_equals_filter2d_with_the_disc(coc_px):
    radiance = np.random.default_rng(3).uniform(0.01, 1e4, (60, 80, 3)).astype(np.float32)
    coc = np.full((60, 80), coc_px, np.float32)
    expected = cv2.filter2D(radiance, -1, disc_kernel(abs(coc_px)), borderType=cv2.BORDER_REFLECT)
    np.testing.assert_allclose(layered_blur(radiance, coc), expected, rtol=1e-5, atol=1e-5 * 1e4)
    np.testing.assert_allclose(reference_blur(radiance, coc), expected, rtol=1e-5, atol=1e-5 * 1e4)


@pytest.mark.parametrize("coc_px", [4.0, 8.0, 16.0, 30.0, -8.0, -30.0])
def test_edge_spread_measures_the_coc(coc_px):
    radiance = np.full((48, 128, 3), 0.5, np.float32)
    radiance[:, 64:] = 2.0
    blurred = layered_blur(radiance, np.full((48, 128), coc_px, np.float32))
    assert _edge_spread_coc_px(blurred) == pytest.approx(abs(coc_px), rel=0.03)


def test_edge_spread_on_a_slanted_plane_follows_the_local_coc():
    # CoC grows 6 → 18 px down the frame; each 40-row band is measured against its own mean CoC.
    radiance = np.full((240, 160, 3), 1.0, np.float32)
    radiance[:, 80:] = 3.0
    coc = np.repeat(np.linspace(6.0, 18.0, 240, dtype=np.float32)[:, None], 160, axis=1)
    blurred = layered_blur(radiance, coc)
    for top in range(20, 200, 40):
        band = slice(top, top + 40)
        assert _edge_spread_coc_px(blurred[band]) == pytest.approx(coc[band, 0].mean(), rel=0.03)


def test_bright_point_does_not_leak_beyond_its_disc():
    radiance = np.full((96, 96, 3), 0.01, np.float32)
    radiance[48, 48] = 1e5
    blurred = layered_blur(radiance, np.full((96, 96), 20.0, np.float32))
    yy, xx = np.mgrid[:96, :96]
    outside = np.hypot(yy - 48, xx - 48) > 11.5
    np.testing.assert_allclose(blurred[outside], 0.01, rtol=1e-4)
    assert blurred.sum(dtype=np.float64) == pytest.approx(radiance.sum(dtype=np.float64), rel=1e-5)


# --- layered_blur: occlusion -------------------------------------------------------------------------


def test_sharp_foreground_does_not_bleed_into_blurred_background():
    radiance = np.zeros((80, 80, 3), np.float32)
    radiance[..., 1] = 1.0  # green background, 10 px behind focus
    coc = np.full((80, 80), 10.0, np.float32)
    radiance[25:55, 25:55] = (100.0, 0.0, 0.0)  # red foreground, in focus
    coc[25:55, 25:55] = 0.0
    blurred = layered_blur(radiance, coc)
    np.testing.assert_array_equal(blurred[25:55, 25:55], radiance[25:55, 25:55])
    background = coc > 0.0
    assert np.all(blurred[background, 0] == 0.0)
    np.testing.assert_allclose(blurred[background, 1], 1.0, rtol=1e-6)


def test_blurred_foreground_spreads_over_sharp_background():
    radiance = np.zeros((80, 80, 3), np.float32)
    radiance[..., 1] = 1.0  # green background, in focus
    coc = np.zeros((80, 80), np.float32)
    in_front = np.zeros((80, 80), bool)
    in_front[25:55, 25:55] = True
    radiance[in_front] = (100.0, 0.0, 0.0)  # red foreground, 10 px in front of focus
    coc[in_front] = -10.0
    blurred = layered_blur(radiance, coc)
    # Over the background (coverage 1): out = A·red + (1 − A)·green, A the foreground's blurred mask.
    coverage = cv2.filter2D(in_front.astype(np.float32), -1, disc_kernel(10.0), borderType=cv2.BORDER_REFLECT)
    behind = ~in_front
    np.testing.assert_allclose(blurred[behind, 0], 100.0 * coverage[behind], atol=1e-4)
    np.testing.assert_allclose(blurred[behind, 1], 1.0 - coverage[behind], atol=1e-6)
    # Over itself the foreground has nothing behind it to show: its own colour fills the coverage.
    np.testing.assert_allclose(blurred[in_front], radiance[in_front], rtol=1e-5)
    assert blurred[40, 56, 0] > 10.0  # one pixel outside the edge
    np.testing.assert_array_equal(blurred[:, :15], radiance[:, :15])  # beyond the disc


# --- layered_blur against the per-pixel reference -------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_layered_blur_matches_the_reference(seed):
    # Measured with the default steps (0.5 px, 10 %): 3.0–3.4 % RMS relative error on these scenes,
    # concentrated at occlusion edges against the 20× brighter sky; it is the within-bin grouping of
    # pixels at slightly different depths that the reference composites one by one.
    radiance, coc = _street(seed)
    reference = reference_blur(radiance, coc)
    assert _rms_relative_error(layered_blur(radiance, coc), reference) < 0.045
    # One bin per distinct CoC reproduces the reference.
    fine = layered_blur(radiance, coc, step_px=0.1, step_rel=0.0)
    assert _rms_relative_error(fine, reference) < 1e-5


def test_coarser_bins_cost_accuracy():
    radiance, coc = _street(4)
    reference = reference_blur(radiance, coc)
    errors = [
        _rms_relative_error(layered_blur(radiance, coc, step_px=0.5, step_rel=step_rel), reference)
        for step_rel in (0.05, 0.4)
    ]
    assert errors[0] < errors[1]


# --- layered_blur: input handling --------------------------------------------------------------------


def test_all_sharp_image_is_returned_unchanged():
    rng = np.random.default_rng(5)
    radiance = rng.uniform(0.0, 1e5, (30, 40, 3)).astype(np.float32)
    coc = rng.uniform(-0.5, 0.5, (30, 40)).astype(np.float32)
    blurred = layered_blur(radiance, coc)
    np.testing.assert_array_equal(blurred, radiance)
    assert blurred is not radiance and blurred.dtype == np.float32


def test_output_shape_and_dtype():
    radiance, coc = _street(0, width_px=40, height_px=30)
    blurred = layered_blur(radiance, coc)
    assert blurred.shape == (30, 40, 3) and blurred.dtype == np.float32
    assert np.all(np.isfinite(blurred))


@pytest.mark.parametrize("where", ["radiance", "coc"])
@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_input_raises(where, bad):
    radiance = np.ones((20, 20, 3), np.float32)
    coc = np.full((20, 20), 3.0, np.float32)
    (radiance if where == "radiance" else coc)[5, 5] = bad
    with pytest.raises(ValueError, match=where):
        layered_blur(radiance, coc)
    with pytest.raises(ValueError, match=where):
        reference_blur(radiance, coc)


@pytest.mark.parametrize(
    ("radiance_shape", "coc_shape"), [((20, 20, 3), (20, 21)), ((20, 20), (20, 20)), ((20, 20, 4), (20, 20))]
)
def test_shape_mismatch_raises(radiance_shape, coc_shape):
    with pytest.raises(ValueError, match="shape"):
        layered_blur(np.ones(radiance_shape, np.float32), np.ones(coc_shape, np.float32))


@pytest.mark.parametrize("settings", [{"step_px": 0.0}, {"step_rel": -0.1}, {"sharp_px": np.nan}])
def test_bad_step_settings_raise(settings):
    with pytest.raises(ValueError, match=next(iter(settings))):
        layered_blur(np.ones((8, 8, 3), np.float32), np.full((8, 8), 3.0, np.float32), **settings)
