"""Snow over a rendered frame (`camgen.world.snow`): the haze of the far flakes, then the short streaks of
the near ones in the frame's exposure, depth-tested against the surfaces, lit by the sky, the ground, the
sun, the scene's lamps and, in night mode, the camera's own IR illuminator.

The drawing is rain's (`camgen.world.rain.streak_layers`, the frame's exposure as `camgen.render.rain`
spans it) with two of its options: a flake's footprint is spread by its own image and by the lens's defocus
(flakes near the lens are large, soft discs, as a drop imaged that wide would be, which rain leaves out),
and each flake carries its own radiance in the lamps' and the illuminator's light (I/d²: the flakes in a
lantern's beam glitter, those near an IR camera's lens glow). The faintest flakes (`FLAKE_AREA_MIN_PX2`)
are drawn as their mean, a veil (`left_out_flakes`).

The haze is the snow's visual range (Rasmussen et al. 1999) over each pixel's distance beyond
`STREAK_RANGE_M`, by Koschmieder's law (`camgen.world.fog`), the far ground's distance where no mesh is hit.
A scene that sets `environment.fog` gives the visibility it sees in the snow: no snow haze is added to it
(a reported visibility in snowfall is the snow's and the air's together).

Defocus: a point z metres away, focused at s, is blurred over a circle of A·f·|1/z − 1/s| pixels (A = f/N
the aperture's diameter); a flake's footprint is a Gaussian of σ = √(image² + circle²)/4 (a disc of
diameter D has σ = D/4 along each axis). The optics' depth of field, when planned, then blurs the frame by
each pixel's surface depth, not the flake's (a flake near the lens is blurred by this module only).
"""

from __future__ import annotations

import itertools
import math

import cv2
import numpy as np

from camgen.render.gl import pyrender
from camgen.render.renderer import View, far_ground_depth_m, frustum_corners_m, horizon_airlight, ray_lengths
from camgen.render.scene_graph import relative_intensity
from camgen.world.fog import apply_fog
from camgen.world.night import SPOT_FULL_INTENSITY_FRACTION, nir_equivalent_intensity_cd
from camgen.world.rain import NEAR_M, STREAK_RANGE_M, streak_layers
from camgen.world.snow import (
    flake_classes,
    flake_radiance,
    flakes_in_box,
    illuminated_flake_radiance,
    snow_visibility_m,
    wind_drift_m_s,
)

FLAKE_AREA_MIN_PX2 = 0.04
"""A class of flakes is drawn out to where its flakes image at this many px², at most STREAK_RANGE_M (at full
contrast 10 steps of 8 bits in one pixel, spread over a streak of a few: one or two each, under a sensor's
noise); from there to STREAK_RANGE_M its flakes are drawn as their mean, a veil (`left_out_flakes`), and
beyond as the haze. In the snowy street's frame (f = 1034 px) the smallest three of 14 classes stop at 5.4,
8.9 and 13 m; drawing every class to 15 m instead cost 1.8 s of CPU a frame against 1.1 s (the rainy
street's: 1.1 s, A/B in turn, load 5)."""


def flake_ranges_m(snow, f_px: float) -> np.ndarray:
    """(C,) the distance out to which each class of `flake_classes` is drawn, m: where a flake of the class's
    diameter D images at FLAKE_AREA_MIN_PX2, π/4 (D f / r)² = A, at most STREAK_RANGE_M."""
    diameters_mm = flake_classes(snow.rate_mm_h, snow.kind)[0]
    return np.minimum(diameters_mm * 1e-3 * f_px * math.sqrt(math.pi / 4 / FLAKE_AREA_MIN_PX2), STREAK_RANGE_M)


FLAKE_IMAGE_MAX_PX = 256.0
"""Flakes are drawn however wide they image (within NEAR_M of the lens they are left out, as drops are)."""


