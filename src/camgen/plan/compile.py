"""compile(scene, profiles) → Job: resolve cameras, sample their states, and decide the stages.

Skip rules (DESIGN.md "Skip what a scene does not need"): a stage whose effect stays under its
threshold in `PlanSettings` is left out, and a render pass no stage consumes is not rendered. Every
decision is recorded with the measured effect, the threshold and the reason.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

import camgen
from camgen.config.loader import LoadedScene, check_cameras
from camgen.config.profile import Isp, Profile, Sensor
from camgen.config.scene import (
    Actor,
    Camera,
    Scene,
    actor_shape,
    is_character,
    is_procedural_person,
)
from camgen.errors import ConfigError, Problem
from camgen.io.annotations import ANNOTATIONS_OF_DELIVERED_FRAMES
from camgen.job import CameraJob, CameraState, Decision, Job, PlanSettings, RenderSpec, Stage
from camgen.motion.pose import T_world_from_cam, rot_z
from camgen.motion.ptz import HeadTrack
from camgen.motion.trajectory import Route, actor_routes
from camgen.optics.diffraction import (
    CHANNEL_WAVELENGTHS_UM,
    FLOAT32_RESOLUTION,
    MONO_WAVELENGTH_UM,
    airy_sigma_px,
    channel_sigmas_px,
    diffraction_effect_rel,
    kernel_reach_px,
)
from camgen.optics.distortion import max_displacement_px, undistort_normalized
from camgen.optics.intrinsics import (
    blur_circle_diameter_mm,
    corner_radius_normalized,
    corner_radius_px,
    hyperfocal_distance_m,
)
from camgen.optics.projection import LensInversionError
from camgen.optics.remap import SUPPORT_PX, LensGeometry, border_points_px, source_overshoot_px
from camgen.optics.vignetting import aperture_weight, relative_illumination
from camgen.plan.budget import check_job_size
from camgen.plan.camera_state import LensState as _LensState
from camgen.plan.camera_state import camera_image_speed_px_s, camera_state, head_pose, lens_state
from camgen.plan.ptz import head_track, holding_track, installed_focal_length_mm
from camgen.plan.visibility import Bounds, box_corners, local_bounds, placement, visible_depth_range_m
from camgen.props import prop_box_corners
from camgen.props.sway import swaying_props
from camgen.sensor.capture import NOISE_TERM_OFF, NOISE_TERMS, noise_term_is_on
from camgen.world.rain import STREAK_RANGE_M, ground_is_wet, wet_ground_height_m
from camgen.world.snow import snow_visibility_m

MOTION_SAMPLE_STEP_PX = 1.0
"""Largest image motion between the sub-frames that integrate one exposure, px."""
MOTION_SAMPLES_MAX = 32
LIMB_SPEED_FACTOR = 2.5
"""How much faster than its route a procedural person's fastest limb moves (see `_actor_motion_px`)."""


