"""Auto-exposure: meter the raw frame, step the exposure towards a target level at a limited speed.

Real cameras meter frame n and set frame n+1, and limit how fast they change (in stops per second,
faster when darkening), so a sudden light change is visible for a number of frames. Here:

    error_ev = log2(target / metered)            (metered: mean above black over full scale)
    step_ev  = clip(error_ev, −speed_down·Δt, +speed_up·Δt)
    exposure_{n+1} = exposure_n · 2^step_ev      (exposure = time × linear gain)

so a step change of the light by a factor F is corrected after ⌈|log2 F| / (speed·Δt)⌉ frames
(`frames_to_adapt`). The exposure product is split as a camera does: exposure time first, up to its
limit (at most the frame interval), then analog gain; darkening removes gain first.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from camgen.config.profile import Sensor
from camgen.sensor.characteristics import saturation_e
from camgen.sensor.exposure import gain_db, gain_linear

STEP_EV_MAX = 1000.0
"""Largest exposure step computed, EV: far beyond any exposure range, and 2^1000 is still finite."""


@dataclass(frozen=True)
class ExposureLimits:
    exposure_time_min_s: float
    exposure_time_max_s: float
    gain_max_db: float

    @property
    def product_min_s(self) -> float:
        return self.exposure_time_min_s

    @property
    def product_max_s(self) -> float:
        return self.exposure_time_max_s * gain_linear(self.gain_max_db)


@dataclass(frozen=True)
class ExposureSetting:
    exposure_time_s: float
    gain_db: float

    @property
    def product_s(self) -> float:
        """Exposure time × linear gain, s: what the output level is proportional to."""
        return self.exposure_time_s * gain_linear(self.gain_db)


def split_exposure(product_s: float, limits: ExposureLimits) -> ExposureSetting:
    """Exposure time and gain for an exposure product, clipped to what the camera can do."""
    product_s = min(max(product_s, limits.product_min_s), limits.product_max_s)
    time_s = min(product_s, limits.exposure_time_max_s)
    gain = max(product_s / time_s, 1.0)
    return ExposureSetting(exposure_time_s=time_s, gain_db=min(gain_db(gain), limits.gain_max_db))


METERING_STRIDE = 3
"""Every third row and column is metered: an odd step visits every CFA phase in its proportion."""


def metering_window(
    height_px: int, width_px: int, region_frac: tuple[float, float, float, float], stride: int = METERING_STRIDE
) -> tuple[slice, slice]:
    """Row and column slices of the metering window [x0, y0, x1, y1] (fractions of width and height),
    read every `stride`-th site; the stride must be odd so that every CFA phase counts."""
    if stride % 2 == 0:
        raise ValueError(f"stride must be odd to visit every CFA phase, got {stride}")
    x0, y0, x1, y1 = region_frac
    return (
        slice(int(y0 * height_px), max(math.ceil(y1 * height_px), int(y0 * height_px) + 1), stride),
        slice(int(x0 * width_px), max(math.ceil(x1 * width_px), int(x0 * width_px) + 1), stride),
    )


def metered_level_frac(
    raw_dn: np.ndarray,
    *,
    black_level_dn: float,
    white_level_dn: float,
    region_frac: tuple[float, float, float, float] = (0.0, 0.0, 1.0, 1.0),
) -> float:
    """Mean raw level above black in the metering window (`metering_window`), as a fraction of the
    range above black."""
    window = raw_dn[metering_window(raw_dn.shape[0], raw_dn.shape[1], region_frac)]
    mean_dn = float(np.mean(window, dtype=np.float64))
    return (mean_dn - black_level_dn) / (white_level_dn - black_level_dn)


def next_exposure(
    current: ExposureSetting,
    metered_frac: float,
    *,
    target_frac: float,
    speed_up_ev_per_s: float,
    speed_down_ev_per_s: float,
    frame_interval_s: float,
    limits: ExposureLimits,
) -> ExposureSetting:
    """The setting of the next frame after metering `metered_frac` with `current` (module docstring).

    A black frame (metered ≤ 0) asks for the fastest brightening.
    """
    if metered_frac > 0:
        error_ev = math.log2(target_frac / metered_frac)
    else:
        error_ev = math.inf
    step_ev = min(max(error_ev, -speed_down_ev_per_s * frame_interval_s), speed_up_ev_per_s * frame_interval_s)
    # The split clips the product to the limits; bounding the step keeps 2^step finite for the (valid)
    # very fast speeds, where 2.0 ** step would overflow, and changes nothing else.
    return split_exposure(current.product_s * 2.0 ** min(step_ev, STEP_EV_MAX), limits)


def frames_to_adapt(light_factor: float, *, speed_ev_per_s: float, frame_interval_s: float) -> int:
    """Frames after a light change by `light_factor` until auto-exposure has corrected it."""
    return math.ceil(abs(math.log2(light_factor)) / (speed_ev_per_s * frame_interval_s) - 1e-9)


def settled_exposure(
    rate_e_per_s: np.ndarray,
    start: ExposureSetting,
    *,
    sensor: Sensor,
    target_frac: float,
    limits: ExposureLimits,
    iterations: int = 30,
) -> ExposureSetting:
    """Where auto-exposure settles for a steady light: the setting at which the noise-free metered level
    of the sites in the metering window (`rate_e_per_s`, electrons per second each) reaches `target_frac`
    of the range above black, from `start`, without the speed limit. The level is linear in the exposure
    product until sites saturate, so a few multiplicative corrections converge; `iterations` bounds them.
    A window that collects nothing asks for the most exposure the limits allow."""
    range_dn = sensor.white_level_dn - sensor.black_level_dn
    setting = start
    for _ in range(iterations):
        clip_e, _ = saturation_e(
            sensor.full_well_e,
            sensor.conversion_gain_dn_per_e,
            sensor.black_level_dn,
            sensor.bit_depth,
            setting.gain_db,
        )
        electrons = np.minimum(rate_e_per_s * setting.exposure_time_s, clip_e)
        level = float(np.mean(electrons)) * sensor.conversion_gain_dn_per_e * gain_linear(setting.gain_db) / range_dn
        if level <= 0:
            return split_exposure(limits.product_max_s, limits)
        settled = split_exposure(setting.product_s * target_frac / level, limits)
        if abs(settled.product_s / setting.product_s - 1) < 1e-4:
            return settled
        setting = settled
    return setting
