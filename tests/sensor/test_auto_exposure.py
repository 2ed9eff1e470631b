"""Auto-exposure arithmetic: how the exposure product splits, how fast it moves, what it meters."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.sensor.auto_exposure import (
    ExposureLimits,
    ExposureSetting,
    frames_to_adapt,
    metered_level_frac,
    metering_window,
    next_exposure,
    split_exposure,
)
from camgen.sensor.exposure import gain_db, gain_linear, photons_per_cd_m2_s

LIMITS = ExposureLimits(exposure_time_min_s=1e-5, exposure_time_max_s=0.04, gain_max_db=30.0)


def test_time_first_then_gain_and_clipped_to_the_camera():
    assert split_exposure(0.01, LIMITS) == ExposureSetting(0.01, 0.0)
    longer = split_exposure(0.16, LIMITS)
    assert longer.exposure_time_s == 0.04 and longer.gain_db == pytest.approx(20 * math.log10(4))
    assert split_exposure(100.0, LIMITS) == ExposureSetting(0.04, 30.0)
    assert split_exposure(1e-9, LIMITS) == ExposureSetting(1e-5, 0.0)


def test_one_frame_moves_at_most_the_speed_limit():
    current = ExposureSetting(0.01, 0.0)
    kwargs = dict(target_frac=0.18, speed_up_ev_per_s=4, speed_down_ev_per_s=8, frame_interval_s=0.04, limits=LIMITS)
    darker = next_exposure(current, 0.18 * 8, **kwargs)
    assert darker.product_s == pytest.approx(0.01 * 2 ** (-8 * 0.04))
    brighter = next_exposure(current, 0.18 / 8, **kwargs)
    assert brighter.product_s == pytest.approx(0.01 * 2 ** (4 * 0.04))
    assert next_exposure(current, 0.17, **kwargs).product_s == pytest.approx(0.01 * 0.18 / 0.17)
    assert next_exposure(current, 0.0, **kwargs).product_s == pytest.approx(0.01 * 2 ** (4 * 0.04))
    assert frames_to_adapt(8, speed_ev_per_s=8, frame_interval_s=0.04) == 10  # 3 EV at 0.32 EV per frame
    assert frames_to_adapt(1 / 8, speed_ev_per_s=3, frame_interval_s=0.04) == 25


def test_metering_counts_every_cfa_phase():
    raw = np.zeros((60, 78), np.uint16)  # multiples of 6: the stride 3 meets each phase equally often
    raw[0::2, 0::2] = 1000  # red sites of an RGGB mosaic only
    level = metered_level_frac(raw, black_level_dn=0, white_level_dn=4000)
    assert level == pytest.approx(0.25 * 1000 / 4000, rel=1e-9)
    assert metered_level_frac(raw, black_level_dn=0, white_level_dn=4000, region_frac=(0.5, 0.5, 1, 1)) > 0
    with pytest.raises(ValueError, match="odd"):
        metering_window(60, 80, (0, 0, 1, 1), stride=2)


def test_camera_equation_closed_form():
    # E = π·L/(4N²) lux; one lux·s on 1 µm² is 4.0919e3 photons of 540 THz light.
    assert photons_per_cd_m2_s(1.0, 1.0) == pytest.approx(math.pi / 4 * 4.0919e3, rel=1e-4)
    assert photons_per_cd_m2_s(9.0, 2.0) / photons_per_cd_m2_s(9.0, 4.0) == pytest.approx(4.0)
    assert gain_db(gain_linear(17.0)) == pytest.approx(17.0)
    with pytest.raises(ValueError):
        photons_per_cd_m2_s(0.0, 2.0)
