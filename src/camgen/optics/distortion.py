"""Brown–Conrady lens distortion in OpenCV's order and direction.

The model maps *undistorted* normalised coordinates (x, y) = (X/Z, Y/Z) to *distorted* ones, exactly
as `cv2.projectPoints` does with ``distCoeffs = (k1, k2, p1, p2, k3, k4, k5, k6)``::

    r² = x² + y²
    R  = (1 + k1 r² + k2 r⁴ + k3 r⁶) / (1 + k4 r² + k5 r⁴ + k6 r⁶)
    x' = x R + 2 p1 x y + p2 (r² + 2 x²)
    y' = y R + p1 (r² + 2 y²) + 2 p2 x y

References: D. C. Brown, "Decentering distortion of lenses", Photogramm. Eng. 1966; OpenCV
``calib3d`` documentation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

N_COEFFICIENTS = 8


def _coefficients(coeffs) -> np.ndarray:
    c = np.zeros(N_COEFFICIENTS)
    values = np.asarray(coeffs, dtype=np.float64).ravel()
    if values.size > N_COEFFICIENTS:
        raise ValueError(f"at most {N_COEFFICIENTS} distortion coefficients, got {values.size}")
    c[: values.size] = values
    return c


def _radial(r2: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """R(r²) and dR/d(r²)."""
    k1, k2, _, _, k3, k4, k5, k6 = c
    num = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    den = 1.0 + r2 * (k4 + r2 * (k5 + r2 * k6))
    dnum = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2)
    dden = k4 + r2 * (2.0 * k5 + 3.0 * k6 * r2)
    return num / den, (dnum * den - num * dden) / (den * den)


def distort_normalized(points: np.ndarray, coeffs) -> np.ndarray:
    """Undistorted → distorted normalised coordinates; `points` has shape (..., 2)."""
    c = _coefficients(coeffs)
    p = np.asarray(points, dtype=np.float64)
    x, y = p[..., 0], p[..., 1]
    r2 = x * x + y * y
    radial, _ = _radial(r2, c)
    p1, p2 = c[2], c[3]
    xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
    yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
    return np.stack([xd, yd], axis=-1)


@dataclass(frozen=True)
class Undistorted:
    """Result of inverting the distortion: points (..., 2), the residual |distort(points) − target| and
    the Jacobian determinant of the distortion there (≤ 0 where the mapping folds over)."""

    points: np.ndarray
    residual: np.ndarray
    jacobian_det: np.ndarray


def undistort_normalized(
    points: np.ndarray, coeffs, *, max_iterations: int = 50, initial: np.ndarray | None = None
) -> Undistorted:
    """Distorted → undistorted normalised coordinates by Newton's method with the analytic Jacobian.

    Starts from `initial` (same shape as `points`) or, by default, from the radial part inverted on
    the lens's monotone branch (`_radial_start`). The caller decides what residual is acceptable (in
    pixels, residual·f_px); nothing is clamped.
    """
    c = _coefficients(coeffs)
    target = np.asarray(points, dtype=np.float64)
    p1, p2 = c[2], c[3]
    start = _radial_start(target, c) if initial is None else np.asarray(initial, dtype=np.float64)
    x = start[..., 0].copy()
    y = start[..., 1].copy()
    with np.errstate(all="ignore"):  # non-convergence is caught by the residual, not by warnings
        for _ in range(max_iterations):
            r2 = x * x + y * y
            radial, dradial = _radial(r2, c)
            fx = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) - target[..., 0]
            fy = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y - target[..., 1]
            a = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x
            b = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y
            d = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x
            det = a * d - b * b
            step_x = (d * fx - b * fy) / det
            step_y = (a * fy - b * fx) / det
            x = x - step_x
            y = y - step_y
            if np.all(np.abs(step_x) + np.abs(step_y) < 1e-13):  # ~1e-10 px at f = 1000 px
                break
    with np.errstate(all="ignore"):
        residual = np.hypot(*np.moveaxis(distort_normalized(np.stack([x, y], -1), c) - target, -1, 0))
        r2 = x * x + y * y
        radial, dradial = _radial(r2, c)
        a = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x
        b = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y
        d = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x
    return Undistorted(points=np.stack([x, y], axis=-1), residual=residual, jacobian_det=a * d - b * b)


def _radial_start(target: np.ndarray, c: np.ndarray, samples: int = 4097) -> np.ndarray:
    """A starting point on the lens's monotone branch: the radial part inverted by table lookup.

    Starting Newton at the distorted point itself can land beyond a fold or a pole of the rational
    model (and converge to a root no ray reaches, or diverge); the table confines the start to the
    branch r ∈ [0, r_fold) where g(r) = r·R(r²) rises.
    """
    radius_d = np.hypot(target[..., 0], target[..., 1])
    largest = float(np.nanmax(radius_d, initial=0.0)) if radius_d.size else 0.0
    if not np.isfinite(largest) or largest == 0.0:
        return target
    r, g = _monotone_branch(c, 4.0 * max(1.0, largest), samples)
    radius_u = np.interp(radius_d, g, r)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(radius_d > 0, radius_u / radius_d, 1.0)
    return target * scale[..., None]


def _monotone_branch(c: np.ndarray, r_max: float, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """Samples (r, g(r)) of the radial mapping from r = 0 up to the first fold, pole or non-finite value."""
    r = np.linspace(0.0, r_max, samples)
    r2 = r * r
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        g, dg = radial_mapping(r, c)
        denominator = 1.0 + r2 * (c[5] + r2 * (c[6] + r2 * c[7]))
    # Stop at a fold (g' ≤ 0), at a pole of the rational model (denominator ≤ 0), or where g stops
    # rising between samples (a fold or pole narrower than the sampling step).
    bad = ~np.isfinite(g) | ~np.isfinite(dg) | (dg <= 0.0) | (denominator <= 0.0)
    bad[1:] |= np.diff(g) <= 0.0
    bad[0] = False
    if not bad.any():
        return r, g
    first = int(np.argmax(bad))
    return r[:first], g[:first]


def radial_mapping(r: np.ndarray, coeffs) -> tuple[np.ndarray, np.ndarray]:
    """g(r) = r·R(r²) and g'(r) for the radial part, r in undistorted normalised units."""
    c = _coefficients(coeffs)
    r = np.asarray(r, dtype=np.float64)
    r2 = r * r
    radial, dradial = _radial(r2, c)
    return r * radial, radial + 2.0 * r2 * dradial


