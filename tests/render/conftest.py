"""Helpers for the rendering tests (their OpenGL context, `renderer`, is tests/conftest.py's)."""

from __future__ import annotations

import numpy as np

from camgen.config.scene import Scene


def scene_from(**document) -> Scene:
    """A Scene from keyword arguments, with one placeholder camera unless cameras are given."""
    document.setdefault("duration_s", 1.0)
    document.setdefault("cameras", [{"name": "cam", "profile": "unused", "mount": {"position_m": [0.0, 0.0, 1.0]}}])
    return Scene.model_validate(document)


def look_at(position_m, target_m) -> np.ndarray:
    """T_world_from_cam of an OpenCV camera at `position_m` looking at `target_m`, image up ≈ world +Z."""
    position, target = np.asarray(position_m, float), np.asarray(target_m, float)
    z = target - position
    z /= np.linalg.norm(z)
    x = np.cross(z, [0.0, 0.0, 1.0])
    if np.linalg.norm(x) < 1e-9:
        x = np.array([1.0, 0.0, 0.0])
    x /= np.linalg.norm(x)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    T[:3, 3] = position
    return T


def camera_matrix(fx: float, fy: float, cx: float, cy: float) -> np.ndarray:
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