def snow_layers(
    view: View,
    depth_m: np.ndarray,
    state,
    snow,
    wind=None,
    ground_m: float = -np.inf,
    illuminator_cd: float | None = None,
    illuminator_half_angle_rad: float = math.radians(40.0),
    lamps=None,
) -> tuple[np.ndarray, np.ndarray | None]:
    """(α, Σ α·L_own): the flakes' coverage (H, W) within each class's range of the view's camera
    (`flake_ranges_m`, at most STREAK_RANGE_M) at the state's time, each falling over its exposure and
    drifting in `wind`, and, with an IR illuminator of `illuminator_cd` (the renderer's candela for its
    850 nm light) at the lens, the flakes' radiance in its beam summed by coverage, (H, W), and with `lamps`
    (world points (N, 3) → a flake's radiance there in the scene's lamps (N, 3): `lamp_flake_radiance`) their
    light too, (H, W, 3); None with neither.
    `state`: a `CameraState` (time_s, exposure_time_s, focal_length_mm, f_number, focus_distance_m);
    `snow`: a `camgen.config.scene.Snow`."""
    drift = wind_drift_m_s(wind)
    K = view.K_px
    f_px = math.sqrt(abs(K[0, 0] * K[1, 1]))
    ranges_m = flake_ranges_m(snow, f_px)
    diameters, _, speeds = flake_classes(snow.rate_mm_h, snow.kind)
    aperture_m = state.focal_length_mm * 1e-3 / state.f_number
    # How far past the frame's edge a flake's half streak and its footprint's 3σ reach, at most, m.
    reach_m = state.exposure_time_s / 2 * math.hypot(*drift, float(speeds.max()))
    reach_m += 0.75 * (float(diameters.max()) * 1e-3 + aperture_m * max(1.0, STREAK_RANGE_M / state.focus_distance_m))
    tan_x = max(abs(-0.5 - K[0, 2]), abs(view.width_px - 0.5 - K[0, 2])) / K[0, 0]
    tan_y = max(abs(-0.5 - K[1, 2]), abs(view.height_px - 0.5 - K[1, 2])) / K[1, 1]
    T = view.T_world_from_cam
    R = T[:3, :3]
    found = []
    for c, range_m in enumerate(ranges_m):
        if range_m <= NEAR_M:
            continue
        corners = frustum_corners_m(view, NEAR_M, range_m)
        low_m, high_m = corners.min(axis=0), corners.max(axis=0)
        low_m[2] = max(low_m[2], ground_m)
        if low_m[2] < high_m[2]:
            planes = _frustum_planes(T, tan_x, tan_y, reach_m, NEAR_M, range_m)
            flakes = flakes_in_box(
                low_m, high_m, state.time_s, snow.rate_mm_h, snow.seed, snow.kind, drift, [c], planes
            )
            found.append((*flakes, np.full(len(flakes[0]), range_m)))
    if not found:
        return np.zeros(depth_m.shape, np.float32), None
    positions, diameters_mm, speeds_m_s, range_m = (np.concatenate(parts) for parts in zip(*found, strict=True))
    offset = positions - T[:3, 3]
    # p_cam = Rᵀ (p − c), column by column (as `camgen.render.rain`).
    x, y, z = (offset[:, 0] * R[0, i] + offset[:, 1] * R[1, i] + offset[:, 2] * R[2, i] for i in range(3))
    keep = (z > NEAR_M) & (x * x + y * y + z * z <= range_m * range_m)
    keep &= (np.abs(x) <= z * tan_x + reach_m) & (np.abs(y) <= z * tan_y + reach_m)
    positions_cam = np.column_stack([x[keep], y[keep], z[keep]])
    diameters_mm, speeds_m_s, positions = diameters_mm[keep], speeds_m_s[keep], positions[keep]
    # Each flake's displacement over the exposure, (u, w, −v)·T in the world, in the camera frame.
    T_s = state.exposure_time_s
    fall_cam = np.outer(-speeds_m_s * T_s, R[2]) + (drift[0] * R[0] + drift[1] * R[1]) * T_s
    z = positions_cam[:, 2]
    circle_px = aperture_m * f_px * np.abs(1.0 / z - 1.0 / state.focus_distance_m)
    spread_px = np.hypot(diameters_mm * 1e-3 * f_px / z, circle_px) / 4
    values = None
    if illuminator_cd is not None:
        distance_m = np.sqrt(np.einsum("ij,ij->i", positions_cam, positions_cam))
        cos_angle = positions_cam[:, 2] / np.maximum(distance_m, 1e-9)
        outer = math.cos(illuminator_half_angle_rad)
        inner = math.cos(SPOT_FULL_INTENSITY_FRACTION * illuminator_half_angle_rad)
        beam = np.clip((cos_angle - outer) / (inner - outer), 0.0, 1.0) ** 2  # pyrender's spot falloff
        values = illuminated_flake_radiance(illuminator_cd * beam / np.maximum(distance_m, NEAR_M) ** 2)
    if lamps is not None:
        lit = lamps(positions)
        values = lit if values is None else lit + values[:, None]
    return streak_layers(
        positions_cam,
        diameters_mm,
        fall_cam,
        view.K_px,
        depth_m,
        image_max_px=FLAKE_IMAGE_MAX_PX,
        spread_px=spread_px,
        values=values,
    )


