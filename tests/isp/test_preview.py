"""The preview's exposure and sRGB encoding against their closed forms."""

from __future__ import annotations

import numpy as np

from camgen.isp.preview import preview_exposure_scale, preview_srgb8, srgb_encode


def test_srgb_reference_values():
    # IEC 61966-2-1: 0.0031308 → 0.04045 (the joint), 0.18 → 0.4613561, 1 → 1.
    np.testing.assert_allclose(
        srgb_encode(np.array([0.0, 0.0031308, 0.18, 1.0, 2.0])), [0, 0.04045, 0.4613561, 1, 1], atol=1e-6
    )


def test_log_average_maps_to_the_key():
    radiance = np.ones((4, 4, 3), np.float32)
    radiance[:2] *= 100.0  # log-average luminance is 10
    assert np.isclose(preview_exposure_scale(radiance, key=0.18), 0.018, rtol=1e-6)
    assert preview_exposure_scale(np.zeros((2, 2, 3), np.float32)) == 1.0


def test_preview_is_8_bit_and_clips_highlights():
    radiance = np.array([[[0.0, 0.5, 1e6]]], np.float32)
    np.testing.assert_array_equal(preview_srgb8(radiance, 1.0), [[[0, 188, 255]]])
