"""Brown–Conrady in OpenCV's convention, checked against cv2.projectPoints and closed forms."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from camgen.optics.distortion import (
    distort_normalized,
    max_displacement_px,
    radial_reach,
    undistort_normalized,
)

COEFFS = [
    np.array([-0.28, 0.07, 0.001, -0.0008, -0.006, 0.0, 0.0, 0.0]),  # barrel
    np.array([0.12, 0.02, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),  # pincushion
    np.array([-0.3, 0.25, 0.0005, 0.0003, -0.05, 0.0, 0.0, 0.0]),  # mustache
    np.array([0.1, 0.02, 0.001, 0.002, 0.0, 0.35, 0.05, 0.001]),  # rational model
]


@pytest.mark.parametrize("coeffs", COEFFS, ids=["barrel", "pincushion", "mustache", "rational"])
def test_distortion_equals_cv2_project_points(coeffs):
    rng = np.random.default_rng(1)
    points = rng.uniform(-0.6, 0.6, size=(500, 2))
    object_points = np.column_stack([points, np.ones(len(points))])
    projected, _ = cv2.projectPoints(object_points, np.zeros(3), np.zeros(3), np.eye(3), coeffs)
    np.testing.assert_allclose(distort_normalized(points, coeffs), projected.reshape(-1, 2), atol=1e-12)


@pytest.mark.parametrize("coeffs", COEFFS, ids=["barrel", "pincushion", "mustache", "rational"])
def test_undistort_inverts_with_small_residual(coeffs):
    rng = np.random.default_rng(2)
    truth = rng.uniform(-0.5, 0.5, size=(1000, 2))
    result = undistort_normalized(distort_normalized(truth, coeffs), coeffs)
    assert result.residual.max() < 1e-12
    np.testing.assert_allclose(result.points, truth, atol=1e-10)


def test_batch_shapes_are_kept():
    grid = np.zeros((4, 5, 2))
    assert distort_normalized(grid, COEFFS[0]).shape == (4, 5, 2)
    assert undistort_normalized(grid, COEFFS[0]).points.shape == (4, 5, 2)


def test_radial_reach_closed_form():
    # g(r) = r + k1 r³ turns back at r = 1/√(−3 k1), where g = (2/3)/√(−3 k1).
    k1 = -0.4
    expected = (2 / 3) / np.sqrt(-3 * k1)
    assert radial_reach([k1], r_undistorted_max=5.0, samples=200001) == pytest.approx(expected, rel=1e-6)
    # Pincushion never turns back: the reach is g at the end of the interval.
    assert radial_reach([0.1], r_undistorted_max=2.0) == pytest.approx(2.0 + 0.1 * 8.0)


def test_zero_distortion_displaces_nothing():
    K = np.array([[1000.0, 0, 959.5], [0, 1000.0, 539.5], [0, 0, 1]])
    assert max_displacement_px(np.zeros(8), K, 1920, 1080) == 0.0
    corner_r = np.hypot(960, 540) / 1000
    k1 = -0.1
    # With k1 only, the corner moves by |k1|·r³·f pixels.
    assert max_displacement_px([k1], K, 1920, 1080) == pytest.approx(abs(k1) * corner_r**3 * 1000, rel=1e-9)
