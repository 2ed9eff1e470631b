"""Where auto-exposure settles for a steady light (`settled_exposure`, the camera pipeline's converged start and
fit match's exposure at a light): checked against the noise-free metered level written out from the sensor
model's definition, DN = min(black + K·G·min(e, full well), 2^bits − 1)."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.config.profile import Sensor
from camgen.sensor.auto_exposure import ExposureLimits, ExposureSetting, settled_exposure
from camgen.sensor.exposure import gain_linear

SENSOR = Sensor(
    width_px=64,
    height_px=48,
    pixel_pitch_um=3.0,
    bit_depth=12,
    full_well_e=10_000,
    conversion_gain_dn_per_e=0.35,
    black_level_dn=100,
    analog_gain_max_db=30.0,
)
LIMITS = ExposureLimits(exposure_time_min_s=1e-5, exposure_time_max_s=0.04, gain_max_db=30.0)
START = ExposureSetting(0.01, 0.0)


def metered_level(rate_e_per_s: np.ndarray, setting: ExposureSetting) -> float:
    electrons = np.minimum(rate_e_per_s * setting.exposure_time_s, SENSOR.full_well_e)
    dn = np.minimum(
        SENSOR.black_level_dn + SENSOR.conversion_gain_dn_per_e * gain_linear(setting.gain_db) * electrons,
        SENSOR.white_level_dn,
    )
    return float(np.mean(dn) - SENSOR.black_level_dn) / (SENSOR.white_level_dn - SENSOR.black_level_dn)


@pytest.mark.parametrize(
    ("rate_e_per_s", "target_frac", "rel"),
    [
        (np.full((10, 10), 200_000.0), 0.18, 1e-4),  # bright: a short exposure at unity gain
        (np.full((10, 10), 3_000.0), 0.18, 1e-4),  # dim: the longest exposure and some gain
        # Half the window clipped at any exposure (1.0 each), the other half metering 0.2 at the target: the
        # level is affine in the exposure, the multiplicative steps shrink by 0.5/0.6 each and stop at a step
        # of 1e-4, 0.14 % short of the target (measured)
        (np.concatenate([np.full(50, 1e12), np.full(50, 30_000.0)]), 0.6, 3e-3),
    ],
    ids=["bright", "dim", "half_clipped"],
)
def test_the_settled_setting_meters_at_the_target(rate_e_per_s, target_frac, rel):
    setting = settled_exposure(rate_e_per_s, START, sensor=SENSOR, target_frac=target_frac, limits=LIMITS)
    assert LIMITS.exposure_time_min_s <= setting.exposure_time_s <= LIMITS.exposure_time_max_s
    assert 0.0 <= setting.gain_db <= LIMITS.gain_max_db
    assert metered_level(rate_e_per_s, setting) == pytest.approx(target_frac, rel=rel)


def test_uniform_light_settles_at_the_closed_form_product():
    rate_e_per_s = np.full(100, 200_000.0)
    setting = settled_exposure(rate_e_per_s, START, sensor=SENSOR, target_frac=0.18, limits=LIMITS)
    range_dn = SENSOR.white_level_dn - SENSOR.black_level_dn
    product_s = 0.18 * range_dn / (200_000.0 * SENSOR.conversion_gain_dn_per_e)  # linear: no site clips
    assert setting.product_s == pytest.approx(product_s, rel=1e-4)
    assert setting.gain_db == 0.0  # time before gain


def test_the_limits_hold_where_the_target_is_out_of_reach():
    dark = settled_exposure(np.zeros(100), START, sensor=SENSOR, target_frac=0.18, limits=LIMITS)
    assert dark == ExposureSetting(LIMITS.exposure_time_max_s, LIMITS.gain_max_db)
    faint = settled_exposure(np.full(100, 1.0), START, sensor=SENSOR, target_frac=0.18, limits=LIMITS)
    assert faint == ExposureSetting(LIMITS.exposure_time_max_s, LIMITS.gain_max_db)
    blinding = settled_exposure(np.full(100, 1e12), START, sensor=SENSOR, target_frac=0.18, limits=LIMITS)
    assert blinding == ExposureSetting(LIMITS.exposure_time_min_s, 0.0)
