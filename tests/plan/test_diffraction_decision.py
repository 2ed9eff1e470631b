"""The plan keeps `optics.diffraction` only where the kernel it applies changes a pixel: the Airy pattern's
Gaussian (σ = 0.42·λ·N) sampled on the sensor's pixels, whose off-centre taps must weigh more than float32's
resolution (2⁻²⁴) of its centre. The Airy disc's diameter, on which the plan decided before, is 5.8σ: a
disc of 0.95 px is a kernel whose neighbour taps are 1e-8 of its centre."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from camgen.config import load_scene
from camgen.job import Stage
from camgen.plan import compile_scene
from camgen.plan import lens_stages as lens_stages_module
from camgen.plan.camera_pipeline import CameraPipeline, frame_rng
from camgen.plan.lens_stages import LensStages
from tests.conftest import FIXED_PROFILE, SCENE, write

FLOAT32_RESOLUTION = 2.0**-24
SHORT_EXPOSURE = "exposure: {mode: manual, exposure_time_s: 0.0005}\n"  # no motion blur: no blur margin


def closed_form_weight(f_number, pitch_um, wavelength_um):
    """(1 + s)² − 1, s = 2·Σ_{k=1…⌈4σ⌉} exp(−k²/2σ²): the sampled 2-D Gaussian's off-centre weight over its centre."""
    sigma = 0.42 * wavelength_um * f_number / pitch_um
    s = 2 * sum(math.exp(-(k**2) / (2 * sigma**2)) for k in range(1, math.ceil(4 * sigma) + 1))
    return 2 * s + s * s


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
        (1.6, 4.35, "RGGB", 0.60),  # the 30× dome at 1280×720, wide: σ = 0.093 px, neighbour taps 5e-26
        (1.0, 3.0, "RGGB", 0.60),  # σ = 0.084 px
        (1.95, 3.0, "RGGB", 0.60),  # σ = 0.164 px, just under the threshold (0.1666 px)
        (2.0, 3.0, "RGGB", 0.60),  # σ = 0.168 px, just over it
        (4.4, 4.35, "RGGB", 0.60),  # the dome at 1280×720, tele: σ = 0.255 px
        (8.0, 2.0, "RGGB", 0.60),  # σ = 1.0 px
        (2.1, 3.0, "mono", 0.55),  # one λ for a mono sensor: σ = 0.162 px, under
        (2.2, 3.0, "mono", 0.55),  # σ = 0.169 px, over
    ],
)
def test_diffraction_is_planned_where_its_sampled_kernel_is_not_the_identity(
    workspace, f_number, pitch_um, cfa, wavelength_um
):
    camera = plan(workspace, f_number, pitch_um, cfa)
    d = diffraction(camera)
    weight = closed_form_weight(f_number, pitch_um, wavelength_um)
    assert d.effect == pytest.approx(weight, rel=1e-5)
    assert d.threshold == FLOAT32_RESOLUTION and d.unit == "relative"
    assert d.included == (weight > FLOAT32_RESOLUTION)
    assert ("optics.diffraction" in [s.name for s in camera.stages]) == d.included
    # Without distortion, motion or defocus, the margin is the kernel's reach or nothing.
    sigma_red_px = 0.42 * 0.60 * f_number / pitch_um
    expected_margin = math.ceil(4 * sigma_red_px) if d.included else 0
    assert camera.render.margin_px == (expected_margin,) * 4
    if not d.included:
        assert "the identity" in d.reason


def test_a_wide_airy_disc_with_an_identity_kernel_is_skipped(workspace):
    """f/1.95 on 3 µm: an Airy disc of 0.95 px (over the 0.5 px blur threshold the plan compared it with)
    whose Gaussian's neighbour taps are 8e-9 of its centre: skipped, with no render margin."""
    camera = plan(workspace, 1.95, 3.0)
    assert 2.44 * 0.60 * 1.95 / 3.0 > 0.5
    assert not diffraction(camera).included
    assert camera.render.margin_px == (0, 0, 0, 0)


def _convolved_everywhere(radiance, *, f_number, pixel_pitch_um, mono=False):
    """The stage without its identity shortcut: every channel through cv2.GaussianBlur at its own σ."""
    out = np.empty_like(radiance)
    wavelengths = (0.55,) * 3 if mono else (0.60, 0.53, 0.46)
    for c, wavelength in enumerate(wavelengths):
        sigma = 0.42 * wavelength * f_number / pixel_pitch_um
        size = 2 * math.ceil(4 * sigma) + 1
        out[..., c] = cv2.GaussianBlur(
            np.ascontiguousarray(radiance[..., c]), (size, size), sigma, borderType=cv2.BORDER_REFLECT
        )
    return out


@pytest.mark.opengl
def test_where_the_plan_skips_diffraction_the_convolution_changes_no_delivered_pixel(workspace, renderer, monkeypatch):
    """A rendered frame just under the threshold (f/1.95 on 3 µm, σ = 0.164 px in red): the radiance
    convolved with every channel's kernel differs from the unblurred one by at most the kernel's off-centre
    weight times a pixel's largest neighbour difference, and the delivered raw and 8-bit frames are the
    same bytes."""
    from camgen.render.sequence import render_camera

    write(workspace, "profiles/fixed.yaml", FIXED_PROFILE.replace("f_number: 2.0", "f_number: 1.95") + SHORT_EXPOSURE)
    job = compile_scene(load_scene(write(workspace, "scenes/s.yaml", SCENE)))
    camera = job.cameras[0]
    weight = diffraction(camera).effect
    assert not diffraction(camera).included and 0 < weight <= FLOAT32_RESOLUTION
    at = [s.name for s in camera.stages].index("sensor.exposure")
    forced = Stage(name="optics.diffraction", passes=("radiance",))
    blurred = camera.model_copy(update={"stages": (*camera.stages[:at], forced, *camera.stages[at:])})
    monkeypatch.setattr(lens_stages_module, "diffraction_blur", _convolved_everywhere)
    k = 4
    frame = next(render_camera(renderer, job, camera, frames=[k]))
    state = camera.states[k]
    sharp = LensStages(camera).blur(state, frame.passes)
    convolved = LensStages(blurred).blur(state, frame.passes)
    assert sharp is frame.passes.radiance and convolved is not sharp
    padded = np.pad(sharp, ((1, 1), (1, 1), (0, 0)), mode="symmetric").astype(np.float64)
    h, w = sharp.shape[:2]
    neighbour_difference = np.max(
        [np.abs(padded[1 + dy : 1 + dy + h, 1 + dx : 1 + dx + w] - sharp) for dy in (-1, 0, 1) for dx in (-1, 0, 1)],
        axis=0,
    )
    assert np.all(np.abs(convolved.astype(np.float64) - sharp) <= weight * neighbour_difference + np.spacing(sharp))
    delivered = []
    for camera_job in (camera, blurred):
        pipeline = CameraPipeline(job, camera_job)
        delivered.append(pipeline.process(pipeline.state_for(k), frame.passes, rng=frame_rng(job.seed, 0, k)))
    np.testing.assert_array_equal(delivered[0].raw_dn, delivered[1].raw_dn)
    np.testing.assert_array_equal(delivered[0].rgb8, delivered[1].rgb8)
