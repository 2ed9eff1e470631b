"""Denoise and sharpen on 8-bit images: noise reduction, edges kept, unsharp mask against its formula."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from camgen.isp.enhance import denoise, sharpen


def edge_width_10_90_px(profile: np.ndarray) -> float:
    """Distance between the 10 % and 90 % crossings of a rising edge profile, px (linear interpolation)."""
    low, high = profile[:5].mean(), profile[-5:].mean()
    positions = []
    for level in low + np.array([0.1, 0.9]) * (high - low):
        i = int(np.argmax(profile >= level))  # first sample at or above the level
        positions.append(i - 1 + (level - profile[i - 1]) / (profile[i] - profile[i - 1]))
    return positions[1] - positions[0]


def noisy_step(sigma: float, seed: int = 0) -> np.ndarray:
    """(64, 64, 3) uint8: 60 on the left half, 140 on the right, plus Gaussian noise of `sigma` codes."""
    clean = np.where(np.arange(64) < 32, 60.0, 140.0)[None, :, None] * np.ones((64, 64, 3))
    noise = np.random.default_rng(seed).normal(0.0, sigma, clean.shape)
    return np.clip(np.rint(clean + noise), 0, 255).astype(np.uint8)


def test_denoise_reduces_noise_on_a_flat_patch_and_keeps_the_edge():
    image = noisy_step(sigma=4.0)
    out = denoise(image, 1.0)
    assert out.shape == image.shape and out.dtype == np.uint8
    flat = (slice(8, 56), slice(4, 26))
    assert out[flat].std() < 0.5 * image[flat].std()
    before = edge_width_10_90_px(image[8:56, 24:40, 1].mean(axis=0))
    after = edge_width_10_90_px(out[8:56, 24:40, 1].mean(axis=0))
    assert before == pytest.approx(0.8, abs=0.05)  # a one-sample step
    assert after <= before + 1.0


def test_denoise_strength_scales_the_smoothing():
    image = noisy_step(sigma=4.0)
    flat = (slice(8, 56), slice(4, 26))
    stds = [denoise(image, s)[flat].std() for s in (0.1, 0.5, 1.0)]
    assert stds[0] > stds[1] > stds[2]


def test_denoise_and_sharpen_are_identity_when_off():
    image = noisy_step(sigma=4.0)
    assert denoise(image, 0.0) is image
    assert sharpen(image, 0.0, 1.0) is image


def test_denoise_works_on_grey_images():
    grey = noisy_step(sigma=4.0)[..., 0].copy()
    out = denoise(grey, 0.8)
    assert out.shape == grey.shape and out[8:56, 4:26].std() < grey[8:56, 4:26].std()


@pytest.mark.parametrize(("amount", "radius_px"), [(0.5, 2.0), (1.0, 1.0), (2.0, 2.5)])
def test_sharpen_is_the_unsharp_mask_formula_on_a_blurred_step(amount, radius_px):
    step = np.where(np.arange(64) < 32, 60, 190).astype(np.uint8)[None, :, None] * np.ones((16, 1, 3), np.uint8)
    blurred_step = cv2.GaussianBlur(step, (0, 0), 1.0)
    out = sharpen(blurred_step, amount, radius_px)
    detail = blurred_step.astype(np.float64) - cv2.GaussianBlur(blurred_step, (0, 0), radius_px)
    expected = np.clip(blurred_step + amount * detail, 0, 255)
    assert np.abs(out - expected).max() <= 0.5 + 1e-9
    # The edge now overshoots on both sides, by the formula's amount; the input did not.
    assert blurred_step.max() == 190 and blurred_step.min() == 60
    row, formula = out[8, :, 1].astype(int), expected[8, :, 1]
    assert row.max() > 190 and row.max() - 190 == pytest.approx(formula.max() - 190, abs=0.5)
    assert row.min() < 60 and 60 - row.min() == pytest.approx(60 - formula.min(), abs=0.5)


def test_sharpen_saturates_instead_of_wrapping():
    step = np.where(np.arange(32) < 16, 0, 255).astype(np.uint8)[None, :, None] * np.ones((8, 1, 3), np.uint8)
    out = sharpen(step, 3.0, 1.0)
    np.testing.assert_array_equal(out, step)  # every overshoot is clipped at 0 and 255
    grey = np.array([[10, 10, 245, 245]] * 4, np.uint8)
    out = sharpen(grey, 5.0, 0.8)
    assert out.shape == grey.shape and out[0, 1] == 0 and out[0, 2] == 255


@pytest.mark.parametrize(
    ("image", "match"),
    [
        (np.zeros((8, 8, 3), np.uint16), "uint8"),
        (np.zeros((8, 8, 4), np.uint8), r"\(H, W, 3\)"),
        (np.zeros((8,), np.uint8), r"\(H, W\)"),
        (np.zeros((0, 8), np.uint8), "non-empty"),
    ],
)
def test_bad_images_are_refused(image, match):
    with pytest.raises(ValueError, match=match):
        denoise(image, 0.5)
    with pytest.raises(ValueError, match=match):
        sharpen(image, 0.5, 1.0)


@pytest.mark.parametrize("strength", [-0.1, 1.5, float("nan")])
def test_denoise_refuses_strengths_outside_the_unit_interval(strength):
    with pytest.raises(ValueError, match="strength"):
        denoise(np.zeros((8, 8, 3), np.uint8), strength)


@pytest.mark.parametrize(
    ("amount", "radius_px", "match"),
    [(-1.0, 1.0, "amount"), (float("inf"), 1.0, "amount"), (1.0, 0.0, "radius_px"), (1.0, float("nan"), "radius_px")],
)
def test_sharpen_refuses_bad_parameters(amount, radius_px, match):
    with pytest.raises(ValueError, match=match):
        sharpen(np.zeros((8, 8, 3), np.uint8), amount, radius_px)
