"""Sensor stress: exposure 1 µs–10 s, zero to saturating light, 8–16-bit ADCs, 1 × 1 to 8K sensors.

Raw DN must be finite integers in [0, 2^bits − 1]; zero light must read black level plus dark signal,
saturating light the full well (or the ADC's clip), and the noise must be unbiased: the sample mean of
n sites lies within 5 standard errors (σ/√n; a 5σ miss has probability 6·10⁻⁷) of the closed-form
expectation K·G·μ + black, on both sides of the Poisson/Gaussian switch `gaussian_above_e`. Rounding
is unbiased only when a smooth noise spans a DN (Poisson electrons alone lie on a lattice K DN
apart), so the unbiasedness cases keep the read noise ≥ 1 DN and stay 8σ clear of the clips.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, example, given
from hypothesis import strategies as st

from camgen.config.profile import Sensor
from camgen.sensor.capture import SensorModel
from camgen.sensor.characteristics import dark_current_e_per_s, saturation_e
from camgen.sensor.exposure import gain_linear
from camgen.sensor.noise import Adc, TemporalNoise, sample_raw
from tests.stress import stress_settings

SHAPES = st.sampled_from([(1, 1), (1, 2), (2, 1), (2, 2), (3, 5), (5, 3), (16, 16), (64, 96)])
FLOAT32_MAX = float(np.finfo(np.float32).max)


SIDE_PX = st.integers(1, 64)


def sensors(width_px=SIDE_PX, height_px=SIDE_PX):
    """Profile sensors over the schema's ranges (mono and Bayer, 8–16 bits, 0–72 dB, −40…105 °C, a full
    well of at least 10 read-noise σ)."""
    return st.builds(
        lambda w, h, pitch, cfa, bits, full_well, gain, black_frac, gain_max, temp, noise: Sensor(
            width_px=w,
            height_px=h,
            pixel_pitch_um=pitch,
            cfa=cfa,
            bit_depth=bits,
            full_well_e=full_well,
            conversion_gain_dn_per_e=gain,
            black_level_dn=black_frac * (2**bits - 1),
            analog_gain_max_db=gain_max,
            temperature_c=temp,
            # read noise a hair under full_well / 10: the profile's 10× rule must hold after rounding
            noise={**noise, "read_noise_e": min(noise["read_noise_e"], full_well / 10 * (1 - 1e-9))},
        ),
        width_px,
        height_px,
        st.floats(0.5, 100.0),
        st.sampled_from(["RGGB", "BGGR", "GRBG", "GBRG", "mono"]),
        st.integers(8, 16),
        st.floats(100.0, 1e6),
        st.floats(1e-3, 10.0),
        st.floats(0.0, 0.5),
        st.floats(0.0, 72.0),
        st.floats(-40.0, 105.0),
        st.fixed_dictionaries(
            {
                "read_noise_e": st.floats(0.0, 50.0),
                "prnu_pct": st.floats(0.0, 10.0),
                "dsnu_e": st.floats(0.0, 20.0),
                "row_fpn_e": st.floats(0.0, 5.0),
                "column_fpn_e": st.floats(0.0, 5.0),
                "dark_current_e_per_s": st.floats(0.0, 1e3),
                "hot_pixel_fraction": st.just(0.0),
                "blooming": st.booleans(),
                "shot_noise": st.booleans(),
            }
        ),
    )


@stress_settings(40)
@given(
    sensor=sensors(),
    exposure_time_s=st.floats(1e-6, 10.0),
    gain_frac=st.floats(0.0, 1.0),
    photon_rate=st.sampled_from([0.0, 1e3, 1e9, 1e20, FLOAT32_MAX, math.inf]),
    seed=st.integers(0, 2**32 - 1),
)
@example(  # found: a one-row sensor crashed in cv2.sqrt (an empty row band)
    sensor=Sensor(width_px=2, height_px=1, pixel_pitch_um=1.0, full_well_e=100.0, conversion_gain_dn_per_e=1.0),
    exposure_time_s=1.0,
    gain_frac=0.0,
    photon_rate=0.0,
    seed=0,
)
@example(  # found: infinite light read 0 DN at some sites (inf − inf = NaN in the noise)
    sensor=Sensor(
        width_px=1,
        height_px=5,
        pixel_pitch_um=1.0,
        bit_depth=8,
        full_well_e=100.0,
        conversion_gain_dn_per_e=1.0,
        noise={"read_noise_e": 0.0, "dsnu_e": 0.0, "blooming": False},
    ),
    exposure_time_s=1.0,
    gain_frac=0.0,
    photon_rate=math.inf,
    seed=0,
)
def test_raw_is_finite_and_within_the_adc_range_for_any_light(sensor, exposure_time_s, gain_frac, photon_rate, seed):
    """Any schema sensor at any exposure and gain, with light from none to beyond float32 (an
    infinite rate is the limit of ever brighter light): raw DN in [0, 2^bits − 1], and light that
    fills every well (≥ 1e20 photons/s, 1e14 e⁻ in 1 µs) reads the saturation clip at every live
    site — the ADC's white level, or K·G·full well + black rounded, within the read noise, DSNU and
    FPN (8σ) and the dark current that still adds below the clip."""
    gain_db = gain_frac * sensor.analog_gain_max_db
    model = SensorModel.build(sensor, serial=7)
    rate = np.full((sensor.height_px, sensor.width_px), photon_rate, np.float32)
    raw = model.capture(rate, exposure_time_s=exposure_time_s, gain_db=gain_db, rng=np.random.default_rng(seed))
    assert raw.dtype == np.uint16 and raw.shape == rate.shape
    assert raw.max() <= sensor.white_level_dn
    if photon_rate >= 1e20:
        response = model.electrons_per_photon
        live = np.broadcast_to(np.asarray(response) > 1e-6, raw.shape)  # PRNU is clipped at 0 (dead)
        noise = sensor.noise
        k = sensor.conversion_gain_dn_per_e * gain_linear(gain_db)
        sigma_e = math.sqrt(noise.read_noise_e**2 + noise.dsnu_e**2 + noise.row_fpn_e**2 + noise.column_fpn_e**2)
        clip_dn = min(sensor.white_level_dn, k * sensor.full_well_e + sensor.black_level_dn)
        assert np.all(raw[live] >= math.floor(clip_dn - 8 * k * sigma_e - 1))
        assert np.all(raw[live] <= math.ceil(clip_dn + 8 * k * sigma_e + 1))


@stress_settings(30)
@given(shape=SHAPES, exposure_time_s=st.floats(1e-6, 10.0), seed=st.integers(0, 2**32 - 1))
@example(shape=(1, 2), exposure_time_s=1.0, seed=0)
def test_any_sensor_size_down_to_one_pixel_samples(shape, exposure_time_s, seed):
    """The schema allows sensors from 1 × 1 px: the two row bands of `sample_raw` must cope with a
    band of no rows, and the output keep the shape, with the same draws with or without saturation."""
    rate = np.full(shape, 50.0, np.float32)
    raw = sample_raw(
        rate,
        per_unit=1.0,
        exposure_time_s=exposure_time_s,
        dark_e_per_s=0.0,
        offset_e=None,
        noise=TemporalNoise(read_noise_e=2.0, full_well_e=1e4, blooming=True),
        adc=Adc(gain_dn_per_e=1.0, black_level_dn=64.0, bit_depth=16),
        rng=np.random.default_rng(seed),
    )
    assert raw.shape == shape and raw.dtype == np.uint16
    expected = 64.0 + min(50.0 * exposure_time_s, 1e4)
    sigma = math.sqrt(min(50.0 * exposure_time_s, 1e4) + 4.0 + 1.0 / 12.0)
    assert np.all(np.abs(raw - expected) <= 6 * sigma + 1)


def test_nan_light_is_refused():
    """NaN light is no light level at all (a broken render): refused, not read as 0 DN."""
    rate = np.full((4, 4), 10.0, np.float32)
    rate[2, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        sample_raw(
            rate,
            per_unit=1.0,
            exposure_time_s=0.01,
            dark_e_per_s=0.0,
            offset_e=None,
            noise=TemporalNoise(read_noise_e=2.0, full_well_e=1e4),
            adc=Adc(gain_dn_per_e=1.0, black_level_dn=64.0, bit_depth=12),
            rng=np.random.default_rng(0),
        )


@stress_settings(30)
@given(
    mean_e=st.one_of(st.sampled_from([0.0, 0.3, 1.0, 19.5, 19.999, 20.0, 20.001, 20.5, 1e3]), st.floats(0.0, 3e4)),
    gaussian_above_e=st.sampled_from([20.0, 0.0, 5.0, 100.0, math.inf]),
    read_noise_e=st.floats(0.0, 20.0),
    gain_dn_per_e=st.floats(0.05, 8.0),
    bit_depth=st.integers(12, 16),
    shot_noise=st.booleans(),
    exposure_time_s=st.sampled_from([1e-6, 1e-3, 1.0, 10.0]),
    seed=st.integers(0, 2**32 - 1),
)
@example(
    mean_e=19.999,
    gaussian_above_e=20.0,
    read_noise_e=1.0,
    gain_dn_per_e=1.0,
    bit_depth=12,
    shot_noise=True,
    exposure_time_s=1e-6,
    seed=0,
)
@example(
    mean_e=20.001,
    gaussian_above_e=20.0,
    read_noise_e=1.0,
    gain_dn_per_e=1.0,
    bit_depth=12,
    shot_noise=True,
    exposure_time_s=10.0,
    seed=0,
)
def test_noise_is_unbiased_across_the_poisson_gaussian_switch(
    mean_e, gaussian_above_e, read_noise_e, gain_dn_per_e, bit_depth, shot_noise, exposure_time_s, seed
):
    """mean(DN) = K·μ + black within 5 standard errors, σ² = K²·(μ·[shot] + σ_read²) + 1/12 over
    n = 128 × 128 sites, for μ on both sides of the switch to the Gaussian approximation, at exposures
    from 1 µs to 10 s (the rate is μ/t) and 12–16-bit ADCs; the black level sits 8σ above 0 and the
    signal 8σ below the white level, so no clip biases the mean; read noise ≥ 1 DN, so no rounding
    does."""
    n = 128
    sigma_dn = gain_dn_per_e * math.sqrt(mean_e * shot_noise + read_noise_e**2)
    # Poisson electrons alone sit on a lattice K DN apart, which rounding biases (K = 2.5: 2.5 → 3);
    # read noise of ≥ 1 DN smooths it (the bias falls as exp(−2π²σ²), 3e-9 DN).
    assume(gain_dn_per_e * read_noise_e >= 1.0)
    black_dn = math.ceil(8 * sigma_dn) + 1
    expected_dn = gain_dn_per_e * mean_e + black_dn
    assume(expected_dn + 8 * sigma_dn <= 2**bit_depth - 1)
    raw = sample_raw(
        np.full((n, n), mean_e / exposure_time_s, np.float32),
        per_unit=1.0,
        exposure_time_s=exposure_time_s,
        dark_e_per_s=0.0,
        offset_e=None,
        noise=TemporalNoise(read_noise_e=read_noise_e, shot_noise=shot_noise, gaussian_above_e=gaussian_above_e),
        adc=Adc(gain_dn_per_e=gain_dn_per_e, black_level_dn=float(black_dn), bit_depth=bit_depth),
        rng=np.random.default_rng(seed),
    )
    # μ passes through float32 (rate and t): its relative rounding, 1e-7, is far inside the bound.
    standard_error = math.sqrt(sigma_dn**2 + 1.0 / 12.0) / n
    assert abs(raw.mean(dtype=np.float64) - expected_dn) <= 5 * standard_error + 2e-7 * expected_dn


@stress_settings(25)
@given(
    sensor=sensors(width_px=st.just(96), height_px=st.just(64)),
    exposure_time_s=st.floats(1e-6, 10.0),
    seed=st.integers(0, 2**32 - 1),
)
def test_zero_light_reads_black_plus_dark_signal(sensor, exposure_time_s, seed):
    """With no light every site holds its dark signal D(T)·t (dark current doubling every
    `dark_current_doubling_c`) plus zero-mean DSNU, FPN and read noise: the mean DN is
    black + K·D(T)·t within 5 standard errors of the temporal noise plus the fixed patterns' own
    sample means (DSNU σ/√n, row σ/√H, column σ/√W), wherever the clips stay 8σ away."""
    noise = sensor.noise
    k = sensor.conversion_gain_dn_per_e
    dark_e = (
        dark_current_e_per_s(
            noise.dark_current_e_per_s,
            sensor.temperature_c,
            noise.dark_current_reference_c,
            noise.dark_current_doubling_c,
        )
        * exposure_time_s
    )
    assume(dark_e < 0.5 * sensor.full_well_e)
    height, width = sensor.height_px, sensor.width_px
    temporal_dn = k * math.sqrt(dark_e * noise.shot_noise + noise.read_noise_e**2)
    pixel_dn = k * math.sqrt(noise.dsnu_e**2 + noise.row_fpn_e**2 + noise.column_fpn_e**2)
    assume(k * noise.read_noise_e >= 1.0)  # smooth at the DN scale: rounding unbiased (see above)
    expected_dn = sensor.black_level_dn + k * dark_e
    spread_dn = math.sqrt(temporal_dn**2 + pixel_dn**2)
    assume(expected_dn - 8 * spread_dn >= 0 and expected_dn + 8 * spread_dn <= sensor.white_level_dn)
    model = SensorModel.build(sensor, serial=11)
    raw = model.capture(
        np.zeros((height, width), np.float32), exposure_time_s=exposure_time_s, rng=np.random.default_rng(seed)
    )
    n = height * width
    standard_error = math.sqrt(
        (temporal_dn**2 + 1 / 12 + (k * noise.dsnu_e) ** 2) / n
        + (k * noise.row_fpn_e) ** 2 / height
        + (k * noise.column_fpn_e) ** 2 / width
    )
    assert abs(raw.mean(dtype=np.float64) - expected_dn) <= 5 * standard_error + 1e-6 * expected_dn


@stress_settings(20)
@given(
    full_well_e=st.floats(100.0, 1e6),
    gain_dn_per_e=st.floats(1e-3, 10.0),
    bit_depth=st.integers(8, 16),
    gain_db=st.floats(0.0, 72.0),
)
def test_saturation_level_is_the_lower_of_full_well_and_adc(full_well_e, gain_dn_per_e, bit_depth, gain_db):
    """`saturation_e` reports whichever clips first, in electrons: the ADC's (2^bits − 1 − black)/(K·G)
    or the full well; it never exceeds either."""
    black = 0.1 * (2**bit_depth - 1)
    electrons, limit = saturation_e(full_well_e, gain_dn_per_e, black, bit_depth, gain_db)
    adc_e = (2**bit_depth - 1 - black) / (gain_dn_per_e * gain_linear(gain_db))
    assert math.isfinite(electrons) and electrons == min(adc_e, full_well_e)
    assert limit == ("ADC" if adc_e < full_well_e else "full well")
