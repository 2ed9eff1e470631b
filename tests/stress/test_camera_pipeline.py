"""The whole camera (lens → sensor → ISP, `CameraPipeline`) from no light to light that saturates
every site, with auto-exposure running: every frame is finite and inside its ranges.

Built once from a small compiled job (as tests/plan/test_camera_pipeline.py does) with distortion,
lateral CA and vignetting, so the fused mosaic remap runs too. Radiance near float32's largest
(3.4e38) is left out: the bilinear remap's weighted sums overflow to inf there and inf·0 gives NaN,
which the sensor refuses with ValueError; a clamp of the rendered radiance would keep it finite.
"""

from __future__ import annotations

import functools
import math
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from camgen.config import load_scene
from camgen.plan import compile_scene
from camgen.plan.camera_pipeline import CameraPipeline, frame_rng
from camgen.render.renderer import Passes
from camgen.sensor.exposure import gain_linear
from tests.conftest import FIXED_PROFILE, SCENE, write
from tests.stress import stress_settings

PROFILE = FIXED_PROFILE.replace(
    "  min_focus_distance_m: 0.3\n",
    "  min_focus_distance_m: 0.3\n  distortion: {k1: -0.2, k2: 0.05}\n"
    "  chromatic_aberration: {lateral_scale_r: 1.002, lateral_scale_b: 0.998}\n"
    "  vignetting: {relative_illumination_corner: 0.6}\n",
).replace("  black_level_dn: 64\n", "  black_level_dn: 64\n  analog_gain_max_db: 30\n")


@functools.cache
def job_and_camera():
    workspace = Path(tempfile.mkdtemp(prefix="camgen-stress-"))
    write(workspace, "profiles/fixed.yaml", PROFILE)
    job = compile_scene(load_scene(write(workspace, "scenes/s.yaml", SCENE)))
    return job, job.cameras[0]


@stress_settings(6)
@given(
    light_cd_m2=st.lists(
        st.one_of(st.sampled_from([0.0, 1e-6, 1e30]), st.floats(0.0, 1e8)),
        min_size=1,
        max_size=4,
    ),
    seed=st.integers(0, 2**32 - 1),
)
def test_frames_stay_finite_and_in_range_from_darkness_to_saturation(light_cd_m2, seed):
    """Uniform radiance from 0 to 1e30 cd/m² (21 orders beyond the sun), frame after frame: raw DN within
    [0, 2^bits − 1], a black scene reads about the black level (within 8 DN: read noise, DSNU and
    1/30 s of dark current at 0.4 DN/e⁻), a blinding one reads the saturation clip at every site
    (the full well, K·G·10 000 e⁻ + 64 DN, or the 12-bit white, within 8σ of read noise and DSNU),
    the metered level is finite, and auto-exposure keeps its time and gain inside the camera's limits."""
    job, camera = job_and_camera()
    pipeline = CameraPipeline(job, camera)
    sensor = camera.profile.sensor
    spec = camera.render
    for index, light in enumerate(light_cd_m2):
        state = pipeline.state_for(0)
        passes = Passes(radiance=np.full((spec.height_px, spec.width_px, 3), light, np.float32))
        captured = pipeline.process(state, passes, rng=frame_rng(seed, 0, index))
        raw = captured.raw_dn
        assert raw.shape == (sensor.height_px, sensor.width_px) and raw.max() <= sensor.white_level_dn
        assert math.isfinite(captured.metered_level_frac)
        if light == 0.0:
            assert abs(float(np.median(raw)) - sensor.black_level_dn) <= 8
        if light >= 1e30:
            k = sensor.conversion_gain_dn_per_e * gain_linear(captured.state.gain_db)
            clip_dn = min(sensor.white_level_dn, k * sensor.full_well_e + sensor.black_level_dn)
            noise = sensor.noise
            sigma_dn = k * math.hypot(noise.read_noise_e, noise.dsnu_e, noise.row_fpn_e, noise.column_fpn_e)
            assert np.all(np.abs(raw - clip_dn) <= 8 * sigma_dn + 1)
        if captured.rgb8 is not None:
            assert captured.rgb8.shape == (sensor.height_px, sensor.width_px, 3) and captured.rgb8.dtype == np.uint8
        limits = pipeline.limits
        setting = pipeline.setting
        assert limits.exposure_time_min_s <= setting.exposure_time_s <= limits.exposure_time_max_s
        assert 0.0 <= setting.gain_db <= limits.gain_max_db + 1e-9
