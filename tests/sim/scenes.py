"""A tiny world for the simulation tests: a PTZ dome and a fixed camera over a yard, one red box
walking across (160 × 120 px, 10 fps), written to a temporary directory."""

from __future__ import annotations

from pathlib import Path

from tests.conftest import write

PTZ_PROFILE = """\
description: tiny ptz dome for the simulation tests
sensor:
  width_px: 160
  height_px: 120
  pixel_pitch_um: 12.0
  full_well_e: 10000
  conversion_gain_dn_per_e: 0.4
  black_level_dn: 64
  noise:
    read_noise_e: 2.0
lens:
  focal_length_range_mm: [4.0, 40.0]
  f_number: 1.6
ptz:
  pan_range_deg: [-170, 170]
  pan_continuous: false
  tilt_range_deg: [-90, 10]
  pan_max_deg_s: 100
  pan_accel_deg_s2: 200
  tilt_max_deg_s: 60
  tilt_accel_deg_s2: 150
  zoom_wide_to_tele_s: 2.0
  command_latency_s: 0.1
"""

FIXED_PROFILE = """\
description: tiny fixed camera for the simulation tests
sensor:
  width_px: 160
  height_px: 120
  pixel_pitch_um: 12.0
  full_well_e: 10000
  conversion_gain_dn_per_e: 0.4
  black_level_dn: 64
  noise:
    read_noise_e: 2.0
lens:
  focal_length_mm: 4.0
  f_number: 2.0
"""

SCENE = """\
duration_s: {duration_s}
fps: 10
seed: 4
environment:
  meshes:
    - {{type: plane, name: ground, size_m: [60, 60], material: {{color_rgb: [0.3, 0.3, 0.28]}}}}
    - {{type: box, name: crate, size_m: [1, 1, 1], position_m: [-3, 12, 0.5], material: {{color_rgb: [0.2, 0.3, 0.6]}}}}
    - type: box
      name: wall
      size_m: [30, 0.4, 3]
      position_m: [0, 20, 1.5]
      material: {{color_rgb: [0.55, 0.5, 0.45]}}
lights:
  - {{type: ambient, illuminance_lux: {illuminance_lux}}}
actors:
  - name: walker
    class: person
    shape:
      type: box
      name: walker_body
      size_m: [0.5, 0.5, 1.75]
      position_m: [0, 0, 0.875]
      material: {{color_rgb: [0.8, 0.05, 0.04]}}
    path: {{waypoints_m: [[{start_x_m}, 8], [{end_x_m}, 8]], speed_m_s: {speed_m_s}}}
cameras:
  - name: dome
    profile: ptz
    mount: {{position_m: [0, -2, 3], yaw_deg: 90, pitch_deg: 0}}
    ptz:
      pan_deg: {dome_pan_deg}
      tilt_deg: -12
      zoom_x: 1.5
      presets:
        - {{name: gate, pan_deg: 30, tilt_deg: -20, zoom_x: 2}}
      program: {program}
  - name: overview
    profile: fixed
    mount: {{position_m: [0, -4, 3], yaw_deg: 90, pitch_deg: -12}}
outputs:
  video: true
  frames: png
  annotations: [mot]
"""


def write_world(
    directory: Path,
    *,
    duration_s: float = 1.0,
    start_x_m: float = -1.0,
    end_x_m: float = 8.0,
    speed_m_s: float = 1.5,
    program: str = "{type: hold}",
    illuminance_lux: float = 2000.0,
    dome_pan_deg: float = 0.0,
) -> Path:
    """The scene file (profiles beside it, in profiles/)."""
    write(directory, "profiles/ptz.yaml", PTZ_PROFILE)
    write(directory, "profiles/fixed.yaml", FIXED_PROFILE)
    text = SCENE.format(
        duration_s=duration_s,
        start_x_m=start_x_m,
        end_x_m=end_x_m,
        speed_m_s=speed_m_s,
        program=program,
        illuminance_lux=illuminance_lux,
        dome_pan_deg=dome_pan_deg,
    )
    return write(directory, "world.yaml", text)
