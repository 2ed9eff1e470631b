"""The lens model on points: pixels through Brown–Conrady, and world points through the full camera.

The same functions build the image remap (`camgen.optics.remap`), so annotations, camera metadata and
pixels share one lens model. Pixel convention (DESIGN.md): OpenCV, pixel centres at integers.

- *undistorted* pixels: the ideal pinhole image, u = fx·x + cx with (x, y) = (X/Z, Y/Z);
- *distorted* pixels: what the sensor records, u' = fx·x' + cx with (x', y') = distort(x, y), exactly
  as `cv2.projectPoints` (see `camgen.optics.distortion`).
"""

from __future__ import annotations

import functools

import numpy as np

from camgen.optics.distortion import distort_normalized, monotone_radius, undistort_normalized

INVERSE_RESIDUAL_MAX_PX = 1e-3
"""Largest accepted residual |distort(undistort(p)) − p| of the iterative inverse, px."""


class LensInversionError(ValueError):
    """The distortion could not be inverted to the required residual (the point lies where the
    model folds over or is undefined)."""


def _intrinsics(K_px) -> tuple[float, float, float, float, float]:
    K = np.asarray(K_px, dtype=np.float64)
    return K[0, 0], K[1, 1], K[0, 2], K[1, 2], K[0, 1]


def _to_normalized(points_px: np.ndarray, K_px) -> np.ndarray:
    fx, fy, cx, cy, skew = _intrinsics(K_px)
    p = np.asarray(points_px, dtype=np.float64)
    y = (p[..., 1] - cy) / fy
    x = (p[..., 0] - cx - skew * y) / fx
    return np.stack([x, y], axis=-1)


def _to_pixels(normalized: np.ndarray, K_px) -> np.ndarray:
    fx, fy, cx, cy, skew = _intrinsics(K_px)
    x, y = normalized[..., 0], normalized[..., 1]
    return np.stack([fx * x + skew * y + cx, fy * y + cy], axis=-1)


def distort_points(points_px: np.ndarray, K_px, distortion) -> np.ndarray:
    """Undistorted (pinhole) pixel coordinates → distorted pixel coordinates.

    Parameters
    ----------
    points_px : (..., 2) array, px
        Positions in the ideal pinhole image of camera matrix `K_px`.
    K_px : (3, 3) array
        Camera matrix, px.
    distortion : up to 8 coefficients
        OpenCV order (k1, k2, p1, p2, k3, k4, k5, k6).
    """
    return _to_pixels(distort_normalized(_to_normalized(points_px, K_px), distortion), K_px)


def undistort_points(
    points_px: np.ndarray,
    K_px,
    distortion,
    *,
    residual_max_px: float = INVERSE_RESIDUAL_MAX_PX,
    initial_px: np.ndarray | None = None,
) -> np.ndarray:
    """Distorted pixel coordinates → undistorted (pinhole) pixel coordinates.

    Newton's method on the full model (`undistort_normalized`); every point's residual
    |distort(result) − input| is checked, and `LensInversionError` names the worst one if it exceeds
    `residual_max_px`. `initial_px` is an optional starting guess (undistorted pixels).
    """
    K = np.asarray(K_px, dtype=np.float64)
    initial = None if initial_px is None else _to_normalized(initial_px, K)
    target = _to_normalized(points_px, K)
    result = undistort_normalized(target, distortion, initial=initial)
    residual_px = result.residual * max(K[0, 0], K[1, 1])
    # A root beyond the fold radius (or through the opposite side of the axis) also has a zero
    # residual, but no ray on the lens's monotone branch lands there: it is not the inverse.
    radius = np.hypot(result.points[..., 0], result.points[..., 1])
    same_side = np.sum(result.points * target, axis=-1) >= 0.0
    folded = ~(result.jacobian_det > 0.0)
    bad = ~(residual_px <= residual_max_px) | ~same_side | folded | ~(radius < fold_radius_normalized(distortion))
    if np.any(bad):
        worst = np.unravel_index(int(np.argmax(bad)), bad.shape)
        point = np.asarray(points_px, dtype=np.float64)[worst]
        raise LensInversionError(
            f"the distortion {list(np.ravel(distortion))} cannot be inverted at pixel "
            f"({point[0]:.2f}, {point[1]:.2f}): "
            f"residual {float(residual_px[worst]):.3g} px (at most {residual_max_px:g} px on the lens's monotone "
            f"branch; {int(bad.sum())} point(s) fail); the model folds over or is undefined there"
        )
    return _to_pixels(result.points, K)


def fold_radius_normalized(distortion, r_max: float = 20.0) -> float:
    """Undistorted normalised radius where the radial mapping r·R(r²) stops rising, at a fold or a
    pole of the rational model (∞ if it does not within `r_max`).

    Scene points beyond this radius would wrap back into the image under the polynomial model, so
    `project_points` reports them as not visible instead. Kept per coefficients (`_fold_radius`): finding it
    samples the mapping 20 001 times (~1 ms), and the annotations project points through the same lens tens of
    times a frame.
    """
    return _fold_radius(tuple(float(c) for c in np.ravel(np.asarray(distortion, dtype=np.float64))), float(r_max))


@functools.lru_cache(maxsize=64)
def _fold_radius(distortion: tuple[float, ...], r_max: float) -> float:
    return monotone_radius(distortion, r_max)


def project_points(
    points_world_m: np.ndarray, T_world_from_cam: np.ndarray, K_px, distortion
) -> tuple[np.ndarray, np.ndarray]:
    """World points → distorted pixel coordinates and depth, through the full camera.

    Returns ``(points_px (N, 2), depth_m (N,))``. Identical to `cv2.projectPoints` for points in front
    of the camera and inside the lens's fold radius; points behind the camera (z ≤ 0) or beyond the
    fold radius get NaN pixel coordinates (they are not imaged), with their depth still given.
    """
    points = np.asarray(points_world_m, dtype=np.float64).reshape(-1, 3)
    T_cam_from_world = np.linalg.inv(np.asarray(T_world_from_cam, dtype=np.float64))
    cam = points @ T_cam_from_world[:3, :3].T + T_cam_from_world[:3, 3]
    depth_m = cam[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        normalized = cam[:, :2] / depth_m[:, None]
    radius = np.hypot(normalized[:, 0], normalized[:, 1])
    imaged = (depth_m > 0) & (radius < fold_radius_normalized(distortion))
    normalized[~imaged] = np.nan
    return _to_pixels(distort_normalized(normalized, distortion), K_px), depth_m
