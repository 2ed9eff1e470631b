"""Denoise and sharpen on 8-bit images: noise reduction, edges kept, unsharp mask against its formula."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from camgen.isp.enhance import denoise, sharpen, suppress_false_colour


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


# False-colour suppression (`suppress_false_colour`), against BT.601's formulas and numpy's median.


def bt601_ycrcb(rgb8: np.ndarray) -> np.ndarray:
    """(H, W, 3) float64 Y, Cr, Cb of ITU-R BT.601 full range, by its formulas (not OpenCV's conversion)."""
    r, g, b = (rgb8[..., k].astype(np.float64) for k in range(3))
    y = 0.299 * r + 0.587 * g + 0.114 * b
    return np.stack([y, (r - y) * 0.713 + 128.0, (b - y) * 0.564 + 128.0], axis=-1)


def median_replicated(plane: np.ndarray, size: int) -> np.ndarray:
    """Each pixel's median over a size × size window, the edge pixels repeated beyond the border (as
    OpenCV's medianBlur borders)."""
    half = size // 2
    padded = np.pad(plane, half, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, (size, size))
    return np.median(windows, axis=(-2, -1))


def line_mosaic_demosaiced() -> tuple[np.ndarray, np.ndarray]:
    """A white line 1.2 px wide across a grey field at 17°, sampled through an RGGB mosaic (box-filtered 8×
    over each pixel) and demosaiced edge-aware as `camgen.isp.demosaic` does, in 8 bits; and the mask of the
    pixels on the line."""
    from camgen.isp.demosaic import demosaic

    size, fine = 96, 8
    ys, xs = np.mgrid[0 : size * fine, 0 : size * fine] / fine
    distance = np.abs((ys - 48) * np.cos(np.radians(17)) - (xs - 48) * np.sin(np.radians(17)))
    scene = np.where(distance < 0.6, 0.9, 0.25)
    scene = scene.reshape(size, fine, size, fine).mean(axis=(1, 3))
    mosaic = np.rint(scene * 60000).astype(np.uint16)  # every site sees the grey scene: R = G = B
    rgb = demosaic(mosaic, "RGGB", "edge_aware")
    on_line = scene > 0.4
    return np.rint(rgb / 257.0).astype(np.uint8), on_line


def test_false_colour_suppression_takes_the_median_of_cr_and_cb_and_keeps_y():
    rng = np.random.default_rng(3)
    image = rng.integers(50, 200, (30, 40, 3), dtype=np.uint8)
    image[10:20, 10:30] = (200, 40, 40)  # a flat colour patch among the noise
    out = suppress_false_colour(image, 5)
    before, after = bt601_ycrcb(image), bt601_ycrcb(out)
    kept = ~((out == 0) | (out == 255)).any(axis=-1)  # a move past the range clips (Y and colour change)
    assert kept.mean() > 0.9
    for channel in (1, 2):
        expected = median_replicated(np.rint(before[..., channel]), 5)
        np.testing.assert_allclose(after[..., channel][kept], expected[kept], atol=2.0)  # 8-bit rounding
    np.testing.assert_allclose(after[..., 0][kept], before[..., 0][kept], atol=1.0)


def test_false_colour_suppression_leaves_grey_and_flat_colour_exactly_as_they_were():
    grey = np.repeat(np.random.default_rng(0).integers(0, 256, (24, 24, 1), dtype=np.uint8), 3, axis=2)
    np.testing.assert_array_equal(suppress_false_colour(grey, 5), grey)
    flat = np.full((24, 24, 3), (30, 120, 220), np.uint8)
    np.testing.assert_array_equal(suppress_false_colour(flat, 7), flat)
    assert suppress_false_colour(flat, 0) is flat
    mono = grey[..., 0]
    assert suppress_false_colour(mono, 5) is mono


def test_false_colour_suppression_removes_the_colour_a_demosaiced_thin_line_gets():
    image, on_line = line_mosaic_demosaiced()
    chroma = np.hypot(*(bt601_ycrcb(image)[..., 1:] - 128.0).transpose(2, 0, 1))
    cleaned = suppress_false_colour(image, 5)
    chroma_after = np.hypot(*(bt601_ycrcb(cleaned)[..., 1:] - 128.0).transpose(2, 0, 1))
    assert chroma[on_line].mean() > 4.0  # the scene is grey; demosaicing coloured the line
    assert chroma_after[on_line].mean() < chroma[on_line].mean() / 4
    luma_change = np.abs(bt601_ycrcb(cleaned)[..., 0] - bt601_ycrcb(image)[..., 0])
    assert luma_change.max() <= 1.0  # the line stays as bright as it was


@pytest.mark.parametrize("size", [1, 2, 4, 9, -3, True, 5.0])
def test_false_colour_suppression_refuses_windows_it_does_not_take(size):
    with pytest.raises(ValueError, match="size_px must be one of"):
        suppress_false_colour(np.zeros((8, 8, 3), np.uint8), size)


def test_the_camera_isp_runs_false_colour_suppression_where_the_plan_keeps_it():
    """`CameraIsp.process` with `isp.false_colour` among its steps gives the 8-bit image it gives without,
    through `suppress_false_colour` at the profile's window (denoise and sharpening, which follow it, left off):
    a demosaiced thin line's colour is taken out in the camera's own pipeline, not only by the function."""
    from camgen.config.loader import load_profile
    from camgen.isp.pipeline import CameraIsp
    from camgen.plan.compile import isp_steps
    from tests.conftest import REPO

    bullet = load_profile(REPO / "profiles/bullet_4mp_2p8mm.yaml").profile
    steps = isp_steps(bullet.isp, bullet.sensor) - {"isp.denoise", "isp.sharpen", "isp.contrast_stretch"}
    assert "isp.false_colour" in steps
    size, fine = 96, 8
    ys, xs = np.mgrid[0 : size * fine, 0 : size * fine] / fine
    distance = np.abs((ys - 48) * np.cos(np.radians(17)) - (xs - 48) * np.sin(np.radians(17)))
    scene = np.where(distance < 0.6, 0.9, 0.25).reshape(size, fine, size, fine).mean(axis=(1, 3))
    black, white = bullet.sensor.black_level_dn, 2**bullet.sensor.bit_depth - 1
    raw = np.rint(black + scene * 0.8 * (white - black)).astype(np.uint16)  # a grey scene on every site

    def process(with_steps: set[str]) -> np.ndarray:
        return CameraIsp(bullet.isp, bullet.sensor, frame_interval_s=0.04, steps=with_steps).process(raw)

    without = process(steps - {"isp.false_colour"})
    with_it = process(steps)
    np.testing.assert_array_equal(with_it, suppress_false_colour(without, bullet.isp.false_colour_median_px))
    assert not np.array_equal(with_it, without)
    # In night mode the camera sends grey: the colour filter is not run (it cost 6-12 ms a 1080p frame for nothing).
    grey_out = CameraIsp(bullet.isp, bullet.sensor, frame_interval_s=0.04, steps=steps).process(raw, grey_out=True)
    np.testing.assert_array_equal(grey_out, without)
