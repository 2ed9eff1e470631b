"""Tone curves against their standards' reference values; the 8-bit tables and their application."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import cv2
import numpy as np
import pytest

from camgen.isp.tone import TONE_CURVES, apply_lut, tone_curve, tone_lut


def test_srgb_reference_values():
    # IEC 61966-2-1: the joint 0.0031308 → 0.04045, middle grey 0.18 → 0.4613561.
    np.testing.assert_allclose(
        tone_curve(np.array([0.0, 0.0031308, 0.18, 1.0]), "srgb"), [0, 0.04045, 0.4613561, 1], atol=1e-6
    )


def test_bt709_reference_values():
    # ITU-R BT.709-6: 4.5·L below 0.018; 1.099·L^0.45 − 0.099 from it (0.081 to 2.5e-4, the
    # rounded constants' step), 0.18 → 0.409007728864.
    got = tone_curve(np.array([0.0, 0.01, 0.018, 0.18, 1.0]), "bt709")
    np.testing.assert_allclose(got[[0, 1, 3, 4]], [0.0, 0.045, 0.409007728864, 1.0], atol=1e-9)
    assert abs(got[2] - 0.081) < 2.5e-4


@pytest.mark.parametrize("gamma", [1.8, 2.2, 2.4])
def test_gamma_curve_is_the_inverse_power(gamma):
    x = np.linspace(0, 1, 11)
    np.testing.assert_allclose(tone_curve(x, "gamma", gamma), x ** (1 / gamma), rtol=1e-15)
    assert tone_curve(0.5, "gamma", 2.0) == pytest.approx(np.sqrt(0.5))


def test_linear_is_identity_and_every_curve_clips_to_the_unit_interval():
    x = np.array([-1.0, 0.0, 0.25, 1.0, 7.0])
    np.testing.assert_array_equal(tone_curve(x, "linear"), [0.0, 0.0, 0.25, 1.0, 1.0])
    for curve in TONE_CURVES:
        got = tone_curve(x, curve)
        assert got[0] == 0.0 and got[-1] == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("curve", TONE_CURVES)
def test_curves_keep_shape_and_propagate_nan(curve):
    x = np.full((2, 3, 4), 0.5)
    x[1, 2, 3] = np.nan
    got = tone_curve(x, curve)
    assert got.shape == (2, 3, 4) and got.dtype == np.float64
    assert np.isnan(got[1, 2, 3]) and np.isfinite(got[0]).all()


@pytest.mark.parametrize("curve", TONE_CURVES)
@pytest.mark.parametrize("size", [2, 256, 4096, 65536])
def test_luts_are_monotone_with_black_and_white_at_the_ends(curve, size):
    lut = tone_lut(curve, size=size)
    assert lut.shape == (size,) and lut.dtype == np.uint8
    assert np.all(np.diff(lut.astype(int)) >= 0)
    assert lut[0] == 0 and lut[-1] == 255


def test_lut_entries_are_the_rounded_curve():
    lut = tone_lut("srgb", size=4096)
    expected = np.rint(255 * tone_curve(np.arange(4096) / 4095, "srgb"))
    np.testing.assert_array_equal(lut, expected)
    np.testing.assert_array_equal(tone_lut("linear", size=256), np.arange(256))


@pytest.mark.parametrize("curve", TONE_CURVES)
def test_lut_output_range_maps_black_and_white_inside(curve):
    lut = tone_lut(curve, 2.2, size=65536, output_low_frac=16 / 255, output_high_frac=235 / 255)
    assert lut[0] == 16 and lut[-1] == 235 and lut.min() == 16 and lut.max() == 235
    assert np.all(np.diff(lut.astype(int)) >= 0)


@pytest.mark.parametrize(
    ("args", "kwargs", "match"),
    [
        (("log",), {}, "srgb, bt709, gamma, linear"),
        (("gamma", 0.0), {}, "gamma"),
        (("gamma", float("nan")), {}, "gamma"),
        (("srgb",), {"size": 1}, "size"),
        (("srgb",), {"size": 65537}, "size"),
        (("srgb",), {"size": 256.0}, "size"),
        (("srgb",), {"output_low_frac": 0.5, "output_high_frac": 0.5}, "output_low_frac < output_high_frac"),
        (("srgb",), {"output_high_frac": 1.1}, "≤ 1"),
    ],
)
def test_lut_refuses_bad_input(args, kwargs, match):
    with pytest.raises(ValueError, match=match):
        tone_lut(*args, **kwargs)


def test_curve_refuses_unknown_names():
    with pytest.raises(ValueError, match="expected one of srgb, bt709, gamma, linear"):
        tone_curve(np.zeros(3), "sRGB")


@pytest.mark.parametrize("shape", [(48, 64, 3), (48, 64), (100,), (2, 3, 4, 5)])
def test_apply_lut_equals_numpy_indexing(shape):
    rng = np.random.default_rng(5)
    image = rng.integers(0, 65536, shape, dtype=np.uint16)
    lut = rng.integers(0, 256, 65536, dtype=np.uint8)
    out = apply_lut(image, lut)
    assert out.shape == shape and out.dtype == np.uint8
    np.testing.assert_array_equal(out, lut[image])


@pytest.fixture(params=[1, 2], ids=["opencv-1-thread", "opencv-2-threads"])
def opencv_threads(request):
    """Run a test with OpenCV on 1 thread (the executor splits the work) and on 2 (it does not)."""
    before = cv2.getNumThreads()
    cv2.setNumThreads(request.param)
    yield request.param
    cv2.setNumThreads(before)


@pytest.mark.parametrize("shape", [(1080, 1920, 3), (7, 5), (1, 9), (4,)])
def test_apply_lut_with_an_executor_is_exact(shape, opencv_threads):
    rng = np.random.default_rng(7)
    image = rng.integers(0, 65536, shape, dtype=np.uint16)
    lut = rng.integers(0, 256, 65536, dtype=np.uint8)
    with ThreadPoolExecutor(2) as executor:
        out = apply_lut(image, lut, executor=executor)
    assert out.shape == shape and out.dtype == np.uint8
    np.testing.assert_array_equal(out, lut[image])


def test_apply_lut_on_a_strided_view_and_with_a_real_curve():
    image = np.random.default_rng(6).integers(0, 65536, (40, 60, 3), dtype=np.uint16)[::2, 1::3]
    lut = tone_lut("bt709")
    np.testing.assert_array_equal(apply_lut(image, lut), lut[image])


def test_short_lut_saturates_codes_beyond_its_end():
    lut = tone_lut("srgb", size=4096)
    image = np.array([[0, 2048, 4095, 4096, 65535]], np.uint16)
    np.testing.assert_array_equal(apply_lut(image, lut), lut[np.minimum(image, 4095)])
    assert apply_lut(np.zeros((0, 3), np.uint16), lut).shape == (0, 3)


@pytest.mark.parametrize(
    ("image", "lut", "match"),
    [
        (np.zeros((4, 4), np.uint8), np.zeros(65536, np.uint8), "image_u16"),
        (np.zeros((4, 4), np.float32), np.zeros(65536, np.uint8), "image_u16"),
        (np.zeros((4, 4), np.uint16), np.zeros(65536, np.uint16), "lut_u8"),
        (np.zeros((4, 4), np.uint16), np.zeros(65537, np.uint8), "lut_u8"),
        (np.zeros((4, 4), np.uint16), np.zeros((256, 256), np.uint8), "lut_u8"),
        (np.zeros((4, 4), np.uint16), np.zeros(0, np.uint8), "lut_u8"),
    ],
)
def test_apply_lut_refuses_bad_input(image, lut, match):
    with pytest.raises(ValueError, match=match):
        apply_lut(image, lut)
