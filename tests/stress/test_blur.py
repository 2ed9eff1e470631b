"""Blur kernels conserve energy and leave a constant image constant, over the schema's ranges.

Diffraction (f-number 0.5–64, pitch 0.5–100 µm), depth of field (any signed CoC map), axial CA (disc
kernels up to the |shift|/N/p that ±500 µm allows), motion blur (sub-frame averaging), and the 8-bit
denoise and sharpen stages. Sums are compared in float64 against float32 outputs: a relative 1e-5 is
a few float32 ulps accumulated over the kernel.
"""

from __future__ import annotations

import cv2
import numpy as np
from hypothesis import example, given
from hypothesis import strategies as st

from camgen.isp.enhance import denoise, sharpen
from camgen.optics.depth_of_field import disc_kernel, layered_blur
from camgen.optics.diffraction import CHANNEL_WAVELENGTHS_UM, airy_sigma_px, diffraction_blur
from camgen.optics.motion_blur import sub_frame_count, sub_frame_offsets
from tests.stress import stress_settings

TINY_AND_ODD = st.sampled_from([(1, 1), (1, 2), (2, 1), (2, 2), (3, 5), (7, 4), (17, 31), (64, 48)])


@stress_settings(40)
@given(
    f_number=st.floats(0.5, 64.0),
    pitch_um=st.floats(0.5, 100.0),
    mono=st.booleans(),
    level=st.one_of(st.just(0.0), st.floats(1e-6, 1e6)),
)
def test_diffraction_conserves_energy_and_has_the_airy_width(f_number, pitch_um, mono, level):
    """An impulse far from the border keeps its energy (sum 1 within 1e-5) and spreads with the
    second moment of the Airy Gaussian, σ² = (0.42·λ·N/p)² per axis (within 3 % where σ ≥ 1 px; the
    kernel is truncated at ±4σ, which removes 0.3 % of the variance); a constant image stays constant
    everywhere (the border is mirrored)."""
    sigma_max = airy_sigma_px(f_number, pitch_um, max(CHANNEL_WAVELENGTHS_UM))
    half = int(np.ceil(4 * sigma_max)) + 2
    size = 2 * half + 1
    impulse = np.zeros((size, size, 3), np.float32)
    impulse[half, half] = 1.0
    out = diffraction_blur(impulse, f_number=f_number, pixel_pitch_um=pitch_um, mono=mono)
    assert np.isfinite(out).all() and out.min() >= 0.0
    np.testing.assert_allclose(out.sum(axis=(0, 1), dtype=np.float64), 1.0, rtol=1e-5)
    offsets = np.arange(size) - half
    for channel in range(3):
        wavelength = 0.55 if mono else CHANNEL_WAVELENGTHS_UM[channel]
        sigma = airy_sigma_px(f_number, pitch_um, wavelength)
        marginal = out[..., channel].sum(axis=0, dtype=np.float64)
        variance = float(np.sum(marginal * offsets**2) / marginal.sum())
        if sigma >= 1.0:
            assert abs(variance / sigma**2 - 1.0) < 0.03
    flat = np.full((9, 11, 3), level, np.float32)
    np.testing.assert_allclose(
        diffraction_blur(flat, f_number=f_number, pixel_pitch_um=pitch_um, mono=mono), level, rtol=1e-6
    )


@stress_settings(40)
@given(
    shape=TINY_AND_ODD,
    coc_max_px=st.floats(0.0, 40.0),
    level=st.floats(0.0, 1e5),
    seed=st.integers(0, 2**32 - 1),
)
@example(shape=(1, 1), coc_max_px=30.0, level=1.0, seed=0)
def test_layered_depth_of_field_keeps_a_constant_image_constant(shape, coc_max_px, level, seed):
    """Premultiplied compositing divided by the coverage is a weighted mean of radiances: a constant
    radiance stays that constant under any signed CoC map (every depth order, discs far larger than
    the frame, 1 × 1 images), within float32 rounding (1e-5 relative)."""
    rng = np.random.default_rng(seed)
    coc = rng.uniform(-coc_max_px, coc_max_px, shape).astype(np.float32)
    radiance = np.full((*shape, 3), level, np.float32)
    out = layered_blur(radiance, coc)
    assert out.shape == radiance.shape and np.isfinite(out).all()
    np.testing.assert_allclose(out, level, rtol=1e-5, atol=1e-30)


