"""ISP stress: tone curves and contrast stretch over every setting the schema allows, and raw frames
from 1 × 1 to 8K through demosaicing and the whole `CameraIsp`.

Closed forms: every tone curve is non-decreasing from curve(0) = 0 to curve(1) = 1; the 8-bit table
runs from 255·low to 255·high (rounded); a black frame (raw at the black level) comes out at the
table's black and a clipped frame (raw at the ADC's white) at its white, whatever the curve, gamma,
output range, white balance, CCM, bit depth or stretch.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from camgen.config.profile import Isp, Sensor
from camgen.isp.contrast import adapt_limits, limit_stretch_gain, stretch_limits
from camgen.isp.demosaic import DEMOSAIC_METHODS, MIN_SIZE_PX, demosaic
from camgen.isp.pipeline import FULL_SCALE, CameraIsp
from camgen.isp.tone import TONE_CURVES, tone_curve, tone_lut
from tests.stress import stress_settings

ALL_STEPS = {
    "isp.demosaic",
    "isp.white_balance",
    "isp.ccm",
    "isp.denoise",
    "isp.contrast_stretch",
    "isp.tone",
    "isp.sharpen",
}
gammas = st.floats(0.1, 5.0, exclude_min=True)
output_ranges = st.tuples(st.floats(0.0, 1.0), st.floats(0.0, 1.0)).filter(lambda r: r[0] < r[1])


@stress_settings(60)
@given(curve=st.sampled_from(TONE_CURVES), gamma=gammas, output_range=output_ranges)
def test_tone_curves_and_tables_are_monotone_and_in_range(curve, gamma, output_range):
    """Every curve is non-decreasing over [0, 1] (the BT.709 pieces meet with a +2.5e-4 step, not a
    drop), maps 0 → 0 and 1 → 1 (within 1e-12), and clips outside; its 65 536-entry table is
    non-decreasing from 255·low to 255·high, each rounded to the nearest code."""
    x = np.linspace(0.0, 1.0, 200_001)
    y = tone_curve(x, curve, gamma)
    assert np.isfinite(y).all() and np.all(np.diff(y) >= 0)
    assert abs(y[0]) <= 1e-12 and abs(y[-1] - 1.0) <= 1e-12
    np.testing.assert_array_equal(tone_curve(np.array([-1.0, 2.0, np.inf]), curve, gamma), [y[0], y[-1], y[-1]])
    low, high = output_range
    lut = tone_lut(curve, gamma, output_low_frac=low, output_high_frac=high)
    assert lut.dtype == np.uint8 and np.all(np.diff(lut.astype(int)) >= 0)
    # 255·low may be a tie (127.5), where curve(1) = 1 − 1e-16 rounds down: half a code either way.
    assert abs(lut[0] - 255 * low) <= 0.5 + 1e-9 and abs(lut[-1] - 255 * high) <= 0.5 + 1e-9


@stress_settings(60)
@given(
    samples=st.lists(st.integers(0, 65535), min_size=1, max_size=300),
    percentiles=st.tuples(st.floats(0.0, 100.0), st.floats(0.0, 100.0)).filter(lambda p: p[0] < p[1]),
    max_gain=st.floats(1.0, 1000.0),
    previous=st.one_of(st.none(), st.tuples(st.floats(0, 65535), st.floats(0, 65535))),
    adaptation_time_s=st.floats(0.0, 100.0),
    frame_interval_s=st.floats(1 / 240, 10.0),
)
def test_contrast_stretch_is_monotone_and_bounded(
    samples, percentiles, max_gain, previous, adaptation_time_s, frame_interval_s
):
    """The limits are np.percentile of the samples (high widened to ≥ low + 1); the gain limit keeps
    them inside [0, full scale] with a span ≥ full scale / max_gain (the stretch amplifies at most
    `max_gain` times); adaptation moves each limit part of the way towards its target, never past
    it; the stretch (x − lo)/(hi − lo) is then strictly increasing."""
    data = np.array(samples, np.uint16)
    low, high = stretch_limits(data, *percentiles, subsample=1)
    assert low == pytest.approx(np.percentile(data, percentiles[0]), abs=1e-9)
    assert high == pytest.approx(max(np.percentile(data, percentiles[1]), low + 1), abs=1e-9)
    lo, hi = limit_stretch_gain((low, high), full_scale=FULL_SCALE, max_gain=max_gain)
    assert hi - lo >= FULL_SCALE / max_gain * (1 - 1e-12) and hi > lo
    if high - low < FULL_SCALE / max_gain:
        assert 0.0 <= lo and hi <= FULL_SCALE * (1 + 1e-12)
    adapted = adapt_limits(previous, (lo, hi), frame_interval_s=frame_interval_s, adaptation_time_s=adaptation_time_s)
    start = (lo, hi) if previous is None else previous
    for value, begin, goal in zip(adapted, start, (lo, hi), strict=True):
        assert np.isfinite(value) and min(begin, goal) - 1e-9 <= value <= max(begin, goal) + 1e-9


@stress_settings(30)
@given(
    shape=st.sampled_from([(1, 1), (2, 2), (2, 7), (3, 3), (3, 4), (5, 7), (33, 17)]),
    cfa=st.sampled_from(["RGGB", "BGGR", "GRBG", "GBRG"]),
    method=st.sampled_from(DEMOSAIC_METHODS),
    level=st.integers(0, 65535),
)
@example(shape=(4320, 7680), cfa="RGGB", method="edge_aware", level=40000)
def test_demosaic_reproduces_a_flat_field_or_refuses_a_tiny_mosaic(shape, cfa, method, level):
    """Below 3 × 3 px OpenCV returns zeros, so `demosaic` refuses with a message naming the minimum;
    from 3 × 3 to 8K a flat mosaic comes back flat (exactly for bilinear and edge-aware; within the
    square-root companding step 2·√x + 1 DN for VNG)."""
    mosaic = np.full(shape, level, np.uint16)
    if min(shape) < MIN_SIZE_PX:
        with pytest.raises(ValueError, match="at least 3"):
            demosaic(mosaic, cfa, method)
        return
    rgb = demosaic(mosaic, cfa, method)
    assert rgb.shape == (*shape, 3) and rgb.dtype == np.uint16
    tolerance = 0 if method != "vng" else 2 * np.sqrt(level) + 1
    assert np.all(np.abs(rgb.astype(np.int64) - level) <= tolerance)


def _isp(curve, gamma, output_range, stretch, demosaic_method, wb_fixed, denoise_strength, sharpen_amount):
    return Isp(
        demosaic=demosaic_method,
        white_balance={"mode": "fixed", "gains_rgb": (1.8, 1.0, 1.4)} if wb_fixed else {"mode": "auto_grey_world"},
        ccm=((1.5, -0.35, -0.15), (-0.25, 1.4, -0.15), (-0.05, -0.45, 1.5)),
        contrast_stretch={"output_range_frac": output_range, "max_gain": 8.0} if stretch else None,
        tone_curve=curve,
        gamma=gamma,
        denoise_strength=denoise_strength,
        sharpen_amount=sharpen_amount,
    )


@stress_settings(40)
@given(
    shape=st.sampled_from([(1, 1), (1, 4), (2, 2), (3, 3), (4, 6), (5, 9), (48, 64)]),
    cfa=st.sampled_from(["RGGB", "BGGR", "GRBG", "GBRG", "mono"]),
    bit_depth=st.integers(8, 16),
    black_frac=st.floats(0.0, 0.5),
    curve=st.sampled_from(TONE_CURVES),
    gamma=gammas,
    output_range=output_ranges,
    stretch=st.booleans(),
    demosaic_method=st.sampled_from(DEMOSAIC_METHODS),
    wb_fixed=st.booleans(),
    denoise_strength=st.floats(0.0, 1.0),
    sharpen_amount=st.floats(0.0, 5.0),
    gain_db=st.floats(0.0, 72.0),
)
@example(
    shape=(4320, 7680),
    cfa="RGGB",
    bit_depth=12,
    black_frac=0.05,
    curve="bt709",
    gamma=2.2,
    output_range=(0.06, 0.92),
    stretch=True,
    demosaic_method="edge_aware",
    wb_fixed=False,
    denoise_strength=0.5,
    sharpen_amount=0.3,
    gain_db=6.0,
)
def test_black_and_clipped_frames_map_to_the_output_black_and_white(
    shape,
    cfa,
    bit_depth,
    black_frac,
    curve,
    gamma,
    output_range,
    stretch,
    demosaic_method,
    wb_fixed,
    denoise_strength,
    sharpen_amount,
    gain_db,
):
    """A raw frame at the black level comes out at the tone table's black (its first entry, 255·low rounded) and a
    frame at the ADC's white at its white (its last entry), in every channel and pixel (white balance
    gains ≥ 1 and CCM rows summing to 1 keep grey, the stretch of a flat frame is widened about it,
    denoise and sharpen keep flat images): shapes (H, W, 3) uint8 from 1 × 1 (mono) or 3 × 3 (Bayer,
    smaller refused with a message) up to 8K."""
    height, width = shape
    white = 2**bit_depth - 1
    sensor = Sensor(
        width_px=width,
        height_px=height,
        pixel_pitch_um=3.0,
        cfa=cfa,
        bit_depth=bit_depth,
        full_well_e=1e4,
        conversion_gain_dn_per_e=0.4,
        black_level_dn=round(black_frac * white),
        analog_gain_max_db=72.0,
    )
    low, high = output_range if stretch else (0.0, 1.0)
    isp = CameraIsp(
        _isp(curve, gamma, output_range, stretch, demosaic_method, wb_fixed, denoise_strength, sharpen_amount),
        sensor,
        frame_interval_s=0.04,
        steps=ALL_STEPS,
    )
    table = tone_lut(curve, gamma, output_low_frac=low, output_high_frac=high)
    frames = [
        (table[0], np.full(shape, sensor.black_level_dn, np.uint16)),
        (table[-1], np.full(shape, white, np.uint16)),
    ]
    for expected, raw in frames:
        if cfa != "mono" and min(shape) < MIN_SIZE_PX:
            with pytest.raises(ValueError, match="at least 3"):
                isp.process(raw, gain_db)
            return
        out = isp.process(raw, gain_db)
        assert out.shape == (height, width, 3) and out.dtype == np.uint8
        assert np.all(out == expected), (expected, np.unique(out))
        isp.limits = None  # a new scene: no adaptation from the previous frame


@stress_settings(30)
@given(
    bit_depth=st.integers(8, 16),
    curve=st.sampled_from(TONE_CURVES),
    gamma=gammas,
    output_range=output_ranges,
    stretch=st.booleans(),
    gain_db=st.floats(0.0, 72.0),
)
def test_a_mono_ramp_stays_monotone_through_the_isp(bit_depth, curve, gamma, output_range, stretch, gain_db):
    """Black level, scaling, stretch (an increasing affine map, clipped) and the tone table are all
    non-decreasing, so a raw ramp over the ADC's whole range stays non-decreasing in the 8-bit output,
    which spans the table's black to white."""
    white = 2**bit_depth - 1
    sensor = Sensor(
        width_px=257,
        height_px=3,
        pixel_pitch_um=3.0,
        cfa="mono",
        bit_depth=bit_depth,
        full_well_e=1e4,
        conversion_gain_dn_per_e=0.4,
        black_level_dn=round(0.05 * white),
        analog_gain_max_db=72.0,
    )
    isp = CameraIsp(
        _isp(curve, gamma, output_range, stretch, "bilinear", True, 0.0, 0.0),
        sensor,
        frame_interval_s=0.04,
        steps=ALL_STEPS - {"isp.denoise", "isp.sharpen"},
    )
    ramp = np.rint(np.linspace(0, white, 257)).astype(np.uint16)
    out = isp.process(np.tile(ramp, (3, 1)), gain_db)
    row = out[1, :, 0].astype(int)
    assert np.all(np.diff(row) >= 0)
    low, high = output_range if stretch else (0.0, 1.0)
    table = tone_lut(curve, gamma, output_low_frac=low, output_high_frac=high)
    assert row[0] == table[0] and row[-1] == table[-1]