def left_out_flakes(
    view: View,
    distance_m: np.ndarray,
    snow,
    illuminator_cd: float | None = None,
    illuminator_half_angle_rad: float = math.radians(40.0),
    lamps=None,
) -> tuple[np.ndarray, np.ndarray | None]:
    """(T, L_own): the flakes `snow_layers` leaves out (each class beyond its `flake_ranges_m`, out to
    STREAK_RANGE_M) as their mean over each pixel's ray, `distance_m` long (+inf for the sky): they cover
    1 − T of it, T = exp(−Σ_c n_c (π/4) D_c² ℓ_c) with ℓ_c the ray's length between the class's range and
    min(distance, STREAK_RANGE_M) (the coverage a drawn flake carries, per metre), so the frame's mean
    brightening by the snow does not depend on how many flakes are drawn; with an illuminator, the light they
    send back, Σ_c n_c (π/4) D_c² ∫ (2/3) ω I b(θ)/(π z²) dz along that stretch (thin: no dimming within it),
    (H, W); with `lamps` (as `snow_layers`') their light too, summed at LAMP_VEIL_SAMPLES points along the rays
    of every LAMP_VEIL_STEP_PX-th pixel each way and interpolated, (H, W, 3); else None."""
    f_px = math.sqrt(abs(view.K_px[0, 0] * view.K_px[1, 1]))
    ranges_m = flake_ranges_m(snow, f_px)
    diameters_mm, densities, _ = flake_classes(snow.rate_mm_h, snow.kind)
    coverage_per_m = densities * math.pi / 4 * (diameters_mm * 1e-3) ** 2
    reach_m = np.minimum(distance_m, np.float32(STREAK_RANGE_M))
    depth = np.zeros(distance_m.shape, np.float32)
    inverse = np.zeros(distance_m.shape, np.float32) if illuminator_cd is not None else None
    for range_m, per_m in zip(ranges_m, coverage_per_m, strict=True):
        if range_m >= STREAK_RANGE_M:
            continue
        depth += np.float32(per_m) * np.maximum(reach_m - np.float32(range_m), 0.0)
        if inverse is not None:  # ∫ dz / z² from the range to the ray's end within STREAK_RANGE_M
            inverse += np.float32(per_m) * np.maximum(1 / np.float32(range_m) - 1 / np.maximum(reach_m, range_m), 0.0)
    glow = None
    if inverse is not None:
        cos_angle = 1.0 / ray_lengths(view)
        outer = math.cos(illuminator_half_angle_rad)
        inner = math.cos(SPOT_FULL_INTENSITY_FRACTION * illuminator_half_angle_rad)
        beam = np.clip((cos_angle - outer) / (inner - outer), 0.0, 1.0) ** 2
        glow = (illuminated_flake_radiance(illuminator_cd * beam) * inverse).astype(np.float32)
    if lamps is not None and np.any(ranges_m < STREAK_RANGE_M):
        lit = _lamp_veil(view, reach_m, ranges_m, coverage_per_m, lamps)
        glow = lit if glow is None else lit + glow[..., None]
    return np.exp(-depth), glow


LAMP_VEIL_STEP_PX = 8
LAMP_VEIL_SAMPLES = 8
"""The lamps' light on the flakes left out (`left_out_flakes`) is summed at this many points along the rays of
every LAMP_VEIL_STEP_PX-th pixel each way (a lamp's light varies over metres, not pixels)."""


