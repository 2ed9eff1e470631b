"""Edges of the fused sensor chain: round-off below zero, and the float32 path against float64."""

from __future__ import annotations

import numpy as np

from camgen.sensor.noise import Adc, TemporalNoise, sample_electrons, sample_raw

ADC = Adc(gain_dn_per_e=0.4, black_level_dn=64.0, bit_depth=12)


def test_round_off_below_zero_light_is_zero_light():
    # FFT convolutions of large blur discs leave values like −3e-12 where the light is zero.
    rate = np.zeros((40, 60), np.float32)
    rate[::3] = -3e-12
    raw = sample_raw(
        rate,
        per_unit=1.0,
        exposure_time_s=1.0,
        dark_e_per_s=0.0,
        offset_e=None,
        noise=TemporalNoise(read_noise_e=0.0),
        adc=ADC,
        rng=np.random.default_rng(0),
    )
    assert np.all(raw == 64)
    electrons = sample_electrons(-rate, read_noise_e=0.0, rng=np.random.default_rng(0))
    assert np.all(electrons >= 0)


def test_sample_raw_is_digitized_sample_electrons():
    """The fused chain draws exactly what the separate steps draw."""
    rng = np.random.default_rng(1)
    rate = rng.uniform(0, 3000, (51, 64)).astype(np.float32)
    offset = rng.normal(0, 1.5, rate.shape).astype(np.float32)
    noise = TemporalNoise(read_noise_e=2.5, full_well_e=2500.0, blooming=True)
    raw = sample_raw(
        rate,
        per_unit=0.5,
        exposure_time_s=2.0,
        dark_e_per_s=3.0,
        offset_e=offset,
        noise=noise,
        adc=ADC,
        rng=np.random.default_rng(7),
    )
    electrons = sample_electrons(
        rate * np.float32(1.0) + np.float32(6.0),
        read_noise_e=2.5,
        offset_e=offset,
        full_well_e=2500.0,
        blooming=True,
        rng=np.random.default_rng(7),
    )
    expected = np.clip(np.floor(electrons * np.float32(0.4) + np.float32(64.5)), 0, 4095).astype(np.uint16)
    assert np.abs(raw.astype(int) - expected).max() <= 1
    assert np.mean(raw != expected) < 1e-3
