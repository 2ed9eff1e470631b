"""Optical flow and scene flow from the known motion: where the surface point seen at each pixel of
frame t is at frame t + 1.

Each output pixel's ray (undistorted, normalised: the lens model's inverse at that pixel) and its
camera z give the surface point X in the world at t (`surface_points_m`); the point moves by its
displacement d (0 for the environment, the pose change for a rigid actor, the nearest skinned vertex's
motion for a person, `nearest_vertex_displacement_m`) and is projected through the next frame's camera
(pose, camera matrix, distortion: the lens model of the pixels and annotations, with the same
distortion and fold radius as `camgen.optics.projection.project_points`). Forward flow = p(t + 1) − p(t),
px, as Middlebury and Sintel define it (Baker et al. 2011, "A Database and Evaluation Methodology for
Optical Flow", IJCV 92); it is defined for points hidden at t + 1 too.

Pixels that see no surface (the sky, depth +inf) are points at infinity: only the camera's rotation,
zoom and lens move them. A point that lands behind the next camera, or beyond the lens's fold radius,
has no image position: its flow is `UNKNOWN_FLOW_PX`, Middlebury's marker for unknown flow.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from camgen.optics.distortion import distort_normalized
from camgen.optics.projection import fold_radius_normalized

__all__ = [
    "UNKNOWN_FLOW_PX",
    "forward_flow_px",
    "nearest_vertex_displacement_m",
    "rigid_displacement_m",
    "surface_points_m",
]

UNKNOWN_FLOW_PX = 1e10
"""Flow of a pixel with no image position at t + 1: Middlebury's UNKNOWN_FLOW (its readers treat
|u| or |v| > 1e9 as unknown; flowIO.h of the Middlebury flow-code)."""


def surface_points_m(rays_normalized: np.ndarray, depth_m: np.ndarray, T_world_from_cam: np.ndarray) -> np.ndarray:
    """The world point each pixel sees: X = T · (x·z, y·z, z).

    Parameters
    ----------
    rays_normalized : (H, W, 2) float
        Undistorted normalised ray (x, y) = (X/Z, Y/Z) of each pixel (camera frame, OpenCV).
    depth_m : (H, W) float
        Camera z, m; +inf where no surface is seen.
    T_world_from_cam : (4, 4)

    Returns
    -------
    (H, W, 3) float64, m; NaN where depth is not finite.
    """
    z = np.asarray(depth_m, dtype=np.float64)
    z = np.where(np.isfinite(z), z, np.nan)
    cam = np.concatenate([rays_normalized * z[..., None], z[..., None]], axis=-1)
    T = np.asarray(T_world_from_cam, dtype=np.float64)
    return cam @ T[:3, :3].T + T[:3, 3]


def rigid_displacement_m(points_m: np.ndarray, T_world_from_actor: np.ndarray, T_world_from_actor_next: np.ndarray):
    """Displacement (…, 3) m of points (…, 3) m fixed to a rigid body whose pose changes between frames:
    M·X − X with M = T_next · T⁻¹."""
    M = np.asarray(T_world_from_actor_next, dtype=np.float64) @ np.linalg.inv(T_world_from_actor)
    return points_m @ M[:3, :3].T + M[:3, 3] - points_m


def nearest_vertex_displacement_m(points_m: np.ndarray, vertices_m: np.ndarray, vertices_next_m: np.ndarray):
    """Displacement (N, 3) m of surface points (N, 3) on a deforming mesh: that of the nearest vertex
    (same vertex order at both times).

    An approximation: a point between vertices moves with its nearest one instead of with the
    barycentric blend of its triangle's corners; the error is at most the difference in motion of
    neighbouring vertices (edges of a few cm on a person, `camgen.actors`)."""
    vertices = np.asarray(vertices_m, dtype=np.float64)
    if len(points_m) == 0:
        return np.zeros((0, 3))
    _, nearest = cKDTree(vertices).query(points_m)
    return np.asarray(vertices_next_m, dtype=np.float64)[nearest] - vertices[nearest]


def forward_flow_px(
    pixels_px: np.ndarray,
    rays_normalized: np.ndarray,
    depth_m: np.ndarray,
    displacement_m: np.ndarray,
    T_world_from_cam: np.ndarray,
    T_world_from_cam_next: np.ndarray,
    K_next_px,
    distortion_next,
) -> np.ndarray:
    """Forward optical flow (H, W, 2) float32, px: where each pixel's surface point is in the next frame,
    minus the pixel.

    Parameters
    ----------
    pixels_px : (H, W, 2) float
        Each pixel's own position (u, v), px (OpenCV: centres at integers).
    rays_normalized : (H, W, 2) float
        Its undistorted normalised ray at t.
    depth_m : (H, W) float
        Camera z at t, m; +inf for the sky (a point at infinity along the ray).
    displacement_m : (H, W, 3) float
        World motion of the pixel's surface point from t to t + 1, m (ignored where depth is +inf).
    T_world_from_cam, T_world_from_cam_next : (4, 4)
        The camera's pose at t and t + 1.
    K_next_px : (3, 3)
        Camera matrix of the next frame's image (the stream's, for a virtual PTZ).
    distortion_next : sequence of float
        Brown–Conrady coefficients of the next frame (OpenCV order).

    Returns
    -------
    (H, W, 2) float32 (u, v) flow, px; `UNKNOWN_FLOW_PX` where the point is not imaged at t + 1.
    """
    depth = np.asarray(depth_m, dtype=np.float64)
    finite = np.isfinite(depth)
    T, T_next = np.asarray(T_world_from_cam, dtype=np.float64), np.asarray(T_world_from_cam_next, dtype=np.float64)
    # In the next camera's frame, component by component (a full frame's (N, 3) matrix products cost
    # several times more): X' = R1ᵀ·(R0·c + t0 + d − t1) for the point c = z·(x, y, 1) seen at t, and
    # X' = R1ᵀ·R0·(x, y, 1) for a point at infinity (the sky: only the camera's turn moves it).
    R_rel = T_next[:3, :3].T @ T[:3, :3]
    offset = T_next[:3, :3].T @ (T[:3, 3] - T_next[:3, 3])
    z = np.where(finite, depth, 1.0)
    x, y = rays_normalized[..., 0] * z, rays_normalized[..., 1] * z
    d = np.where(finite[..., None], displacement_m, 0.0)
    cam = [
        R_rel[i, 0] * x
        + R_rel[i, 1] * y
        + R_rel[i, 2] * z
        + np.where(finite, offset[i], 0.0)
        + T_next[0, i] * d[..., 0]
        + T_next[1, i] * d[..., 1]
        + T_next[2, i] * d[..., 2]
        for i in range(3)
    ]
    with np.errstate(divide="ignore", invalid="ignore"):
        normalized = np.stack([cam[0] / cam[2], cam[1] / cam[2]], axis=-1)
    # Imaged as `project_points` decides: in front of the camera and inside the lens's fold radius.
    imaged = (cam[2] > 0) & (np.hypot(normalized[..., 0], normalized[..., 1]) < fold_radius_normalized(distortion_next))
    distorted = distort_normalized(normalized, distortion_next)
    K = np.asarray(K_next_px, dtype=np.float64)
    u = K[0, 0] * distorted[..., 0] + K[0, 1] * distorted[..., 1] + K[0, 2] - pixels_px[..., 0]
    v = K[1, 1] * distorted[..., 1] + K[1, 2] - pixels_px[..., 1]
    flow = np.stack([u, v], axis=-1)
    flow[~(imaged & np.isfinite(u) & np.isfinite(v))] = UNKNOWN_FLOW_PX
    return flow.astype(np.float32)
