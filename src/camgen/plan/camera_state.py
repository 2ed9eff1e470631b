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
from functools import cached_property

import numpy as np

from camgen.config.profile import Profile
from camgen.config.scene import Camera
from camgen.isp.eptz import eptz_window_px, output_camera_matrix, window_centre_px
from camgen.job import CameraState, Matrix3, Matrix4
from camgen.motion.pose import R_world_from_cam, T_world_from_cam
from camgen.optics.intrinsics import corner_radius_normalized, corner_radius_px


@dataclass(frozen=True)
class LensState:
    """The lens at one focal length: its f-number, distortion (OpenCV order, 8) and camera matrix."""

    focal_length_mm: float
    f_number: float
    distortion: np.ndarray
    K: np.ndarray

    @cached_property
    def K_px(self) -> Matrix3:
        """K as the state's nested tuple, made once: a long sequence's states share it."""
        return matrix_tuple(self.K)

    @cached_property
    def distortion_tuple(self) -> tuple[float, ...]:
        return tuple(float(x) for x in self.distortion)


NO_DISTORTION = (0.0,) * 8


def matrix_tuple(matrix: np.ndarray) -> tuple:
    """A matrix as nested tuples of Python floats, as the job stores it."""
    return tuple(map(tuple, np.asarray(matrix, dtype=np.float64).tolist()))


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
    T_world_from_cam_: np.ndarray | Matrix4,
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
    T_world_from_cam_ : (4, 4) ndarray, or its `matrix_tuple`
        The camera's pose (`head_pose`). Pass the tuple to share one pose among many frames' states.
    apply_distortion : bool
        Whether the plan resamples the pixels through the distortion; if not, the state's distortion
        is zero (the state describes the pixels as delivered).
    eptz_sizes_px : ((W, H), (W, H)) or None
        A virtual PTZ's sensor and stream sizes, px: the state then carries the window the stream
        shows and the stream's camera matrix.
    """
    window = output_K = None
    if eptz_sizes_px is not None:
        sensor_size, output_size = eptz_sizes_px
        applied = lens.distortion if apply_distortion else np.zeros(8)
        centre = window_centre_px(pan_deg, tilt_deg, lens.K, applied)
        window = tuple(int(x) for x in eptz_window_px(centre, zoom_x, sensor_size, output_size))
        output_K = matrix_tuple(output_camera_matrix(lens.K, window, output_size))
    pose = T_world_from_cam_ if isinstance(T_world_from_cam_, tuple) else matrix_tuple(T_world_from_cam_)
    return CameraState(
        frame=int(frame),
        time_s=float(time_s),
        pan_deg=float(pan_deg),
        tilt_deg=float(tilt_deg),
        zoom_x=float(zoom_x),
        focal_length_mm=float(lens.focal_length_mm),
        f_number=float(lens.f_number),
        focus_distance_m=float(focus_distance_m),
        exposure_time_s=float(exposure_time_s),
        gain_db=float(gain_db),
        K_px=lens.K_px,
        distortion=lens.distortion_tuple if apply_distortion else NO_DISTORTION,
        T_world_from_cam=pose,
        pan_deg_s=float(pan_deg_s),
        tilt_deg_s=float(tilt_deg_s),
        log_zoom_per_s=float(log_zoom_per_s),
        ptz_mode=None if ptz_mode is None else str(ptz_mode),
        follow_target=None if follow_target is None else str(follow_target),
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