def radial_reach(coeffs, r_undistorted_max: float, samples: int = 20001) -> float:
    """The largest distorted radius the radial mapping reaches monotonically from the centre.

    Walks g(r) outward from r = 0 until g'(r) ≤ 0 (the lens folds over: two scene directions land on
    one image radius), a pole of the rational model, or `r_undistorted_max`. An image whose corners
    lie beyond the returned radius sees a folded or undefined part of the model.
    """
    _, g = _monotone_branch(_coefficients(coeffs), r_undistorted_max, samples)
    return float(g[-1])


def fold_inside(coeffs, corner_radius: float) -> float | None:
    """The distorted radius where the radial mapping turns back (`radial_reach`), when that lies inside an
    image whose farthest corner is at normalised radius `corner_radius`; None when the mapping rises
    monotonically out to the corner. The search runs out to 20 × the corner radius (at least 20), past
    any lens a profile describes."""
    reach = radial_reach(coeffs, r_undistorted_max=20.0 * max(corner_radius, 1.0))
    return reach if reach < corner_radius else None


def monotone_radius(coeffs, r_undistorted_max: float = 20.0, samples: int = 20001) -> float:
    """Undistorted radius where the monotone branch ends (fold or pole); ∞ if it reaches the limit."""
    r, _ = _monotone_branch(_coefficients(coeffs), r_undistorted_max, samples)
    return float(r[-1]) if len(r) < samples else np.inf


def max_displacement_px(coeffs, K_px: np.ndarray, width_px: int, height_px: int, samples_per_edge: int = 64) -> float:
    """Largest image displacement the distortion causes over the frame, in pixels.

    Sampled on a grid including the border, where radial distortion is largest.
    """
    xs = np.linspace(-0.5, width_px - 0.5, samples_per_edge)
    ys = np.linspace(-0.5, height_px - 0.5, samples_per_edge)
    u, v = np.meshgrid(xs, ys)
    fx, fy, cx, cy = K_px[0, 0], K_px[1, 1], K_px[0, 2], K_px[1, 2]
    normalized = np.stack([(u - cx) / fx, (v - cy) / fy], axis=-1)
    moved = distort_normalized(normalized, coeffs) - normalized
    return float(np.max(np.hypot(moved[..., 0] * fx, moved[..., 1] * fy)))
