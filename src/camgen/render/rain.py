"""Rain over a rendered frame (`camgen.world.rain`): the haze of the far drops, then the streaks of the
near ones in the frame's exposure, depth-tested against the surfaces.

The exposure is the one the frame is actually taken with: `CameraRenderer.frame` receives the camera
state whose `exposure_time_s` auto-exposure has decided (the same source motion blur integrates over),
and the streaks span it, centred on the frame time as the motion-blur sub-frames are.
"""

from __future__ import annotations

import numpy as np

from camgen.render.renderer import View, far_ground_depth_m, frustum_corners_m, horizon_airlight, ray_lengths
from camgen.world.fog import apply_fog
from camgen.world.rain import (
    NEAR_M,
    STREAK_RANGE_M,
    apply_rain,
    drop_radiance,
    drops_in_box,
    rain_visibility_m,
    streak_coverage,
)


def rain_coverage(
    view: View,
    depth_m: np.ndarray,
    time_s: float,
    exposure_time_s: float,
    rate_mm_h: float,
    seed: int,
    ground_m: float = -np.inf,
):
    """(H, W) α of the streaks of the seeded drops within `STREAK_RANGE_M` of the view's camera at
    `time_s`, each falling over `exposure_time_s` (`camgen.world.rain.streak_coverage`); no drop is
    looked for below `ground_m` (the lowest geometry: drops there are hidden)."""
    corners = frustum_corners_m(view, NEAR_M, STREAK_RANGE_M)
    low_m, high_m = corners.min(axis=0), corners.max(axis=0)
    low_m[2] = max(low_m[2], ground_m)
    if low_m[2] >= high_m[2]:
        return np.zeros(depth_m.shape, np.float32)
    positions, diameters_mm, speeds_m_s = drops_in_box(low_m, high_m, time_s, rate_mm_h, seed)
    T = view.T_world_from_cam
    offset = positions - T[:3, 3]
    near = np.einsum("ij,ij->i", offset, offset) <= STREAK_RANGE_M**2
    offset = offset[near]
    R = T[:3, :3]
    # p_cam = Rᵀ (p − c), column by column (a BLAS matmul with an inner size of 3 is slower).
    positions_cam = np.column_stack(
        [offset[:, 0] * R[0, i] + offset[:, 1] * R[1, i] + offset[:, 2] * R[2, i] for i in range(3)]
    )
    fall_cam = np.outer(-speeds_m_s[near] * exposure_time_s, R[2])  # (0, 0, −v T) in the camera frame
    return streak_coverage(positions_cam, diameters_mm[near], fall_cam, view.K_px, depth_m)


def rainy_radiance(
    graph, view: View, radiance: np.ndarray, depth_m: np.ndarray, time_s: float, exposure_time_s: float
) -> np.ndarray:
    """`radiance` (H, W, 3) of `view` in the graph's rain: Koschmieder haze of the rain's visual range
    over each pixel's distance beyond STREAK_RANGE_M (the far ground's where no mesh is hit, as fog
    does), then the near drops' streaks."""
    rate_mm_h, seed = graph.rain_rate_mm_h, graph.rain_seed
    if getattr(graph, "far_ground", None) is not None:  # the ground beyond the meshes is at a finite distance
        depth_m = np.where(np.isinf(depth_m), far_ground_depth_m(graph.far_ground, view), depth_m)
    airlight = horizon_airlight(graph, view)
    beyond_m = np.maximum(depth_m * ray_lengths(view) - np.float32(STREAK_RANGE_M), 0.0)
    hazy = apply_fog(radiance, beyond_m, airlight, rain_visibility_m(rate_mm_h))
    ground_m = float(graph.scene.bounds[0][2]) if graph.scene.mesh_nodes else -np.inf
    coverage = rain_coverage(view, depth_m, time_s, exposure_time_s, rate_mm_h, seed, ground_m)
    return apply_rain(hazy, coverage, drop_radiance(airlight, hazy))
