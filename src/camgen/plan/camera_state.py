"""One camera's state at one instant from where its head points: the lens at the zoom, the pose, the
virtual PTZ's window.

`camgen.plan.compile` builds every frame's state of a job through `camera_state`, from the head track
its PTZ program gives; `camgen.sim` builds the next frame's state through the same function from the
head a controller commands, so a simulation that commands nothing renders exactly what a job of the
held head renders.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from camgen.config.profile import Profile
from camgen.config.scene import Camera
from camgen.isp.eptz import eptz_window_px, output_camera_matrix, window_centre_px
from camgen.job import CameraState
from camgen.motion.pose import R_world_from_cam, T_world_from_cam
from camgen.optics.intrinsics import corner_radius_normalized, corner_radius_px


@dataclass(frozen=True)
class LensState:
    """The lens at one focal length: its f-number, distortion (OpenCV order, 8) and camera matrix."""

    focal_length_mm: float
    f_number: float
    distortion: np.ndarray
    K: np.ndarray


def lens_state(profile: Profile, focal_length_mm: float) -> LensState:
    """The profile's lens set to `focal_length_mm` (rounded to 1e-9 mm, as the plan keys zoom steps)."""
    key = round(float(focal_length_mm), 9)
    f_number, distortion = profile.lens.at_focal_length(key)
    return LensState(key, f_number, distortion.as_array(), profile.camera_matrix_px(key))


def head_pose(camera: Camera, pan_deg: float, tilt_deg: float) -> np.ndarray:
    """T_world_from_cam (4, 4) of the camera with its head at (pan, tilt), degrees; a virtual PTZ's
    optics do not move, so pass (0, 0) for it."""
    m = camera.mount
    return T_world_from_cam(m.position_m, R_world_from_cam(m.yaw_deg, m.pitch_deg, m.roll_deg, pan_deg, tilt_deg))


def camera_state(
    *,
    frame: int,
    time_s: float,
    pan_deg: float,
    tilt_deg: float,
    zoom_x: float,
    lens: LensState,
    T_world_from_cam_: np.ndarray,
    focus_distance_m: float,
    exposure_time_s: float,
    gain_db: float,
    apply_distortion: bool,
    eptz_sizes_px: tuple[tuple[int, int], tuple[int, int]] | None = None,
    pan_deg_s: float = 0.0,
    tilt_deg_s: float = 0.0,
    log_zoom_per_s: float = 0.0,
    ptz_mode: str | None = None,
    follow_target: str | None = None,
) -> CameraState:
    """The CameraState of one frame.

    Parameters
    ----------
    pan_deg, tilt_deg, zoom_x : float
        Where the (mechanical or virtual) head points, degrees, and its magnification.
    lens : LensState
        The lens at the frame's focal length (`lens_state`).
    T_world_from_cam_ : (4, 4) ndarray
        The camera's pose (`head_pose`).
    apply_distortion : bool
        Whether the plan resamples the pixels through the distortion; if not, the state's distortion
        is zero (the state describes the pixels as delivered).
    eptz_sizes_px : ((W, H), (W, H)) or None
        A virtual PTZ's sensor and stream sizes, px: the state then carries the window the stream
        shows and the stream's camera matrix.
    """
    applied = lens.distortion if apply_distortion else np.zeros(8)
    window = output_K = None
    if eptz_sizes_px is not None:
        sensor_size, output_size = eptz_sizes_px
        centre = window_centre_px(pan_deg, tilt_deg, lens.K, applied)
        window = eptz_window_px(centre, zoom_x, sensor_size, output_size)
        output_K = tuple(map(tuple, output_camera_matrix(lens.K, window, output_size).tolist()))
    return CameraState(
        frame=frame,
        time_s=time_s,
        pan_deg=pan_deg,
        tilt_deg=tilt_deg,
        zoom_x=zoom_x,
        focal_length_mm=lens.focal_length_mm,
        f_number=lens.f_number,
        focus_distance_m=focus_distance_m,
        exposure_time_s=exposure_time_s,
        gain_db=gain_db,
        K_px=tuple(map(tuple, lens.K.tolist())),
        distortion=tuple(float(x) for x in applied),
        T_world_from_cam=tuple(map(tuple, T_world_from_cam_.tolist())),
        pan_deg_s=pan_deg_s,
        tilt_deg_s=tilt_deg_s,
        log_zoom_per_s=log_zoom_per_s,
        ptz_mode=ptz_mode,
        follow_target=follow_target,
        window_px=window,
        output_K_px=output_K,
    )


def camera_image_speed_px_s(
    pan_deg_s: float, tilt_deg_s: float, log_zoom_per_s: float, K: np.ndarray, width_px: int, height_px: int
) -> float:
    """Image speed of the farthest pixel while the head pans, tilts and zooms at these rates, px/s.

    A rotation at angular speed ω moves the image point at normalised radius r by at most f·ω·(1 + r²)
    (pan and tilt turn about perpendicular axes, so ω = √(pan rate² + tilt rate²)); a zoom at rate
    d ln f/dt moves it by its distance from the principal point times that rate.
    """
    if pan_deg_s == 0 and tilt_deg_s == 0 and log_zoom_per_s == 0:
        return 0.0
    omega_rad_s = math.radians(math.hypot(pan_deg_s, tilt_deg_s))
    corner_norm = corner_radius_normalized(K, width_px, height_px)
    rotation = max(K[0, 0], K[1, 1]) * omega_rad_s * (1.0 + corner_norm**2)
    return rotation + corner_radius_px(K, width_px, height_px) * abs(log_zoom_per_s)
