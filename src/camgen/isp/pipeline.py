"""The camera's ISP as one fused chain: raw DN → 8-bit RGB, with the state that adapts over frames.

Order, as in camera ISPs (DESIGN.md):

    lin   = (raw − black) · wb_c · 65535/(sat − black)              on the mosaic, 16-bit linear code
    rgb   = demosaic(lin)                                            OpenCV (bilinear, edge-aware, VNG)
    out   = 65535 · (CCM·rgb − lo) / (hi − lo)                       one 3×4 affine (`cv2.transform`)
    out8  = tone(out)                                                a 65 536-entry table
    out8  = sharpen(denoise(suppress_false_colour(out8)))            when the profile asks

White balance (fixed, or grey world measured on this frame's mosaic) is applied before demosaicing, as
real ISPs do, so edge-aware interpolation sees balanced channels; its gains are scaled so the smallest
is 1, which clips saturated sites to white. The contrast-stretch limits lo, hi are the profile's
percentiles of the white-balanced linear samples (measured on the mosaic, a subsample), approached
with the profile's adaptation time constant; CCM rows sum to one, so a grey stays grey and the
stretch commutes with the CCM. The stretch amplifies at most `max_gain` times; without a stretch,
lo = 0 and hi = full scale.
"""

from __future__ import annotations

from concurrent.futures import Executor

import cv2
import numpy as np

from camgen.config.profile import Isp, Sensor
from camgen.isp.contrast import adapt_limits, limit_stretch_gain, stretch_limits
from camgen.isp.demosaic import demosaic
from camgen.isp.enhance import denoise, sharpen, suppress_false_colour
from camgen.isp.tone import apply_lut, tone_lut
from camgen.isp.white_balance import cfa_gain_image, grey_world_gains
from camgen.sensor.characteristics import saturation_e
from camgen.sensor.exposure import gain_linear

FULL_SCALE = 65535.0
"""The 16-bit linear code of the ISP: black to saturation (full well or ADC) maps onto 0…65535."""
SATURATED_FRAC = 0.98
"""Sites above this fraction of the range from black to saturation count as clipped (grey world ignores them)."""
WHITE_BALANCE_GAIN_RANGE = (0.25, 4.0)
"""Grey-world gains are clamped to this range (a dark or single-coloured frame would ask for more)."""


