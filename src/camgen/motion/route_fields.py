"""The fields every route checks and freezes when it is made (`camgen.motion.trajectory.Route`,
`camgen.motion.vehicle_route.VehicleRoute`)."""

from __future__ import annotations

import math

import numpy as np


def freeze_route_fields(route) -> None:
    """Check a (frozen dataclass) route's waypoints_m, pauses_s, speed_m_s, start_s and loop and store
    them as read-only float arrays and plain numbers (`Route`, `camgen.motion.vehicle_route.VehicleRoute`).

    Raises
    ------
    ValueError
        For waypoints not (N ≥ 1, 2), pauses not one per waypoint, values not finite, a pause below 0, a
        speed not above 0 or a start time below 0.
    """
    points = np.array(route.waypoints_m, dtype=np.float64)
    pauses = np.array(route.pauses_s, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 2 or len(points) == 0:
        raise ValueError(f"waypoints_m must have shape (N, 2) with N ≥ 1, got {points.shape}")
    if pauses.shape != (len(points),):
        raise ValueError(f"pauses_s must have shape ({len(points)},) like the waypoints, got {pauses.shape}")
    if not (np.all(np.isfinite(points)) and np.all(np.isfinite(pauses)) and np.all(pauses >= 0)):
        raise ValueError("waypoints_m must be finite and pauses_s finite and ≥ 0")
    if not (route.speed_m_s > 0 and math.isfinite(route.speed_m_s)):
        raise ValueError(f"speed_m_s must be > 0, got {route.speed_m_s}")
    if not (route.start_s >= 0 and math.isfinite(route.start_s)):
        raise ValueError(f"start_s must be ≥ 0, got {route.start_s}")
    points.setflags(write=False)
    pauses.setflags(write=False)
    object.__setattr__(route, "waypoints_m", points)
    object.__setattr__(route, "pauses_s", pauses)
    object.__setattr__(route, "speed_m_s", float(route.speed_m_s))
    object.__setattr__(route, "start_s", float(route.start_s))
    object.__setattr__(route, "loop", bool(route.loop))
