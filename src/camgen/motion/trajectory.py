"""Actor trajectories: constant speed along straight segments between ground waypoints."""

from __future__ import annotations

import numpy as np


def position_on_path(
    waypoints_m: np.ndarray, speed_m_s: float, start_s: float, loop: bool, time_s: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Ground position (…, 2) in metres and heading (…) in radians at `time_s` (any shape).

    Before `start_s` the actor waits at the first waypoint; without `loop` it stops at the last one,
    keeping the heading of the final segment. A looping path closes back to the first waypoint.
    """
    points = np.asarray(waypoints_m, dtype=np.float64).reshape(-1, 2)
    t = np.asarray(time_s, dtype=np.float64)
    if len(points) == 1:
        return np.broadcast_to(points[0], (*t.shape, 2)).copy(), np.zeros(t.shape)
    if loop:
        points = np.vstack([points, points[:1]])
    segments = np.diff(points, axis=0)
    lengths = np.hypot(segments[:, 0], segments[:, 1])
    cumulative = np.concatenate([[0.0], np.cumsum(lengths)])
    total = cumulative[-1]
    distance = np.clip(t - start_s, 0.0, None) * speed_m_s
    distance = np.mod(distance, total) if loop else np.minimum(distance, total)
    index = np.clip(np.searchsorted(cumulative, distance, side="right") - 1, 0, len(lengths) - 1)
    fraction = (distance - cumulative[index]) / lengths[index]
    position = points[index] + fraction[..., None] * segments[index]
    heading = np.arctan2(segments[index, 1], segments[index, 0])
    return position, heading
