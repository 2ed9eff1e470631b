"""Keypoints of people in an image: projected through the lens, with COCO's visibility flags.

COCO (Lin et al. 2014, "Microsoft COCO: Common Objects in Context"; the keypoint annotation format):
each keypoint is (x, y, v) with v = 0 not labelled (here: outside the image or behind the camera),
v = 1 labelled but not visible, v = 2 visible. x, y are in COCO's pixel-edge coordinates, so an
OpenCV pixel position p (centres at integers, DESIGN.md) is written p + ½.
"""

from __future__ import annotations

import numpy as np

from camgen.optics.projection import project_points

VISIBILITY_RADIUS_PX = 1
"""A keypoint is visible when its person's own pixels appear within this many pixels of it: a joint
lies inside the body, so the surface over it belongs to the person unless something hides it."""


def keypoint_visibility(
    keypoints_world_m: np.ndarray,
    T_world_from_cam: np.ndarray,
    K_px: np.ndarray,
    distortion,
    instance_id: np.ndarray,
    track_id: int,
    width_px: int,
    height_px: int,
) -> np.ndarray:
    """(K, 3) COCO keypoints (x, y, v) of one person from its world keypoints (K, 3).

    Visibility: 0 when the point is not imaged or falls outside the image; else 2 when the instance
    pass shows this person at the keypoint's pixel (or within `VISIBILITY_RADIUS_PX`), 1 when
    something else (another object, or the person's own farther side is all that could show) is there.
    """
    points_px, _ = project_points(keypoints_world_m, T_world_from_cam, K_px, distortion)
    out = np.zeros((len(points_px), 3))
    for k, (u, v) in enumerate(points_px):
        if not (np.isfinite(u) and np.isfinite(v)) or not (-0.5 <= u < width_px - 0.5 and -0.5 <= v < height_px - 0.5):
            continue
        col, row = round(u), round(v)
        r = VISIBILITY_RADIUS_PX
        window = instance_id[max(row - r, 0) : row + r + 1, max(col - r, 0) : col + r + 1]
        out[k] = (u + 0.5, v + 0.5, 2 if np.any(window == track_id) else 1)
    return out
