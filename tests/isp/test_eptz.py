"""Virtual PTZ: the window's camera matrix describes the cropped and scaled pixels exactly."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.isp.eptz import (
    crop_and_scale,
    eptz_window_px,
    full_window_size_px,
    output_camera_matrix,
    window_centre_px,
)
from camgen.optics.projection import distort_points

K = np.array([[800.0, 0.0, 319.5], [0.0, 800.0, 179.5], [0.0, 0.0, 1.0]])
SENSOR = (640, 360)


def blob(size_px, centre_px, sigma_px=3.0) -> np.ndarray:
    u, v = np.meshgrid(np.arange(size_px[0]), np.arange(size_px[1]))
    return np.exp(-((u - centre_px[0]) ** 2 + (v - centre_px[1]) ** 2) / (2 * sigma_px**2)).astype(np.float32)


def centroid(image: np.ndarray) -> np.ndarray:
    v, u = np.indices(image.shape)
    return np.array([(u * image).sum(), (v * image).sum()]) / image.sum()


@pytest.mark.parametrize(
    ("window", "output"),
    [((100, 50, 320, 180), (160, 90)), ((37, 11, 401, 227), (320, 180)), ((200, 100, 160, 90), (320, 180))],
)
def test_output_matrix_maps_sensor_positions_onto_the_scaled_crop(window, output):
    """A blob at sensor position p appears in the stream where K'·K⁻¹ puts it (shrinking: area
    averaging; enlarging: bilinear), to 0.02 px."""
    K_out = output_camera_matrix(K, window, output)
    x0, y0, w, h = window
    for p in ([x0 + w * 0.3, y0 + h * 0.6], [x0 + w * 0.71, y0 + h * 0.25]):
        sigma = 3.0 * max(w / output[0], 1.0)
        scaled = crop_and_scale(blob(SENSOR, p, sigma), window, output)
        assert scaled.shape == (output[1], output[0])
        normalized = (np.array(p) - K[:2, 2]) / np.diag(K)[:2]
        expected = normalized * np.diag(K_out)[:2] + K_out[:2, 2]
        np.testing.assert_allclose(centroid(scaled), expected, atol=0.02)


def test_nearest_scaling_keeps_exact_ids_at_the_same_positions():
    ids = np.arange(SENSOR[0] * SENSOR[1], dtype=np.uint32).reshape(SENSOR[1], SENSOR[0])
    window, output = (10, 20, 300, 150), (200, 100)
    out = crop_and_scale(ids, window, output, nearest=True)
    assert out.dtype == np.uint32 and out.shape == (100, 200)
    K_out = output_camera_matrix(K, window, output)
    # each output pixel's id is the sensor pixel whose centre is nearest its own centre
    u, v = np.meshgrid(np.arange(200), np.arange(100))
    sensor_u = (u - K_out[0, 2]) / K_out[0, 0] * K[0, 0] + K[0, 2]
    sensor_v = (v - K_out[1, 2]) / K_out[1, 1] * K[1, 1] + K[1, 2]
    expected = ids[np.floor(sensor_v + 0.5).astype(int), np.floor(sensor_u + 0.5).astype(int)]
    np.testing.assert_array_equal(out, expected)


def test_window_centre_follows_the_lens():
    distortion = np.array([-0.1, 0.01, 0, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(window_centre_px(0.0, 0.0, K, distortion), K[:2, 2], atol=1e-9)
    # pan left (positive) moves the window left, tilt up moves it up; the distorted position is used
    centre = window_centre_px(10.0, 5.0, K, distortion)
    pinhole = [K[0, 2] - 800 * np.tan(np.radians(10)), K[1, 2] - 800 * np.tan(np.radians(5)) / np.cos(np.radians(10))]
    np.testing.assert_allclose(centre, distort_points(np.array(pinhole), K, distortion), atol=1e-9)
    with pytest.raises(ValueError, match="behind"):
        window_centre_px(120.0, 0.0, K, distortion)


def test_windows_keep_the_output_aspect_and_stay_on_the_sensor():
    assert full_window_size_px(SENSOR, (320, 180)) == (640.0, 360.0)
    assert full_window_size_px(SENSOR, (400, 300)) == (480.0, 360.0)
    assert eptz_window_px(np.array([319.5, 179.5]), 1.0, SENSOR, (320, 180)) == (0, 0, 640, 360)
    assert eptz_window_px(np.array([319.5, 179.5]), 2.0, SENSOR, (320, 180)) == (160, 90, 320, 180)
    # near the border the window stops at the sensor edge instead of leaving it
    x0, y0, w, h = eptz_window_px(np.array([5.0, 350.0]), 3.0, SENSOR, (320, 180))
    assert (x0, y0 + h) == (0, 360) and (w, h) == (213, 120)