def _lamp_veil(view: View, reach_m: np.ndarray, ranges_m, coverage_per_m, lamps) -> np.ndarray:
    """(H, W, 3) Σ_c n_c (π/4) D_c² ∫ L_lamps(z) dz from each class's range to the ray's end within
    STREAK_RANGE_M (`reach_m`, (H, W)), by the midpoint rule on LAMP_VEIL_SAMPLES stretches, evaluated at
    every LAMP_VEIL_STEP_PX-th pixel and interpolated between."""
    height_px, width_px = reach_m.shape
    step = LAMP_VEIL_STEP_PX
    v, u = np.mgrid[step // 2 : height_px : step, step // 2 : width_px : step].astype(np.float64)
    rays = np.stack([u, v, np.ones_like(u)], axis=-1) @ np.linalg.inv(view.K_px).T
    rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
    T = view.T_world_from_cam
    directions = rays.reshape(-1, 3) @ T[:3, :3].T
    reach = reach_m[step // 2 :: step, step // 2 :: step].reshape(-1)
    edges = np.linspace(float(np.min(ranges_m)), STREAK_RANGE_M, LAMP_VEIL_SAMPLES + 1)
    coarse = np.zeros((len(reach), 3))
    for near_m, far_m in itertools.pairwise(edges):
        middle_m = 0.5 * (near_m + far_m)
        per_m = float(np.sum(np.asarray(coverage_per_m)[np.asarray(ranges_m) < middle_m]))
        seen = reach >= middle_m
        if per_m > 0 and seen.any():
            coarse[seen] += per_m * (far_m - near_m) * lamps(T[:3, 3] + directions[seen] * middle_m)
    coarse = coarse.reshape((*v.shape, 3)).astype(np.float32)
    return cv2.resize(coarse, (width_px, height_px), interpolation=cv2.INTER_LINEAR)


def lamp_illuminance_lx(graph, points_m: np.ndarray) -> np.ndarray:
    """(N, 3) the illuminance the graph's point, spot and lamp lights give points (N, 3) in the world, from
    each light's direction, lux per colour channel: I(θ)/d² times its colour, I(θ) as the lit shader takes it
    (`camgen.render.scene_graph.relative_intensity`: a spot's cone or an IES lamp's table), no shadows. The
    sun is `environment_flake_radiance`'s."""
    points_m = np.asarray(points_m, np.float64)
    total = np.zeros((len(points_m), 3))
    for node in graph.scene.light_nodes:
        light = node.light
        if not isinstance(light, pyrender.PointLight | pyrender.SpotLight):
            continue
        pose = graph.scene.get_pose(node)
        offset = points_m - pose[:3, 3]
        distance2 = np.maximum(np.einsum("ij,ij->i", offset, offset), NEAR_M**2)
        factor = relative_intensity(light, pose, offset / np.sqrt(distance2)[:, None])
        total += (light.intensity * factor / distance2)[:, None] * np.asarray(light.color, np.float64)
    return total


def lamp_flake_radiance(graph):
    """world points (N, 3) → (N, 3) a flake's radiance there in the graph's lamps, ω E/(4π)
    (`camgen.world.snow.flake_radiance`, `lamp_illuminance_lx`); None for a graph without such lights."""
    if not any(isinstance(node.light, pyrender.PointLight | pyrender.SpotLight) for node in graph.scene.light_nodes):
        return None
    return lambda points_m: flake_radiance(0.0, 0.0, lamp_illuminance_lx(graph, points_m))


def _frustum_planes(
    T_world_from_cam: np.ndarray, tan_x: float, tan_y: float, reach_m: float, near_m: float, far_m: float
) -> np.ndarray:
    """(6, 4) half-spaces n·p + d ≥ 0 in the world around a view's frustum: |x| ≤ z tan_x + reach,
    |y| ≤ z tan_y + reach, near ≤ z ≤ far in its camera frame (p_cam = Rᵀ (p − c))."""
    in_camera = np.array(
        [
            [-1.0, 0.0, tan_x, reach_m],
            [1.0, 0.0, tan_x, reach_m],
            [0.0, -1.0, tan_y, reach_m],
            [0.0, 1.0, tan_y, reach_m],
            [0.0, 0.0, 1.0, -near_m],
            [0.0, 0.0, -1.0, far_m],
        ]
    )
    R, centre = T_world_from_cam[:3, :3], T_world_from_cam[:3, 3]
    normals = in_camera[:, :3] @ R.T  # n_world = R n_cam
    return np.column_stack([normals, in_camera[:, 3] - normals @ centre])


def environment_flake_radiance(graph, radiance: np.ndarray, depth_m: np.ndarray) -> np.ndarray:
    """(3,) a flake's radiance in the graph's daylight (`camgen.world.snow.flake_radiance`): the sky's radiance
    is the ambient light's (E/π, what lights every diffuse surface); the ground's is the far ground's
    reflectance (the scene's ground plane's mean, `camgen.render.scene_graph.FarGround`) under that sky and
    the sun, ρ (π L_sky + E_sun sin(elevation))/π, the same whichever way the camera looks (lamps light the
    flakes directly: `lamp_flake_radiance`; their pools on the ground are not counted); without a ground
    plane, the mean of the frame's surfaces (every 4th pixel each way; the sky's where the frame shows none);
    the sun's illuminance is each directional light's."""
    sky = np.asarray(graph.scene.ambient_light, np.float64)
    sun, on_ground = np.zeros(3), np.zeros(3)
    for node in graph.scene.light_nodes:
        if isinstance(node.light, pyrender.DirectionalLight):
            illuminance = node.light.intensity * np.asarray(node.light.color, np.float64)
            sun += illuminance
            on_ground += illuminance * max(float(graph.scene.get_pose(node)[2, 2]), 0.0)  # towards it: +z axis
    far_ground = getattr(graph, "far_ground", None)
    if far_ground is not None:
        ground = np.asarray(far_ground.reflectance_rgb, np.float64) * (sky + on_ground / math.pi)
    else:
        surfaces = np.isfinite(depth_m[::4, ::4])
        ground = radiance[::4, ::4][surfaces].mean(axis=0, dtype=np.float64) if surfaces.any() else sky
    return flake_radiance(sky, ground, sun)


def snowy_radiance(graph, view: View, radiance: np.ndarray, depth_m: np.ndarray, state, profile=None) -> np.ndarray:
    """`radiance` (H, W, 3) of `view` in the snow of the graph's scene (`graph.source`): Koschmieder haze of
    the snow's visual range beyond STREAK_RANGE_M unless the scene sets its own fog, then the near flakes left
    out as their mean (`left_out_flakes`: T, L_veil), then the drawn ones, (1 − α)·L' + α L_flake + Σ α_i L_IR,i
    with L' = T·L + (1 − T)·L_flake + L_veil (the IR terms in night mode with the `profile`'s illuminator)."""
    if depth_m is None:
        raise ValueError("snow needs the depth pass, which the plan did not draw")
    environment = graph.source[0].environment
    snow = environment.snow
    if getattr(graph, "far_ground", None) is not None:  # the ground beyond the meshes is at a finite distance
        depth_m = np.where(np.isinf(depth_m), far_ground_depth_m(graph.far_ground, view), depth_m)
    distance_m = depth_m * ray_lengths(view)
    airlight = horizon_airlight(graph, view)
    if environment.fog is None:
        beyond_m = np.maximum(distance_m - np.float32(STREAK_RANGE_M), 0.0)
        radiance = apply_fog(radiance, beyond_m, airlight, snow_visibility_m(snow.rate_mm_h, snow.kind))
    illuminator_cd, half_angle_rad = None, math.radians(40.0)
    night = None if profile is None else profile.night_mode
    if state.night_mode and night is not None and night.ir_illuminator is not None:
        illuminator = night.ir_illuminator
        illuminator_cd = nir_equivalent_intensity_cd(illuminator.radiant_intensity_mw_sr, profile.sensor.qe_850nm_rel)
        half_angle_rad = math.radians(illuminator.half_angle_deg)
    flake = environment_flake_radiance(graph, radiance, depth_m)
    lamps = lamp_flake_radiance(graph)
    transmittance, glow = left_out_flakes(view, distance_m, snow, illuminator_cd, half_angle_rad, lamps)
    ground_m = float(graph.scene.bounds[0][2]) if graph.scene.mesh_nodes else -np.inf
    coverage, lit = snow_layers(
        view, depth_m, state, snow, environment.wind, ground_m, illuminator_cd, half_angle_rad, lamps
    )
    # The veil, then the drawn flakes over it: F + (L − F)·T, then (1 − α)·that + α·F = F + (L − F)·T·(1 − α).
    seen = transmittance
    seen *= 1.0 - coverage
    out = np.subtract(radiance, flake, dtype=np.float32)
    out *= seen[..., None]
    out += flake
    if glow is not None:  # the veil's own light, behind the drawn flakes too
        glow = glow * (1.0 - coverage if glow.ndim == 2 else (1.0 - coverage)[..., None])
        out += glow if glow.ndim == 3 else glow[..., None]
    if lit is not None:
        out += lit if lit.ndim == 3 else lit[..., None]
    return out