def _path_positions(route: Route, times_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ground positions (…, 2) m and headings (…) rad of an actor on `route` at `times_s` (…) s."""
    return route.at(times_s)


def actor_swept_boxes(actor: Actor, route: Route, file_bounds, duration_s: float) -> list[np.ndarray]:
    """World corners of boxes that contain everything the actor occupies during the sequence.

    Along one straight leg the actor's box slides along its heading, so the volume it sweeps is its
    box stretched by the distance covered: one oriented box per leg travelled (a loop's legs once).
    Standing still sweeps nothing more: a pause is at a leg's end, with that leg's heading. A vehicle's
    arcs come as short chords, the box grown by the route's `leg_pad_m` so it covers the arc between.
    """
    shape = actor_shape(actor)
    low, high = local_bounds(shape, file_bounds)
    corners_local = box_corners(low, high, placement(shape))
    low, high = corners_local.min(axis=0), corners_local.max(axis=0)
    arc_pad_m = route.leg_pad_m(float(np.max(np.hypot(corners_local[:, 0], corners_local[:, 1]))))
    grow = np.array([arc_pad_m, arc_pad_m, 0.0])
    low, high = low - grow, high + grow
    starts_m, headings_rad, lengths_m = route.legs_until(duration_s)
    return [
        box_corners(low, high + np.array([length, 0.0, 0.0]), T_world_from_cam((*start, 0.0), rot_z(heading)))
        for start, heading, length in zip(starts_m, headings_rad, lengths_m, strict=True)
    ]


def _source_overshoot_px(
    K: np.ndarray, distortion: np.ndarray, ca_scales: tuple[float, ...], width_px: int, height_px: int, where: str
) -> tuple[float, ...]:
    """How far beyond each frame edge the output frame samples the pinhole image through the lens, px."""
    geometry = LensGeometry(
        K_px=tuple(map(tuple, K.tolist())),
        distortion=tuple(float(c) for c in distortion),
        ca_scales=tuple(ca_scales),
        width_px=width_px,
        height_px=height_px,
        margin_px=(0, 0, 0, 0),
    )
    try:
        return source_overshoot_px(geometry)
    except LensInversionError as error:
        raise ConfigError(
            f"{where}: the distortion cannot be inverted at the image border ({error}); the coefficients do "
            "not describe a valid lens there"
        ) from None


def _corner_illumination(K, distortion, width_px, height_px, vignetting, weight) -> float:
    """Darkest relative illumination along the frame border (the corners, for a centred lens)."""
    border = border_points_px(width_px, height_px)
    fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    distorted = np.stack([(border[:, 0] - cx) / fx, (border[:, 1] - cy) / fy], -1)
    undistorted = undistort_normalized(distorted, distortion).points
    gain = relative_illumination(
        undistorted,
        distorted,
        corner_radius_normalized=corner_radius_normalized(K, width_px, height_px),
        natural_cos4=vignetting.natural_cos4,
        polynomial=vignetting.optical_polynomial,
        weight=weight,
    )
    return float(np.min(gain))


_BOX_EDGES = np.array([(k, k | bit) for bit in (1, 2, 4) for k in range(8) if not k & bit])
"""The 12 edges of a box whose corner k takes x from bit 0 of k, y from bit 1 and z from bit 2 (`box_corners`)."""
MOTION_TIMES_PER_BLOCK = 2048
"""Times `_actor_motion_px` measures at once (its arrays of points × times stay small)."""


def _actor_motion_px(
    actors: list[Actor],
    routes: Mapping[str, Route],
    times_s: np.ndarray,
    exposure_s: float,
    T_world_from_cam_: np.ndarray,
    K: np.ndarray,
    width_px: int,
    height_px: int,
    file_bounds: Mapping[str, Bounds] | None,
) -> float:
    """Largest image displacement within one exposure of a point of an actor's box that is in the image, px.

    The box is the actor's shape's in its own frame (`actor_shape`, `local_bounds`: x along its heading, the
    route's point at its origin) from the ground to its top, placed at the route's point and heading at the
    exposure's start and at its end (`_path_positions`; a person's at the start's heading for both, for its
    body turns round a waypoint over a stride, `camgen.actors.gait`, not at once as its route does). Its
    points: the route's point and the box's 8 corners at ground and top height, and where each of its 12
    edges crosses, at the start, the plane through the camera of the principal point's column (x = 0 in
    the camera's frame) or of its row (y = 0): so a long vehicle near the camera whose corners and
    centre lie outside the image while its front or side crosses it counts too. A point counts where
    either end of its path lies in the image. (A box face that covers the whole image while every edge
    of it lies outside is not sampled.)

    Speed (a one-hour plan has 90 000 times for each actor): each time first gets a cheap upper bound on
    any such point's displacement, from the box's bounding sphere and the way its points can travel
    (`_motion_bound_px`: 0 where the sphere lies outside the view's frustum); the points are then measured
    only at the times whose bound exceeds the largest displacement measured so far, likeliest first.
    """
    T_cam_from_world = np.linalg.inv(T_world_from_cam_)
    boxes = []
    for actor in actors:
        route = routes[actor.name]
        if not route.moves:
            continue
        shape = actor_shape(actor)
        placed = box_corners(*local_bounds(shape, file_bounds), placement(shape))
        low, high = placed.min(axis=0), placed.max(axis=0)
        low[2] = 0.0
        points = np.concatenate([box_corners(low, high, np.eye(4)), [[0.0, 0.0, 0.0], [0.0, 0.0, high[2]]]])
        ends = [_path_positions(route, times) for times in (times_s, times_s + exposure_s)]
        person = is_procedural_person(actor) or is_character(actor)
        if person:
            ends[1] = (ends[1][0], ends[0][1])
        # A walking person's swinging foot and hand move up to about 2.5 times as fast as
        # the body (the foot's speed peaks at ~2.4 × walking speed in mid-swing: Winter 1991).
        limbs = LIMB_SPEED_FACTOR if person else 1.0
        bound = limbs * _motion_bound_px(T_cam_from_world, K, width_px, height_px, points, ends)
        boxes.append((bound, limbs, points, ends))
    boxes.sort(key=lambda box: -float(box[0].max(initial=0.0)))
    worst = 0.0
    for bound, limbs, points, ends in boxes:
        # Each actor's likeliest time first, so that the bound rules out most of its other times.
        for times in (np.argmax(bound)[None], np.flatnonzero(bound > worst)):
            times = times[np.argsort(-bound[times], kind="stable")]
            for first in range(0, len(times), MOTION_TIMES_PER_BLOCK):
                block = times[first : first + MOTION_TIMES_PER_BLOCK]
                block = block[bound[block] > worst]
                if not len(block):
                    break
                paths = [_box_points_cam(T_cam_from_world, xy[block], heading[block], points) for xy, heading in ends]
                worst = max(worst, limbs * _box_shift_px(paths, K, width_px, height_px))
    return worst


def _motion_bound_px(
    T_cam_from_world: np.ndarray, K: np.ndarray, width_px: int, height_px: int, points_m: np.ndarray, ends
) -> np.ndarray:
    """(N,) upper bound, px, on the image displacement of any point of the box through `points_m` (P, 3),
    placed at `ends` ([start, end] (ground points (N, 2), headings (N,))), that lies in the image at either
    end; 0 where the box's bounding sphere, grown by the way its points travel, lies outside the frustum.

    A point at camera-frame p₀ that moves by d to p₁ = p₀ + d moves in the image by
    x₁/z₁ − x₀/z₀ = (d_x − (x₀/z₀)·d_z)/z₁ = (d_x − (x₁/z₁)·d_z)/z₀ (in normalised units); in the image at
    either end |x/z| ≤ tₓ there, so |Δ(x/z)| ≤ D·(1 + tₓ)/z_lo for |d| ≤ D and z₀, z₁ ≥ z_lo (and
    likewise y). D is the route point's way plus the turn's arc at the points' largest radius; z_lo the
    sphere's nearest depth less D (no bound, inf, nearer than 0.1 m)."""
    fx, skew, cx, fy, cy = K[0, 0], K[0, 1], K[0, 2], K[1, 1], K[1, 2]
    ty = max(cy + 0.5, height_px - 0.5 - cy) / fy
    tx = (max(cx + 0.5, width_px - 0.5 - cx) + abs(skew) * ty) / fx
    gain = math.hypot(fx * (1 + tx) + abs(skew) * (1 + ty), fy * (1 + ty))
    # The frustum's side planes through the camera (inward normals, camera frame): u > −0.5, u < W − 0.5,
    # v > −0.5 and v < H − 0.5 for u = (fx·x + s·y)/z + cx, v = fy·y/z + cy, z > 0.
    planes = np.array(
        [[fx, skew, cx + 0.5], [-fx, -skew, width_px - 0.5 - cx], [0.0, fy, cy + 0.5], [0.0, -fy, height_px - 0.5 - cy]]
    )
    planes /= np.linalg.norm(planes, axis=1, keepdims=True)
    middle = (points_m.min(axis=0) + points_m.max(axis=0)) / 2
    radius_m = float(np.linalg.norm(points_m.max(axis=0) - points_m.min(axis=0))) / 2
    (xy0, heading0), (xy1, heading1) = ends
    turn_rad = np.abs(np.remainder(heading1 - heading0 + math.pi, 2 * math.pi) - math.pi)
    way_m = (
        np.hypot(xy1[:, 0] - xy0[:, 0], xy1[:, 1] - xy0[:, 1])
        + float(np.max(np.hypot(points_m[:, 0], points_m[:, 1]))) * turn_rad
    )
    c, s = np.cos(heading0), np.sin(heading0)
    centre = _cam_from_world_points(
        T_cam_from_world,
        xy0[:, 0] + c * middle[0] - s * middle[1],
        xy0[:, 1] + s * middle[0] + c * middle[1],
        float(middle[2]),
    )
    reach_m = radius_m + way_m
    seen = centre[2] > 0.1 - reach_m
    for n in planes:
        seen &= n[0] * centre[0] + n[1] * centre[1] + n[2] * centre[2] > -reach_m
    near_m = centre[2] - reach_m
    with np.errstate(divide="ignore"):
        bound = np.where(near_m > 0.1, gain * way_m / near_m, np.inf)
    return np.where(seen, bound, 0.0)


def _box_points_cam(T_cam_from_world: np.ndarray, xy_m: np.ndarray, heading_rad: np.ndarray, points_m: np.ndarray):
    """Camera-frame (x, y, z), each (P, N) m, of an actor's local points (P, 3) placed at N ground points
    (N, 2) and headings (N,): R·p_world + t with p_world = (x + cos h·pₓ − sin h·p_y, y + sin h·pₓ +
    cos h·p_y, p_z), linear in the local point."""
    R, t = T_cam_from_world[:3, :3], T_cam_from_world[:3, 3]
    c, s = np.cos(heading_rad), np.sin(heading_rad)
    px, py, pz = points_m[:, :1], points_m[:, 1:2], points_m[:, 2:]
    cam = []
    for i in range(3):
        base = R[i, 0] * xy_m[:, 0] + R[i, 1] * xy_m[:, 1] + t[i]
        along, across = R[i, 0] * c + R[i, 1] * s, R[i, 1] * c - R[i, 0] * s
        cam.append(base + px * along + py * across + R[i, 2] * pz)
    return cam


def _box_shift_px(paths, K: np.ndarray, width_px: int, height_px: int) -> float:
    """Largest image displacement between the two ends of `paths` ([start, end] camera-frame (x, y, z), each
    (10, N), of a box's 8 corners and 2 more points) over the points in the image at either end: those and
    the points where the box's edges cross the principal point's column's and row's planes at the start
    (see `_actor_motion_px`); 0 where none is."""
    a, b = _BOX_EDGES[:, 0], _BOX_EDGES[:, 1]
    ends = [list(cam) for cam in paths]
    for axis in (0, 1):
        from_a, from_b = paths[0][axis][a], paths[0][axis][b]
        with np.errstate(divide="ignore", invalid="ignore"):
            share = from_a / (from_a - from_b)
        share[~((share >= 0.0) & (share <= 1.0))] = np.nan  # no crossing: its NaN depth drops it below
        for cam, path in zip(ends, paths, strict=True):
            for i in range(3):
                cam[i] = np.concatenate([cam[i], path[i][a] + share * (path[i][b] - path[i][a])])
    visible = np.minimum(ends[0][2], ends[1][2]) > 0.1  # NaN compares False
    if not visible.any():
        return 0.0
    uv = [_pixel_of(K, x[visible], y[visible], z[visible]) for x, y, z in ends]
    inside = np.zeros(len(uv[0][0]), bool)
    for u, v in uv:
        inside |= (u > -0.5) & (u < width_px - 0.5) & (v > -0.5) & (v < height_px - 0.5)
    shift_px = np.hypot(uv[1][0] - uv[0][0], uv[1][1] - uv[0][1])
    return float(np.max(shift_px[inside], initial=0.0))


def _cam_from_world_points(
    T_cam_from_world: np.ndarray, x_m: np.ndarray, y_m: np.ndarray, z_m: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Camera-frame coordinates (x, y, z), m, of the world points (x_m, y_m, z_m)."""
    R, t = T_cam_from_world[:3, :3], T_cam_from_world[:3, 3]
    return tuple(R[i, 0] * x_m + R[i, 1] * y_m + (R[i, 2] * z_m + t[i]) for i in range(3))


def _pixel_of(K: np.ndarray, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pinhole pixel (u, v) of camera-frame points."""
    xn, yn = x / z, y / z
    return K[0, 0] * xn + K[0, 1] * yn + K[0, 2], K[1, 0] * xn + K[1, 1] * yn + K[1, 2]


def _sway_motion_px(
    swaying: list,
    duration_s: float,
    exposure_s: float,
    T_world_from_cam_: np.ndarray,
    K: np.ndarray,
    width_px: int,
    height_px: int,
) -> float:
    """Largest image displacement within one exposure of a vertex of a prop swaying in the wind
    (`camgen.props.sway`), px: its speed bound seen at the nearest corner of its box, for each prop whose
    box reaches into the view."""
    T_cam_from_world = np.linalg.inv(T_world_from_cam_)
    worst = 0.0
    for prop, sway in swaying:
        vertices = prop.model.arrays()[0]
        corners = box_corners(vertices.min(axis=0), vertices.max(axis=0), prop.T_world_from_prop)
        cams = corners @ T_cam_from_world[:3, :3].T + T_cam_from_world[:3, 3]
        front = cams[cams[:, 2] > 0.1]
        if len(front) == 0:
            continue
        uv = (front[:, :2] / front[:, 2:3]) @ K[:2, :2].T + K[:2, 2]
        if len(front) == len(cams) and (
            uv[:, 0].max() < -0.5
            or uv[:, 0].min() > width_px - 0.5
            or uv[:, 1].max() < -0.5
            or uv[:, 1].min() > height_px - 0.5
        ):
            continue
        near_m = max(float(cams[:, 2].min()), 0.1)
        worst = max(worst, float(K[0, 0]) * sway.speed_max_m_s(duration_s) * exposure_s / near_m)
    return worst


def _camera_motion_px(track: HeadTrack, frame: int, K: np.ndarray, width_px: int, height_px: int) -> float:
    """Image speed of the farthest pixel while the head pans, tilts and zooms at frame `frame`, px/s."""
    return camera_image_speed_px_s(
        float(track.pan_deg_s[frame]),
        float(track.tilt_deg_s[frame]),
        float(track.log_zoom_per_s[frame]),
        K,
        width_px,
        height_px,
    )


def focus_distance_m(
    camera: Camera, profile: Profile, focal_length_mm: float, f_number: float, depth_range: tuple[float, float] | None
) -> tuple[float, str]:
    """Where the lens is focused, and why.

    Unless the scene or profile says, the camera is focused as an installer would focus it on what it
    watches: at s = 2·n·d/(n + d), which gives equal blur circles at the nearest (n) and farthest (d)
    visible surfaces. With nothing in view it falls back to the hyperfocal distance.
    """
    if camera.focus_distance_m is not None:
        return camera.focus_distance_m, "set on the camera"
    if profile.lens.focus_distance_m is not None:
        return profile.lens.focus_distance_m, "set in the profile"
    lens_min = max(profile.lens.min_focus_distance_m, 2.0 * focal_length_mm * 1e-3)
    if depth_range is None:
        hyperfocal = hyperfocal_distance_m(focal_length_mm, f_number, profile.coc_mm)
        return max(hyperfocal, lens_min), f"hyperfocal for a {profile.coc_mm * 1e3:g} µm circle of confusion"
    near, far = depth_range
    balanced = 2.0 * near * far / (near + far)
    return max(balanced, lens_min), "balanced between the nearest and farthest visible surfaces"


def _decision(stage: str, include: bool, force: bool, reason: str, **measure) -> Decision:
    if force and not include:
        return Decision(stage=stage, included=True, reason=f"forced on ({reason})", **measure)
    return Decision(stage=stage, included=include, reason=reason, **measure)


def _frame_track(scene: Scene, camera: Camera, profile: Profile, routes, file_bounds) -> tuple[HeadTrack, np.ndarray]:
    """Per-frame pan, tilt, zoom, their rates, the program's mode and target, and the focal length.

    A fixed camera holds with no mode; a virtual PTZ crops, so its lens stays where it is installed."""
    track = head_track(scene, camera, profile, routes, file_bounds)
    if track is not None and camera.eptz is None:
        return track, profile.lens.focal_length_min_mm * track.zoom_x
    focal_length_mm = installed_focal_length_mm(camera, profile)
    if track is None:
        zoom_x = focal_length_mm / profile.lens.focal_length_min_mm
        track = holding_track(0.0, 0.0, zoom_x, scene.frame_count, scene.fps, None)
    return track, np.full(scene.frame_count, focal_length_mm)


def _autofocus(wanted_m: np.ndarray, time_constant_s: float, fps: float) -> np.ndarray:
    """Focus distance per frame that follows `wanted_m` with a first-order lag in dioptres."""
    if time_constant_s <= 0 or len(wanted_m) < 2:
        return wanted_m
    alpha = 1.0 - math.exp(-1.0 / (fps * time_constant_s))
    dioptres = 1.0 / wanted_m
    out = np.empty_like(dioptres)
    out[0] = dioptres[0]  # the camera has been focused on its first view
    for k in range(1, len(dioptres)):
        out[k] = out[k - 1] + alpha * (dioptres[k] - out[k - 1])
    return 1.0 / out


def _compile_camera(
    scene: Scene,
    camera_index: int,
    camera: Camera,
    profile: Profile,
    profile_name: str,
    settings: PlanSettings,
    static_boxes: list[np.ndarray],
    actor_boxes: list[np.ndarray],
    file_bounds,
    routes,
) -> CameraJob:
    sensor, lens, outputs = profile.sensor, profile.lens, scene.outputs
    force = settings.force_all_stages
    W, H = sensor.width_px, sensor.height_px
    pitch_mm = sensor.pixel_pitch_um * 1e-3
    frames = scene.frame_count
    times = np.arange(frames) / scene.fps
    track, focal_lengths_mm = _frame_track(scene, camera, profile, routes, file_bounds)
    # Distinct lens states (zoom steps) and views (pan, tilt, zoom): the decisions take the worst case.
    # (Python's round, once per distinct value: a long sequence repeats its values.)
    rounded = {
        value: round(value, 9)
        for value in {*focal_lengths_mm.tolist(), *track.pan_deg.tolist(), *track.tilt_deg.tolist()}
    }
    lens_of: dict[float, _LensState] = {}
    for focal_length_mm in focal_lengths_mm.tolist():
        key = rounded[focal_length_mm]
        if key not in lens_of:
            lens_of[key] = lens_state(profile, key)
    frame_lens = [lens_of[rounded[f]] for f in focal_lengths_mm.tolist()]
    states_lens = list(lens_of.values())
    virtual = camera.eptz is not None  # the camera itself does not move
    view_keys = [
        (0.0, 0.0, ls.focal_length_mm) if virtual else (rounded[p], rounded[t], ls.focal_length_mm)
        for p, t, ls in zip(track.pan_deg.tolist(), track.tilt_deg.tolist(), frame_lens, strict=True)
    ]
    pose_of = {key: head_pose(camera, key[0], key[1]) for key in dict.fromkeys(view_keys)}
    exposure = profile.exposure
    frame_period_s = 1.0 / scene.fps
    exposure_longest_s = (
        exposure.exposure_time_s if exposure.mode == "manual" else min(exposure.exposure_time_max_s, frame_period_s)
    )

    # Re-ID crops, MOT's img1/ and YOLO's images/ are cut from or are the delivered frames.
    delivered = bool(set(outputs.annotations) & set(ANNOTATIONS_OF_DELIVERED_FRAMES))
    needs_image = (
        outputs.video
        or outputs.frames is not None
        or outputs.raw_dng
        or outputs.raw is not None
        or outputs.radiance is not None
        or delivered
    )
    motion_outputs = [name for name, use in (("flow", outputs.flow), ("scene_flow", outputs.scene_flow)) if use]
    needs_isp = outputs.video or outputs.frames is not None or delivered
    annotations = bool(outputs.annotations)
    mono = sensor.cfa == "mono"
    decisions: list[Decision] = []
    stages: list[Stage] = []
    tol = settings.geometry_tolerance_px
    blur_max = settings.blur_diameter_threshold_px
    zooms = len(states_lens) > 1
    over_zoom = f" over {len(states_lens)} zoom steps" if zooms else ""

    # --- geometric lens effects: one remap ------------------------------------------------------
    distortion_px = max(max_displacement_px(ls.distortion, ls.K, W, H) for ls in states_lens)
    no_distortion = all(not np.any(ls.distortion) for ls in states_lens)
    # The depth output is through the lens too (README: every pass is placed by the distortion).
    use_distortion = needs_image or annotations or bool(motion_outputs) or outputs.depth is not None
    decisions.append(
        _decision(
            "optics.distortion",
            distortion_px > tol and use_distortion,
            force,
            "all coefficients are zero" if no_distortion else f"largest displacement {distortion_px:.3g} px{over_zoom}",
            effect=distortion_px,
            threshold=tol,
            unit="px",
        )
    )
    ca = lens.chromatic_aberration
    ca_scales = (1.0,) if mono else (ca.lateral_scale_r, 1.0, ca.lateral_scale_b)
    corner_px = max(corner_radius_px(ls.K, W, H) for ls in states_lens)
    ca_px = max(abs(s - 1.0) for s in ca_scales) * corner_px
    decisions.append(
        _decision(
            "optics.lateral_ca",
            ca_px > tol and needs_image and not mono,
            force and not mono,
            "monochrome sensor" if mono else f"largest colour fringe {ca_px:.3g} px at the corner",
            effect=ca_px,
            threshold=tol,
            unit="px",
        )
    )
    remap = decisions[-2].included or decisions[-1].included
    geometric_margin = (0.0, 0.0, 0.0, 0.0)
    if remap:
        overshoots = [
            _source_overshoot_px(
                ls.K,
                ls.distortion if decisions[-2].included else np.zeros(8),
                ca_scales if decisions[-1].included else (1.0,),
                W,
                H,
                f"cameras[{camera_index}]",
            )
            for ls in states_lens
        ]
        geometric_margin = tuple(
            max(side) + SUPPORT_PX[settings.remap_interpolation] for side in zip(*overshoots, strict=True)
        )
    # What the lens actually sees: the pinhole extent the output frame samples (wider under barrel).
    seen_left, seen_top, seen_right, seen_bottom = (math.ceil(x) for x in geometric_margin)
    depth_of_view: dict = {}
    for key in dict.fromkeys(view_keys):
        K_seen = lens_of[key[2]].K.copy()
        K_seen[0, 2] += seen_left
        K_seen[1, 2] += seen_top
        depth_of_view[key] = visible_depth_range_m(
            static_boxes + actor_boxes, pose_of[key], K_seen, W + seen_left + seen_right, H + seen_top + seen_bottom
        )
    focus_wanted, focus_reasons = [], []
    for key, ls in zip(view_keys, frame_lens, strict=True):
        focus_m, focus_reason = focus_distance_m(camera, profile, ls.focal_length_mm, ls.f_number, depth_of_view[key])
        focus_wanted.append(focus_m)
        focus_reasons.append(focus_reason)
    autofocus_s = profile.ptz.autofocus_time_s if profile.ptz is not None else 0.0
    automatic_focus = camera.focus_distance_m is None and lens.focus_distance_m is None
    focus_per_frame = _autofocus(np.array(focus_wanted), autofocus_s if automatic_focus else 0.0, scene.fps)

    # --- photometric lens effects ------------------------------------------------------------------
    vignetting = lens.vignetting
    relative, vignetting_weight = 1.0, 1.0
    for ls in states_lens:
        weight = aperture_weight(
            ls.f_number, lens.at_focal_length(ls.focal_length_mm)[0], vignetting.full_illumination_f_number
        )
        corner = _corner_illumination(ls.K, ls.distortion, W, H, vignetting, weight)
        if corner < relative or ls is states_lens[0]:
            relative, vignetting_weight = corner, weight
    falloff = 1.0 - relative
    decisions.append(
        _decision(
            "optics.vignetting",
            falloff > settings.illumination_tolerance_rel and needs_image,
            force and needs_image,
            f"darkest border illumination {relative:.3f} of the centre{over_zoom}",
            effect=falloff,
            threshold=settings.illumination_tolerance_rel,
            unit="relative",
        )
    )

    coc_px, dof_reason = 0.0, "no geometry in view"
    # Each frame's largest blur circle, computed once per view and focus (a long sequence repeats them);
    # the reason names the last frame that reaches the largest.
    frame_coc_px = np.full(frames, -np.inf)
    coc_of: dict = {}
    for k, (key, ls) in enumerate(zip(view_keys, frame_lens, strict=True)):
        depth_range = depth_of_view[key]
        if depth_range is None:
            continue
        focus_m = float(focus_per_frame[k])
        if (key, focus_m) not in coc_of:
            coc_mm = blur_circle_diameter_mm(np.array(depth_range), ls.focal_length_mm, ls.f_number, focus_m)
            coc_of[key, focus_m] = float(np.max(coc_mm) / pitch_mm)
        frame_coc_px[k] = coc_of[key, focus_m]
    if np.isfinite(frame_coc_px).any():
        k = int(frames - 1 - np.argmax(frame_coc_px[::-1]))
        ls, (near, far) = frame_lens[k], depth_of_view[view_keys[k]]
        coc_px = float(frame_coc_px[k])
        dof_reason = (
            f"blur circle up to {coc_px:.3g} px over depths {near:.3g}–{far:.3g} m "
            f"(f = {ls.focal_length_mm:.4g} mm, N = {ls.f_number:.3g}, focus {focus_per_frame[k]:.3g} m, "
            f"{focus_reasons[k]}{', autofocus lag' if autofocus_s > 0 and automatic_focus else ''}"
            f"{f', frame {k}' if len(depth_of_view) > 1 else ''})"
        )
    decisions.append(
        _decision(
            "optics.depth_of_field",
            coc_px > blur_max and needs_image,
            force and needs_image,
            dof_reason,
            effect=coc_px,
            threshold=blur_max,
            unit="px",
        )
    )
    f_number_max = max(ls.f_number for ls in states_lens)
    f_number_min = min(ls.f_number for ls in states_lens)
    # Decided on the kernel applied (`camgen.optics.diffraction`: the discrete Gaussian of the Airy Gaussian's
    # variance): kept wherever it changes a pixel, which is wherever there is an aperture; a sub-pixel spot is
    # still a visible blur at edges (see the module). The widest kernel is the slowest aperture's at the longest
    # wavelength.
    diffraction_sigmas_px = channel_sigmas_px(f_number_max, sensor.pixel_pitch_um, mono)
    diffraction_rel = diffraction_effect_rel(f_number_max, sensor.pixel_pitch_um, mono)
    decisions.append(
        _decision(
            "optics.diffraction",
            diffraction_rel > FLOAT32_RESOLUTION and needs_image,
            force and needs_image,
            f"Airy Gaussian σ = 0.42·λ·N = {max(diffraction_sigmas_px):.3g} px at N = {f_number_max:.3g}, "
            f"λ = {MONO_WAVELENGTH_UM if mono else max(CHANNEL_WAVELENGTHS_UM)} µm: its discrete kernel's "
            f"off-centre taps weigh {diffraction_rel:.3g} of its centre",
            effect=diffraction_rel,
            threshold=FLOAT32_RESOLUTION,
            unit="relative",
        )
    )
    axial_shifts_um = (0.0,) if mono else (ca.axial_focus_shift_r_um, 0.0, ca.axial_focus_shift_b_um)
    axial_px = tuple(abs(shift) / f_number_min / sensor.pixel_pitch_um for shift in axial_shifts_um)
    decisions.append(
        _decision(
            "optics.axial_ca",
            max(axial_px) > blur_max and needs_image,
            force and needs_image and not mono,
            "monochrome sensor"
            if mono
            else f"per-channel blur discs {axial_px[0]:.3g}, {axial_px[2]:.3g} px (red, blue) "
            f"at N = {f_number_min:.3g}",
            effect=max(axial_px),
            threshold=blur_max,
            unit="px",
        )
    )
    motion_px = 0.0
    groups: dict = {}
    for k, key in enumerate(view_keys):
        groups.setdefault(key, []).append(k)
    swaying = swaying_props(scene.environment, scene_seed=scene.seed)
    for key, indices in groups.items():
        if swaying:
            motion_px = max(
                motion_px,
                _sway_motion_px(swaying, scene.duration_s, exposure_longest_s, pose_of[key], lens_of[key[2]].K, W, H),
            )
        motion_px = max(
            motion_px,
            _actor_motion_px(
                scene.actors,
                routes,
                times[indices],
                exposure_longest_s,
                pose_of[key],
                lens_of[key[2]].K,
                W,
                H,
                file_bounds,
            ),
        )
    camera_motion_px = [
        0.0 if virtual else round(_camera_motion_px(track, k, ls.K, W, H) * exposure_longest_s, 3)
        for k, ls in enumerate(frame_lens)
    ]
    camera_worst_px = max(camera_motion_px)
    decisions.append(
        _decision(
            "optics.motion_blur",
            motion_px + camera_worst_px > blur_max and needs_image,
            force and needs_image,
            f"largest {'actor or swaying-prop' if swaying else 'actor'} motion {motion_px:.3g} px and camera "
            f"motion {camera_worst_px:.3g} px during a "
            f"{exposure_longest_s:.3g} s exposure "
            f"({'manual' if exposure.mode == 'manual' else 'longest auto-exposure'})",
            effect=motion_px + camera_worst_px,
            threshold=blur_max,
            unit="px",
        )
    )
    include = {d.stage: d.included for d in decisions}

    # --- margins the render needs ---------------------------------------------------------------------
    left, top, right, bottom = geometric_margin
    blur_radius = 0.0
    if include["optics.depth_of_field"]:
        blur_radius = max(blur_radius, coc_px / 2)
    if include["optics.diffraction"]:  # the reach of the longest wavelength's kernel
        red_sigma_px = airy_sigma_px(f_number_max, sensor.pixel_pitch_um, max(CHANNEL_WAVELENGTHS_UM))
        blur_radius = max(blur_radius, kernel_reach_px(red_sigma_px))
    if include["optics.axial_ca"]:
        blur_radius = max(blur_radius, max(axial_px) / 2)
    if include["optics.motion_blur"]:
        # Camera motion needs no margin: each sub-frame is a complete render of its own view.
        blur_radius = max(blur_radius, motion_px)
    margin = tuple(math.ceil(x + blur_radius) for x in (left, top, right, bottom))

    # --- passes -------------------------------------------------------------------------------------
    passes: list[str] = []
    if needs_image:
        passes.append("radiance")
        decisions.append(
            Decision(stage="pass.radiance", included=True, reason="video, frames, raw, radiance or annotation images")
        )
    else:
        decisions.append(Decision(stage="pass.radiance", included=False, reason="no image output requested"))
    mirrors = wet_ground_height_m(scene.environment) is not None  # the wet ground's water film (camgen.render.wet)
    depth_consumers = [
        name
        for name, use in (
            ("depth of field", include["optics.depth_of_field"]),
            ("depth output", outputs.depth is not None),
            (" and ".join(motion_outputs) + " output", bool(motion_outputs)),
            ("rain's depth test", scene.environment.rain is not None and needs_image),
            ("snow's depth test", scene.environment.snow is not None and needs_image),
            ("the wet ground's reflections", mirrors and needs_image),
        )
        if use
    ]
    depth_needed = bool(depth_consumers)
    decisions.append(
        Decision(
            stage="pass.depth_m",
            included=depth_needed,
            reason="consumed by " + " and ".join(depth_consumers)
            if depth_needed
            else "no depth of field and no depth or flow output",
        )
    )
    if depth_needed:
        passes.append("depth_m")
    fog = scene.environment.fog
    if fog is not None and needs_image:
        decisions.append(
            Decision(
                stage="render.fog",
                included=True,
                reason=f"visual range {fog.visibility_m:g} m: Koschmieder's law on each pixel's distance, from a "
                "depth target drawn with the radiance (no depth pass or output of its own)",
            )
        )
    rain = scene.environment.rain
    if rain is not None and needs_image:
        decisions.append(
            Decision(
                stage="render.rain",
                included=True,
                reason=f"{rain.rate_mm_h:g} mm/h: drop streaks over each frame's exposure within "
                f"{STREAK_RANGE_M:g} m, depth-tested, and haze beyond (camgen.world.rain)",
            )
        )
    snow = scene.environment.snow
    if snow is not None and needs_image:
        visibility = (
            f"haze of {snow_visibility_m(snow.rate_mm_h, snow.kind):.0f} m visibility beyond (Rasmussen et al. 1999)"
            if scene.environment.fog is None
            else f"no haze of its own beyond (environment.fog's {scene.environment.fog.visibility_m:g} m is the "
            "visibility in the snow)"
        )
        decisions.append(
            Decision(
                stage="render.snow",
                included=True,
                reason=f"{snow.rate_mm_h:g} mm/h of {snow.kind} snow: flake streaks over each frame's exposure within "
                f"{STREAK_RANGE_M:g} m (the smallest flakes nearer: camgen.render.snow.flake_ranges_m), depth-tested "
                f"and defocused, and a {visibility} (camgen.world.snow)",
            )
        )
    if ground_is_wet(scene.environment) and needs_image:
        decisions.append(
            Decision(
                stage="render.wet_reflections",
                included=mirrors,
                reason="wet ground: the scene mirrored in its water film, drawn at each frame time, spread by the "
                "film's ripples and added by water's Fresnel reflectance (camgen.render.wet)"
                if mirrors
                else "wet ground, but no level plane facing up among environment.meshes for its water film to lie "
                "on (camgen.world.rain.wet_ground_height_m): nothing is mirrored",
            )
        )
    wind = scene.environment.wind
    if wind is not None and wind.speed_m_s > 0 and needs_image:
        decisions.append(
            Decision(
                stage="render.wind",
                included=True,
                reason=f"{wind.speed_m_s:g} m/s: trees and bushes sway and their leaves flutter (camgen.props.sway); "
                "they are drawn with the actors each frame, never into a kept background",
            )
        )
    ids_reason = ", ".join(outputs.annotations) if annotations else ""
    if motion_outputs:  # a surface's motion is its instance's
        ids_reason = ", ".join(([ids_reason] if ids_reason else []) + motion_outputs)
    decisions.append(
        Decision(
            stage="pass.instance_id",
            included=bool(ids_reason),
            reason=f"requested by {ids_reason}" if ids_reason else "no annotations or flow requested",
        )
    )
    if ids_reason:
        passes.append("instance_id")
    # The kept background is redrawn whenever the view changes: worth it while the camera mostly rests.
    still_frames = sum(1 for k in range(1, frames) if view_keys[k] == view_keys[k - 1]) + 1
    still = still_frames >= frames / 2
    shadow_lights = scene.environment.shadows and any(light.type in ("sun", "spot", "lamp") for light in scene.lights)
    daylight_moves = _daylight_moves(scene, decisions) and needs_image
    static_background = still and bool(scene.actors) and needs_image and not shadow_lights and not daylight_moves
    if static_background:
        static_reason = (
            "camera and environment are static; actors are composited per frame"
            if len(pose_of) == 1
            else f"the camera rests in {still_frames} of {frames} frames; the environment is redrawn when it moves"
        )
        if swaying:
            static_reason += "; the trees and bushes swaying in the wind are drawn with the actors"
    elif daylight_moves:
        static_reason = (
            "the site's daylight changes over the sequence (world.daylight), so every frame is drawn in full"
        )
    elif scene.actors and needs_image and not shadow_lights:
        static_reason = (
            f"the camera moves in {frames - still_frames} of {frames} frames; a frame after a still one redraws "
            "only what moved (camgen.render.sequence, still frames)"
        )
    elif not scene.actors:
        static_reason = "no actors: the environment alone is drawn, once while the camera holds still (still frames)"
    elif not needs_image:
        static_reason = "no image output (the geometric passes alone are cheap)"
    else:
        static_reason = (
            "actors cast shadows on the environment (environment.shadows); a frame after a still one redraws "
            "only what moved, with its shadows (camgen.render.sequence, still frames)"
        )
    decisions.append(Decision(stage="render.static_background", included=static_background, reason=static_reason))

    stages.append(
        Stage(
            name="render",
            passes=tuple(passes),
            params={"supersampling": settings.supersampling, "static_background": static_background},
        )
    )
    # Blur stages run on the margin-rendered pinhole image, before the remap (see `camgen.plan.lens_stages`).
    blur_stages = (
        (
            "optics.motion_blur",
            {
                "displacement_max_px": motion_px,
                "camera_motion_px": camera_motion_px,
                "exposure_longest_s": exposure_longest_s,
                "sample_step_px": MOTION_SAMPLE_STEP_PX,
                "samples_max": MOTION_SAMPLES_MAX,
                "threshold_px": blur_max,
            },
        ),
        (
            "optics.depth_of_field",
            {
                "coc_max_px": coc_px,
                "step_px": settings.dof_step_px,
                "step_rel": settings.dof_step_rel,
            },
        ),
        ("optics.axial_ca", {"focus_shift_um": list(axial_shifts_um)}),
        (
            "optics.diffraction",
            {"sigma_max_px": max(diffraction_sigmas_px), "off_centre_weight_rel": diffraction_rel},
        ),
    )
    for name, params in blur_stages:
        if include[name]:
            consumed = ("radiance", "depth_m") if name == "optics.depth_of_field" else ("radiance",)
            stages.append(Stage(name=name, passes=consumed, params=params))
    if remap:
        stages.append(
            Stage(
                name="optics.remap",
                passes=tuple(passes),  # every rendered pass goes through the same lens map
                params={
                    "distortion": include["optics.distortion"],
                    "lateral_ca": include["optics.lateral_ca"],
                    "interpolation": settings.remap_interpolation,
                    "geometric_passes": "nearest",
                },
            )
        )
    if include["optics.vignetting"]:
        stages.append(
            Stage(
                name="optics.vignetting",
                passes=("radiance",),
                params={"border_relative_illumination": relative, "aperture_weight": vignetting_weight},
            )
        )

    if needs_image:
        _sensor_and_isp(profile, outputs, needs_isp, mono, force, stages, decisions)
    if virtual:
        eptz = camera.eptz
        stages.append(
            Stage(
                name="isp.eptz",
                passes=tuple(passes),  # the stream and its annotations are the same crop
                params={"output_size_px": list(eptz.output_size_px), "zoom_max_x": eptz.zoom_max_x},
            )
        )
    if needs_isp and outputs.video:
        stages.append(Stage(name="io.video", params={"codec": profile.codec.name}))
    if outputs.frames is not None:
        stages.append(Stage(name="io.frames", params={"format": outputs.frames}))
    if annotations:
        params: dict = {"formats": list(outputs.annotations)}
        if {"mot", "yolo"} & set(outputs.annotations):
            params["images"] = outputs.annotation_images
        if outputs.mot_detections:
            params["detections"] = "hog"
        stages.append(Stage(name="annotate", passes=("instance_id",), params=params))
    if outputs.depth is not None:
        stages.append(Stage(name="io.depth", passes=("depth_m",), params={"format": outputs.depth}))
    if outputs.radiance is not None:
        stages.append(Stage(name="io.radiance", passes=("radiance",), params={"format": outputs.radiance}))
    if outputs.flow is not None:
        stages.append(Stage(name="io.flow", passes=("depth_m", "instance_id"), params={"format": outputs.flow}))
    if outputs.scene_flow:
        stages.append(Stage(name="io.scene_flow", passes=("depth_m", "instance_id"), params={"format": "exr"}))
    if outputs.camera_metadata:
        stages.append(Stage(name="io.camera_metadata"))

    output_size = tuple(camera.eptz.output_size_px) if virtual else None

    template_of: dict = {}

    def frame_state(k: int, ls: _LensState) -> CameraState:
        mode, target = track.modes[k], track.targets[k]
        per_frame = dict(
            frame=k,
            time_s=float(times[k]),
            pan_deg=float(track.pan_deg[k]),
            tilt_deg=float(track.tilt_deg[k]),
            zoom_x=float(track.zoom_x[k]),
            focus_distance_m=float(focus_per_frame[k]),
            pan_deg_s=float(track.pan_deg_s[k]),
            tilt_deg_s=float(track.tilt_deg_s[k]),
            log_zoom_per_s=float(track.log_zoom_per_s[k]),
            ptz_mode=None if mode is None else str(mode),
            follow_target=None if target is None else str(target),
        )
        template = None if virtual else template_of.get(view_keys[k])
        if template is not None:
            # The frames of one view share its lens, pose and exposure: a copy of the view's first state
            # with this frame's scalars (plain Python values, as validation makes them) is what
            # `camera_state` would build, at a third of the time (an hour's 90,000 states: 7.5 s of
            # validation otherwise). A virtual PTZ's window moves within a view: it is built each frame.
            return template.model_copy(update=per_frame)
        state = camera_state(
            **per_frame,
            lens=ls,
            T_world_from_cam_=pose_of[view_keys[k]],
            exposure_time_s=exposure.exposure_time_s,
            gain_db=exposure.gain_db,
            apply_distortion=include["optics.distortion"],
            eptz_sizes_px=((W, H), output_size) if virtual else None,
        )
        template_of.setdefault(view_keys[k], state)
        return state

    states = tuple(frame_state(k, ls) for k, ls in enumerate(frame_lens))
    if _night_mode(scene, camera, profile, decisions):
        states = tuple(state.model_copy(update={"night_mode": True}) for state in states)
    render = RenderSpec(
        width_px=W + margin[0] + margin[2],
        height_px=H + margin[1] + margin[3],
        margin_px=margin,
        passes=tuple(passes),
        supersampling=settings.supersampling,
        static_background=static_background,
    )
    return CameraJob(
        name=camera.name,
        profile_name=profile_name,
        profile=profile,
        serial=camera.serial if camera.serial is not None else profile.serial,
        width_px=W,
        height_px=H,
        exposure_mode=exposure.mode,
        output_size_px=output_size,
        render=render,
        stages=tuple(stages),
        decisions=tuple(decisions),
        states=states,
    )


def scene_sky_illuminance_lux(scene) -> float:
    """The horizontal illuminance the sky gives the scene, lux: its ambient lights plus each sun light's
    illuminance times the sine of its elevation (lamps light only their pools and are left out), at the
    first frame."""
    total = 0.0
    for light in scene.lights:
        if light.type == "ambient":
            total += light.illuminance_lux
        elif light.type == "sun":
            total += light.illuminance_lux * math.sin(math.radians(light.elevation_deg))
    return total


def _night_mode(scene, camera, profile, decisions: list[Decision]) -> bool:
    """Whether the camera films the sequence in IR night mode (`camgen.world.night`): the scene camera's
    `night_mode` (on/off), or, for auto, whether the sky's illuminance (`scene_sky_illuminance_lux`) is
    below the profile's `night_mode.switch_lux`. A site's daylight is above any switch level (it ends
    at sunset), so the mode holds for the whole sequence."""
    night = profile.night_mode
    if night is None or not night.ir_cut_filter:
        if camera.night_mode is True:
            raise ConfigError(
                f"camera {camera.name!r}: night_mode is on, but its profile has no night mode with a removable "
                "IR-cut filter (profile key night_mode); give the profile one, or use night_mode: auto or false"
            )
        return False
    illuminance_lux = scene_sky_illuminance_lux(scene)
    if camera.night_mode == "auto":
        on = illuminance_lux < night.switch_lux
        reason = (
            f"the sky gives {illuminance_lux:.3g} lx, {'below' if on else 'not below'} the profile's switch level "
            f"{night.switch_lux:g} lx"
        )
    else:
        on = camera.night_mode
        reason = f"the scene's camera sets night_mode: {'on' if on else 'off'}"
    decisions.append(
        Decision(
            stage="camera.night_mode",
            included=on,
            reason=reason + ("; IR-cut filter out, IR illuminator on, monochrome stream" if on else "; colour"),
            effect=illuminance_lux,
            threshold=night.switch_lux,
            unit="lx",
        )
    )
    return on


def _daylight_moves(scene, decisions: list[Decision]) -> bool:
    """Whether a site's daylight changes over the sequence enough for each frame to be lit on its own
    (`camgen.world.site.daylight_change`); the decision is recorded when the scene has a site."""
    from camgen.world.site import DIRECTION_CHANGE_DEG, ILLUMINANCE_CHANGE_REL, daylight_change

    site = scene.environment.site
    if site is None or scene.environment.night_sky is not None:  # a night sky holds its level
        return False
    change = daylight_change(site.latitude_deg, site.longitude_deg, site.time, scene.environment.sky, scene.duration_s)
    decisions.append(
        Decision(
            stage="world.daylight",
            included=change.varies,
            reason=f"over {scene.duration_s:g} s the sun turns {change.direction_deg:.3g}° (threshold "
            f"{DIRECTION_CHANGE_DEG:g}°) and daylight changes by {100 * change.illuminance_rel:.3g} % (threshold "
            f"{100 * ILLUMINANCE_CHANGE_REL:g} %): "
            + ("each frame is lit for its own time" if change.varies else "the first frame's daylight is held"),
        )
    )
    return change.varies


def _sensor_and_isp(profile, outputs, needs_isp, mono, force, stages, decisions) -> None:
    sensor, noise, isp = profile.sensor, profile.sensor.noise, profile.isp
    stages.append(Stage(name="sensor.exposure", passes=("radiance",), params={"mode": profile.exposure.mode}))
    active = []
    for term in NOISE_TERMS:
        on = noise_term_is_on(noise, term)
        key, off = NOISE_TERM_OFF[term]
        off_reason = f"{key} is {'false' if isinstance(off, bool) else f'{off:g}'}"
        decisions.append(_decision(f"sensor.noise.{term}", on, force, "set in the profile" if on else off_reason))
        if on or force:
            active.append(term)
    stages.append(Stage(name="sensor.noise", params={"terms": active}))
    stages.append(
        Stage(name="sensor.adc", params={"bit_depth": sensor.bit_depth, "black_level_dn": sensor.black_level_dn})
    )
    if outputs.raw_dng:
        stages.append(Stage(name="io.raw_dng"))
    if outputs.raw is not None:
        stages.append(Stage(name="io.raw", params={"format": outputs.raw}))
    if not needs_isp:
        decisions.append(Decision(stage="isp", included=False, reason="only raw output requested"))
        return
    isp_steps = isp_stage_choices(isp, sensor)
    for name, on, reason, params in isp_steps:
        applicable = not (mono and name in ("isp.demosaic", "isp.white_balance", "isp.ccm"))
        decision = _decision(name, on, force and applicable, reason)
        decisions.append(decision)
        if decision.included:
            stages.append(Stage(name=name, params=params))


def isp_stage_choices(isp: Isp, sensor: Sensor) -> list[tuple[str, bool, str, dict]]:
    """(stage, wanted, reason, params) of every ISP stage for this profile, in the ISP's order."""
    mono = sensor.cfa == "mono"
    wb = isp.white_balance
    return [
        (
            "isp.demosaic",
            not mono,
            "monochrome sensor" if mono else f"{sensor.cfa} mosaic, {isp.demosaic}",
            {"method": isp.demosaic, "cfa": sensor.cfa},
        ),
        (
            "isp.white_balance",
            not mono and (wb.mode == "auto_grey_world" or wb.gains_rgb != (1.0, 1.0, 1.0)),
            "monochrome sensor" if mono else f"{wb.mode}, gains {list(wb.gains_rgb)}",
            {"mode": wb.mode},
        ),
        (
            "isp.ccm",
            not mono and not isp.ccm_is_identity,
            "identity matrix" if isp.ccm_is_identity else "colour-correction matrix set",
            {},
        ),
        (
            "isp.false_colour",
            not mono and isp.false_colour_median_px > 0,
            "monochrome sensor" if mono else f"median of the colour differences over {isp.false_colour_median_px} px",
            {},
        ),
        ("isp.denoise", isp.denoise_strength > 0, f"strength {isp.denoise_strength:g}", {}),
        (
            "isp.contrast_stretch",
            isp.contrast_stretch is not None,
            "set" if isp.contrast_stretch else "contrast_stretch is null",
            {},
        ),
        ("isp.tone", isp.tone_curve != "linear", f"tone curve {isp.tone_curve}", {"curve": isp.tone_curve}),
        ("isp.sharpen", isp.sharpen_amount > 0, f"amount {isp.sharpen_amount:g}", {}),
    ]


def isp_steps(isp: Isp, sensor: Sensor) -> set[str]:
    """The ISP stages a camera with this profile runs (those `isp_stage_choices` wants; not forced)."""
    return {name for name, wanted, _, _ in isp_stage_choices(isp, sensor) if wanted}


STANDING_CHECK_STEP_S = 0.05
"""Whole-body actions are checked to fall where the person stands at this step of scene time, s."""


def standing_action_problems(scene: Scene, routes: Mapping[str, Route]) -> list[Problem]:
    """A sit or a fall must happen where the person stands (`camgen.actors.actions`): one that
    overlaps a walked leg of the route is refused, naming when the person walks."""
    problems = []
    for i, actor in enumerate(scene.actors):
        for k, action in enumerate(actor.actions):
            if action.type not in ("sit", "fall"):
                continue
            route = routes[actor.name]
            end = min(action.start_s + action.duration_s, scene.duration_s)
            times = np.append(np.arange(action.start_s, end, STANDING_CHECK_STEP_S), end)
            walking = [t for t in times if route.standing(float(t)) is None]
            if walking:
                problems.append(
                    Problem(
                        ("actors", i, "actions", k, "start_s"),
                        f"starts a {action.type} at {action.start_s:g} s, but {actor.name} walks at "
                        f"{walking[0]:.2f} s of it; a person sits or falls where they stand: give the path a "
                        "pause_s there, or start the action after the person arrives",
                    )
                )
    return problems


def compile(
    scene: Scene,
    profiles: Mapping[str, Profile],
    *,
    scene_name: str = "scene",
    profile_names: Mapping[str, str] | None = None,
    settings: PlanSettings | None = None,
    file_bounds: Mapping[str, Bounds] | None = None,
) -> Job:
    """Compile a scene and the profile of each camera (keyed by camera name) into a Job."""
    settings = settings or PlanSettings()
    missing = [c.name for c in scene.cameras if c.name not in profiles]
    if missing:
        raise ConfigError(f"no profile given for camera(s) {', '.join(missing)}")
    problems = check_cameras(scene, dict(profiles))
    if problems:
        raise ConfigError(problems)
    check_job_size(scene)
    static_boxes = [box_corners(*local_bounds(mesh, file_bounds), placement(mesh)) for mesh in scene.environment.meshes]
    static_boxes += prop_box_corners(scene.environment, scene_seed=scene.seed)
    routes = actor_routes(scene)
    problems = standing_action_problems(scene, routes)
    if problems:
        raise ConfigError(problems)
    actor_boxes = [
        box
        for actor in scene.actors
        for box in actor_swept_boxes(actor, routes[actor.name], file_bounds, scene.duration_s)
    ]
    cameras = tuple(
        _compile_camera(
            scene,
            i,
            camera,
            installed_profile(camera, profiles[camera.name]),
            (profile_names or {}).get(camera.name, camera.profile),
            settings,
            static_boxes,
            actor_boxes,
            file_bounds,
            routes,
        )
        for i, camera in enumerate(scene.cameras)
    )
    job = Job(
        camgen_version=camgen.__version__,
        scene_name=scene_name,
        scene=scene,
        settings=settings,
        frame_count=scene.frame_count,
        fps=scene.fps,
        seed=scene.seed,
        cameras=cameras,
    )
    return job.model_copy(update={"job_id": job.content_hash()})


def installed_profile(camera: Camera, profile: Profile) -> Profile:
    """The profile as this unit is set up: the camera's own exposure zone (`metering_region_frac`), where it
    has one, replaces the profile's metering window."""
    if camera.metering_region_frac is None:
        return profile
    auto = profile.exposure.auto.model_copy(update={"metering_region_frac": camera.metering_region_frac})
    return profile.model_copy(update={"exposure": profile.exposure.model_copy(update={"auto": auto})})


def compile_scene(loaded: LoadedScene, settings: PlanSettings | None = None) -> Job:
    """Compile a scene as returned by `camgen.config.load_scene`; problems point into its file."""
    try:
        return compile(
            loaded.scene,
            loaded.profile_models,
            scene_name=loaded.name,
            profile_names=loaded.profile_names,
            settings=settings,
            file_bounds=loaded.file_bounds,
        )
    except ConfigError as exc:
        # A problem about a key of the scene (no location: compile sees models, not the file) points at it.
        located = [
            Problem(p.path, p.message, loaded.locate(p.path)) if p.path and not p.location else p for p in exc.problems
        ]
        raise ConfigError(located) from None
