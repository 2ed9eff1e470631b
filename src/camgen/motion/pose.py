"""Camera orientation from a mount and a pan/tilt head.

Frames: world is right-handed, Z up. The head frame H has x forward, y left, z up; the mount turns
H by yaw (about z), then pitch (about the new y, positive raising x towards z), then roll (about x).
Pan turns about the head's z, tilt raises the axis like pitch. The camera frame is OpenCV's
(x right, y down, z forward), so the last step maps (right, down, forward) onto (−y, −z, x) of H.
"""

from __future__ import annotations

import math

import numpy as np

# Columns: the head-frame directions of the OpenCV camera axes x (right), y (down), z (forward).
R_HEAD_FROM_CV = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def rot_x(angle_rad: float) -> np.ndarray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(angle_rad: float) -> np.ndarray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(angle_rad: float) -> np.ndarray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def R_world_from_mount(yaw_deg: float, pitch_deg: float, roll_deg: float) -> np.ndarray:
    """Rotation taking the mount's head-frame axes (x forward, y left, z up at pan = tilt = 0) to world axes."""
    return rot_z(math.radians(yaw_deg)) @ rot_y(-math.radians(pitch_deg)) @ rot_x(math.radians(roll_deg))


def R_mount_from_head(pan_deg: float, tilt_deg: float) -> np.ndarray:
    return rot_z(math.radians(pan_deg)) @ rot_y(-math.radians(tilt_deg))


def R_world_from_cam(
    yaw_deg: float, pitch_deg: float, roll_deg: float, pan_deg: float = 0.0, tilt_deg: float = 0.0
) -> np.ndarray:
    """Rotation taking OpenCV camera axes to world axes (3×3, float64)."""
    return R_world_from_mount(yaw_deg, pitch_deg, roll_deg) @ R_mount_from_head(pan_deg, tilt_deg) @ R_HEAD_FROM_CV


def T_world_from_cam(position_m, R: np.ndarray) -> np.ndarray:
    """4×4 rigid transform from camera to world coordinates."""
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = np.asarray(position_m, dtype=np.float64)
    return T


def rotation_xyz_deg(rotation_deg) -> np.ndarray:
    """Extrinsic rotation about world X, then Y, then Z (degrees) as a 3×3 matrix."""
    rx, ry, rz = (math.radians(a) for a in rotation_deg)
    return rot_z(rz) @ rot_y(ry) @ rot_x(rx)
