"""What part of the scene a camera can see: mesh bounds, and the depth range of geometry clipped to the
view frustum."""

from __future__ import annotations

import numpy as np

from camgen.config.placement import Bounds, box_corners, local_bounds, placement

__all__ = ["Bounds", "box_corners", "local_bounds", "placement", "visible_depth_range_m"]

# The 6 faces of a box whose corners are indexed by bits (x, y, z) = (i & 1, i >> 1 & 1, i >> 2 & 1), as
# `box_corners` orders them.
_BOX_FACES = ((0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4), (1, 3, 7, 5))


def _clip(polygon: np.ndarray, normal: np.ndarray, offset: float) -> np.ndarray:
    """Sutherland–Hodgman: keep the part of a convex polygon (n, 3) where normal·p + offset ≥ 0."""
    if len(polygon) == 0:
        return polygon
    side = polygon @ normal + offset
    out = []
    for i in range(len(polygon)):
        j = (i + 1) % len(polygon)
        if side[i] >= 0:
            out.append(polygon[i])
        if (side[i] >= 0) != (side[j] >= 0):
            t = side[i] / (side[i] - side[j])
            out.append(polygon[i] + t * (polygon[j] - polygon[i]))
    return np.array(out).reshape(-1, 3)


def frustum_planes(K_px: np.ndarray, width_px: int, height_px: int, near_m: float) -> list[tuple[np.ndarray, float]]:
    """Half-spaces (normal, offset) in the OpenCV camera frame bounding what the image sees."""
    fx, fy, cx, cy = K_px[0, 0], K_px[1, 1], K_px[0, 2], K_px[1, 2]
    left, right = (-0.5 - cx) / fx, (width_px - 0.5 - cx) / fx
    top, bottom = (-0.5 - cy) / fy, (height_px - 0.5 - cy) / fy
    return [
        (np.array([0.0, 0.0, 1.0]), -near_m),
        (np.array([1.0, 0.0, -left]), 0.0),
        (np.array([-1.0, 0.0, right]), 0.0),
        (np.array([0.0, 1.0, -top]), 0.0),
        (np.array([0.0, -1.0, bottom]), 0.0),
    ]


def visible_depth_range_m(
    boxes_world: list[np.ndarray],
    T_world_from_cam: np.ndarray,
    K_px: np.ndarray,
    width_px: int,
    height_px: int,
    near_m: float = 0.05,
) -> tuple[float, float] | None:
    """Nearest and farthest z-depth (m) of the boxes' surfaces inside the frustum; None if none is seen.

    Exact for boxes (each face is clipped to the frustum); for other shapes, of their bounding boxes,
    which bounds the true range from outside.
    """
    T_cam_from_world = np.linalg.inv(T_world_from_cam)
    planes = frustum_planes(K_px, width_px, height_px, near_m)
    z_min, z_max = np.inf, -np.inf
    for corners in boxes_world:
        cam = corners @ T_cam_from_world[:3, :3].T + T_cam_from_world[:3, 3]
        for face in _BOX_FACES:
            polygon = cam[list(face)]
            for normal, offset in planes:
                polygon = _clip(polygon, normal, offset)
            if len(polygon):
                z_min = min(z_min, float(polygon[:, 2].min()))
                z_max = max(z_max, float(polygon[:, 2].max()))
    return (z_min, z_max) if np.isfinite(z_min) else None
