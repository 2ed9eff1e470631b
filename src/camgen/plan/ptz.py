"""Per-frame pan, tilt and zoom of a scene camera: its program run on its head (`camgen.motion`).

The head's limits come from the profile (`ptz`: ranges, speeds, accelerations, steps, zoom time)
and the camera (its own speed limits); follow-target sees the scene's actors through their routes.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from camgen.config.loader import head_ranges
from camgen.config.profile import Profile
from camgen.config.scene import Camera, Scene, nominal_shape
from camgen.isp.eptz import eptz_window_px, full_window_size_px, window_centre_px
from camgen.motion.pose import R_world_from_cam, R_world_from_mount, T_world_from_cam, rot_z
from camgen.motion.programs import Follow, FollowView, Position, build_controller
from camgen.motion.ptz import AxisLimits, HeadLimits, HeadPose, HeadTrack, simulate_head
from camgen.motion.trajectory import Route
from camgen.optics.projection import project_points
from camgen.plan.visibility import box_corners, local_bounds, placement

ZOOM_RAMP_S = 0.2
"""Time the zoom motor takes to reach its full rate, s (an estimate: zoom modules publish the sweep
time only)."""


def head_limits(camera: Camera, profile: Profile) -> HeadLimits:
    """The axis limits of a PTZ camera: its profile's head with the camera's own speed limits."""
    head, ptz, lens = profile.ptz, camera.ptz, profile.lens
    pan_speed = min(head.pan_max_deg_s, ptz.pan_max_deg_s or math.inf)
    tilt_speed = min(head.tilt_max_deg_s, ptz.tilt_max_deg_s or math.inf)
    pan_low, pan_high = head.pan_range_deg
    log_zoom_max = math.log(lens.zoom_max_x)
    zoom_rate = log_zoom_max / head.zoom_wide_to_tele_s if log_zoom_max > 0 else 1.0
    return HeadLimits(
        pan=AxisLimits(
            pan_speed,
            head.pan_accel_deg_s2,
            low=pan_low,
            high=pan_high,
            endless=head.pan_continuous,
            step=head.pan_step_deg,
            angular=True,
        ),
        tilt=AxisLimits(
            tilt_speed,
            head.tilt_accel_deg_s2,
            low=head.tilt_range_deg[0],
            high=head.tilt_range_deg[1],
            step=head.tilt_step_deg,
        ),
        zoom=AxisLimits(zoom_rate, zoom_rate / ZOOM_RAMP_S, low=0.0, high=max(log_zoom_max, 1e-12)),
    )


def actor_centre(actor, route: Route, file_bounds=None):
    """(time_s → world centre (3,) of the actor's bounding box, the box height in m)."""
    shape = nominal_shape(actor)
    corners = box_corners(*local_bounds(shape, file_bounds), placement(shape))
    low, high = corners.min(axis=0), corners.max(axis=0)
    centre_local = (low + high) / 2

    def at(time_s: float) -> np.ndarray:
        xy, heading = route.at(time_s)
        offset = rot_z(float(heading)) @ centre_local
        return np.array([float(xy[0]) + offset[0], float(xy[1]) + offset[1], offset[2]])

    return at, float(high[2] - low[2])


def eptz_limits(camera: Camera, profile: Profile) -> HeadLimits:
    """The virtual head's axes: the window centre stays within the sensor's field of view."""
    ranges = head_ranges(camera, profile)
    eptz = camera.eptz
    log_zoom_max = math.log(eptz.zoom_max_x)
    zoom_rate = log_zoom_max / eptz.zoom_wide_to_tele_s if log_zoom_max > 0 else 1.0
    return HeadLimits(
        pan=AxisLimits(eptz.pan_max_deg_s, eptz.accel_deg_s2, low=ranges.pan_deg[0], high=ranges.pan_deg[1]),
        tilt=AxisLimits(eptz.tilt_max_deg_s, eptz.accel_deg_s2, low=ranges.tilt_deg[0], high=ranges.tilt_deg[1]),
        zoom=AxisLimits(zoom_rate, zoom_rate / ZOOM_RAMP_S, low=0.0, high=max(log_zoom_max, 1e-12)),
    )


def _window_view(camera: Camera, profile: Profile, K: np.ndarray):
    """Whether a world point is in a virtual PTZ's window at a pose (the sensor image, cropped)."""
    mount, sensor = camera.mount, profile.sensor
    T = T_world_from_cam(mount.position_m, R_world_from_cam(mount.yaw_deg, mount.pitch_deg, mount.roll_deg))
    focal_length_mm = installed_focal_length_mm(camera, profile)
    distortion = profile.lens.at_focal_length(focal_length_mm)[1].as_array()
    sensor_size = (sensor.width_px, sensor.height_px)

    def in_view(point_m: np.ndarray, pose: HeadPose) -> bool:
        centre = window_centre_px(pose.pan_deg, pose.tilt_deg, K, distortion)
        x0, y0, width, height = eptz_window_px(centre, pose.zoom_x, sensor_size, camera.eptz.output_size_px)
        uv, depth = project_points(point_m[None], T, K, distortion)
        u, v = uv[0]
        return bool(depth[0] > 0 and x0 - 0.5 <= u <= x0 + width - 0.5 and y0 - 0.5 <= v <= y0 + height - 0.5)

    return in_view


def installed_focal_length_mm(camera: Camera, profile: Profile) -> float:
    """Where a fixed camera's lens is set (a virtual PTZ's too): the scene's focal length, else the
    wide end."""
    return camera.focal_length_mm or profile.lens.focal_length_min_mm


def holding_track(
    pan_deg: float, tilt_deg: float, zoom_x: float, frame_count: int, fps: float, mode: str | None
) -> HeadTrack:
    """A head (or a fixed camera, `mode` None) that stays where it is for every frame."""
    zeros = np.zeros(frame_count)
    return HeadTrack(
        time_s=np.arange(frame_count) / fps,
        pan_deg=np.full(frame_count, pan_deg),
        tilt_deg=np.full(frame_count, tilt_deg),
        zoom_x=np.full(frame_count, zoom_x),
        pan_unwrapped_deg=np.full(frame_count, pan_deg),
        pan_deg_s=zeros,
        tilt_deg_s=zeros,
        log_zoom_per_s=zeros,
        modes=(mode,) * frame_count,
        targets=(None,) * frame_count,
    )


def head_track(
    scene: Scene,
    camera: Camera,
    profile: Profile,
    routes: Mapping[str, Route],
    file_bounds=None,
) -> HeadTrack | None:
    """The (mechanical or virtual) head's motion at every frame, or None for a fixed camera."""
    settings = camera.head
    if settings is None:
        return None
    virtual = camera.eptz is not None
    limits = eptz_limits(camera, profile) if virtual else head_limits(camera, profile)
    home = Position(settings.pan_deg, settings.tilt_deg, settings.zoom_x)
    mount = camera.mount
    sensor = profile.sensor
    focal_length_mm = installed_focal_length_mm(camera, profile) if virtual else profile.lens.focal_length_min_mm
    K = profile.camera_matrix_px(focal_length_mm)
    width_px, height_px = sensor.width_px, sensor.height_px
    fx, fy = float(K[0, 0]), float(K[1, 1])
    if virtual:  # the stream at zoom 1: the full window scaled to the output size
        width_px, height_px = camera.eptz.output_size_px
        full_w, full_h = full_window_size_px((sensor.width_px, sensor.height_px), (width_px, height_px))
        fx, fy = fx * width_px / full_w, fy * height_px / full_h
    view = FollowView(
        mount_position_m=tuple(mount.position_m),
        R_world_from_mount=R_world_from_mount(mount.yaw_deg, mount.pitch_deg, mount.roll_deg),
        fx_wide_px=fx,
        fy_wide_px=fy,
        width_px=width_px,
        height_px=height_px,
        zoom_max_x=math.exp(limits.zoom.high),
        fps=scene.fps,
    )
    actors = {actor.name: actor for actor in scene.actors}

    in_view = _window_view(camera, profile, K) if virtual else None

    def follow(program, fallback):
        target_at, height_m = actor_centre(actors[program.target], routes[program.target], file_bounds)
        return Follow(program, view, target_at, height_m, fallback, in_view)

    if settings.program is None or settings.program.type == "hold":
        # nothing to simulate: the head stays at home
        return holding_track(settings.pan_deg, settings.tilt_deg, settings.zoom_x, scene.frame_count, scene.fps, "hold")
    controller = build_controller(
        settings.program, home, settings.presets, endless_pan=limits.pan.endless, follow=follow
    )
    start = HeadPose(settings.pan_deg, settings.tilt_deg, settings.zoom_x)
    return simulate_head(controller, limits, start, scene.frame_count, scene.fps)
