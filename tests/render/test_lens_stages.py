"""The lens stages as the plan wires them: skipping a stage under its threshold changes the image by
less than the threshold (DESIGN.md), and the output frame is what the profile says it is."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.plan import PlanSettings, compile_scene
from camgen.plan.lens_stages import LensStages
from camgen.render.sequence import render_camera
from tests.conftest import FIXED_PROFILE, SCENE, write

pytestmark = pytest.mark.opengl

# Every lens effect present but under its threshold: a 0.003 px distortion, a 0.003 px colour fringe,
# 0.2 % corner falloff and 0.1 px of motion in 0.5 ms; and diffraction (f/1.0 on 3 µm, σ = 0.084 px), which has
# no threshold: its discrete kernel changes pixels at any aperture, so the plan keeps it (camgen.optics.diffraction).
FAINT = FIXED_PROFILE.replace("f_number: 2.0", "f_number: 1.0") + (
    "  distortion: {k1: 0.00001}\n"
    "  chromatic_aberration: {lateral_scale_r: 1.00001, lateral_scale_b: 0.99999}\n"
    "  vignetting: {relative_illumination_corner: 0.998}\n"
    "exposure: {mode: manual, exposure_time_s: 0.0005}\n"
)


def _output(renderer, workspace, force: bool):
    write(workspace, "profiles/fixed.yaml", FAINT)
    job = compile_scene(
        load_scene(write(workspace, "scenes/s.yaml", SCENE + "outputs: {annotations: [mot]}\n")),
        PlanSettings(force_all_stages=force),
    )
    camera = job.cameras[0]
    frame = next(render_camera(renderer, job, camera, frames=[4]))
    return camera, LensStages(camera).apply(camera.states[4], frame.passes)


def test_skipping_faint_lens_effects_changes_the_image_by_less_than_their_thresholds(workspace, renderer):
    skipped_camera, skipped = _output(renderer, workspace, force=False)
    forced_camera, forced = _output(renderer, workspace, force=True)
    skipped_stages = {s.name for s in skipped_camera.stages if s.name.startswith("optics.")}
    forced_stages = {s.name for s in forced_camera.stages if s.name.startswith("optics.")}
    assert skipped_stages == {"optics.diffraction"}
    assert forced_stages >= {"optics.remap", "optics.vignetting", "optics.diffraction", "optics.motion_blur"}
    assert forced.radiance.shape == skipped.radiance.shape == (480, 640, 3)
    np.testing.assert_array_equal(forced.instance_id, skipped.instance_id)  # 0.003 px moves no pixel centre
    relative = np.abs(forced.radiance - skipped.radiance) / np.maximum(skipped.radiance, 1e-6)
    # Away from edges the difference is the vignetting under its 0.5 % threshold; at edges a
    # sub-threshold shift or blur moves a few pixels by more, but only a few.
    assert np.median(relative) < 0.005
    assert np.mean(relative > 0.005) < 0.01
