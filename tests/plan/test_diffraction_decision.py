"""The plan keeps `optics.diffraction` wherever the kernel it applies changes a pixel: the Airy pattern's Gaussian
(σ = 0.42·λ·N) as the discrete Gaussian of that variance (`camgen.optics.diffraction`), whose off-centre taps must
weigh more than float32's resolution (2⁻²⁴) of its centre — about 2σ², so at any real aperture; its reach sets the
render margin."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.plan import compile_scene
from camgen.plan.camera_pipeline import CameraPipeline, frame_rng
from camgen.plan.lens_stages import LensStages
from tests.conftest import FIXED_PROFILE, SCENE, write

FLOAT32_RESOLUTION = 2.0**-24
SHORT_EXPOSURE = "exposure: {mode: manual, exposure_time_s: 0.0005}\n"  # no motion blur: no blur margin


def plan(workspace, f_number, pitch_um, cfa="RGGB", name="s.yaml"):
    profile = (
        FIXED_PROFILE.replace("f_number: 2.0", f"f_number: {f_number}")
        .replace("pixel_pitch_um: 3.0", f"pixel_pitch_um: {pitch_um}")
        .replace("cfa: RGGB", f"cfa: {cfa}")
    )
    write(workspace, "profiles/fixed.yaml", profile + SHORT_EXPOSURE)
    return compile_scene(load_scene(write(workspace, f"scenes/{name}", SCENE))).cameras[0]


def diffraction(camera):
    (d,) = [d for d in camera.decisions if d.stage == "optics.diffraction"]
    return d


@pytest.mark.parametrize(
    ("f_number", "pitch_um", "cfa", "wavelength_um"),
    [
        (1.6, 4.35, "RGGB", 0.60),  # the 30× dome at 1280×720, wide: σ = 0.093 px, off-centre weight 0.017
        (1.6, 2.9, "RGGB", 0.60),  # the 2.9 µm bullet at f/1.6: σ = 0.139 px
        (4.4, 4.35, "RGGB", 0.60),  # the dome at 1280×720, tele: σ = 0.255 px
        (8.0, 2.0, "RGGB", 0.60),  # σ = 1.0 px
        (1.6, 3.0, "mono", 0.55),  # one λ for a mono sensor: σ = 0.123 px
    ],
)
def test_diffraction_is_planned_wherever_its_discrete_kernel_changes_a_pixel(
    workspace, f_number, pitch_um, cfa, wavelength_um
):
    from camgen.optics.diffraction import kernel_taps

    camera = plan(workspace, f_number, pitch_um, cfa)
    d = diffraction(camera)
    sigma_px = 0.42 * wavelength_um * f_number / pitch_um
    taps = kernel_taps(sigma_px).astype(np.float64)
    centre = len(taps) // 2
    s = (taps.sum() - taps[centre]) / taps[centre]
    assert d.effect == pytest.approx(2 * s + s * s, rel=1e-6)
    if sigma_px < 0.3:
        assert d.effect == pytest.approx(2 * sigma_px**2, rel=0.1)  # about 2σ² under a third of a pixel
    assert d.threshold == FLOAT32_RESOLUTION and d.unit == "relative"
    assert d.included and "optics.diffraction" in [s.name for s in camera.stages]
    # Without distortion, motion or defocus, the margin is the kernel's reach, ⌈4σ⌉ + 1 in red.
    sigma_red_px = 0.42 * 0.60 * f_number / pitch_um
    assert camera.render.margin_px == (math.ceil(4 * sigma_red_px) + 1,) * 4


def test_a_pinhole_sized_kernel_is_skipped(workspace):
    """Only a kernel at float32's resolution is skipped: the decision's function at f/0.5 on 2 mm pixels (σ = 6e-5
    px, weight 8e-9 under 2⁻²⁴) and on 50 µm pixels (σ = 2.5e-3 px, weight 1.3e-5 over it)."""
    from camgen.optics.diffraction import diffraction_effect_rel

    assert diffraction_effect_rel(0.5, 2000.0) < FLOAT32_RESOLUTION < diffraction_effect_rel(0.5, 50.0)


@pytest.mark.opengl
def test_a_planned_diffraction_blurs_the_delivered_frame_by_its_variance(workspace, renderer):
    """The 2.9 µm bullet at f/1.6 (σ 0.14 px in green): planned, and the frame's radiance through the stage is the
    rendered one convolved with the discrete Gaussian of each channel's variance; the delivered 8-bit frame differs
    from the unblurred one (before, the sampled Gaussian left it as it was)."""
    from camgen.optics.diffraction import kernel_taps
    from camgen.render.sequence import render_camera

    write(
        workspace,
        "profiles/fixed.yaml",
        FIXED_PROFILE.replace("f_number: 2.0", "f_number: 1.6").replace("pixel_pitch_um: 3.0", "pixel_pitch_um: 2.9")
        + SHORT_EXPOSURE,
    )
    job = compile_scene(load_scene(write(workspace, "scenes/s.yaml", SCENE)))
    camera = job.cameras[0]
    assert diffraction(camera).included
    k = 4
    frame = next(render_camera(renderer, job, camera, frames=[k]))
    state = camera.states[k]
    sharp = frame.passes.radiance.copy()
    blurred = LensStages(camera).blur(state, frame.passes)
    import cv2

    for c, wavelength in enumerate((0.60, 0.53, 0.46)):
        taps = kernel_taps(0.42 * wavelength * 1.6 / 2.9)
        reference = cv2.sepFilter2D(sharp[..., c], cv2.CV_64F, taps, taps, borderType=cv2.BORDER_REFLECT)
        np.testing.assert_allclose(blurred[..., c], reference, rtol=1e-4, atol=1e-4 * float(sharp.max()))
    without = camera.model_copy(update={"stages": tuple(s for s in camera.stages if s.name != "optics.diffraction")})
    delivered = []
    for camera_job in (camera, without):
        pipeline = CameraPipeline(job, camera_job)
        delivered.append(pipeline.process(pipeline.state_for(k), frame.passes, rng=frame_rng(job.seed, 0, k)))
    assert not np.array_equal(delivered[0].rgb8, delivered[1].rgb8)
