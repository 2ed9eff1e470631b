"""Pixel density of a point through the full lens model, from the projection's local Jacobian.

The Jacobian J = ∂(u, v)/∂(X, Y, Z) (2 × 3, px/m) of the distorted projection (`camgen.optics.
projection.project_points`, exactly `cv2.projectPoints`) is the chain of the camera matrix, the lens's
distortion (its 2 × 2 Jacobian by central differences of `distort_normalized`) and the perspective
division (`projection_jacobian`). From it:

- ground density: the smaller singular value of J's ground columns ∂(u, v)/∂(X, Y), px/m: the image
  length of a metre along the ground in its least resolved direction (for a pinhole at the image centre,
  f·sin(elevation)/distance, the foreshortened direction towards the camera);
- vertical density: ‖J·ẑ‖, the image length per metre of a vertical element: the derivative of the image
  of a vertical 1.8 m segment at its probe point (the midpoint of a person standing on the ground grid's
  point, or the face on a face-height plane), so equal to the segment's image length / 1.8 m to second
  order; for a fronto-parallel target f/distance;
- across density: ‖J·t̂‖ with t̂ the horizontal direction across the sight line (a person's width);
- person density: min(vertical, across), the density on a standing person in its worse direction, which
  the DORI classes (`camgen.coverage.dori`) are judged on.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from camgen.coverage.views import CameraView, PtzReach, centring_axes
from camgen.optics.distortion import distort_normalized
from camgen.optics.projection import project_points

DISTORTION_STEP = 1e-6
PERSON_HEIGHT_M = 1.8
"""The standing person whose vertical density is measured, m."""


def in_image(points_px: np.ndarray, width_px: int, height_px: int) -> np.ndarray:
    """Whether distorted pixel positions (N, 2) land on the image (pixel edges at −0.5 and size − 0.5); NaN
    (not imaged) is not."""
    u, v = points_px[..., 0], points_px[..., 1]
    with np.errstate(invalid="ignore"):
        return (u >= -0.5) & (u <= width_px - 0.5) & (v >= -0.5) & (v <= height_px - 0.5)


def projection_jacobian(points_m: np.ndarray, view: CameraView) -> tuple[np.ndarray, np.ndarray]:
    """Distorted pixels (N, 2) and the Jacobian ∂(u, v)/∂(X, Y, Z) (N, 2, 3), px/m, of world points (N, 3).

    J = K₂ · ∂distort/∂(x, y) · ∂(x, y)/∂(camera point) · R_cam_from_world, with (x, y) = (X_c/Z_c, Y_c/Z_c)
    and K₂ the camera matrix's 2 × 2 part; the distortion's 2 × 2 Jacobian by central differences
    (step 1e-6 in normalised units) of the same `distort_normalized` the projection uses."""
    points = np.asarray(points_m, dtype=np.float64).reshape(-1, 3)
    uv, _ = project_points(points, view.T_world_from_cam, view.K_px, view.distortion)
    R = view.T_world_from_cam[:3, :3].T  # R_cam_from_world
    cam = (points - view.T_world_from_cam[:3, 3]) @ R.T
    z = cam[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        x, y = cam[:, 0] / z, cam[:, 1] / z
        perspective = np.zeros((len(points), 2, 3))
        perspective[:, 0, 0] = perspective[:, 1, 1] = 1.0 / z
        perspective[:, 0, 2] = -x / z
        perspective[:, 1, 2] = -y / z
    normalized = np.stack([x, y], -1)
    lens = np.empty((len(points), 2, 2))
    for axis in range(2):
        step = np.zeros(2)
        step[axis] = DISTORTION_STEP
        plus = distort_normalized(normalized + step, view.distortion)
        minus = distort_normalized(normalized - step, view.distortion)
        lens[:, :, axis] = (plus - minus) / (2 * DISTORTION_STEP)
    K2 = np.asarray(view.K_px, dtype=np.float64)[:2, :2]
    return uv, K2 @ lens @ perspective @ R


def across_direction(points_m: np.ndarray, centre_m: np.ndarray) -> np.ndarray:
    """Horizontal unit vectors (N, 3) across the sight line from `centre_m` to each point (x̂ straight below)."""
    g = np.asarray(points_m, dtype=np.float64).reshape(-1, 3)[:, :2] - np.asarray(centre_m)[:2]
    norm = np.hypot(g[:, 0], g[:, 1])
    safe = norm > 1e-9
    t = np.zeros((len(g), 3))
    t[:, 0] = np.where(safe, -g[:, 1] / np.where(safe, norm, 1), 1.0)
    t[:, 1] = np.where(safe, g[:, 0] / np.where(safe, norm, 1), 0.0)
    return t


def ground_density_px_m(J: np.ndarray) -> np.ndarray:
    """Smaller singular value of ∂(u, v)/∂(X, Y) (N,), px/m (NaN stays NaN).

    For a 2 × 2 matrix A, σ²_min = (‖A‖²_F − √(‖A‖⁴_F − 4 det(A)²)) / 2."""
    A = J[:, :, :2]
    frobenius2 = np.einsum("nij,nij->n", A, A)
    det = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] * A[:, 1, 0]
    # The form with the sum in the denominator keeps precision when the two singular values differ widely.
    root = np.sqrt(np.maximum(frobenius2 * frobenius2 - 4 * det * det, 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.sqrt(np.where(frobenius2 > 0, 2 * det * det / (frobenius2 + root), 0.0))


@dataclass(frozen=True)
class Densities:
    """Densities at N points, px/m (NaN where the point is not imaged)."""

    ground_px_m: np.ndarray
    vertical_px_m: np.ndarray
    across_px_m: np.ndarray

    @property
    def person_px_m(self) -> np.ndarray:
        return np.fmin(self.vertical_px_m, self.across_px_m) * _nan_if_any(self.vertical_px_m, self.across_px_m)


def _nan_if_any(*arrays: np.ndarray) -> np.ndarray:
    return np.where(np.any([np.isnan(a) for a in arrays], axis=0), np.nan, 1.0)


def person_probe_m(points_m: np.ndarray, plane_height_m: float) -> np.ndarray:
    """Where a person at each grid point is measured: the middle of a 1.8 m person standing on the ground
    grid's point, the point itself on a plane above the ground (the face at 1.6 m)."""
    probe = np.array(points_m, dtype=np.float64).reshape(-1, 3)
    if plane_height_m == 0:
        probe[:, 2] += PERSON_HEIGHT_M / 2
    return probe


