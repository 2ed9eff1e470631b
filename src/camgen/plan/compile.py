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
from camgen.config.profile import Profile
from camgen.config.scene import (
    Actor,
    BoxMesh,
    Camera,
    CheckerboardMesh,
    CylinderMesh,
    FileMesh,
    PlaneMesh,
    Scene,
    SphereMesh,
    actor_shape,
)
from camgen.errors import ConfigError
from camgen.motion.pose import R_world_from_cam, T_world_from_cam, rot_z, rotation_xyz_deg
from camgen.motion.trajectory import position_on_path
from camgen.optics.diffraction import CHANNEL_WAVELENGTHS_UM
from camgen.optics.distortion import max_displacement_px, undistort_normalized
from camgen.optics.intrinsics import (
    airy_sigma_um,
    blur_circle_diameter_mm,
    camera_matrix_px,
    corner_radius_normalized,
    corner_radius_px,
    hyperfocal_distance_m,
)
from camgen.optics.projection import LensInversionError
from camgen.optics.remap import SUPPORT_PX, LensGeometry, border_points_px, source_overshoot_px
from camgen.optics.vignetting import aperture_weight, relative_illumination
from camgen.plan.job import CameraJob, CameraState, Decision, Job, PlanSettings, RenderSpec, Stage
from camgen.plan.visibility import box_corners, visible_depth_range_m
from camgen.sensor.capture import NOISE_TERM_OFF, NOISE_TERMS, noise_term_is_on

WAVELENGTH_UM = 0.55  # mid-visible, for the diffraction estimate
MOTION_SAMPLE_STEP_PX = 1.0
"""Largest image motion between the sub-frames that integrate one exposure, px."""
MOTION_SAMPLES_MAX = 32

Bounds = tuple[np.ndarray, np.ndarray]


def local_bounds(shape, file_bounds: Mapping[str, Bounds] | None = None) -> Bounds:
    """Axis-aligned bounds of a mesh in its own frame, before its placement."""
    if isinstance(shape, BoxMesh):
        half = np.array(shape.size_m) / 2
        return -half, half
    if isinstance(shape, CylinderMesh):
        half = np.array([shape.radius_m, shape.radius_m, shape.height_m / 2])
        return -half, half
    if isinstance(shape, SphereMesh):
        return -np.full(3, shape.radius_m), np.full(3, shape.radius_m)
    if isinstance(shape, PlaneMesh):
        half = np.array([shape.size_m[0] / 2, shape.size_m[1] / 2, 0.0])
        return -half, half
    if isinstance(shape, CheckerboardMesh):
        border = shape.border_width_m
        half = np.array([s * shape.square_size_m / 2 + border for s in shape.squares] + [0.0])
        return -half, half
    if isinstance(shape, FileMesh):
        if not file_bounds or shape.path not in file_bounds:
            raise ConfigError(f"the bounds of mesh file {shape.path!r} were not loaded; use camgen.config.load_scene")
        low, high = file_bounds[shape.path]
        return np.asarray(low) * shape.scale, np.asarray(high) * shape.scale
    raise TypeError(f"unknown shape {type(shape).__name__}")


def _placement(shape) -> np.ndarray:
    return T_world_from_cam(shape.position_m, rotation_xyz_deg(shape.rotation_deg))


