"""Licence plates in an image: the projected plate quad, its box and whether it can be read.

A plate is a flat rectangle on the vehicle (`camgen.vehicles.body`). Its corners, projected through the
same camera model as the pixels (`camgen.optics.projection.project_points`, distortion included), give
the quad; the box is that of points along the quad's edges (a distorting lens bends them). The plate is
visible when it faces the camera and at least `PLATE_VISIBLE_SHARE` of sample points spread over it
land on pixels of its own vehicle in the instance pass (nothing else in front of it).
"""

from __future__ import annotations

import math

import numpy as np

from camgen.optics.projection import project_points

PLATE_EDGE_SAMPLES = 8
"""Points per edge of the quad whose projections bound the plate's box."""
PLATE_GRID = (9, 3)
"""Sample points across and up the plate for its visibility."""
PLATE_VISIBLE_SHARE = 0.5
"""Share of the samples that must show the vehicle for the plate to count as visible."""


def _bilinear(corners: np.ndarray, s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Points of the quad (top left, top right, bottom right, bottom left) at s across, t down."""
    top = corners[0] + s[:, None] * (corners[1] - corners[0])
    bottom = corners[3] + s[:, None] * (corners[2] - corners[3])
    return top + t[:, None] * (bottom - top)


def plate_annotation(
    corners_world_m: np.ndarray,
    T_world_from_cam: np.ndarray,
    K_px: np.ndarray,
    distortion,
    instance_id: np.ndarray,
    track_id: int,
) -> dict | None:
    """A plate's annotation, or None when no part of it is imaged inside the image.

    Returns a dict: ``quad`` (4 × [x, y], COCO's pixel-edge coordinates, in the order top left, top
    right, bottom right, bottom left as one reads the plate), ``bbox`` [x, y, w, h] of the plate's
    projection clipped to the image, ``visible`` (it faces the camera and is not covered) and
    ``visible_share`` (the share of its sample points that show its vehicle, 0 when it faces away).
    """
    height_px, width_px = instance_id.shape
    corners = np.asarray(corners_world_m, dtype=np.float64)
    u = np.linspace(0.0, 1.0, PLATE_EDGE_SAMPLES + 1)[:-1]
    edges = np.concatenate([corners[k] + u[:, None] * (corners[(k + 1) % 4] - corners[k]) for k in range(4)])
    points_px, _ = project_points(edges, T_world_from_cam, K_px, distortion)
    imaged = np.all(np.isfinite(points_px), axis=1)
    if not imaged.any():
        return None
    x0, y0 = np.maximum(points_px[imaged].min(axis=0) + 0.5, 0.0)
    x1, y1 = np.minimum(points_px[imaged].max(axis=0) + 0.5, (width_px, height_px))
    if x1 <= x0 or y1 <= y0:
        return None
    quad_px, _ = project_points(corners, T_world_from_cam, K_px, distortion)
    normal = np.cross(corners[3] - corners[0], corners[1] - corners[0])  # out of the plate's face
    facing = float(normal @ (np.asarray(T_world_from_cam)[:3, 3] - corners.mean(axis=0))) > 0
    share = 0.0
    if facing:
        nx, ny = PLATE_GRID
        s, t = np.meshgrid((np.arange(nx) + 0.5) / nx, (np.arange(ny) + 0.5) / ny)
        samples_px, _ = project_points(_bilinear(corners, s.ravel(), t.ravel()), T_world_from_cam, K_px, distortion)
        hits = 0
        for px, py in samples_px:
            if np.isfinite(px) and -0.5 <= px < width_px - 0.5 and -0.5 <= py < height_px - 0.5:
                hits += int(instance_id[math.floor(py + 0.5), math.floor(px + 0.5)] == track_id)
        share = hits / len(samples_px)
    return {
        "quad": [[round(float(x) + 0.5, 3), round(float(y) + 0.5, 3)] for x, y in quad_px],
        "bbox": [round(float(x0), 3), round(float(y0), 3), round(float(x1 - x0), 3), round(float(y1 - y0), 3)],
        "visible": bool(facing and share >= PLATE_VISIBLE_SHARE),
        "visible_share": round(share, 4),
    }
