"""The cameras as coverage sees them: each scene camera's matrix, lens and pose at its home view,
and a PTZ head's reach, built with the functions the plan uses (`camgen.plan.compile`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from camgen.config.profile import Profile
from camgen.config.scene import Camera
from camgen.isp.eptz import eptz_window_px, full_window_size_px, output_camera_matrix, window_centre_px
from camgen.motion.pose import R_HEAD_FROM_CV, R_world_from_cam, R_world_from_mount, T_world_from_cam
from camgen.plan.ptz import installed_focal_length_mm


@dataclass(frozen=True)
class CameraView:
    """One camera at one pose: what the lens model needs to project world points."""

    name: str
    K_px: np.ndarray
    """(3, 3) camera matrix, px."""
    distortion: np.ndarray
    """(8,) Brown–Conrady coefficients, OpenCV order."""
    T_world_from_cam: np.ndarray
    """(4, 4)."""
    width_px: int
    height_px: int
    focal_length_mm: float
    detail_scale: float = 1.0
    """Share of the image's px/m that carries detail: a virtual PTZ's window scaled up to a larger stream
    (the scaler interpolates) has window width / stream width; else 1."""

    @property
    def centre_m(self) -> np.ndarray:
        return self.T_world_from_cam[:3, 3]


def view_at(
    name: str, profile: Profile, mount, focal_length_mm: float, pan_deg: float = 0.0, tilt_deg: float = 0.0
) -> CameraView:
    """The view of a camera of `profile` on `mount` at a focal length and head position, as
    `camgen.plan.compile` builds a frame's state: K from the profile, the lens's distortion at that focal
    length, the pose from the mount and head."""
    R = R_world_from_cam(mount.yaw_deg, mount.pitch_deg, mount.roll_deg, pan_deg, tilt_deg)
    return CameraView(
        name=name,
        K_px=profile.camera_matrix_px(focal_length_mm),
        distortion=profile.lens.at_focal_length(focal_length_mm)[1].as_array(),
        T_world_from_cam=T_world_from_cam(mount.position_m, R),
        width_px=profile.sensor.width_px,
        height_px=profile.sensor.height_px,
        focal_length_mm=focal_length_mm,
    )


def home_view(camera: Camera, profile: Profile) -> CameraView:
    """A camera's view at its home position: a fixed camera at its installed focal length; a PTZ at its
    `ptz` pan, tilt and zoom (focal length = wide end × zoom_x, as the plan sets it); a virtual PTZ as the
    stream of its home window (`eptz_view`)."""
    if camera.ptz is not None and profile.ptz is not None:
        ptz = camera.ptz
        focal_length_mm = profile.lens.focal_length_min_mm * ptz.zoom_x
        return view_at(camera.name, profile, camera.mount, focal_length_mm, ptz.pan_deg, ptz.tilt_deg)
    sensor = view_at(camera.name, profile, camera.mount, installed_focal_length_mm(camera, profile))
    if camera.eptz is not None:
        eptz = camera.eptz
        return eptz_view(sensor, eptz.pan_deg, eptz.tilt_deg, eptz.zoom_x, eptz.output_size_px)
    return sensor


def eptz_view(
    sensor: CameraView, pan_deg: float, tilt_deg: float, zoom_x: float, output_size_px: tuple[int, int]
) -> CameraView:
    """The stream of a virtual PTZ's window as a camera of its own, as `camgen.plan` builds a frame's state:
    the sensor window (`camgen.isp.eptz.eptz_window_px`) centred where the lens images (pan, tilt), scaled
    to the stream; its camera matrix K' (`output_camera_matrix`) with the lens's distortion projects onto
    the stream's pixels exactly. Its px/m counts detail only up to the sensor's own: a window narrower
    than the stream is scaled up, so `detail_scale` = window width / stream width there."""
    centre = window_centre_px(pan_deg, tilt_deg, sensor.K_px, sensor.distortion)
    window = eptz_window_px(centre, zoom_x, (sensor.width_px, sensor.height_px), output_size_px)
    return replace(
        sensor,
        K_px=output_camera_matrix(sensor.K_px, window, output_size_px),
        width_px=int(output_size_px[0]),
        height_px=int(output_size_px[1]),
        detail_scale=min(1.0, window[2] / output_size_px[0]),
    )


@dataclass(frozen=True)
class PtzReach:
    """Where a PTZ head can aim: a point is reached when the head can centre it (pan and tilt within
    range); centred, it is imaged by the lens's centre, where the distortion's Jacobian is the identity."""

    name: str
    position_m: np.ndarray
    R_world_from_mount: np.ndarray
    pan_range_deg: tuple[float, float] | None
    """None: endless pan."""
    tilt_range_deg: tuple[float, float]
    fx_wide_px: float
    fy_wide_px: float
    zoom_max_x: float


def ptz_reach(camera: Camera, profile: Profile) -> PtzReach | None:
    """The reach of a camera's mechanical PTZ head; None for other cameras."""
    if camera.ptz is None or profile.ptz is None:
        return None
    head, mount = profile.ptz, camera.mount
    K = profile.camera_matrix_px(profile.lens.focal_length_min_mm)
    return PtzReach(
        name=camera.name,
        position_m=np.asarray(mount.position_m, dtype=np.float64),
        R_world_from_mount=R_world_from_mount(mount.yaw_deg, mount.pitch_deg, mount.roll_deg),
        pan_range_deg=None if head.pan_continuous else tuple(head.pan_range_deg),
        tilt_range_deg=tuple(head.tilt_range_deg),
        fx_wide_px=float(K[0, 0]),
        fy_wide_px=float(K[1, 1]),
        zoom_max_x=profile.lens.zoom_max_x,
    )


