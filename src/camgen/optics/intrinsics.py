"""Pinhole intrinsics from hardware, angular field of view, and thin-lens depth of field.

References: the seed paper ("Virtual camera modeling for multi-view simulation of surveillance
scenes", eqs. 1–3) and S. F. Ray, *Applied Photographic Optics*, 3rd ed., ch. 7 (depth of field).
"""

from __future__ import annotations

import math

import numpy as np


def focal_length_px(focal_length_mm: float, pixel_pitch_um: float) -> float:
    """Focal length in pixels: f_px = f_mm / pitch_mm."""
    return focal_length_mm / (pixel_pitch_um * 1e-3)


def camera_matrix_px(
    focal_length_mm: float,
    pixel_pitch_x_um: float,
    pixel_pitch_y_um: float,
    width_px: int,
    height_px: int,
    principal_point_offset_px: tuple[float, float] = (0.0, 0.0),
) -> np.ndarray:
    """K (3×3, float64) in the OpenCV pixel convention: pixel centres at integers, (0, 0) top-left.

    The optical axis meets the sensor centre, ``((W−1)/2, (H−1)/2)``, plus the offset.
    """
    fx = focal_length_px(focal_length_mm, pixel_pitch_x_um)
    fy = focal_length_px(focal_length_mm, pixel_pitch_y_um)
    cx = (width_px - 1) / 2.0 + principal_point_offset_px[0]
    cy = (height_px - 1) / 2.0 + principal_point_offset_px[1]
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def _corner_offsets_px(K_px: np.ndarray, width_px: int, height_px: int) -> tuple[float, float]:
    """Largest |u − cx| and |v − cy| over the frame's outer pixel edges."""
    du = np.array([-0.5, width_px - 0.5]) - K_px[0, 2]
    dv = np.array([-0.5, height_px - 0.5]) - K_px[1, 2]
    return float(np.max(np.abs(du))), float(np.max(np.abs(dv)))


def corner_radius_px(K_px: np.ndarray, width_px: int, height_px: int) -> float:
    """Distance from the principal point to the farthest image corner, pixels."""
    du, dv = _corner_offsets_px(K_px, width_px, height_px)
    return float(np.hypot(du, dv))


def corner_radius_normalized(K_px: np.ndarray, width_px: int, height_px: int) -> float:
    """The same corner in normalised image coordinates (x/z, y/z), honouring fx ≠ fy."""
    du, dv = _corner_offsets_px(K_px, width_px, height_px)
    return float(np.hypot(du / K_px[0, 0], dv / K_px[1, 1]))


def angular_fov_deg(sensor_extent_mm: float, focal_length_mm: float) -> float:
    """AFOV = 2·atan(h / 2f) in degrees (seed paper eq. 2), for a lens focused at infinity."""
    return math.degrees(2.0 * math.atan(sensor_extent_mm / (2.0 * focal_length_mm)))


def aperture_diameter_mm(focal_length_mm: float, f_number: float) -> float:
    """Entrance pupil diameter D = f / N (seed paper eq. 3)."""
    return focal_length_mm / f_number


def hyperfocal_distance_m(focal_length_mm: float, f_number: float, coc_mm: float) -> float:
    """H = f² / (N·c) + f, in metres: focused at H, everything from H/2 to infinity is acceptably sharp."""
    f = focal_length_mm
    return (f * f / (f_number * coc_mm) + f) * 1e-3


def blur_circle_diameter_mm(
    depth_m: np.ndarray | float,
    focal_length_mm: float,
    f_number: float,
    focus_distance_m: float,
) -> np.ndarray:
    """Thin-lens blur circle diameter on the sensor, c = A·|d − s|/d · f/(s − f), in mm.

    A = f/N is the aperture diameter, s the focus distance and d the object distance, both measured
    from the lens. Valid for d, s > f; shape follows `depth_m`.
    """
    f_m = focal_length_mm * 1e-3
    d = np.asarray(depth_m, dtype=np.float64)
    s = focus_distance_m
    aperture_m = f_m / f_number
    return aperture_m * np.abs(d - s) / d * f_m / (s - f_m) * 1e3


def airy_sigma_um(f_number: float, wavelength_um: float = 0.55) -> float:
    """Gaussian approximation of the Airy disc: σ ≈ 0.42·λ·N (µm)."""
    return 0.42 * wavelength_um * f_number