def _path_positions(actor: Actor, times_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    path = actor.path
    return position_on_path(np.array(path.waypoints_m), path.speed_m_s, path.start_s, path.loop, times_s)


def _actor_swept_boxes(actor: Actor, file_bounds, duration_s: float) -> list[np.ndarray]:
    """World corners of boxes that contain everything the actor occupies during the sequence.

    Along one straight segment the actor's box slides along its heading, so the volume it sweeps is
    its box stretched by the distance covered: one oriented box per segment travelled.
    """
    shape = actor_shape(actor)
    low, high = local_bounds(shape, file_bounds)
    corners_local = box_corners(low, high, _placement(shape))
    low, high = corners_local.min(axis=0), corners_local.max(axis=0)
    path = actor.path
    points = np.array(path.waypoints_m, dtype=np.float64)
    if len(points) == 1:
        return [box_corners(low, high, T_world_from_cam((*points[0], 0.0), np.eye(3)))]
    if path.loop:
        points = np.vstack([points, points[:1]])
    lengths = np.hypot(*np.diff(points, axis=0).T)
    travelled = max(0.0, duration_s - path.start_s) * path.speed_m_s
    if path.loop:
        travelled = min(travelled, lengths.sum())
    boxes, start = [], 0.0
    for i, length in enumerate(lengths):
        covered = min(length, travelled - start)
        if covered < 0:
            break
        dx, dy = points[i + 1] - points[i]
        T = T_world_from_cam((*points[i], 0.0), rot_z(math.atan2(dy, dx)))
        boxes.append(box_corners(low, high + np.array([covered, 0.0, 0.0]), T))
        start += length
    return boxes


def _camera_focal_length_mm(camera: Camera, profile: Profile) -> tuple[float, float]:
    lens = profile.lens
    if camera.ptz is not None:
        return lens.focal_length_min_mm * camera.ptz.zoom_x, camera.ptz.zoom_x
    if camera.focal_length_mm is not None:
        return camera.focal_length_mm, camera.focal_length_mm / lens.focal_length_min_mm
    return lens.focal_length_min_mm, 1.0


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


def _actor_motion_px(
    actors: list[Actor],
    times_s: np.ndarray,
    exposure_s: float,
    T_world_from_cam_: np.ndarray,
    K: np.ndarray,
    width_px: int,
    height_px: int,
    file_bounds: Mapping[str, Bounds] | None,
) -> float:
    """Largest image displacement of an actor point (ground and top) within one exposure, px."""
    T_cam_from_world = np.linalg.inv(T_world_from_cam_)
    worst = 0.0
    for actor in actors:
        if len(actor.path.waypoints_m) < 2:
            continue
        shape = actor_shape(actor)
        top = float(box_corners(*local_bounds(shape, file_bounds), _placement(shape))[:, 2].max())
        ends = [_path_positions(actor, t)[0] for t in (times_s, times_s + exposure_s)]
        for height in (0.0, top):
            pts = [np.column_stack([xy, np.full(len(xy), height)]) for xy in ends]
            cams = [p @ T_cam_from_world[:3, :3].T + T_cam_from_world[:3, 3] for p in pts]
            z = np.minimum(cams[0][:, 2], cams[1][:, 2])
            visible = z > 0.1
            if not visible.any():
                continue
            uv = [(c[visible, :2] / c[visible, 2:3]) @ K[:2, :2].T + K[:2, 2] for c in cams]
            inside = (
                (uv[0][:, 0] > -0.5)
                & (uv[0][:, 0] < width_px - 0.5)
                & (uv[0][:, 1] > -0.5)
                & (uv[0][:, 1] < height_px - 0.5)
            )
            if inside.any():
                worst = max(worst, float(np.max(np.hypot(*(uv[1] - uv[0])[inside].T))))
    return worst


def _focus_distance_m(
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
) -> CameraJob:
    sensor, lens, outputs = profile.sensor, profile.lens, scene.outputs
    force = settings.force_all_stages
    W, H = sensor.width_px, sensor.height_px
    pitch_mm = sensor.pixel_pitch_um * 1e-3
    focal_length_mm, zoom_x = _camera_focal_length_mm(camera, profile)
    f_number, distortion = lens.at_focal_length(focal_length_mm)
    dist = distortion.as_array()
    K = camera_matrix_px(
        focal_length_mm, sensor.pixel_pitch_um, sensor.pitch_y_um, W, H, sensor.principal_point_offset_px
    )
    pan = camera.ptz.pan_deg if camera.ptz else 0.0
    tilt = camera.ptz.tilt_deg if camera.ptz else 0.0
    m = camera.mount
    T = T_world_from_cam(m.position_m, R_world_from_cam(m.yaw_deg, m.pitch_deg, m.roll_deg, pan, tilt))
    exposure = profile.exposure
    frame_period_s = 1.0 / scene.fps
    exposure_longest_s = (
        exposure.exposure_time_s if exposure.mode == "manual" else min(exposure.exposure_time_max_s, frame_period_s)
    )

    needs_image = outputs.video or outputs.frames is not None or outputs.raw_dng
    needs_isp = outputs.video or outputs.frames is not None
    annotations = bool(outputs.annotations)
    mono = sensor.cfa == "mono"
    decisions: list[Decision] = []
    stages: list[Stage] = []
    tol = settings.geometry_tolerance_px
    blur_max = settings.blur_diameter_threshold_px

    # --- geometric lens effects: one remap ------------------------------------------------------
    distortion_px = max_displacement_px(dist, K, W, H)
    use_distortion = needs_image or annotations
    decisions.append(
        _decision(
            "optics.distortion",
            distortion_px > tol and use_distortion,
            force,
            "all coefficients are zero" if distortion.is_zero else f"largest displacement {distortion_px:.3g} px",
            effect=distortion_px,
            threshold=tol,
            unit="px",
        )
    )
    ca = lens.chromatic_aberration
    ca_scales = (1.0,) if mono else (ca.lateral_scale_r, 1.0, ca.lateral_scale_b)
    corner_px = corner_radius_px(K, W, H)
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
        overshoot = _source_overshoot_px(
            K,
            dist if decisions[-2].included else np.zeros(8),
            ca_scales if decisions[-1].included else (1.0,),
            W,
            H,
            f"cameras[{camera_index}]",
        )
        geometric_margin = tuple(x + SUPPORT_PX[settings.remap_interpolation] for x in overshoot)
    # What the lens actually sees: the pinhole extent the output frame samples (wider under barrel).
    seen_left, seen_top, seen_right, seen_bottom = (math.ceil(x) for x in geometric_margin)
    K_seen = K.copy()
    K_seen[0, 2] += seen_left
    K_seen[1, 2] += seen_top
    depth_range = visible_depth_range_m(
        static_boxes + actor_boxes, T, K_seen, W + seen_left + seen_right, H + seen_top + seen_bottom
    )
    focus_m, focus_reason = _focus_distance_m(camera, profile, focal_length_mm, f_number, depth_range)

    # --- photometric lens effects ------------------------------------------------------------------
    vignetting = lens.vignetting
    vignetting_weight = aperture_weight(
        f_number, lens.at_focal_length(focal_length_mm)[0], vignetting.full_illumination_f_number
    )
    relative = _corner_illumination(K, dist, W, H, vignetting, vignetting_weight)
    falloff = 1.0 - relative
    decisions.append(
        _decision(
            "optics.vignetting",
            falloff > settings.illumination_tolerance_rel and needs_image,
            force and needs_image,
            f"darkest border illumination {relative:.3f} of the centre",
            effect=falloff,
            threshold=settings.illumination_tolerance_rel,
            unit="relative",
        )
    )

    if depth_range is None:
        coc_px, dof_reason = 0.0, "no geometry in view"
    else:
        near, far = depth_range
        coc_mm = blur_circle_diameter_mm(np.array([near, far]), focal_length_mm, f_number, focus_m)
        coc_px = float(np.max(coc_mm) / pitch_mm)
        dof_reason = (
            f"blur circle up to {coc_px:.3g} px over depths {near:.3g}–{far:.3g} m "
            f"(f = {focal_length_mm:.4g} mm, N = {f_number:.3g}, focus {focus_m:.3g} m, {focus_reason})"
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
    airy_px = 2.44 * (WAVELENGTH_UM if mono else max(CHANNEL_WAVELENGTHS_UM)) * f_number / sensor.pixel_pitch_um
    decisions.append(
        _decision(
            "optics.diffraction",
            airy_px > blur_max and needs_image,
            force and needs_image,
            f"Airy disc diameter 2.44·λ·N = {airy_px:.3g} px at N = {f_number:.3g}, "
            f"λ = {WAVELENGTH_UM if mono else max(CHANNEL_WAVELENGTHS_UM)} µm",
            effect=airy_px,
            threshold=blur_max,
            unit="px",
        )
    )
    axial_shifts_um = (0.0,) if mono else (ca.axial_focus_shift_r_um, 0.0, ca.axial_focus_shift_b_um)
    axial_px = tuple(abs(shift) / f_number / sensor.pixel_pitch_um for shift in axial_shifts_um)
    decisions.append(
        _decision(
            "optics.axial_ca",
            max(axial_px) > blur_max and needs_image,
            force and needs_image and not mono,
            "monochrome sensor"
            if mono
            else f"per-channel blur discs {axial_px[0]:.3g}, {axial_px[2]:.3g} px (red, blue) at N = {f_number:.3g}",
            effect=max(axial_px),
            threshold=blur_max,
            unit="px",
        )
    )
    times = np.arange(scene.frame_count) / scene.fps
    motion_px = _actor_motion_px(scene.actors, times, exposure_longest_s, T, K, W, H, file_bounds)
    decisions.append(
        _decision(
            "optics.motion_blur",
            motion_px > blur_max and needs_image,
            force and needs_image,
            f"largest actor motion {motion_px:.3g} px during a {exposure_longest_s:.3g} s exposure "
            f"({'manual' if exposure.mode == 'manual' else 'longest auto-exposure'}); the camera is static",
            effect=motion_px,
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
    if include["optics.diffraction"]:
        blur_radius = max(blur_radius, 4 * airy_sigma_um(f_number, max(CHANNEL_WAVELENGTHS_UM)) / sensor.pixel_pitch_um)
    if include["optics.axial_ca"]:
        blur_radius = max(blur_radius, max(axial_px) / 2)
    if include["optics.motion_blur"]:
        blur_radius = max(blur_radius, motion_px)
    margin = tuple(math.ceil(x + blur_radius) for x in (left, top, right, bottom))

    # --- passes -------------------------------------------------------------------------------------
    passes: list[str] = []
    if needs_image:
        passes.append("radiance")
        decisions.append(Decision(stage="pass.radiance", included=True, reason="video, frames or raw output"))
    else:
        decisions.append(Decision(stage="pass.radiance", included=False, reason="no image output requested"))
    depth_consumers = [
        name
        for name, use in (
            ("depth of field", include["optics.depth_of_field"]),
            ("depth output", outputs.depth is not None),
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
            else "no depth of field and no depth output",
        )
    )
    if depth_needed:
        passes.append("depth_m")
    decisions.append(
        Decision(
            stage="pass.instance_id",
            included=annotations,
            reason=f"annotations requested: {', '.join(outputs.annotations)}"
            if annotations
            else "no annotations requested",
        )
    )
    if annotations:
        passes.append("instance_id")
    static = True  # camera poses are constant until PTZ programs exist (motion issue)
    shadow_lights = scene.environment.shadows and any(light.type in ("sun", "spot") for light in scene.lights)
    static_background = static and bool(scene.actors) and needs_image and not shadow_lights
    if static_background:
        static_reason = "camera and environment are static; actors are composited per frame"
    elif not scene.actors:
        static_reason = "no actors: the environment alone is drawn each frame"
    elif not needs_image:
        static_reason = "no image output (the geometric passes alone are cheap)"
    else:
        static_reason = "actors cast shadows on the environment (environment.shadows), so every frame is drawn in full"
    decisions.append(Decision(stage="render.static_background", included=static_background, reason=static_reason))

    stages.append(
        Stage(
            name="render",
            passes=tuple(passes),
            params={"supersampling": settings.supersampling, "static_background": static_background},
        )
    )
    # Blur stages run on the margin-rendered pinhole image, before the remap (see `camgen.plan.optics`).
    blur_stages = (
        (
            "optics.motion_blur",
            {
                "displacement_max_px": motion_px,
                "exposure_longest_s": exposure_longest_s,
                "sample_step_px": MOTION_SAMPLE_STEP_PX,
                "samples_max": MOTION_SAMPLES_MAX,
                "threshold_px": blur_max,
            },
        ),
        (
            "optics.depth_of_field",
            {
                "focus_distance_m": focus_m,
                "coc_max_px": coc_px,
                "step_px": settings.dof_step_px,
                "step_rel": settings.dof_step_rel,
            },
        ),
        ("optics.axial_ca", {"focus_shift_um": list(axial_shifts_um)}),
        ("optics.diffraction", {"airy_diameter_px": airy_px}),
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
    if needs_isp and outputs.video:
        stages.append(Stage(name="io.video", params={"codec": profile.codec.name}))
    if outputs.frames is not None:
        stages.append(Stage(name="io.frames", params={"format": outputs.frames}))
    if annotations:
        stages.append(Stage(name="annotate", passes=("instance_id",), params={"formats": list(outputs.annotations)}))
    if outputs.depth is not None:
        stages.append(Stage(name="io.depth", passes=("depth_m",), params={"format": outputs.depth}))
    if outputs.camera_metadata:
        stages.append(Stage(name="io.camera_metadata"))

    applied_dist = tuple(float(x) for x in (dist if include["optics.distortion"] else np.zeros(8)))
    state = dict(
        pan_deg=pan,
        tilt_deg=tilt,
        zoom_x=zoom_x,
        focal_length_mm=focal_length_mm,
        f_number=f_number,
        focus_distance_m=focus_m,
        exposure_time_s=exposure.exposure_time_s,
        gain_db=exposure.gain_db,
        K_px=tuple(map(tuple, K.tolist())),
        distortion=applied_dist,
        T_world_from_cam=tuple(map(tuple, T.tolist())),
    )
    states = tuple(CameraState(frame=i, time_s=float(t), **state) for i, t in enumerate(times))
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
        render=render,
        stages=tuple(stages),
        decisions=tuple(decisions),
        states=states,
    )


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
    if not needs_isp:
        decisions.append(Decision(stage="isp", included=False, reason="only raw output requested"))
        return
    wb = isp.white_balance
    isp_steps = [
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
    for name, on, reason, params in isp_steps:
        applicable = not (mono and name in ("isp.demosaic", "isp.white_balance", "isp.ccm"))
        decision = _decision(name, on, force and applicable, reason)
        decisions.append(decision)
        if decision.included:
            stages.append(Stage(name=name, params=params))


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
    static_boxes = [
        box_corners(*local_bounds(mesh, file_bounds), _placement(mesh)) for mesh in scene.environment.meshes
    ]
    actor_boxes = [box for actor in scene.actors for box in _actor_swept_boxes(actor, file_bounds, scene.duration_s)]
    cameras = tuple(
        _compile_camera(
            scene,
            i,
            camera,
            profiles[camera.name],
            (profile_names or {}).get(camera.name, camera.profile),
            settings,
            static_boxes,
            actor_boxes,
            file_bounds,
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


def compile_scene(loaded: LoadedScene, settings: PlanSettings | None = None) -> Job:
    """Compile a scene as returned by `camgen.config.load_scene`."""
    return compile(
        loaded.scene,
        loaded.profile_models,
        scene_name=loaded.name,
        profile_names=loaded.profile_names,
        settings=settings,
        file_bounds=loaded.file_bounds,
    )