class CameraIsp:
    """The ISP of one camera. Keeps the adapting contrast-stretch limits between frames.

    Parameters
    ----------
    isp : Isp
        The profile's ISP settings.
    sensor : Sensor
        For the CFA, black and white levels.
    frame_interval_s : float
        Time between frames (the adaptation step).
    steps : set of str
        The ISP stages the plan kept (``isp.demosaic``, ``isp.white_balance``, ``isp.ccm``,
        ``isp.false_colour``, ``isp.denoise``, ``isp.contrast_stretch``, ``isp.tone``, ``isp.sharpen``).
    executor : Executor, optional
        Runs the tone lookup in parallel halves.
    """

    def __init__(
        self, isp: Isp, sensor: Sensor, *, frame_interval_s: float, steps: set[str], executor: Executor | None = None
    ):
        self.isp, self.sensor, self.steps = isp, sensor, steps
        self.frame_interval_s = frame_interval_s
        self.executor = executor
        self.mono = sensor.cfa == "mono"
        self.limits: tuple[float, float] | None = None
        """The contrast-stretch limits used for the last frame, 16-bit linear code."""
        self.white_balance_gains = np.ones(3)
        """The white-balance gains (R, G, B) of the last frame, smallest 1."""
        self._white_balance_log = None
        low, high = isp.contrast_stretch.output_range_frac if isp.contrast_stretch is not None else (0.0, 1.0)
        self._lut = tone_lut(
            isp.tone_curve if "isp.tone" in steps else "linear",
            isp.gamma,
            output_low_frac=low,
            output_high_frac=high,
        )
        self._site_gains = None
        self._site_gains_for = None

    def carried_state(self) -> dict:
        """What one frame leaves for the next, as JSON-ready numbers that round-trip exactly (floats
        keep their repr): the contrast-stretch limits and the smoothed log white-balance gains. Every
        other attribute is settings or a cache rebuilt from them. `restore_state` takes it back."""
        return {
            "limits": None if self.limits is None else [float(value) for value in self.limits],
            "white_balance_log": None
            if self._white_balance_log is None
            else [float(value) for value in self._white_balance_log],
        }

    def restore_state(self, state: dict) -> None:
        """Continue from a `carried_state`: the next `process` gives what it would have given after the
        frames that state followed."""
        limits, white_balance_log = state["limits"], state["white_balance_log"]
        self.limits = None if limits is None else (float(limits[0]), float(limits[1]))
        self._white_balance_log = None if white_balance_log is None else np.array(white_balance_log, np.float64)

    def saturation_dn(self, gain_db: float) -> float:
        """Raw DN of a saturated site at this gain: the full well or the ADC, whichever clips first."""
        sensor = self.sensor
        electrons, _ = saturation_e(
            sensor.full_well_e, sensor.conversion_gain_dn_per_e, sensor.black_level_dn, sensor.bit_depth, gain_db
        )
        return sensor.black_level_dn + electrons * sensor.conversion_gain_dn_per_e * gain_linear(gain_db)

    def _white_balance(self, raw_dn: np.ndarray, saturation_dn: float) -> np.ndarray:
        """This frame's gains (R, G, B): fixed, or grey world over the unsaturated sites, clamped to
        `WHITE_BALANCE_GAIN_RANGE` and smoothed over frames in log with the stretch's adaptation time
        (night frames near black would otherwise flicker in colour)."""
        wb, sensor = self.isp.white_balance, self.sensor
        if "isp.white_balance" not in self.steps:
            return np.ones(3)
        if wb.mode == "fixed":
            return np.array(wb.gains_rgb, np.float64)
        black = sensor.black_level_dn
        target = grey_world_gains(
            raw_dn, sensor.cfa, black, white_level_dn=black + SATURATED_FRAC * (saturation_dn - black)
        )
        target_log = np.log(np.clip(target, *WHITE_BALANCE_GAIN_RANGE))
        stretch = self.isp.contrast_stretch
        time_constant_s = stretch.adaptation_time_s if stretch is not None else 0.0
        if self._white_balance_log is None or time_constant_s == 0:
            self._white_balance_log = target_log
        else:
            step = 1.0 - np.exp(-self.frame_interval_s / time_constant_s)
            self._white_balance_log = self._white_balance_log + step * (target_log - self._white_balance_log)
        return np.exp(self._white_balance_log)

    def _linear_mosaic(self, raw_dn: np.ndarray, gain_db: float) -> np.ndarray:
        """Black level, white balance and scaling to the 16-bit linear code, on the mosaic: the
        saturation level maps to full scale."""
        sensor = self.sensor
        saturation_dn = self.saturation_dn(gain_db)
        scale = FULL_SCALE / (saturation_dn - sensor.black_level_dn)
        if self.mono:
            gains = np.float32(scale)
        else:
            # The smallest gain is 1, so every channel of a saturated site reaches full scale and clips
            # to white (a green-normalised gain below 1 would tint highlights).
            rgb = self._white_balance(raw_dn, saturation_dn)
            # Gains move in steps of 0.1 % (invisible), so the per-site map is rebuilt only when they do.
            rgb = np.exp(np.round(np.log(rgb / np.min(rgb)), 3))
            self.white_balance_gains = rgb
            key = (*rgb, scale)
            if key != self._site_gains_for:
                height, width = raw_dn.shape
                self._site_gains = cfa_gain_image(rgb * scale, sensor.cfa, height, width)
                self._site_gains_for = key
            gains = self._site_gains
        # Saturating uint16 arithmetic clips below black and above full scale, and rounds.
        above_black = cv2.subtract(raw_dn, float(sensor.black_level_dn))
        if isinstance(gains, np.ndarray):
            return cv2.multiply(above_black, gains, dtype=cv2.CV_16U)
        return cv2.multiply(above_black, float(gains), dtype=cv2.CV_16U)

    def _affine(self, lo: float, hi: float) -> np.ndarray:
        """3×4 (colour) or 1×2 (mono) matrix: 65535·(CCM·x − lo)/(hi − lo)."""
        gain = FULL_SCALE / (hi - lo)
        if self.mono:
            return np.array([[gain, -gain * lo]], np.float32)
        ccm = np.array(self.isp.ccm, np.float64) if "isp.ccm" in self.steps else np.eye(3)
        return np.hstack([ccm * gain, np.full((3, 1), -gain * lo)]).astype(np.float32)

    def process(self, raw_dn: np.ndarray, gain_db: float = 0.0, *, grey_out: bool = False) -> np.ndarray:
        """(H, W) uint16 raw taken at `gain_db` → (H, W, 3) uint8 RGB (a mono camera's grey in all three).
        `grey_out`: the caller sends the result as grey (a day/night camera in night mode), so nothing that only
        moves colour runs (`isp.false_colour`)."""
        isp, steps = self.isp, self.steps
        linear = self._linear_mosaic(raw_dn, gain_db)
        stretch = isp.contrast_stretch
        if stretch is not None and "isp.contrast_stretch" in steps:
            target = limit_stretch_gain(
                stretch_limits(linear, stretch.low_percentile, stretch.high_percentile),
                full_scale=FULL_SCALE,
                max_gain=stretch.max_gain,
            )
            self.limits = adapt_limits(
                self.limits,
                target,
                frame_interval_s=self.frame_interval_s,
                adaptation_time_s=stretch.adaptation_time_s,
            )
        else:
            self.limits = (0.0, FULL_SCALE)
        lo, hi = self.limits
        if self.mono:
            image = cv2.transform(linear[..., None], self._affine(lo, hi))
        else:
            rgb = demosaic(linear, self.sensor.cfa, isp.demosaic)
            image = cv2.transform(rgb, self._affine(lo, hi))
        out = apply_lut(image, self._lut, executor=self.executor)
        if self.mono:
            out = cv2.cvtColor(out.reshape(out.shape[0], out.shape[1]), cv2.COLOR_GRAY2RGB)
        elif "isp.false_colour" in steps and not grey_out:
            out = suppress_false_colour(out, isp.false_colour_median_px)
        if "isp.denoise" in steps:
            out = denoise(out, isp.denoise_strength)
        if "isp.sharpen" in steps:
            out = sharpen(out, isp.sharpen_amount, isp.sharpen_radius_px)
        return out
