"""Small cameras and scenes for the coverage tests."""

from __future__ import annotations

import math

import numpy as np

from camgen.config.scene import Scene
from camgen.coverage.views import CameraView
from camgen.motion.pose import R_world_from_cam, T_world_from_cam

WIDTH_PX, HEIGHT_PX = 320, 240
F_PX = 400.0


def pinhole_view(position_m, yaw_deg=0.0, pitch_deg=0.0, distortion=(), f_px=F_PX) -> CameraView:
    """A 320 × 240 camera with focal length f_px, principal point at the centre."""
    K = np.array([[f_px, 0.0, (WIDTH_PX - 1) / 2], [0.0, f_px, (HEIGHT_PX - 1) / 2], [0.0, 0.0, 1.0]])
    coefficients = np.zeros(8)
    coefficients[: len(distortion)] = distortion
    T = T_world_from_cam(position_m, R_world_from_cam(yaw_deg, pitch_deg, 0.0))
    return CameraView("cam", K, coefficients, T, WIDTH_PX, HEIGHT_PX, focal_length_mm=1.2)


def scene_with(meshes: list[dict], regions: list[dict] | None = None) -> Scene:
    """A scene holding `meshes` (and `regions`), with one camera and a light."""
    return Scene.model_validate(
        {
            "duration_s": 1,
            "environment": {"meshes": meshes},
            "lights": [{"type": "ambient", "illuminance_lux": 1000}],
            "cameras": [{"name": "cam", "profile": "fixed", "mount": {"position_m": [0, 0, 3]}}],
            "regions": regions or [],
        }
    )


def look_at_pitch_deg(height_m: float, distance_m: float) -> float:
    return -math.degrees(math.atan2(height_m, distance_m))
