"""Relative illumination: the cos⁴ law, the optical polynomial, its aperture dependence, validation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydantic import ValidationError

from camgen.config.profile import Vignetting
from camgen.optics.vignetting import (
    aperture_weight,
    natural_falloff,
    optical_relative_illumination,
    relative_illumination,
)


def test_cos4_of_the_chief_ray_angle():
    angles = np.radians([0.0, 20.0, 45.0, 60.0])
    rays = np.column_stack([np.tan(angles) * math.cos(0.3), np.tan(angles) * math.sin(0.3)])
    np.testing.assert_allclose(natural_falloff(rays), np.cos(angles) ** 4, rtol=1e-12)


def test_optical_polynomial_and_the_corner_figure():
    assert optical_relative_illumination(
        np.array(1.0), Vignetting(relative_illumination_corner=0.6).optical_polynomial
    ) == (pytest.approx(0.6))
    rho = np.array([0.0, 0.5, 1.0])
    np.testing.assert_allclose(
        optical_relative_illumination(rho, (-0.2, -0.1, 0.05)),
        [1.0, 1 - 0.2 * 0.25 - 0.1 * 0.0625 + 0.05 * 0.015625, 0.75],
    )


def test_optical_vignetting_fades_in_stops_as_the_aperture_closes():
    assert aperture_weight(1.4, 1.4, 5.6) == 1.0
    assert aperture_weight(2.8, 1.4, 5.6) == pytest.approx(0.5)  # one of two stops
    assert aperture_weight(8.0, 1.4, 5.6) == 0.0
    assert aperture_weight(8.0, 1.4, None) == 1.0


def test_gain_combines_both_at_the_corner():
    corner = np.array([[0.6, 0.45]])  # normalised, undistorted = distorted here
    gain = relative_illumination(
        corner, corner, corner_radius_normalized=0.75, natural_cos4=True, polynomial=(-0.3, 0.0, 0.0), weight=0.5
    )
    assert gain[0] == pytest.approx((1 - 0.15) / (1 + 0.75**2) ** 2)


@pytest.mark.parametrize(
    ("fields", "match"),
    [
        ({"polynomial": (-0.5, -0.6, 0.0)}, r"relative illumination in \(0, 1\].*got -0.1 at ρ = 1"),
        ({"polynomial": (0.2, 0.0, 0.0)}, r"relative illumination in \(0, 1\].*got 1.2"),
        ({"polynomial": (-0.2, 0.0, 0.0), "relative_illumination_corner": 0.5}, "one source, not two"),
    ],
)
def test_bad_polynomials_are_refused(fields, match):
    with pytest.raises(ValidationError, match=match):
        Vignetting(**fields)
