"""Contrast stretch: histogram percentiles against np.percentile, limits, and the adaptation's step response."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.isp.contrast import adapt_limits, percentiles_from_histogram, stretch_limits

PERCENTILES = [0.0, 0.5, 1.0, 5.0, 25.0, 50.0, 75.0, 99.5, 100.0]


@pytest.mark.parametrize(
    "samples",
    [
        np.random.default_rng(0).integers(0, 1000, 5000),
        np.random.default_rng(1).poisson(3.0, 777),  # few distinct values, many ties
        np.random.default_rng(2).choice([5, 900, 60000], 101),  # wide gaps between values
        np.random.default_rng(3).integers(0, 65536, 20001),
        np.array([42]),
        np.array([3, 7]),
    ],
)
def test_histogram_percentiles_equal_np_percentile_of_the_samples(samples):
    hist = np.bincount(samples)
    got = percentiles_from_histogram(hist, PERCENTILES)
    expected = np.percentile(samples, PERCENTILES, method="linear")
    assert np.all(np.abs(got - expected) <= 1.0)  # the promise: within one bin
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9)  # in fact exact for integer samples


@pytest.mark.parametrize("dtype", [np.float64, np.float32, np.int64, np.uint32, np.uint8])
def test_histogram_percentiles_accept_any_count_dtype_and_leave_the_histogram_alone(dtype):
    hist = np.array([0, 2, 0, 2], dtype)  # samples 1, 1, 3, 3
    kept = hist.copy()
    np.testing.assert_allclose(percentiles_from_histogram(hist, [0, 50, 100]), [1.0, 2.0, 3.0])
    assert percentiles_from_histogram(hist, 50.0).shape == ()
    np.testing.assert_array_equal(hist, kept)


@pytest.mark.parametrize(
    ("hist", "percentiles", "match"),
    [
        (np.zeros(10), [50], "no samples"),
        (np.array([1, -1, 3]), [50], "≥ 0"),
        (np.array([1.0, np.nan]), [50], "finite"),
        (np.ones((2, 2)), [50], "1-D"),
        (np.array([]), [50], "non-empty"),
        (np.ones(4), [101], r"\[0, 100\]"),
        (np.ones(4), [-0.1], r"\[0, 100\]"),
    ],
)
def test_histogram_percentiles_refuse_bad_input(hist, percentiles, match):
    with pytest.raises(ValueError, match=match):
        percentiles_from_histogram(hist, percentiles)


@pytest.mark.parametrize("shape", [(120, 160, 3), (120, 160), (5000,)])
@pytest.mark.parametrize(("subsample", "stride"), [(1, 1), (3, 3), (4, 5)])
def test_stretch_limits_are_the_percentiles_of_the_strided_subsample(shape, subsample, stride):
    image = np.random.default_rng(4).normal(20000, 6000, shape).clip(0, 65535).astype(np.uint16)
    low, high = stretch_limits(image, 0.5, 99.5, subsample=subsample)
    strided = image[::stride] if image.ndim == 1 else image[::stride, ::stride]
    np.testing.assert_allclose([low, high], np.percentile(strided, [0.5, 99.5]), atol=1e-9)
    assert isinstance(low, float) and isinstance(high, float)


@pytest.mark.parametrize("subsample", [2, 4, 8])
def test_even_strides_still_read_every_bayer_phase(subsample):
    mosaic = np.tile(np.array([[100, 200], [200, 300]], np.uint16), (60, 80))  # R, G, G, B of an RGGB mosaic
    assert stretch_limits(mosaic, 0.0, 100.0, subsample=subsample) == (100.0, 300.0)
    assert stretch_limits(mosaic, 50.0, 100.0, subsample=subsample)[0] == 200.0


def test_stretch_limits_count_past_float32_precision():
    # 2^24 samples, each of the 65536 values 256 times: beyond OpenCV's exact float32 counts.
    samples = (np.arange(2**24) % 65536).astype(np.uint16)
    low, high = stretch_limits(samples, 50.0, 100.0, subsample=1)
    # Median position (n − 1)/2 = 8388607.5 falls between ranks holding values 32767 and 32768.
    assert (low, high) == (32767.5, 65535.0)


def test_flat_image_is_widened_to_one_dn():
    assert stretch_limits(np.full((64, 64, 3), 1234, np.uint16), 1.0, 99.0) == (1234.0, 1235.0)
    assert stretch_limits(np.full((64, 64), 65535, np.uint16), 1.0, 99.0) == (65535.0, 65536.0)


@pytest.mark.parametrize(
    ("samples", "low", "high", "kwargs", "match"),
    [
        (np.zeros((4, 4), np.uint8), 1, 99, {}, "uint16"),
        (np.zeros((4, 4), np.float32), 1, 99, {}, "uint16"),
        (np.zeros((0, 4), np.uint16), 1, 99, {}, "non-empty"),
        (np.zeros((4, 4), np.uint16), 99, 1, {}, "low_percentile < high_percentile"),
        (np.zeros((4, 4), np.uint16), -1, 99, {}, "0 ≤ low_percentile"),
        (np.zeros((4, 4), np.uint16), 1, 101, {}, "≤ 100"),
        (np.zeros((4, 4), np.uint16), 1, 99, {"subsample": 0}, "subsample"),
    ],
)
def test_stretch_limits_refuse_bad_input(samples, low, high, kwargs, match):
    with pytest.raises(ValueError, match=match):
        stretch_limits(samples, low, high, **kwargs)


def test_adaptation_step_response_follows_the_closed_form():
    dt, tau = 1 / 25, 0.5
    start, target = (100.0, 4000.0), (2000.0, 60000.0)
    limits = start
    for k in range(1, 101):
        limits = adapt_limits(limits, target, frame_interval_s=dt, adaptation_time_s=tau)
        remaining = math.exp(-k * dt / tau)
        for now, s, t in zip(limits, start, target, strict=True):
            assert math.isclose(now, t + (s - t) * remaining, rel_tol=1e-12)
    assert limits[1] > limits[0]


def test_adaptation_time_does_not_depend_on_frame_rate():
    # One second at 10 fps and at 50 fps leaves the same fraction exp(−1/τ).
    results = []
    for fps in (10, 50):
        limits = (0.0, 1000.0)
        for _ in range(fps):
            limits = adapt_limits(limits, (500.0, 2000.0), frame_interval_s=1 / fps, adaptation_time_s=0.25)
        results.append(limits)
    np.testing.assert_allclose(results[0], results[1], rtol=1e-12)


def test_instant_adaptation_and_first_frame_take_the_target():
    assert adapt_limits((0.0, 1.0), (10.0, 20.0), frame_interval_s=0.04, adaptation_time_s=0.0) == (10.0, 20.0)
    assert adapt_limits(None, (10.0, 20.0), frame_interval_s=0.04, adaptation_time_s=3.0) == (10.0, 20.0)


@pytest.mark.parametrize(
    ("previous", "target", "dt", "tau", "match"),
    [
        ((0, 1), (0, 1), 0.0, 1.0, "frame_interval_s"),
        ((0, 1), (0, 1), math.nan, 1.0, "frame_interval_s"),
        ((0, 1), (0, 1), 0.04, -1.0, "adaptation_time_s"),
        ((0, 1), (0, 1), 0.04, math.inf, "adaptation_time_s"),
        ((0, 1), (0, 1, 2), 0.04, 1.0, "target"),
        ((0, math.nan), (0, 1), 0.04, 1.0, "previous"),
    ],
)
def test_adaptation_refuses_bad_input(previous, target, dt, tau, match):
    with pytest.raises(ValueError, match=match):
        adapt_limits(previous, target, frame_interval_s=dt, adaptation_time_s=tau)
