"""Keypoints of people in an image: projected through the lens, with COCO's visibility flags.

COCO (Lin et al. 2014, "Microsoft COCO: Common Objects in Context"; the keypoint annotation format):
each keypoint is (x, y, v) with v = 0 not labelled (here: outside the image or behind the camera),
v = 1 labelled but not visible, v = 2 visible. x, y are in COCO's pixel-edge coordinates, so an
OpenCV pixel position p (centres at integers, DESIGN.md) is written p + ½.
"""

from __future__ import annotations

import math

import numpy as np

from camgen.optics.projection import project_points

COCO_KEYPOINTS = (
    "nose",
    "left_eye",
    "right_eye",
    "left_ear",
    "right_ear",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
)
COCO_SKELETON = (
    (16, 14), (14, 12), (17, 15), (15, 13), (12, 13), (6, 12), (7, 13), (6, 7), (6, 8), (7, 9), (8, 10),
    (9, 11), (2, 3), (1, 2), (1, 3), (2, 4), (3, 5), (4, 6), (5, 7),
)  # fmt: skip
"""COCO's keypoint skeleton, 1-based as in its annotation files."""


VISIBILITY_RADIUS_PX = 1
"""A keypoint's own pixels are looked for this many pixels around it."""
SELF_OCCLUSION_M = 0.15
"""A keypoint farther than this behind its person's own nearest surface at its pixel is hidden by the
person's body (a far shoulder or hip seen from the side); joints lie at most about this deep under
the skin that faces the camera (the trunk's half depth)."""


def keypoint_visibility(
    keypoints_world_m: np.ndarray,
    T_world_from_cam: np.ndarray,
    K_px: np.ndarray,
    distortion,
    instance_id: np.ndarray,
    track_id: int,
    width_px: int,
    height_px: int,
    own_depth_m: np.ndarray | None = None,
    own_depth_at_px: tuple[int, int] = (0, 0),
) -> np.ndarray:
    """(K, 3) COCO keypoints (x, y, v) of one person from its world keypoints (K, 3).

    Visibility: 0 when the point is not imaged or falls outside the image; 1 when something else
    covers it (the scene's instance pass shows no pixel of this person within
    `VISIBILITY_RADIUS_PX`) or, given `own_depth_m` (the person drawn alone, camera z per pixel), when
    the person's own body does (the keypoint lies more than `SELF_OCCLUSION_M` behind the person's
    nearest surface there); 2 otherwise. `own_depth_m` may cover a window of the image only (the
    person's box), its top-left pixel at column, row `own_depth_at_px`: the person is nowhere outside it.
    """
    points_px, depth_m = project_points(keypoints_world_m, T_world_from_cam, K_px, distortion)
    out = np.zeros((len(points_px), 3))
    r = VISIBILITY_RADIUS_PX
    for k, (u, v) in enumerate(points_px):
        if not (np.isfinite(u) and np.isfinite(v)) or not (-0.5 <= u < width_px - 0.5 and -0.5 <= v < height_px - 0.5):
            continue
        col, row = math.floor(u + 0.5), math.floor(v + 0.5)  # the pixel whose square holds the point
        window = (slice(max(row - r, 0), row + r + 1), slice(max(col - r, 0), col + r + 1))
        seen = bool(np.any(instance_id[window] == track_id))
        if seen and own_depth_m is not None:
            col0, row0 = own_depth_at_px
            own = own_depth_m[
                max(row - r - row0, 0) : max(row + r + 1 - row0, 0), max(col - r - col0, 0) : max(col + r + 1 - col0, 0)
            ]
            seen = depth_m[k] <= (float(np.min(own)) if own.size else np.inf) + SELF_OCCLUSION_M
        out[k] = (u + 0.5, v + 0.5, 2 if seen else 1)
    return out