@stress_settings(30)
@given(coc_px=st.floats(-40.0, 40.0), seed=st.integers(0, 2**32 - 1))
def test_layered_depth_of_field_conserves_the_energy_of_one_plane(coc_px, seed):
    """A single plane (one CoC everywhere) is one disc convolution: random radiance inside a frame
    with an empty border wider than the disc keeps its total (1e-5 relative), and the coverage
    division changes nothing (coverage 1 everywhere). Large discs are convolved by FFT, which leaves
    round-off of ±1e-13 of the peak where the light is zero (the sensor clamps it): the output is
    non-negative to 1e-6 of its maximum."""
    half = int(np.ceil(abs(coc_px) / 2)) + 1
    inner = np.random.default_rng(seed).uniform(0.0, 1000.0, (9, 13, 3)).astype(np.float32)
    radiance = cv2.copyMakeBorder(inner, half, half, half, half, cv2.BORDER_CONSTANT, value=(0, 0, 0))
    out = layered_blur(radiance, np.full(radiance.shape[:2], coc_px, np.float32))
    assert np.isfinite(out).all() and out.min() >= -1e-6 * out.max()
    np.testing.assert_allclose(
        out.sum(axis=(0, 1), dtype=np.float64), inner.sum(axis=(0, 1), dtype=np.float64), rtol=1e-5
    )


@stress_settings(40)
@given(shift_um=st.floats(-500.0, 500.0), f_number=st.floats(0.5, 64.0), pitch_um=st.floats(0.5, 100.0))
@example(shift_um=500.0, f_number=0.5, pitch_um=3.0)  # the largest axial-CA disc at a common pitch (333 px)
def test_axial_ca_disc_conserves_energy(shift_um, f_number, pitch_um):
    """The axial-CA blur is a disc of diameter |shift|/N/p (`camgen.plan.lens_stages`): its kernel is
    non-negative, symmetric, sums to 1 within float32 rounding, and its marginal has the documented
    variance R²/4 + 1/12 px² of the disc convolved with the pixel box — up to the sampling of that at
    pixel centres, measured at most 0.146 px² off (at D = 1 px, where the kernel becomes the
    identity) and 0.5 % for R ≥ 5 px over D = 0…60 px in steps of 0.01; a constant channel stays
    constant under it."""
    diameter_px = abs(shift_um) / f_number / pitch_um
    kernel = disc_kernel(diameter_px)
    assert kernel.dtype == np.float32 and kernel.shape[0] % 2 == 1 and kernel.min() >= 0.0
    np.testing.assert_allclose(kernel.sum(dtype=np.float64), 1.0, rtol=1e-5)
    np.testing.assert_array_equal(kernel, kernel.T)
    np.testing.assert_array_equal(kernel, kernel[::-1])
    radius = diameter_px / 2
    offsets = np.arange(kernel.shape[0]) - kernel.shape[0] // 2
    variance = float(np.sum(kernel.sum(axis=0, dtype=np.float64) * offsets**2))
    expected = radius**2 / 4 + 1 / 12
    assert abs(variance - expected) <= 0.15
    if radius >= 5.0:
        assert abs(variance / expected - 1.0) < 0.01
    flat = np.full((5, 6), 123.25, np.float32)
    np.testing.assert_allclose(cv2.filter2D(flat, -1, kernel, borderType=cv2.BORDER_REFLECT), 123.25, rtol=1e-5)


@stress_settings(60)
@given(displacement_px=st.floats(0.0, 1e6), step_px=st.floats(0.05, 10.0), samples_max=st.integers(2, 256))
def test_motion_blur_sub_frames_average_to_a_centred_box(displacement_px, step_px, samples_max):
    """The n sub-frames sit at evenly spaced times inside the exposure, centred on the frame time
    (mean offset 0 within 1e-12), so their mean is a box filter of unit weight centred on the frame;
    n is 1 below the half-pixel threshold, else between 2 and the cap, and never falls as the
    motion grows."""
    count = sub_frame_count(displacement_px, step_px=step_px, samples_max=samples_max)
    assert 1 <= count <= samples_max
    assert (count == 1) == (displacement_px <= 0.5)
    assert sub_frame_count(displacement_px * 2, step_px=step_px, samples_max=samples_max) >= count
    offsets = sub_frame_offsets(count)
    assert offsets.shape == (count,) and np.all(np.abs(offsets) < 0.5)
    assert abs(offsets.mean()) < 1e-12
    np.testing.assert_allclose(np.diff(offsets), 1.0 / count, rtol=1e-9)


@stress_settings(40)
@given(
    shape=TINY_AND_ODD,
    colour=st.booleans(),
    level=st.integers(0, 255),
    strength=st.floats(0.0, 1.0),
    amount=st.floats(0.0, 5.0),
    radius_px=st.floats(1e-3, 50.0),
)
def test_denoise_and_sharpen_keep_a_constant_image_constant(shape, colour, level, strength, amount, radius_px):
    """Bilateral denoise (weights normalised) and the unsharp mask ((1 + a)·I − a·G∗I with a
    normalised Gaussian) leave a flat 8-bit image exactly as it was, at any strength, amount and
    radius the ISP schema allows, on images down to 1 × 1."""
    image = np.full((*shape, 3) if colour else shape, level, np.uint8)
    denoised = denoise(image, strength)
    np.testing.assert_array_equal(denoised, image)
    np.testing.assert_array_equal(sharpen(denoised, amount, radius_px), image)
