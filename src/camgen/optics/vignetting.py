"""Relative illumination across the frame: natural cos⁴ falloff and the lens's optical vignetting.

- Natural: the irradiance of an image point whose chief ray leaves the scene at angle θ to the optical
  axis falls as cos⁴θ; with the undistorted ray (x, y) = (X/Z, Y/Z), cos θ = 1/√(1 + x² + y²), so
  cos⁴θ = (1 + x² + y²)⁻². Reference: Ray, *Applied Photographic Optics*, 3rd ed., §12.
- Optical (mechanical) vignetting: the polynomial of datasheet relative-illumination curves (the form
  of the Adobe lens-profile vignette model), RI(ρ) = 1 + a1·ρ² + a2·ρ⁴ + a3·ρ⁶, ρ the distorted image
  radius over the corner radius. It shrinks as the aperture closes: at the wide-open f-number it
  applies in full, at `full_illumination_f_number` not at all, linearly in stops between.

Applied as a gain on radiance, before the sensor.
"""

from __future__ import annotations

import math

import numpy as np


def natural_falloff(undistorted_normalized: np.ndarray) -> np.ndarray:
    """cos⁴θ of each ray; `undistorted_normalized` (..., 2) holds (X/Z, Y/Z)."""
    p = np.asarray(undistorted_normalized, dtype=np.float64)
    return 1.0 / (1.0 + p[..., 0] ** 2 + p[..., 1] ** 2) ** 2


def aperture_weight(f_number: float, f_number_wide_open: float, full_illumination_f_number: float | None) -> float:
    """Fraction (0–1) of the wide-open optical vignetting left at `f_number`: 1 wide open, 0 from
    `full_illumination_f_number` on, linear in stops (log2 N) between; always 1 when that is None."""
    if full_illumination_f_number is None:
        return 1.0
    if full_illumination_f_number <= f_number_wide_open:
        return 0.0
    stops = math.log2(f_number / f_number_wide_open) / math.log2(full_illumination_f_number / f_number_wide_open)
    return float(np.clip(1.0 - stops, 0.0, 1.0))


def optical_relative_illumination(rho: np.ndarray, polynomial: tuple[float, float, float], weight: float = 1.0):
    """RI(ρ) = 1 + weight·(a1ρ² + a2ρ⁴ + a3ρ⁶); ρ is 0 at the centre and 1 at the farthest corner."""
    a1, a2, a3 = polynomial
    r2 = np.asarray(rho, dtype=np.float64) ** 2
    return 1.0 + weight * r2 * (a1 + r2 * (a2 + r2 * a3))


def relative_illumination(
    undistorted_normalized: np.ndarray,
    distorted_normalized: np.ndarray,
    *,
    corner_radius_normalized: float,
    natural_cos4: bool,
    polynomial: tuple[float, float, float],
    weight: float,
) -> np.ndarray:
    """The gain (..., ) at each image point: cos⁴θ (if `natural_cos4`) times the optical RI."""
    d = np.asarray(distorted_normalized, dtype=np.float64)
    rho = np.hypot(d[..., 0], d[..., 1]) / corner_radius_normalized
    gain = optical_relative_illumination(rho, polynomial, weight)
    if natural_cos4:
        gain = gain * natural_falloff(undistorted_normalized)
    return gain
