"""Derived figures of a profile, for people choosing or checking a camera (`camgen info`)."""

from __future__ import annotations

from dataclasses import dataclass

from camgen.config.profile import Profile
from camgen.optics.intrinsics import angular_fov_deg, focal_length_px, hyperfocal_distance_m
from camgen.sensor.characteristics import (
    dark_current_e_per_s,
    dynamic_range_db,
    saturation_e,
    temporal_dark_noise_e,
)

ZOOM_STEPS_X = (1, 2, 3, 5, 10, 15, 20, 30, 40)


@dataclass(frozen=True)
class ZoomStep:
    zoom_x: float
    focal_length_mm: float
    fx_px: float
    fy_px: float
    hfov_deg: float
    vfov_deg: float
    dfov_deg: float
    f_number: float
    hyperfocal_m: float


@dataclass(frozen=True)
class ProfileInfo:
    sensor_width_mm: float
    sensor_height_mm: float
    sensor_diagonal_mm: float
    pixel_area_um2: float
    saturation_e: float
    saturation_limit: str
    dark_current_e_per_s: float
    dark_noise_e: float
    dynamic_range_db: float
    dynamic_range_exposure_s: float
    coc_um: float
    zoom_steps: tuple[ZoomStep, ...]


def profile_info(profile: Profile) -> ProfileInfo:
    """Sensor size, saturation, DR (at 0 dB and the longest exposure), and optics per zoom step."""
    sensor, lens, noise = profile.sensor, profile.lens, profile.sensor.noise
    width_mm, height_mm = sensor.width_mm, sensor.height_mm
    diagonal_mm = (width_mm**2 + height_mm**2) ** 0.5
    sat_e, limit = saturation_e(
        sensor.full_well_e, sensor.conversion_gain_dn_per_e, sensor.black_level_dn, sensor.bit_depth
    )
    dark = dark_current_e_per_s(
        noise.dark_current_e_per_s, sensor.temperature_c, noise.dark_current_reference_c, noise.dark_current_doubling_c
    )
    exposure_s = profile.exposure.exposure_time_max_s
    sigma_d = temporal_dark_noise_e(noise.read_noise_e, dark, exposure_s, sensor.conversion_gain_dn_per_e)
    zooms = sorted({z for z in ZOOM_STEPS_X if z < lens.zoom_max_x} | {lens.zoom_max_x})
    steps = []
    for zoom in zooms:
        f_mm = lens.focal_length_min_mm * zoom
        f_number, _ = lens.at_focal_length(f_mm)
        steps.append(
            ZoomStep(
                zoom_x=zoom,
                focal_length_mm=f_mm,
                fx_px=focal_length_px(f_mm, sensor.pixel_pitch_um),
                fy_px=focal_length_px(f_mm, sensor.pitch_y_um),
                hfov_deg=angular_fov_deg(width_mm, f_mm),
                vfov_deg=angular_fov_deg(height_mm, f_mm),
                dfov_deg=angular_fov_deg(diagonal_mm, f_mm),
                f_number=f_number,
                hyperfocal_m=hyperfocal_distance_m(f_mm, f_number, profile.coc_mm),
            )
        )
    return ProfileInfo(
        sensor_width_mm=width_mm,
        sensor_height_mm=height_mm,
        sensor_diagonal_mm=diagonal_mm,
        pixel_area_um2=sensor.pixel_pitch_um * sensor.pitch_y_um,
        saturation_e=sat_e,
        saturation_limit=limit,
        dark_current_e_per_s=dark,
        dark_noise_e=sigma_d,
        dynamic_range_db=dynamic_range_db(sat_e, sigma_d),
        dynamic_range_exposure_s=exposure_s,
        coc_um=profile.coc_mm * 1e3,
        zoom_steps=tuple(steps),
    )
