"""Every kind of bad input gets its own clear error: file:line:column, key path, value, what is allowed.

Each case edits a valid file; the line expected in the error is the one marked ``#<``.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from camgen.cli.main import main
from camgen.config import load_dataset, load_profile, load_scene
from camgen.errors import ConfigError
from tests.conftest import FIXED_PROFILE, PTZ_PROFILE, SCENE, write


def edit(base: str, old: str, new: str) -> str:
    assert old in base, f"test setup: {old!r} not in the base file"
    return base.replace(old, new, 1)


RIDER_PATH = "    class: person\n    path:\n      waypoints_m: [[-3, 5], [3, 5]]\n      speed_m_s: 1.4\n"
"""The test scene's walker's class and path (a rider has no path of its own)."""
RIDER = "  - name: {name}\n    class: person\n    rides: {rides} #<\ncameras:\n"
"""A rider added after the test scene's actors (replacing its "cameras:" line)."""

# (id, kind, file text, expected key path, expected message fragment)
CASES = [
    (
        "negative_focal_length",
        "profile",
        edit(FIXED_PROFILE, "focal_length_mm: 4.0", "focal_length_mm: -4.0 #<"),
        "lens.focal_length_mm",
        "must be ≥ 0.5, got -4; real lenses span 0.5–2000 mm",
    ),
    (
        "wrong_type_width",
        "profile",
        edit(FIXED_PROFILE, "width_px: 640", "width_px: wide #<"),
        "sensor.width_px",
        "must be a number, got 'wide'",
    ),
    (
        "fractional_width",
        "profile",
        edit(FIXED_PROFILE, "width_px: 640", "width_px: 640.5 #<"),
        "sensor.width_px",
        "must be a whole number, got 640.5",
    ),
    (
        "unknown_key_typo",
        "profile",
        edit(FIXED_PROFILE, "pixel_pitch_um: 3.0", "pixel_pich_um: 3.0 #<"),
        "sensor.pixel_pich_um",
        "is not a known key; did you mean 'pixel_pitch_um'?",
    ),
    (
        "missing_required",
        "profile",
        edit(FIXED_PROFILE, "  full_well_e: 10000\n", ""),
        "sensor.full_well_e",
        "is required",
    ),
    (
        "unordered_zoom_range",
        "profile",
        edit(PTZ_PROFILE, "focal_length_range_mm: [4.0, 40.0]", "focal_length_range_mm: [40.0, 4.0] #<"),
        "lens.focal_length_range_mm",
        "must be ordered [wide, tele] with wide ≤ tele, got [40, 4]",
    ),
    (
        "f_number_too_small",
        "profile",
        edit(FIXED_PROFILE, "f_number: 2.0", "f_number: 0.3 #<"),
        "lens.f_number",
        "must be ≥ 0.5, got 0.3",
    ),
    (
        "focus_closer_than_lens",
        "profile",
        edit(FIXED_PROFILE, "f_number: 2.0", "f_number: 2.0\n  focus_distance_m: 0.1 #<"),
        "lens.focus_distance_m",
        "must be ≥ min_focus_distance_m (0.3 m), got 0.1",
    ),
    (
        "folding_distortion",
        "profile",
        edit(FIXED_PROFILE, "f_number: 2.0", "f_number: 2.0\n  distortion: {k1: -4.0} #<"),
        "lens.distortion",
        "folds over inside the image",
    ),
    (
        "tangential_distortion_folds",
        "profile",
        edit(FIXED_PROFILE, "f_number: 2.0", "f_number: 2.0\n  distortion: {p2: 0.4} #<"),
        "lens.distortion",
        "cannot be inverted everywhere inside the image",
    ),
    (
        "vignetting_polynomial_brightens",
        "profile",
        edit(FIXED_PROFILE, "f_number: 2.0", "f_number: 2.0\n  vignetting: {polynomial: [0.3, 0, 0]} #<"),
        "lens.vignetting.polynomial",
        "must give a relative illumination in (0, 1] from centre to corner, got 1.3",
    ),
    (
        "vignetting_two_sources",
        "profile",
        edit(
            FIXED_PROFILE,
            "f_number: 2.0",
            "f_number: 2.0\n  vignetting: {relative_illumination_corner: 0.6, polynomial: [-0.4, 0, 0]} #<",
        ),
        "lens.vignetting.polynomial",
        "one source, not two",
    ),
    (
        "vignetting_gone_before_wide_open",
        "profile",
        edit(FIXED_PROFILE, "f_number: 2.0", "f_number: 2.0\n  vignetting: {full_illumination_f_number: 1.4} #<"),
        "lens.vignetting.full_illumination_f_number",
        "must be above the wide-open f_number (2)",
    ),
    (
        "stretch_output_range_reversed",
        "profile",
        FIXED_PROFILE + "isp:\n  contrast_stretch: {output_range_frac: [0.9, 0.1]} #<\n",
        "isp.contrast_stretch.output_range_frac",
        "must be [low, high] with low < high, got [0.9, 0.1]",
    ),
    (
        "stretch_gain_below_one",
        "profile",
        FIXED_PROFILE + "isp:\n  contrast_stretch: {max_gain: 0.5} #<\n",
        "isp.contrast_stretch.max_gain",
        "must be ≥ 1, got 0.5",
    ),
    (
        "ccm_row_not_white_preserving",
        "profile",
        FIXED_PROFILE + "isp:\n  ccm: [[1.5, -0.3, -0.1], [0, 1, 0], [0, 0, 1]] #<\n",
        "isp.ccm[0]",
        "must sum to 1 so that a grey stays grey",
    ),
    (
        "codec_preset_unknown",
        "profile",
        FIXED_PROFILE + "codec: {preset: turbo} #<\n",
        "codec.preset",
        "'veryfast'",
    ),
    (
        "axial_ca_shift_too_large",
        "profile",
        edit(FIXED_PROFILE, "f_number: 2.0", "f_number: 2.0\n  chromatic_aberration: {axial_focus_shift_r_um: 900} #<"),
        "lens.chromatic_aberration.axial_focus_shift_r_um",
        "must be ≤ 500, got 900",
    ),
    (
        "focal_length_twice",
        "profile",
        edit(FIXED_PROFILE, "focal_length_mm: 4.0", "focal_length_mm: 4.0 #<\n  focal_length_range_mm: [4, 8]"),
        "lens.focal_length_mm",
        "exactly one of the two, got both",
    ),
    (
        "cfa_typo",
        "profile",
        edit(FIXED_PROFILE, "cfa: RGGB", "cfa: RGBG #<"),
        "sensor.cfa",
        "must be one of 'RGGB', 'BGGR', 'GRBG', 'GBRG' or 'mono', got 'RGBG'",
    ),
    (
        "bit_depth_too_large",
        "profile",
        edit(FIXED_PROFILE, "bit_depth: 12", "bit_depth: 20 #<"),
        "sensor.bit_depth",
        "must be ≤ 16, got 20",
    ),
    (
        "black_above_white",
        "profile",
        edit(FIXED_PROFILE, "black_level_dn: 64", "black_level_dn: 5000 #<"),
        "sensor.black_level_dn",
        "must be below the white level 4095 DN",
    ),
    (
        "nan_full_well",
        "profile",
        edit(FIXED_PROFILE, "full_well_e: 10000", "full_well_e: .nan #<"),
        "sensor.full_well_e",
        "must be a finite number, got nan",
    ),
    (
        "zoom_table_outside_range",
        "profile",
        edit(PTZ_PROFILE, "f_number: 1.6", "f_number: 1.6\n  zoom_table:\n    - {focal_length_mm: 50, f_number: 4} #<"),
        "lens.zoom_table[0].focal_length_mm",
        "must lie in the lens range [4, 40] mm, got 50",
    ),
    (
        "zoom_table_not_increasing",
        "profile",
        edit(
            PTZ_PROFILE,
            "f_number: 1.6",
            "f_number: 1.6\n  zoom_table:\n    - {focal_length_mm: 20, f_number: 2}\n"
            "    - {focal_length_mm: 10, f_number: 3} #<",
        ),
        "lens.zoom_table[1].focal_length_mm",
        "must increase along the table (previous 20 mm), got 10",
    ),
    (
        "exposure_limits_reversed",
        "profile",
        FIXED_PROFILE + "exposure:\n  exposure_time_min_s: 0.1 #<\n  exposure_time_max_s: 0.01\n",
        "exposure.exposure_time_min_s",
        "must be ≤ exposure_time_max_s (0.01 s), got 0.1",
    ),
    (
        "gain_above_sensor_max",
        "profile",
        FIXED_PROFILE + "exposure:\n  gain_db: 12 #<\n",
        "exposure.gain_db",
        "must be ≤ sensor.analog_gain_max_db (0 dB), got 12",
    ),
    (
        "pan_range_not_360",
        "profile",
        edit(PTZ_PROFILE, "pan_max_deg_s: 100", "pan_max_deg_s: 100\n  pan_range_deg: [-170, 170] #<"),
        "ptz.pan_range_deg",
        "must span exactly 360° when pan_continuous is true",
    ),
    (
        "negative_head_speed",
        "profile",
        edit(PTZ_PROFILE, "pan_max_deg_s: 100", "pan_max_deg_s: -45 #<"),
        "ptz.pan_max_deg_s",
        "must be > 0, got -45",
    ),
    (
        "negative_autofocus_time",
        "profile",
        edit(PTZ_PROFILE, "pan_max_deg_s: 100", "pan_max_deg_s: 100\n  autofocus_time_s: -0.5 #<"),
        "ptz.autofocus_time_s",
        "must be ≥ 0, got -0.5",
    ),
    (
        "autofocus_slower_than_any_camera",
        "profile",
        edit(PTZ_PROFILE, "pan_max_deg_s: 100", "pan_max_deg_s: 100\n  autofocus_time_s: 45 #<"),
        "ptz.autofocus_time_s",
        "must be ≤ 10, got 45; contrast-detection autofocus of CCTV zoom cameras locks in 1–3 s",
    ),
    (
        "duplicate_key",
        "profile",
        edit(FIXED_PROFILE, "  bit_depth: 12", "  bit_depth: 12\n  bit_depth: 10 #<"),
        "sensor.bit_depth",
        "appears twice in this mapping",
    ),
    (
        "yaml_syntax_error",
        "profile",
        edit(FIXED_PROFILE, "  cfa: RGGB", "  cfa: [RGGB #<\n  bits: 3"),
        "",
        "YAML syntax error",
    ),
    (
        "extends_missing_parent",
        "profile",
        "extends: nonexistent_camera #<\n" + FIXED_PROFILE,
        "extends",
        "names profile 'nonexistent_camera', which is not in",
    ),
    ("extends_itself", "profile_self", "extends: self_ref #<\n" + FIXED_PROFILE, "extends", "makes a cycle"),
    (
        "missing_profile_reference",
        "scene",
        edit(SCENE, "profile: fixed", "profile: fixd #<"),
        "cameras[0].profile",
        "names profile 'fixd', which is not in",
    ),
    (
        "empty_actor_path",
        "scene",
        edit(SCENE, "waypoints_m: [[-3, 5], [3, 5]]", "waypoints_m: [] #<"),
        "actors[0].path.waypoints_m",
        "must have at least 1 item, got 0",
    ),
    (
        "metering_zone_reversed",
        "scene",
        edit(SCENE, "      pitch_deg: -20", "      pitch_deg: -20\n    metering_region_frac: [0, 0.6, 1, 0.4] #<"),
        "cameras[0].metering_region_frac",
        "must be [x0, y0, x1, y1] with x0 < x1 and y0 < y1, got [0, 0.6, 1, 0.4]",
    ),
    (
        "repeated_waypoint",
        "scene",
        edit(SCENE, "waypoints_m: [[-3, 5], [3, 5]]", "waypoints_m: [[-3, 5], [-3, 5]] #<"),
        "actors[0].path.waypoints_m[1]",
        "repeats the previous waypoint",
    ),
    (
        "negative_camera_pan_speed",
        "scene",
        edit(
            edit(SCENE, "profile: fixed", "profile: ptz"),
            "pitch_deg: -20\n",
            "pitch_deg: 0\n    ptz:\n      pan_max_deg_s: -30 #<",
        ),
        "cameras[0].ptz.pan_max_deg_s",
        "must be > 0, got -30",
    ),
    (
        "camera_speed_above_head",
        "scene",
        edit(
            edit(SCENE, "profile: fixed", "profile: ptz"),
            "pitch_deg: -20\n",
            "pitch_deg: 0\n    ptz:\n      pan_max_deg_s: 300 #<",
        ),
        "cameras[0].ptz.pan_max_deg_s",
        "must be ≤ the head's maximum 100 deg/s, got 300",
    ),
    (
        "zoom_beyond_lens",
        "scene",
        edit(
            edit(SCENE, "profile: fixed", "profile: ptz"), "pitch_deg: -20\n", "pitch_deg: 0\n    ptz: {zoom_x: 12} #<"
        ),
        "cameras[0].ptz.zoom_x",
        "must lie in [1, 10] (the lens zooms 4–40 mm), got 12",
    ),
    (
        "tilt_outside_head",
        "scene",
        edit(
            edit(SCENE, "profile: fixed", "profile: ptz"),
            "pitch_deg: -20\n",
            "pitch_deg: 0\n    ptz: {tilt_deg: 45} #<",
        ),
        "cameras[0].ptz.tilt_deg",
        "must lie in [-90, 10] (the head's tilt range), got 45",
    ),
    (
        "ptz_on_fixed_camera",
        "scene",
        edit(SCENE, "pitch_deg: -20\n", "pitch_deg: -20\n    ptz: {pan_deg: 10} #<"),
        "cameras[0].ptz",
        "profile 'fixed' has no PTZ head",
    ),
    (
        "varifocal_outside_range",
        "scene",
        edit(SCENE, "pitch_deg: -20\n", "pitch_deg: -20\n    focal_length_mm: 8 #<"),
        "cameras[0].focal_length_mm",
        "must lie in the lens range [4, 4] mm, got 8",
    ),
    (
        "duplicate_camera_name",
        "scene",
        SCENE + "  - name: cam #<\n    profile: fixed\n    mount: {position_m: [0, 0, 3]}\n",
        "cameras[1].name",
        "must be unique, got 'cam' again (first at cameras[0])",
    ),
    (
        "unknown_mesh_type",
        "scene",
        edit(SCENE, "type: plane", "type: cube #<"),
        "environment.meshes[0].type",
        "got 'cube'",
    ),
    (
        "short_position",
        "scene",
        edit(SCENE, "position_m: [0, -5, 3]", "position_m: [0, -5] #<"),
        "cameras[0].mount.position_m",
        "must have 3 items, got 2: [0, -5]",
    ),
    (
        "fps_above_sensor",
        "scene",
        edit(SCENE, "fps: 10", "fps: 120 #<"),
        "fps",
        "must be ≤ 30 Hz, the frame rate limit of the sensor of camera 'cam', got 120",
    ),
    (
        "no_lights",
        "scene",
        edit(SCENE, "  - {type: ambient, illuminance_lux: 1000}\n", "  [] #<\n").replace("lights:\n  []", "lights: []"),
        "lights",
        "must hold at least one light",
    ),
    (
        "shadows_not_bool",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  shadows: sometimes #<\n"),
        "environment.shadows",
        "must be true or false, got 'sometimes'",
    ),
    (
        "ground_to_horizon_not_bool",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  ground_to_horizon: nowhere #<\n"),
        "environment.ground_to_horizon",
        "must be true or false, got 'nowhere'",
    ),
    (
        "checkerboard_negative_border",
        "scene",
        edit(
            SCENE,
            "      size_m: [20, 20]",
            "      size_m: [20, 20]\n    - {type: checkerboard, name: b, squares: [4, 3], square_size_m: 0.1, "
            "border_m: -0.05} #<",
        ),
        "environment.meshes[1].border_m",
        "must be ≥ 0",
    ),
    (
        "checkerboard_dark_colour_above_one",
        "scene",
        edit(
            SCENE,
            "      size_m: [20, 20]",
            "      size_m: [20, 20]\n    - {type: checkerboard, name: b, squares: [4, 3], square_size_m: 0.1, "
            "dark_color_rgb: [0.1, 1.5, 0.1]} #<",
        ),
        "environment.meshes[1].dark_color_rgb[1]",
        "must be ≤ 1",
    ),
    (
        "too_many_spot_lights",
        "scene",
        edit(
            SCENE,
            "  - {type: ambient, illuminance_lux: 1000}\n",
            "  - {type: ambient, illuminance_lux: 1000}\n"
            + "".join(
                f"  - {{type: spot, position_m: [{i}, 0, 3], target_m: [0, 5, 0], intensity_cd: 50}}\n"
                for i in range(4)
            )
            + "  - {type: spot, position_m: [9, 0, 3], target_m: [0, 5, 0], intensity_cd: 50} #<\n",
        ),
        "lights[5]",
        "is spot light number 5; the renderer shades at most 4 spot lights",
    ),
    (
        "missing_mesh_file",
        "scene",
        edit(
            SCENE,
            "    - type: plane\n      name: ground\n      size_m: [20, 20]",
            "    - type: file\n      name: statue\n      path: meshes/statue.glb #<",
        ),
        "environment.meshes[0].path",
        "refers to 'meshes/statue.glb', but",
    ),
    (
        "top_level_typo",
        "scene",
        edit(SCENE, "actors:", "acters: #<"),
        "acters",
        "is not a known key; did you mean 'actors'?",
    ),
    (
        "actor_class_typo",
        "scene",
        edit(SCENE, "class: person", "class: persn #<"),
        "actors[0].class",
        "got 'persn'; did you mean 'person'?",
    ),
    (
        "appearance_on_a_car",
        "scene",
        edit(SCENE, "    class: person\n", "    class: car\n    appearance: {sex: male} #<\n"),
        "actors[0].appearance",
        "describes a procedural person, but this actor is a 'car'; remove appearance",
    ),
    (
        "appearance_unknown_colour",
        "scene",
        edit(SCENE, "    class: person\n", "    class: person\n    appearance: {top_colour: teal} #<\n"),
        "actors[0].appearance.top_colour",
        "got 'teal'",
    ),
    (
        "appearance_stature_out_of_range",
        "scene",
        edit(SCENE, "    class: person\n", "    class: person\n    appearance: {stature_m: 2.5} #<\n"),
        "actors[0].appearance.stature_m",
        "must be ≤ 2.1, got 2.5",
    ),
    (
        "vehicle_on_a_person",
        "scene",
        edit(SCENE, "    class: person\n", "    class: person\n    vehicle: {colour: red} #<\n"),
        "actors[0].vehicle",
        "describes a procedural vehicle, but this actor is a 'person'; remove vehicle",
    ),
    (
        "vehicle_body_type_of_another_class",
        "scene",
        edit(SCENE, "    class: person\n", "    class: car\n    vehicle: {body_type: bus} #<\n"),
        "actors[0].vehicle.body_type",
        "is bus, a body of class 'bus', but this actor is a 'car': use one of sedan, hatchback",
    ),
    (
        "vehicle_unknown_colour",
        "scene",
        edit(SCENE, "    class: person\n", "    class: car\n    vehicle: {colour: teal} #<\n"),
        "actors[0].vehicle.colour",
        "'silver', 'blue', 'red', 'green', 'beige', 'yellow' or 'orange', got 'teal'",
    ),
    (
        "vehicle_plate_text_lowercase",
        "scene",
        edit(SCENE, "    class: person\n", "    class: car\n    vehicle: {plate_text: ab12 cde} #<\n"),
        "actors[0].vehicle.plate_text",
        "one or two groups of 1–4 capital letters or digits",
    ),
    (
        "vehicle_seed_negative",
        "scene",
        edit(SCENE, "    class: person\n", "    class: bus\n    vehicle: {seed: -3} #<\n"),
        "actors[0].vehicle.seed",
        "must be ≥ 0, got -3",
    ),
    (
        "vehicle_lights_on_not_a_boolean",
        "scene",
        edit(SCENE, "    class: person\n", "    class: truck\n    vehicle: {lights_on: bright} #<\n"),
        "actors[0].vehicle.lights_on",
        "must be true, false or auto (auto: lit while the vehicle is driven in under 1 000 lx of daylight), "
        "got 'bright'",
    ),
    (
        "rides_for_a_car",
        "scene",
        edit(SCENE, "    class: person\n", "    class: car\n    rides: walker #<\n"),
        "actors[0].rides",
        "names 'walker' for a procedural person to ride, but this actor is a 'car'",
    ),
    (
        "rider_with_a_path",
        "scene",
        edit(SCENE, "    class: person\n    path:\n", "    class: person\n    rides: bike\n    path: #<\n"),
        "actors[0].path",
        "is given, but this person rides 'bike' and moves with it; remove path",
    ),
    (
        "rider_of_a_missing_actor",
        "scene",
        edit(SCENE, RIDER_PATH, "    class: person\n    rides: bike #<\n"),
        "actors[0].rides",
        "names 'bike', which the scene does not have; give the name of a bicycle or motorcycle actor",
    ),
    (
        "rider_of_a_car",
        "scene",
        edit(
            edit(SCENE, "    class: person\n", "    class: car\n"),
            "cameras:\n",
            RIDER.format(name="driver", rides="walker"),
        ),
        "actors[1].rides",
        "names 'walker', a car; a person rides a procedural bicycle or motorcycle",
    ),
    (
        "two_riders_on_one_bicycle",
        "scene",
        edit(
            edit(SCENE, "    class: person\n", "    class: bicycle\n"),
            "cameras:\n",
            RIDER.format(name="rider", rides="walker").replace(" #<\ncameras:", "")
            + RIDER.format(name="pillion", rides="walker"),
        ),
        "actors[2].rides",
        "which actors[1] already rides; one rider per two-wheeler",
    ),
    (
        "rider_with_actions",
        "scene",
        edit(
            SCENE,
            RIDER_PATH,
            "    class: person\n    rides: bike\n    actions: [{type: wave, start_s: 0, duration_s: 1}] #<\n",
        ),
        "actors[0].actions",
        "are for a person on foot, but this person rides 'bike'",
    ),
    (
        "bicycle_plate_text",
        "scene",
        edit(SCENE, "    class: person\n", "    class: bicycle\n    vehicle: {plate_text: AB12 CDE} #<\n"),
        "actors[0].vehicle.plate_text",
        "but a bicycle carries no licence plate",
    ),
    (
        "driver_on_a_motorcycle",
        "scene",
        edit(SCENE, "    class: person\n", "    class: motorcycle\n    vehicle: {driver: true} #<\n"),
        "actors[0].vehicle.driver",
        "is set, but a motorcycle's rider is a person actor of its own",
    ),
    (
        "motorcycle_body_on_a_bicycle",
        "scene",
        edit(SCENE, "    class: person\n", "    class: bicycle\n    vehicle: {body_type: motorcycle} #<\n"),
        "actors[0].vehicle.body_type",
        "is motorcycle, a body of class 'motorcycle', but this actor is a 'bicycle'",
    ),
    (
        "heading_on_a_moving_path",
        "scene",
        edit(SCENE, "      speed_m_s: 1.4\n", "      speed_m_s: 1.4\n      heading_deg: 90 #<\n"),
        "actors[0].path.heading_deg",
        "sets the facing of an actor that stands on one waypoint, but this path has 2",
    ),
    (
        "annotation_format_typo",
        "scene",
        edit(SCENE, "duration_s: 1", "duration_s: 1\noutputs: {annotations: [mot, reidd]} #<"),
        "outputs.annotations[1]",
        "got 'reidd'; did you mean 'reid'?",
    ),
    (
        "annotation_image_format",
        "scene",
        edit(SCENE, "duration_s: 1", "duration_s: 1\noutputs: {annotation_images: gif} #<"),
        "outputs.annotation_images",
        "must be one of 'jpg' or 'png', got 'gif'",
    ),
    (
        "mot_detections_without_mot",
        "scene",
        edit(SCENE, "duration_s: 1", "duration_s: 1\noutputs: {annotations: [coco], mot_detections: true} #<"),
        "outputs.mot_detections",
        "but outputs.annotations has no 'mot'",
    ),
    (
        "negative_duration",
        "scene",
        edit(SCENE, "duration_s: 1", "duration_s: -1 #<"),
        "duration_s",
        "must be > 0, got -1",
    ),
    (
        "dataset_zip_lengths",
        "dataset",
        "scenes: [scenes/ok.yaml]\nseeds: [1, 2]\ncombine: zip #<\n",
        "combine",
        "zip needs lists of one length, got scenes: 1, seeds: 2",
    ),
    (
        "dataset_split_shares_not_summing_to_one",
        "dataset",
        "scenes: [scenes/ok.yaml]\nsplits: {train: 0.8, val: 0.2, test: 0.2} #<\n",
        "splits",
        "train + val + test must be 1, got 0.8 + 0.2 + 0.2 = 1.2",
    ),
    (
        "dataset_split_share_negative",
        "dataset",
        "scenes: [scenes/ok.yaml]\nsplits:\n  train: 0.9\n  val: -0.1 #<\n  test: 0.2\n",
        "splits.val",
        "must be ≥ 0, got -0.1",
    ),
    (
        "dataset_missing_scene",
        "dataset",
        "scenes:\n  - scenes/nope.yaml #<\n",
        "scenes[0]",
        "refers to 'scenes/nope.yaml', but",
    ),
    (
        "negative_pause",
        "scene",
        edit(SCENE, "speed_m_s: 1.4", "speed_m_s: 1.4\n      pause_s: -2 #<"),
        "actors[0].path.pause_s",
        "must be ≥ 0, got -2; give the seconds to stand at each waypoint",
    ),
    (
        "negative_pause_in_list",
        "scene",
        edit(SCENE, "speed_m_s: 1.4", "speed_m_s: 1.4\n      pause_s: [0, -1] #<"),
        "actors[0].path.pause_s[1]",
        "must be a number ≥ 0 (seconds at waypoint 1), got -1",
    ),
    (
        "pause_list_length",
        "scene",
        edit(SCENE, "speed_m_s: 1.4", "speed_m_s: 1.4\n      pause_s: [1, 2, 3] #<"),
        "actors[0].path.pause_s",
        "must have one pause per waypoint (2), got 3: [1, 2, 3]; add or remove values",
    ),
    (
        "actor_without_motion",
        "scene",
        edit(
            edit(SCENE, "  - name: walker", "  - name: walker #<"),
            "    path:\n      waypoints_m: [[-3, 5], [3, 5]]\n      speed_m_s: 1.4\n",
            "",
        ),
        "actors[0]",
        "needs a path or a random_walk, got neither",
    ),
    (
        "path_and_random_walk",
        "scene",
        edit(
            SCENE,
            "      speed_m_s: 1.4\n",
            "      speed_m_s: 1.4\n    random_walk: #<\n      region_m: [[-5, 0], [5, 10]]\n",
        ),
        "actors[0].random_walk",
        "cannot be given together with path; keep one of the two",
    ),
    (
        "path_motion_unknown",
        "scene",
        edit(SCENE, "      speed_m_s: 1.4\n", "      speed_m_s: 1.4\n      motion: curvy #<\n"),
        "actors[0].path.motion",
        "got 'curvy'",
    ),
    (
        "vehicle_motion_for_a_person",
        "scene",
        edit(SCENE, "      speed_m_s: 1.4\n", "      speed_m_s: 1.4\n      motion: vehicle #<\n"),
        "actors[0].path.motion",
        "is vehicle, but this actor is a 'person', which has no turning circle",
    ),
    (
        "vehicle_random_walk",
        "scene",
        edit(
            SCENE,
            "    class: person\n    path:\n      waypoints_m: [[-3, 5], [3, 5]]\n      speed_m_s: 1.4\n",
            "    class: car\n    random_walk: {region_m: [[-5, 0], [5, 10]]} #<\n",
        ),
        "actors[0].random_walk",
        "is a walk for people: a car cannot turn on the spot",
    ),
    (
        "vehicle_path_too_tight",
        "scene",
        edit(
            edit(SCENE, "    class: person\n", "    class: car\n"),
            "      waypoints_m: [[-3, 5], [3, 5]]\n",
            "      waypoints_m: [[-3, 5], [3, 5], [3, 8]] #<\n",
        ),
        "actors[0].path.waypoints_m[2]",
        "the leg from waypoint 1 [3, 5] to waypoint 2 [3, 8] is 3.00 m long, but rounding its turns (90° and 0°)",
    ),
    (
        "random_walk_region_unordered",
        "scene",
        edit(
            SCENE,
            "    path:\n      waypoints_m: [[-3, 5], [3, 5]]\n",
            "    random_walk:\n      region_m: [[5, 0], [-5, 10]] #<\n",
        ),
        "actors[0].random_walk.region_m",
        "with x_min < x_max and y_min < y_max, got [[5, 0], [-5, 10]]; give the lower-left corner first",
    ),
    (
        "random_walk_start_outside",
        "scene",
        edit(
            SCENE,
            "    path:\n      waypoints_m: [[-3, 5], [3, 5]]\n",
            "    random_walk:\n      region_m: [[-5, 0], [5, 10]]\n      start_m: [8, 5] #<\n",
        ),
        "actors[0].random_walk.start_m",
        "must lie inside region_m [[-5, 0], [5, 10]], got [8, 5]; move it inside",
    ),
    (
        "random_walk_legs_unordered",
        "scene",
        edit(
            SCENE,
            "    path:\n      waypoints_m: [[-3, 5], [3, 5]]\n",
            "    random_walk:\n      region_m: [[-5, 0], [5, 10]]\n      leg_length_m: [10, 3] #<\n",
        ),
        "actors[0].random_walk.leg_length_m",
        "must be ordered [min, max] with min ≤ max, got [10, 3] m; swap them",
    ),
    (
        "random_walk_pauses_unordered",
        "scene",
        edit(
            SCENE,
            "    path:\n      waypoints_m: [[-3, 5], [3, 5]]\n",
            "    random_walk:\n      region_m: [[-5, 0], [5, 10]]\n      pause_s: [3, 1] #<\n",
        ),
        "actors[0].random_walk.pause_s",
        "with min ≤ max, got [3, 1] s; swap them",
    ),
    (
        "random_walk_zero_leg",
        "scene",
        edit(
            SCENE,
            "    path:\n      waypoints_m: [[-3, 5], [3, 5]]\n",
            "    random_walk:\n      region_m: [[-5, 0], [5, 10]]\n      leg_length_m: [0, 3] #<\n",
        ),
        "actors[0].random_walk.leg_length_m[0]",
        "must be > 0, got 0",
    ),
    (
        "tour_names_unknown_preset",
        "scene",
        edit(
            edit(SCENE, "profile: fixed", "profile: ptz"),
            "pitch_deg: -20\n",
            "pitch_deg: 0\n    ptz: {presets: [{name: gate}], program: {type: tour, stops: [{preset: gat}]}} #<\n",
        ),
        "cameras[0].ptz.program.stops[0].preset",
        "names preset 'gat', which this camera does not have (presets: 'gate')",
    ),
    (
        "follow_unknown_actor",
        "scene",
        edit(
            edit(SCENE, "profile: fixed", "profile: ptz"),
            "pitch_deg: -20\n",
            "pitch_deg: 0\n    ptz: {program: {type: follow, target: walkr}} #<\n",
        ),
        "cameras[0].ptz.program.target",
        "names actor 'walkr', which the scene does not have (actors: 'walker')",
    ),
    (
        "keyframes_out_of_order",
        "scene",
        edit(
            edit(SCENE, "profile: fixed", "profile: ptz"),
            "pitch_deg: -20\n",
            "pitch_deg: 0\n    ptz: {program: {type: keyframes, keys: [{time_s: 2}, {time_s: 1}]}} #<\n",
        ),
        "cameras[0].ptz.program.keys[1].time_s",
        "must be later than keys[0].time_s (2 s), got 1",
    ),
    (
        "keyframes_too_fast",
        "scene",
        edit(
            edit(SCENE, "profile: fixed", "profile: ptz"),
            "pitch_deg: -20\n",
            "pitch_deg: 0\n    ptz: {program: {type: keyframes, keys: [{time_s: 0}, {time_s: 0.5, pan_deg: 90}]}} #<\n",
        ),
        "cameras[0].ptz.program.keys[1]",
        "asks for 180 deg/s of pan from keys[0] (90° in 0.5 s), more than the 100 deg/s the head may move",
    ),
    (
        "preset_outside_tilt_range",
        "scene",
        edit(
            edit(SCENE, "profile: fixed", "profile: ptz"),
            "pitch_deg: -20\n",
            "pitch_deg: 0\n    ptz: {presets: [{name: sky, tilt_deg: 40}]} #<\n",
        ),
        "cameras[0].ptz.presets[0].tilt_deg",
        "must lie in [-90, 10] (the head's tilt range), got 40",
    ),
    (
        "eptz_with_ptz",
        "scene",
        edit(
            edit(SCENE, "profile: fixed", "profile: ptz"),
            "pitch_deg: -20\n",
            "pitch_deg: 0\n    ptz: {pan_deg: 0}\n    eptz: {output_size_px: [320, 240]} #<\n",
        ),
        "cameras[0].eptz",
        "must not be set together with ptz",
    ),
    (
        "eptz_output_larger_than_sensor",
        "scene",
        edit(SCENE, "pitch_deg: -20\n", "pitch_deg: -20\n    eptz: {output_size_px: [1280, 720]} #<\n"),
        "cameras[0].eptz.output_size_px",
        "must fit the 640×480 sensor, got 1280×720",
    ),
    (
        "eptz_zoom_beyond_its_maximum",
        "scene",
        edit(
            SCENE,
            "pitch_deg: -20\n",
            "pitch_deg: -20\n    eptz: {output_size_px: [320, 240], zoom_max_x: 2, presets: [{name: a, zoom_x: 3}]}"
            " #<\n",
        ),
        "cameras[0].eptz.presets[0].zoom_x",
        "must be ≤ zoom_max_x (2), got 3",
    ),
    (
        "eptz_odd_output_size",
        "scene",
        edit(SCENE, "pitch_deg: -20\n", "pitch_deg: -20\n    eptz: {output_size_px: [321, 181]} #<\n"),
        "cameras[0].eptz.output_size_px",
        "must be even for the profile's yuv420p chroma subsampling, got 321×181; use e.g. 322×182",
    ),
    (
        "random_walk_legs_too_short",
        "scene",
        edit(
            SCENE,
            "    path:\n      waypoints_m: [[-3, 5], [3, 5]]\n      speed_m_s: 1.4\n",
            "    random_walk: {region_m: [[0, 0], [5, 5]], leg_length_m: [0.001, 1]} #<\n",
        ),
        "actors[0].random_walk.leg_length_m",
        "must give legs and a region of at least 0.1 m",
    ),
    # Issue 26. Values the schema took but the physics could not: each bound names its range and source.
    (
        "conversion_gain_beyond_any_sensor",
        "profile",
        edit(FIXED_PROFILE, "conversion_gain_dn_per_e: 0.4", "conversion_gain_dn_per_e: 1e308 #<"),
        "sensor.conversion_gain_dn_per_e",
        "must be ≤ 100, got 1e+308; system gains K run from 1e-4 DN/e⁻",
    ),
    (
        "plane_larger_than_the_world",
        "scene",
        edit(SCENE, "size_m: [20, 20]", "size_m: [1e308, 20] #<"),
        "environment.meshes[0].size_m[0]",
        "must be ≤ 20000, got 1e+308; nothing is larger than the world, which spans ±10000 m",
    ),
    (
        "sensor_hotter_than_it_works",
        "profile",
        edit(FIXED_PROFILE, "bit_depth: 12", "bit_depth: 12\n  temperature_c: 150 #<"),
        "sensor.temperature_c",
        "must be ≤ 105, got 150; an image sensor works from −40 °C",
    ),
    (
        "dark_current_doubling_too_fast",
        "profile",
        edit(FIXED_PROFILE, "read_noise_e: 2.0", "read_noise_e: 2.0\n    dark_current_doubling_c: 0.1 #<"),
        "sensor.noise.dark_current_doubling_c",
        "must be ≥ 2, got 0.1; silicon's dark current doubles every 3–14 °C",
    ),
    (
        "dark_current_at_temperature_beyond_any_sensor",
        "profile",
        edit(
            edit(FIXED_PROFILE, "bit_depth: 12", "bit_depth: 12\n  temperature_c: 105"),
            "read_noise_e: 2.0",
            "read_noise_e: 2.0\n    dark_current_e_per_s: 1 #<\n    dark_current_reference_c: -40\n"
            "    dark_current_doubling_c: 2",
        ),
        "sensor.noise.dark_current_e_per_s",
        "is 6.68e+21 e⁻/s at temperature_c (105 °C: 1 e⁻/s at -40 °C, doubling every 2 °C), more than the 1e+08",
    ),
    (
        "sensor_wider_than_any",
        "profile",
        edit(FIXED_PROFILE, "width_px: 640", "width_px: 32768 #<"),
        "sensor.width_px",
        "must be ≤ 16384, got 32768; no sensor has more than 16384 pixels along a side",
    ),
    (
        "sensor_more_pixels_than_any",
        "profile",
        edit(edit(FIXED_PROFILE, "width_px: 640", "width_px: 16384 #<"), "height_px: 480", "height_px: 16384"),
        "sensor.width_px",
        "× height_px must be ≤ 160 MP (the largest area sensors sold have 151 MP), got 16384 × 16384 = 268.4 MP",
    ),
    (
        "full_well_of_one_electron",
        "profile",
        edit(edit(FIXED_PROFILE, "full_well_e: 10000", "full_well_e: 1 #<"), "read_noise_e: 2.0", "read_noise_e: 5"),
        "sensor.full_well_e",
        "must be ≥ 100, got 1; real wells hold 100 e⁻ to 10 Me⁻",
    ),
    (
        "full_well_within_the_read_noise",
        "profile",
        edit(edit(FIXED_PROFILE, "full_well_e: 10000", "full_well_e: 200 #<"), "read_noise_e: 2.0", "read_noise_e: 50"),
        "sensor.full_well_e",
        "must be ≥ 10 × noise.read_noise_e = 500 e⁻ (a dynamic range full well / read noise of at least 20 dB",
    ),
    (
        "fixed_pattern_deeper_than_the_well",
        "profile",
        edit(FIXED_PROFILE, "read_noise_e: 2.0", "read_noise_e: 2.0\n    dsnu_e: 20000 #<"),
        "sensor.noise.dsnu_e",
        "must be ≤ full_well_e (10000 e⁻): a fixed-pattern offset larger than the well fills every pixel",
    ),
    (
        "focal_length_of_a_kilometre",
        "profile",
        edit(FIXED_PROFILE, "focal_length_mm: 4.0", "focal_length_mm: 1e6 #<"),
        "lens.focal_length_mm",
        "must be ≤ 2000, got 1e+06; real lenses span 0.5–2000 mm",
    ),
    (
        "bitrate_below_any_camera",
        "profile",
        FIXED_PROFILE + "codec: {bitrate_kbps: 1e-9} #<\n",
        "codec.bitrate_kbps",
        "must be ≥ 32, got 1e-09; surveillance cameras and recorders offer 32 kbit/s and up",
    ),
    (
        "waypoint_beyond_the_world",
        "scene",
        edit(SCENE, "waypoints_m: [[-3, 5], [3, 5]]", "waypoints_m: [[-1e308, 5], [3, 5]] #<"),
        "actors[0].path.waypoints_m[0][0]",
        "must be ≥ -10000, got -1e+308; scenes lie within ±10000 m of the origin",
    ),
    (
        "camera_beyond_the_world",
        "scene",
        edit(SCENE, "position_m: [0, -5, 3]", "position_m: [1e308, -5, 3] #<"),
        "cameras[0].mount.position_m[0]",
        "must be ≤ 10000, got 1e+308; scenes lie within ±10000 m of the origin, where the renderer's float32",
    ),
    # The same class, found by setting every number of a profile and a scene to ±1e308, 1e12 and 1e-300.
    (
        "whole_number_too_large_to_hold",
        "profile",
        edit(FIXED_PROFILE, "width_px: 640", "width_px: 1e308 #<"),
        "sensor.width_px",
        "must be a whole number of a sensible size, got 1e+308; no sensor has more than 16384 pixels",
    ),
    (
        "optical_axis_off_the_sensor",
        "profile",
        edit(FIXED_PROFILE, "cfa: RGGB", "cfa: RGGB\n  principal_point_offset_px: [1e308, 0] #<"),
        "sensor.principal_point_offset_px",
        "must put the optical axis on the sensor, within ±320 px across and ±240 px down, got [1e+308, 0]",
    ),
    (
        "channel_noise_scale_overflows",
        "profile",
        edit(FIXED_PROFILE, "read_noise_e: 2.0", "read_noise_e: 2.0\n    channel_scale: {r: 1e308} #<"),
        "sensor.noise.channel_scale.r",
        "must be ≤ 10, got 1e+308; a channel's noise is 0–10 times the physical model's",
    ),
    (
        "sharpening_radius_of_a_kilometre",
        "profile",
        FIXED_PROFILE + "isp: {sharpen_amount: 1, sharpen_radius_px: 1e12} #<\n",
        "isp.sharpen_radius_px",
        "must be ≤ 20, got 1e+12; a camera sharpens detail a few pixels wide",
    ),
    (
        "false_colour_window_of_even_side",
        "profile",
        FIXED_PROFILE + "isp: {false_colour_median_px: 4} #<\n",
        "isp.false_colour_median_px",
        "must be one of 0, 3, 5 or 7, got 4",
    ),
    (
        "white_balance_gain_overflows",
        "profile",
        FIXED_PROFILE + "isp: {white_balance: {mode: fixed, gains_rgb: [1e308, 1, 1]}} #<\n",
        "isp.white_balance.gains_rgb[0]",
        "must be ≤ 20, got 1e+308; white balance multiplies a channel by 1–4",
    ),
    (
        "key_frame_interval_beyond_the_encoder",
        "profile",
        FIXED_PROFILE + "codec: {gop_frames: 1000000000000} #<\n",
        "codec.gop_frames",
        "must be ≤ 10000, got 1000000000000; cameras set a key frame every 1 to about a thousand frames",
    ),
    (
        "frame_rate_below_the_video_fraction",
        "scene",
        edit(SCENE, "fps: 10", "fps: 1e-300 #<"),
        "fps",
        "must be ≥ 0.001, got 1e-300; the video stores the frame rate as a fraction",
    ),
    (
        "sky_brighter_than_the_sun",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  sky_luminance_cd_m2: 1e308 #<\n"),
        "environment.sky_luminance_cd_m2",
        "must be ≤ 2e+09, got 1e+308; nothing a camera sees is brighter than the sun's disc",
    ),
    (
        "lamp_brighter_than_a_lighthouse",
        "scene",
        edit(
            SCENE,
            "  - {type: ambient, illuminance_lux: 1000}\n",
            "  - {type: ambient, illuminance_lux: 1000}\n"
            "  - {type: point, position_m: [0, 0, 3], intensity_cd: 1e308} #<\n",
        ),
        "lights[1].intensity_cd",
        "must be ≤ 1e+08, got 1e+308; the brightest lamps, lighthouse and searchlight beams",
    ),
    (
        "walker_slower_than_standing",
        "scene",
        edit(SCENE, "speed_m_s: 1.4", "speed_m_s: 1e-300 #<"),
        "actors[0].path.speed_m_s",
        "must be ≥ 0.01, got 1e-300; an actor moves at 0.01–100 m/s",
    ),
    (
        "mesh_file_scaled_beyond_the_world",
        "scene",
        edit(
            SCENE,
            "    - type: plane\n      name: ground\n      size_m: [20, 20]",
            "    - {type: file, name: statue, path: statue.glb, scale: 1e9} #<",
        ),
        "environment.meshes[0].scale",
        "must be ≤ 1000, got 1e+09; a scale turns the file's units into metres",
    ),
    (
        "tilt_range_beyond_a_half_turn",
        "profile",
        edit(PTZ_PROFILE, "tilt_range_deg: [-90, 10]", "tilt_range_deg: [-90, 1e308] #<"),
        "ptz.tilt_range_deg[1]",
        "must be ≤ 180, got 1e+308; a tilt range's ends lie within ±180°",
    ),
    (
        "zoom_sweep_slower_than_any_motor",
        "profile",
        edit(PTZ_PROFILE, "pan_max_deg_s: 100", "pan_max_deg_s: 100\n  zoom_wide_to_tele_s: 1e308 #<"),
        "ptz.zoom_wide_to_tele_s",
        "must be ≤ 100, got 1e+308; a zoom crosses its range in 1–10 s on real cameras",
    ),
    # Types are strict: text, booleans and numbers are not taken for one another.
    (
        "quoted_number",
        "profile",
        edit(FIXED_PROFILE, "width_px: 640", "width_px: '320' #<"),
        "sensor.width_px",
        "must be a number, got '320', which the quotes make text; remove the quotes",
    ),
    (
        "boolean_for_a_number",
        "profile",
        edit(FIXED_PROFILE, "bit_depth: 12", "bit_depth: true #<"),
        "sensor.bit_depth",
        "must be a number, got true: true and false are booleans, not numbers",
    ),
    (
        "boolean_in_a_list_of_numbers",
        "scene",
        edit(SCENE, "position_m: [0, -5, 3]", "position_m: [0, -5, yes] #<"),
        "cameras[0].mount.position_m[2]",
        "must be a number, got true: true",
    ),
    (
        "quoted_boolean",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  shadows: 'false' #<\n"),
        "environment.shadows",
        "must be true or false, got 'false'; remove the quotes",
    ),
    (
        "number_for_a_boolean",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  shadows: 1 #<\n"),
        "environment.shadows",
        "must be true or false, got 1",
    ),
    (
        "exponent_without_a_dot_is_a_number",
        "profile",
        edit(FIXED_PROFILE, "black_level_dn: 64", "black_level_dn: 1e4 #<"),
        "sensor.black_level_dn",
        "must be below the white level 4095 DN of a 12-bit ADC, got 10000",
    ),
    (
        "yaml_tag_on_a_value",
        "profile",
        edit(
            FIXED_PROFILE, "description: test fixed camera", 'description: !!python/object/apply:os.system ["true"] #<'
        ),
        "description",
        "has the YAML tag !!python/object/apply:os.system, which camgen does not read",
    ),
    # A union of forms reports the form that was meant, once.
    (
        "seed_count_zero",
        "dataset",
        "scenes: [scenes/ok.yaml]\nseeds: {start: 0, count: 0} #<\n",
        "seeds.count",
        "must be ≥ 1, got 0",
    ),
    (
        "seed_count_negative",
        "dataset",
        "scenes: [scenes/ok.yaml]\nseeds: {start: 0, count: -1} #<\n",
        "seeds.count",
        "must be ≥ 1, got -1",
    ),
    (
        "seeds_neither_form",
        "dataset",
        "scenes: [scenes/ok.yaml]\nseeds: twelve #<\n",
        "seeds",
        "must be a list or a mapping of keys, got 'twelve'",
    ),
    (
        "seed_list_item_not_a_number",
        "dataset",
        "scenes: [scenes/ok.yaml]\nseeds: [1, x] #<\n",
        "seeds[1]",
        "must be a number, got 'x'",
    ),
    (
        "region_polygon_of_two_points",
        "scene",
        SCENE + "regions:\n  - {name: gate, polygon_m: [[0, 0], [1, 0]], required_class: detect} #<\n",
        "regions[0].polygon_m",
        "must have at least 3 corners [[x, y], …] to enclose an area, got 2",
    ),
    (
        "region_unknown_required_class",
        "scene",
        SCENE + "regions:\n  - {name: gate, polygon_m: [[0, 0], [1, 0], [1, 1]], required_class: identity} #<\n",
        "regions[0].required_class",
        "must be one of 'detect', 'observe', 'recognise' or 'identify', got 'identity'",
    ),
    (
        "scene_without_cameras",
        "scene",
        SCENE[: SCENE.index("cameras:")] + "cameras: [] #<\n",
        "cameras",
        "must have at least 1 item, got 0: []; a scene is seen through its cameras ({name, profile, mount}); "
        "camgen layout, which chooses them, replaces the scene's cameras",
    ),
    (
        "texture_unknown_type",
        "scene",
        edit(SCENE, "      size_m: [20, 20]", "      size_m: [20, 20]\n      material: {texture: {type: cobbles}} #<"),
        "environment.meshes[0].material.texture.type",
        "got 'cobbles'",
    ),
    (
        "texture_tile_too_small",
        "scene",
        edit(
            SCENE,
            "      size_m: [20, 20]",
            "      size_m: [20, 20]\n      material: {texture: {type: asphalt, tile_m: 0.1}} #<",
        ),
        "environment.meshes[0].material.texture.tile_m",
        "must be ≥ 0.5, got 0.1",
    ),
    (
        "sky_unknown_model",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  sky: sunny #<\n"),
        "environment.sky",
        "got 'sunny'",
    ),
    (
        "raw_unknown_format",
        "scene",
        SCENE + "outputs: {raw: jpg} #<\n",
        "outputs.raw",
        "got 'jpg'",
    ),
    (
        "radiance_unknown_format",
        "scene",
        SCENE + "outputs: {radiance: jpg} #<\n",
        "outputs.radiance",
        "must be one of 'png16', 'tiff16' or 'exr', got 'jpg'",
    ),
    (
        "flow_unknown_format",
        "scene",
        SCENE + "outputs: {flow: png} #<\n",
        "outputs.flow",
        "must be one of 'flo', got 'png'",
    ),
    (
        "scene_flow_not_a_switch",
        "scene",
        SCENE + "outputs: {scene_flow: maybe} #<\n",
        "outputs.scene_flow",
        "must be true or false, got 'maybe'",
    ),
    (
        "action_unknown_type",
        "scene",
        edit(
            SCENE,
            "      speed_m_s: 1.4\n",
            "      speed_m_s: 1.4\n    actions: [{type: dance, start_s: 0, duration_s: 1}] #<\n",
        ),
        "actors[0].actions[0].type",
        "got 'dance'",
    ),
    (
        "action_seat_too_high",
        "scene",
        edit(
            SCENE,
            "      speed_m_s: 1.4\n",
            "      speed_m_s: 1.4\n    actions: [{type: sit, start_s: 0, duration_s: 1, seat_height_m: 1.2}] #<\n",
        ),
        "actors[0].actions[0].seat_height_m",
        "must be ≤ 0.8, got 1.2",
    ),
    (
        "site_latitude_beyond_the_pole",
        "scene",
        edit(
            SCENE,
            "environment:\n",
            "environment:\n  site: {latitude_deg: 95, longitude_deg: 2, time: 2026-06-21T12:00:00Z} #<\n",
        ),
        "environment.site.latitude_deg",
        "must be ≤ 90, got 95; latitudes run from −90",
    ),
    (
        "site_time_without_offset",
        "scene",
        edit(
            SCENE,
            "environment:\n",
            "environment:\n  site: {latitude_deg: 48, longitude_deg: 2, time: 2026-06-21T12:00:00} #<\n",
        ),
        "environment.site.time",
        "must say its UTC offset",
    ),
    (
        "site_time_a_date_alone",
        "scene",
        edit(
            SCENE, "environment:\n", "environment:\n  site: {latitude_deg: 48, longitude_deg: 2, time: 2026-06-21} #<\n"
        ),
        "environment.site.time",
        "got the date 2026-06-21 alone",
    ),
    (
        "site_sun_below_the_horizon",
        "scene",
        edit(
            SCENE,
            "environment:\n",
            "environment:\n  site: {latitude_deg: 48.85, longitude_deg: 2.35, time: 2026-06-21T23:30:00+02:00} #<\n",
        ),
        "environment.site.time",
        "below the horizon at 2026-06-21T23:30:00+02:00 (that day the sun rises at 05:49 and sets at 21:56 there)",
    ),
    (
        "site_and_a_sun_direction",
        "scene",
        edit(
            SCENE,
            "  - {type: ambient, illuminance_lux: 1000}\n",
            "  - {type: ambient, illuminance_lux: 1000}\n  - {type: sun, azimuth_deg: 100} #<\n",
        ).replace(
            "environment:\n", "environment:\n  site: {latitude_deg: 48, longitude_deg: 2, time: 2026-06-21T12:00:00Z}\n"
        ),
        "lights[1].azimuth_deg",
        "leave out azimuth_deg and elevation_deg (the site places the sun)",
    ),
    (
        "site_sun_under_overcast",
        "scene",
        edit(
            SCENE,
            "  - {type: ambient, illuminance_lux: 1000}\n",
            "  - {type: ambient, illuminance_lux: 1000}\n  - {type: sun} #<\n",
        ).replace(
            "environment:\n",
            "environment:\n  sky: overcast\n  site: {latitude_deg: 48, longitude_deg: 2, time: 2026-06-21T12:00:00Z}\n",
        ),
        "lights[1]",
        "an overcast sky lets no direct sunlight through",
    ),
    (
        "site_north_beyond_a_turn",
        "scene",
        edit(
            SCENE,
            "environment:\n",
            "environment:\n  site: {latitude_deg: 48, longitude_deg: 2, time: 2026-06-21T12:00Z, north_deg: 400} #<\n",
        ),
        "environment.site.north_deg",
        "must be ≤ 360, got 400",
    ),
    (
        "site_sequence_past_sunset",
        "scene",
        edit(SCENE, "duration_s: 1\n", "duration_s: 3600 #<\n").replace(
            "environment:\n",
            "environment:\n  site: {latitude_deg: 53.55, longitude_deg: 9.99, time: '2026-10-15T18:00:00+02:00'}\n",
        ),
        "duration_s",
        "ends the sequence at 2026-10-15T19:00:00+02:00, when the sun stands 6.09° below the horizon (sunset at 18:22)",
    ),
    (
        "fog_visibility_under_a_metre",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  fog: {visibility_m: 0.2} #<\n"),
        "environment.fog.visibility_m",
        "must be ≥ 1, got 0.2; visual ranges run from a few metres",
    ),
    (
        "rain_rate_zero",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  rain: {rate_mm_h: 0} #<\n"),
        "environment.rain.rate_mm_h",
        "must be > 0, got 0; rain rates run from a drizzle's 0.1 mm/h",
    ),
    (
        "rain_rate_beyond_records",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  rain: {rate_mm_h: 2000} #<\n"),
        "environment.rain.rate_mm_h",
        "must be ≤ 500, got 2000",
    ),
    (
        "rain_seed_negative",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  rain: {rate_mm_h: 5, seed: -1} #<\n"),
        "environment.rain.seed",
        "must be ≥ 0, got -1",
    ),
    (
        "rain_without_rate",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  rain: {seed: 4} #<\n"),
        "environment.rain.rate_mm_h",
        "environment.rain.rate_mm_h is required",
    ),
    (
        "snow_rate_negative",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  snow: {rate_mm_h: -1} #<\n"),
        "environment.snow.rate_mm_h",
        "must be > 0, got -1; snowfall rates run, as melted water, from a flurry's 0.1 mm/h",
    ),
    (
        "snow_rate_beyond_records",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  snow: {rate_mm_h: 80} #<\n"),
        "environment.snow.rate_mm_h",
        "must be ≤ 25, got 80",
    ),
    (
        "snow_kind_unknown",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  snow: {rate_mm_h: 1, kind: slushy} #<\n"),
        "environment.snow.kind",
        "'dry' or 'wet'",
    ),
    (
        "snow_unknown_key",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  snow: {rate_mm_h: 1, depth_cm: 3} #<\n"),
        "environment.snow.depth_cm",
        "depth_cm",
    ),
    (
        "snow_with_rain",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  rain: {rate_mm_h: 2}\n  snow: {rate_mm_h: 1} #<\n"),
        "environment.snow",
        "mixed rain and snow (sleet) is not modelled; keep one of environment.rain and environment.snow",
    ),
    (
        "wind_speed_negative",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  wind: {speed_m_s: -3} #<\n"),
        "environment.wind.speed_m_s",
        "must be ≥ 0, got -3; mean wind speeds run from calm (0) to hurricane force",
    ),
    (
        "wind_speed_beyond_hurricane",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  wind: {speed_m_s: 90} #<\n"),
        "environment.wind.speed_m_s",
        "must be ≤ 40, got 90",
    ),
    (
        "wind_without_speed",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  wind: {direction_deg: 45} #<\n"),
        "environment.wind.speed_m_s",
        "environment.wind.speed_m_s is required",
    ),
    (
        "wind_direction_out_of_range",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  wind: {speed_m_s: 4, direction_deg: 400} #<\n"),
        "environment.wind.direction_deg",
        "must be ≤ 360, got 400; a direction, −360° to 360°",
    ),
    (
        "wind_turbulence_too_high",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  wind: {speed_m_s: 4, turbulence_intensity: 0.9} #<\n"),
        "environment.wind.turbulence_intensity",
        "must be ≤ 0.6, got 0.9; the turbulence intensity σ_u/U",
    ),
    (
        "wind_seed_negative",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  wind: {speed_m_s: 4, seed: -2} #<\n"),
        "environment.wind.seed",
        "must be ≥ 0, got -2",
    ),
    (
        "wind_speed_as_text",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  wind: {speed_m_s: breezy} #<\n"),
        "environment.wind.speed_m_s",
        "breezy",
    ),
    (
        "wet_not_bool",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  wet: soaked #<\n"),
        "environment.wet",
        "must be true or false, got 'soaked'",
    ),
    (
        "lamp_flux_negative",
        "scene",
        edit(
            SCENE,
            "  - {type: ambient, illuminance_lux: 1000}\n",
            "  - {type: ambient, illuminance_lux: 1000}\n  - {type: lamp, position_m: [0, 0, 6], flux_lm: -5000} #<\n",
        ),
        "lights[1].flux_lm",
        "must be > 0, got -5000; street and area lights emit about 1 000–60 000 lm",
    ),
    (
        "lamp_beam_a_hemisphere",
        "scene",
        edit(
            SCENE,
            "  - {type: ambient, illuminance_lux: 1000}\n",
            "  - {type: ambient, illuminance_lux: 1000}\n"
            "  - {type: lamp, position_m: [0, 0, 6], flux_lm: 5000, cone_half_angle_deg: 90} #<\n",
        ),
        "lights[1].cone_half_angle_deg",
        "a lamp lighting a hemisphere is a point light",
    ),
    (
        "lamp_on_the_ground_without_target",
        "scene",
        edit(
            SCENE,
            "  - {type: ambient, illuminance_lux: 1000}\n",
            "  - {type: ambient, illuminance_lux: 1000}\n  - {type: lamp, position_m: [0, 0, 0], flux_lm: 5000} #<\n",
        ),
        "lights[1].position_m",
        "leaves the beam no direction",
    ),
    (
        "lamp_without_flux_or_file",
        "scene",
        edit(
            SCENE,
            "  - {type: ambient, illuminance_lux: 1000}\n",
            "  - {type: ambient, illuminance_lux: 1000}\n  - {type: lamp, position_m: [0, 0, 6]} #<\n",
        ),
        "lights[1].flux_lm",
        "is missing: give the lamp's luminous flux in lumens, or an ies_file",
    ),
    (
        "lamp_c0_beyond_a_turn",
        "scene",
        edit(
            SCENE,
            "  - {type: ambient, illuminance_lux: 1000}\n",
            "  - {type: ambient, illuminance_lux: 1000}\n"
            "  - {type: lamp, position_m: [0, 0, 6], ies_file: a.ies, c0_azimuth_deg: 500} #<\n",
        ),
        "lights[1].c0_azimuth_deg",
        "must be ≤ 360, got 500",
    ),
    (
        "night_sky_unknown",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  night_sky: moonlit #<\n"),
        "environment.night_sky",
        "'natural', 'rural', 'suburban' or 'urban'",
    ),
    (
        "night_sky_with_a_sun",
        "scene",
        edit(
            SCENE,
            "  - {type: ambient, illuminance_lux: 1000}\n",
            "  - {type: ambient}\n  - {type: sun, illuminance_lux: 1000} #<\n",
        ).replace("environment:\n", "environment:\n  night_sky: urban\n"),
        "lights[1]",
        "is a sun light, but environment.night_sky makes this a night scene",
    ),
    (
        "night_sky_with_a_clear_sky",
        "scene",
        edit(SCENE, "environment:\n", "environment:\n  night_sky: urban\n  sky: clear #<\n"),
        "environment.sky",
        "whose skyglow camgen draws uniform",
    ),
    (
        "night_sky_in_twilight",
        "scene",
        edit(
            SCENE,
            "environment:\n",
            "environment:\n  night_sky: urban\n"
            "  site: {latitude_deg: 48, longitude_deg: 2, time: 2026-06-21T22:30:00+02:00} #<\n",
        ),
        "environment.site.time",
        "a night sky needs it 12° or more below (after nautical dusk",
    ),
    (
        "night_mode_switch_negative",
        "profile",
        FIXED_PROFILE + "night_mode:\n  switch_lux: -2 #<\n",
        "night_mode.switch_lux",
        "cameras switch to night mode between about 0.1 and 50 lx",
    ),
    (
        "ir_illuminator_at_940nm",
        "profile",
        FIXED_PROFILE + "night_mode:\n  ir_illuminator: {wavelength_nm: 940} #<\n",
        "night_mode.ir_illuminator.wavelength_nm",
        "must be one of 850, got 940",
    ),
    (
        "ir_illuminator_searchlight",
        "profile",
        FIXED_PROFILE + "night_mode:\n  ir_illuminator: {radiant_intensity_mw_sr: 1e9} #<\n",
        "night_mode.ir_illuminator.radiant_intensity_mw_sr",
        "camera IR illuminators give about 100–20 000 mW/sr",
    ),
    (
        "ir_illuminator_beam_flat",
        "profile",
        FIXED_PROFILE + "night_mode:\n  ir_illuminator: {half_angle_deg: 95} #<\n",
        "night_mode.ir_illuminator.half_angle_deg",
        "a beam's half angle lies between 1° and 89°",
    ),
    (
        "qe_850_above_twice_visible",
        "profile",
        edit(FIXED_PROFILE, "  bit_depth: 12\n", "  bit_depth: 12\n  qe_850nm_rel: 5 #<\n"),
        "sensor.qe_850nm_rel",
        "a silicon sensor's QE at 850 nm is 0–2 times its visible QE",
    ),
    (
        "camera_night_mode_sometimes",
        "scene",
        edit(SCENE, "      pitch_deg: -20\n", "      pitch_deg: -20\n    night_mode: sometimes #<\n"),
        "cameras[0].night_mode",
        "got 'sometimes'",
    ),
    (
        "prop_form_on_a_bench",
        "scene",
        edit(
            SCENE,
            "      size_m: [20, 20]\n",
            "      size_m: [20, 20]\n  props:\n    - {type: bench, position_m: [1, 2], form: conifer} #<\n",
        ),
        "environment.props[0].form",
        "shapes a tree, but this prop is a 'bench'; remove form",
    ),
    (
        "prop_unknown_type",
        "scene",
        edit(
            SCENE,
            "      size_m: [20, 20]\n",
            "      size_m: [20, 20]\n  props:\n    - {type: statue, position_m: [1, 2]} #<\n",
        ),
        "environment.props[0].type",
        "got 'statue'",
    ),
    (
        "prop_height_outside_its_range",
        "scene",
        edit(
            SCENE,
            "      size_m: [20, 20]\n",
            "      size_m: [20, 20]\n  props:\n    - {type: bollard, position_m: [1, 2], height_m: 3} #<\n",
        ),
        "environment.props[0].height_m",
        "must lie within a bollard's 0.9–1 m",
    ),
    (
        "scatter_line_and_region",
        "scene",
        edit(
            SCENE,
            "      size_m: [20, 20]\n",
            "      size_m: [20, 20]\n  scatter:\n"
            "    - {type: tree, along: [[0, 0], [5, 0]], spacing_m: 2, region_m: [[0, 0], [5, 5]]} #<\n",
        ),
        "environment.scatter[0]",
        "needs exactly one of along (a polyline, with spacing_m) or region_m",
    ),
    (
        "scatter_count_beyond_packing",
        "scene",
        edit(
            SCENE,
            "      size_m: [20, 20]\n",
            "      size_m: [20, 20]\n  scatter:\n"
            "    - {type: bush, region_m: [[0, 0], [4, 5]], count: 30, min_gap_m: 1} #<\n",
        ),
        "environment.scatter[0].count",
        "at most 12 props 1 m apart fit at random in 20 m²",
    ),
    (
        "scatter_spacing_under_gap",
        "scene",
        edit(
            SCENE,
            "      size_m: [20, 20]\n",
            "      size_m: [20, 20]\n  scatter:\n"
            "    - {type: bollard, along: [[0, 0], [5, 0]], spacing_m: 1, min_gap_m: 2} #<\n",
        ),
        "environment.scatter[0].spacing_m",
        "must be ≥ min_gap_m (2), got 1",
    ),
    (
        "prop_name_of_a_mesh",
        "scene",
        edit(
            SCENE,
            "      size_m: [20, 20]\n",
            "      size_m: [20, 20]\n  props:\n    - {type: bin, position_m: [1, 2], name: ground} #<\n",
        ),
        "environment.props[0].name",
        "is the instance 'ground', a name environment.meshes[0] has already; give the prop another name",
    ),
]