def centring_axes(reach: PtzReach, points_m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Whether the head can centre each point (N,), and the camera's x (right) and y (down) axes in the
    world (N, 3) when it does: pan = atan2(y, x), tilt = atan2(z, √(x² + y²)) of the point in the mount's
    frame, the pose `camgen.motion.pose.R_world_from_cam` builds."""
    v = (np.asarray(points_m, dtype=np.float64).reshape(-1, 3) - reach.position_m) @ reach.R_world_from_mount
    pan = np.arctan2(v[:, 1], v[:, 0])
    tilt = np.arctan2(v[:, 2], np.hypot(v[:, 0], v[:, 1]))
    low, high = (math.radians(a) for a in reach.tilt_range_deg)
    ok = (tilt >= low - 1e-12) & (tilt <= high + 1e-12)
    if reach.pan_range_deg is not None:
        pan_low, pan_high = (math.radians(a) for a in reach.pan_range_deg)
        wrapped = (pan - pan_low) % (2 * math.pi) + pan_low  # the pan angle ≥ the range's start
        ok &= wrapped <= pan_high + 1e-12
    cp, sp, ct, st = np.cos(pan), np.sin(pan), np.cos(tilt), np.sin(tilt)
    # R_mount_from_head = rot_z(pan) @ rot_y(−tilt); its columns are the head's x, y, z in the mount frame.
    head_x = np.stack([cp * ct, sp * ct, st], -1)
    head_y = np.stack([-sp, cp, np.zeros_like(cp)], -1)
    head_z = np.stack([-cp * st, -sp * st, ct], -1)
    heads = np.stack([head_x, head_y, head_z], -1)  # (N, 3, 3) R_mount_from_head
    R_world_from_cam_ = reach.R_world_from_mount @ heads @ R_HEAD_FROM_CV
    return ok, R_world_from_cam_[:, :, 0], R_world_from_cam_[:, :, 1]


@dataclass(frozen=True)
class EptzReach:
    """Where a virtual PTZ can look: any window inside its sensor, so every point the sensor images; the
    stream's px/m there at zoom z are the sensor's × min(1, stream width · z / full window width)."""

    name: str
    sensor: CameraView
    """The whole sensor through the lens."""
    full_window_width_px: float
    """Width of the zoom-1 window (the largest of the stream's aspect ratio on the sensor), px."""
    output_width_px: int
    zoom_max_x: float

    def detail_scale(self, zoom_x: float) -> float:
        """The stream's px/m over the sensor's at `zoom_x`, capped at the sensor's own detail."""
        return min(1.0, self.output_width_px * zoom_x / self.full_window_width_px)


def eptz_reach(camera: Camera, profile: Profile) -> EptzReach | None:
    """The reach of a camera's virtual PTZ; None for other cameras."""
    if camera.eptz is None:
        return None
    sensor = view_at(camera.name, profile, camera.mount, installed_focal_length_mm(camera, profile))
    eptz = camera.eptz
    full_width, _ = full_window_size_px((sensor.width_px, sensor.height_px), eptz.output_size_px)
    return EptzReach(camera.name, sensor, full_width, int(eptz.output_size_px[0]), eptz.zoom_max_x)