def densities(points_m: np.ndarray, plane_height_m: float, view: CameraView) -> tuple[np.ndarray, Densities]:
    """Distorted pixels of the points (N, 2) and their densities through `view` (times its `detail_scale`)."""
    points = np.asarray(points_m, dtype=np.float64).reshape(-1, 3)
    uv, J = projection_jacobian(points, view)
    probe = person_probe_m(points, plane_height_m)
    _, J_probe = projection_jacobian(probe, view)
    J, J_probe = J * view.detail_scale, J_probe * view.detail_scale  # a scaled-up ePTZ window adds no detail
    t = across_direction(probe, view.centre_m)
    return uv, Densities(
        ground_px_m=ground_density_px_m(J),
        vertical_px_m=np.linalg.norm(J_probe[:, :, 2], axis=1),
        across_px_m=np.linalg.norm(np.einsum("nij,nj->ni", J_probe, t), axis=1),
    )


def centred_densities(
    points_m: np.ndarray, plane_height_m: float, reach: PtzReach, zoom_x: float
) -> tuple[np.ndarray, Densities]:
    """Whether a PTZ head reaches each point (N,), and its densities when it centres the point at `zoom_x`.

    Centred, J = diag(fx, fy)·[x̂ᵀ; ŷᵀ] / depth, with x̂, ŷ the camera's axes aimed at the point (the
    distortion's Jacobian is the identity at the image centre). The head centres the grid point for the
    ground density and the person's probe point for the person's; reached means both can be centred."""
    points = np.asarray(points_m, dtype=np.float64).reshape(-1, 3)
    fx, fy = reach.fx_wide_px * zoom_x, reach.fy_wide_px * zoom_x

    def jacobian(p):
        ok, x_axis, y_axis = centring_axes(reach, p)
        depth = np.linalg.norm(p - reach.position_m, axis=1)
        return ok, np.stack([fx * x_axis, fy * y_axis], 1) / depth[:, None, None]

    probe = person_probe_m(points, plane_height_m)
    ok_ground, J = jacobian(points)
    ok_probe, J_probe = jacobian(probe)
    t = across_direction(probe, reach.position_m)
    return ok_ground & ok_probe, Densities(
        ground_px_m=ground_density_px_m(J),
        vertical_px_m=np.linalg.norm(J_probe[:, :, 2], axis=1),
        across_px_m=np.linalg.norm(np.einsum("nij,nj->ni", J_probe, t), axis=1),
    )
