"""Optical flow and scene flow from the known motion: where the surface point seen at each pixel of
frame t is at frame t + 1.

Each output pixel's ray (undistorted, normalised: the lens model's inverse at that pixel) and its
camera z give the surface point X in the world at t (`surface_points_m`); the point moves by its
displacement d (0 for the environment, the pose change for a rigid actor, the barycentric blend of its
triangle's corner motions on a skinned mesh, `mesh_displacement_m`) and is projected through the next frame's camera
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
    "mesh_displacement_m",
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


MESH_CANDIDATES = 8
"""Triangles (those with the nearest centroids) among which `mesh_displacement_m` finds a point's own."""
LONG_TRIANGLE_REACH = 4.0
"""A triangle whose reach (its farthest corner from its centroid) is over this many times the mesh's median
reach is long (a tree trunk's 4 m side beside a crown of 0.2 m facets): `mesh_displacement_m(…,
long_triangles=True)` weighs it for every point, as a point near its end lies far from its centroid."""
LONG_TRIANGLES_MAX = 64
"""The most long triangles weighed for every point (the longest)."""


def mesh_displacement_m(
    points_m: np.ndarray,
    vertices_m: np.ndarray,
    vertices_next_m: np.ndarray,
    faces: np.ndarray,
    *,
    long_triangles: bool = False,
) -> np.ndarray:
    """Displacement (N, 3) m of surface points (N, 3) on a deforming triangle mesh: the point's
    barycentric blend of its triangle's corner motions, which is exact for a point on the mesh.

    The triangle is the nearest to the point among the `MESH_CANDIDATES` whose centroids are nearest, and,
    with `long_triangles`, the mesh's long triangles (`LONG_TRIANGLE_REACH`: a plant's trunk among its
    crown's facets; off for people, whose hundreds of long triangles would multiply the cost) (closest point on a
    triangle: Ericson 2004, "Real-Time Collision Detection", §5.1.5), so a point sampled off the surface (a
    depth from the neighbouring pixel) takes its closest point's motion.

    Parameters
    ----------
    points_m : (N, 3) float
    vertices_m, vertices_next_m : (V, 3) float
        The mesh's vertices at t and t + 1, same order.
    faces : (F, 3) int
        Vertex indices of each triangle.
    long_triangles : bool
        Weigh the mesh's `LONG_TRIANGLES_MAX` longest long triangles for every point too.
    """
    vertices = np.asarray(vertices_m, dtype=np.float64)
    points = np.asarray(points_m, dtype=np.float64).reshape(-1, 3)
    if len(points) == 0:
        return np.zeros((0, 3))
    faces = np.asarray(faces).reshape(-1, 3)
    corners = vertices[faces]  # (F, 3, 3)
    k = min(MESH_CANDIDATES, len(faces))
    centroids = corners.mean(axis=1)
    _, candidates = cKDTree(centroids).query(points, k=k)
    candidates = np.asarray(candidates).reshape(len(points), k)
    if long_triangles:
        reach = np.linalg.norm(corners - centroids[:, None, :], axis=2).max(axis=1)
        long = np.flatnonzero(reach > LONG_TRIANGLE_REACH * np.median(reach))
        long = long[np.argsort(reach[long])[::-1][:LONG_TRIANGLES_MAX]]
        candidates = np.concatenate([candidates, np.broadcast_to(long, (len(points), len(long)))], axis=1)
    a, b, c = (corners[candidates, i] for i in range(3))  # (N, k, 3) each
    weights = _closest_barycentric(points[:, None, :], a, b, c)
    closest = weights[..., 0:1] * a + weights[..., 1:2] * b + weights[..., 2:3] * c
    distance2 = np.sum((closest - points[:, None, :]) ** 2, axis=-1)
    best = np.argmin(np.where(np.isfinite(distance2), distance2, np.inf), axis=1)  # a degenerate triangle: NaN
    rows = np.arange(len(points))
    triangle, weight = faces[candidates[rows, best]], weights[rows, best]  # (N, 3), (N, 3)
    motion = np.asarray(vertices_next_m, dtype=np.float64) - vertices
    return np.einsum("nj,njk->nk", weight, motion[triangle])


def _closest_barycentric(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Barycentric weights (..., 3) of the point of triangle abc closest to p (Ericson 2004, §5.1.5:
    vertex, edge and face regions, in that order)."""

    def dot(u, v):
        return np.sum(u * v, axis=-1)

    ab, ac = b - a, c - a
    d1, d2 = dot(ab, p - a), dot(ac, p - a)
    d3, d4 = dot(ab, p - b), dot(ac, p - b)
    d5, d6 = dot(ab, p - c), dot(ac, p - c)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):  # only the chosen region's quotient is used
        on_ab = d1 / (d1 - d3)
        on_ac = d2 / (d2 - d6)
        on_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        v_in, w_in = vb / (va + vb + vc), vc / (va + vb + vc)
    zero, one = np.zeros_like(d1), np.ones_like(d1)
    regions = [
        (d1 <= 0) & (d2 <= 0),
        (d3 >= 0) & (d4 <= d3),
        (vc <= 0) & (d1 >= 0) & (d3 <= 0),
        (d6 >= 0) & (d5 <= d6),
        (vb <= 0) & (d2 >= 0) & (d6 <= 0),
        (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0),
    ]
    v = np.select(regions, [zero, one, on_ab, zero, zero, 1 - on_bc], v_in)
    w = np.select(regions, [zero, zero, zero, one, on_ac, on_bc], w_in)
    return np.stack([1 - v - w, v, w], axis=-1)


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
    cam = [R_rel[i, 0] * x + R_rel[i, 1] * y + R_rel[i, 2] * z for i in range(3)]
    for i in range(3):
        cam[i][finite] += offset[i]
    # The surface's own motion, R1ᵀ·d, only where there is some (the actors' pixels).
    moving = finite & np.any(displacement_m != 0, axis=-1)  # NaN (no surface) lies outside `finite`
    if moving.any():
        turned = displacement_m[moving] @ T_next[:3, :3]  # (R1ᵀ·d)ᵀ = dᵀ·R1
        for i in range(3):
            cam[i][moving] += turned[:, i]
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