@pytest.mark.parametrize(("kind", "text", "key", "fragment"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_input_is_located_and_explained(workspace: Path, kind: str, text: str, key: str, fragment: str):
    if kind == "profile_self":
        path = write(workspace, "profiles/self_ref.yaml", text)
        loader = load_profile
    elif kind == "profile":
        path = write(workspace, "profiles/bad.yaml", text)
        loader = load_profile
    elif kind == "scene":
        path = write(workspace, "scenes/bad.yaml", text)
        loader = load_scene
    else:
        write(workspace, "scenes/ok.yaml", SCENE)
        path = write(workspace, "bad_dataset.yaml", text)
        loader = load_dataset

    with pytest.raises(ConfigError) as caught:
        loader(path)

    problems = caught.value.problems
    assert len(problems) == 1, [str(p) for p in problems]
    problem = problems[0]
    message = str(problem)
    assert fragment in message
    if key:
        assert f" {key} " in f" {message} ", message
    marked = [i + 1 for i, line in enumerate(text.splitlines()) if "#<" in line]
    if marked:
        assert problem.location is not None
        assert problem.location.file == str(path)
        assert problem.location.line == marked[0], message
        assert re.match(rf"^{re.escape(str(path))}:{marked[0]}:\d+: ", message), message


def test_cases_are_distinct_and_many():
    assert len(CASES) >= 25
    assert len({c[0] for c in CASES}) == len(CASES)
    assert len({c[4] for c in CASES}) == len(CASES), "each case must check its own message"


def test_all_problems_are_reported_at_once(workspace: Path):
    text = edit(edit(FIXED_PROFILE, "width_px: 640", "width_px: -1"), "f_number: 2.0", "f_number: 0.1")
    path = write(workspace, "profiles/two.yaml", text)
    with pytest.raises(ConfigError) as caught:
        load_profile(path)
    keys = [p.path for p in caught.value.problems]
    assert keys == [("sensor", "width_px"), ("lens", "f_number")]


def test_inherited_error_points_at_the_parent_file(workspace: Path):
    write(workspace, "profiles/base.yaml", edit(FIXED_PROFILE, "bit_depth: 12", "bit_depth: 20"))
    child = write(workspace, "profiles/child.yaml", "extends: base\nserial: 5\n")
    with pytest.raises(ConfigError) as caught:
        load_profile(child)
    (problem,) = caught.value.problems
    assert problem.location.file.endswith("base.yaml")
    assert problem.path == ("sensor", "bit_depth")


@pytest.mark.parametrize("command", ["validate", "plan"])
def test_cli_reports_without_traceback(workspace: Path, command: str, capsys):
    path = write(workspace, "scenes/bad.yaml", edit(SCENE, "fps: 10", "fps: -5"))
    code = main([command, str(path)])
    captured = capsys.readouterr()
    assert code in (1, 2)
    assert "Traceback" not in captured.err + captured.out
    assert f"{path}:2:" in captured.err
    assert "fps must be ≥ 0.001, got -5" in captured.err


# The inputs as reported, where one line breaks two bounds: each is reported at its own place.
BOTH_REPORTED = [
    (
        "sensor_32768_square",
        "profile",
        edit(edit(FIXED_PROFILE, "width_px: 640", "width_px: 32768"), "height_px: 480", "height_px: 32768"),
        [(3, "sensor.width_px must be ≤ 16384"), (4, "sensor.height_px must be ≤ 16384")],
    ),
    (
        "plane_1e308_square",
        "scene",
        edit(SCENE, "size_m: [20, 20]", "size_m: [1e308, 1e308]"),
        [(8, "size_m[0] must be ≤ 20000, got 1e+308"), (8, "size_m[1] must be ≤ 20000, got 1e+308")],
    ),
    (
        "hot_sensor_with_fast_doubling",
        "profile",
        edit(
            edit(FIXED_PROFILE, "bit_depth: 12", "bit_depth: 12\n  temperature_c: 150"),
            "read_noise_e: 2.0",
            "read_noise_e: 2.0\n    dark_current_doubling_c: 0.1",
        ),
        [(8, "sensor.temperature_c must be ≤ 105, got 150"), (14, "dark_current_doubling_c must be ≥ 2, got 0.1")],
    ),
    (
        "waypoints_at_plus_and_minus_1e308",
        "scene",
        edit(SCENE, "waypoints_m: [[-3, 5], [3, 5]]", "waypoints_m: [[-1e308, 5], [1e308, 5]]"),
        [
            (15, "waypoints_m[0][0] must be ≥ -10000, got -1e+308"),
            (15, "waypoints_m[1][0] must be ≤ 10000, got 1e+308"),
        ],
    ),
]


@pytest.mark.parametrize(
    ("kind", "text", "expected"), [c[1:] for c in BOTH_REPORTED], ids=[c[0] for c in BOTH_REPORTED]
)
def test_every_broken_bound_is_reported(workspace: Path, kind: str, text: str, expected: list, capsys):
    path = write(workspace, f"{kind}s/both.yaml", text)
    assert main(["validate", "--kind", kind, str(path)]) == 1
    err = capsys.readouterr().err
    assert "Traceback" not in err
    for line, fragment in expected:
        assert re.search(rf"{re.escape(str(path))}:{line}:\d+: \S*{re.escape(fragment)}", err), (fragment, err)


def test_plan_refuses_a_job_that_cannot_fit_in_memory_before_compiling(workspace: Path, monkeypatch, capsys):
    # On a 1 GiB machine an hour at 30 fps (108 000 frame states, about 1.6 GiB) cannot be compiled.
    monkeypatch.setattr("camgen.plan.budget.memory_bytes", lambda: (2**30, "physical"))
    text = edit(edit(SCENE, "duration_s: 1", "duration_s: 3600 #<"), "fps: 10", "fps: 30")
    path = write(workspace, "scenes/hour.yaml", text)
    assert main(["plan", str(path)]) in (1, 2)
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert f"{path}:1:1: duration_s × fps = 3600 s × 30 Hz = 108000 frames for each of 1 camera(s)" in err
    assert "need about 1.65 GiB, more than 50% of this machine's 1 GiB of physical memory" in err
    assert "duration_s ≤ 1092 s at this fps): shorten duration_s or lower fps, or split the sequence" in err


# Hostile YAML: each must end in a located error, never a traceback or a hang.
ALIAS_BOMB = "\n".join(
    ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    + [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]" for i in range(1, 10)]
    + ["cameras: *a9"]
)
HOSTILE = [
    ("bad_int_tag", "duration_s: !!int foo\n", "duration_s cannot be read"),
    ("python_object_tag", "duration_s: !!python/object:os.system x\n", "has the YAML tag !!python/object:os.system"),
    ("tag_on_a_list", "cameras: !!python/object/apply:os.system [true]\n", "(nothing was constructed or run)"),
    ("binary_tag", "description: !!binary aGVsbG8=\n", "has the YAML tag !!binary"),
    ("bad_merge_key", "duration_s: 2\n<<: 5\n", "has a bad merge key"),
    ("self_alias", "a: &x [*x]\n", "is an alias that contains itself"),
    ("deep_nesting", "a: " + "[" * 3000 + "]" * 3000 + "\n", "is nested too deeply to read"),
    ("alias_bomb", ALIAS_BOMB + "\n", "makes the document expand past"),
    ("markup_in_value", "duration_s: 1\noutputs: {frames: '[/bold]'}\ncameras: []\n", "'[/bold]'"),
    ("top_level_list", "- a\n- b\n", "the top level must be a mapping of keys, got list"),
    ("empty_profile_name", SCENE.replace("profile: fixed", "profile: ''"), "must be non-empty text"),
]


@pytest.mark.parametrize(("text", "fragment"), [c[1:] for c in HOSTILE], ids=[c[0] for c in HOSTILE])
def test_hostile_yaml_gets_a_located_error(workspace: Path, text: str, fragment: str, capsys):
    path = write(workspace, "scenes/hostile.yaml", text)
    assert main(["validate", "--kind", "scene", str(path)]) == 1
    err = capsys.readouterr().err
    assert fragment in err
    assert re.search(rf"{re.escape(str(path))}:\d+:\d+: ", err), err


def test_rational_lens_with_a_pole_far_outside_the_image_is_accepted(workspace: Path):
    text = edit(FIXED_PROFILE, "f_number: 2.0", "f_number: 2.0\n  distortion: {k1: 0.05, k4: -0.004}")
    load_profile(write(workspace, "profiles/rational.yaml", text))


def test_rational_lens_that_turns_back_inside_the_image_is_rejected(workspace: Path):
    # g(r) = r / (1 + 25 r²) peaks at g = 0.1 (r = 0.2), short of the corner radius 0.3.
    text = edit(FIXED_PROFILE, "f_number: 2.0", "f_number: 2.0\n  distortion: {k4: 25.0}")
    with pytest.raises(ConfigError, match="folds over inside the image"):
        load_profile(write(workspace, "profiles/pole.yaml", text))


def test_a_fold_in_the_zoom_table_is_blamed_on_its_entry(workspace: Path):
    text = edit(
        PTZ_PROFILE, "f_number: 1.6", "f_number: 1.6\n  zoom_table:\n    - {focal_length_mm: 4, distortion: {k1: -4}}"
    )
    with pytest.raises(ConfigError) as caught:
        load_profile(write(workspace, "profiles/zt.yaml", text))
    assert caught.value.problems[0].path == ("lens", "zoom_table", 0, "distortion")
