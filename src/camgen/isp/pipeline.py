"""The camera's ISP as one fused chain: raw DN → 8-bit RGB, with the state that adapts over frames.

Order, as in camera ISPs (DESIGN.md):

    lin   = (raw − black) · wb_c · 65535/(white − black)            on the mosaic, 16-bit linear code
    rgb   = demosaic(lin)                                            OpenCV (bilinear, edge-aware, VNG)
    out   = 65535 · (CCM·rgb − lo) / (hi − lo)                       one 3×4 affine (`cv2.transform`)
    out8  = tone(out)                                                a 65 536-entry table
    out8  = sharpen(denoise(out8))                                   when the profile asks

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
from camgen.isp.enhance import denoise, sharpen
from camgen.isp.tone import apply_lut, tone_lut
from camgen.isp.white_balance import cfa_gain_image, grey_world_gains

FULL_SCALE = 65535.0
"""The 16-bit linear code of the ISP: the sensor's range above black maps onto 0…65535."""


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
        ``isp.denoise``, ``isp.contrast_stretch``, ``isp.tone``, ``isp.sharpen``).
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
        self._scale = FULL_SCALE / (sensor.white_level_dn - sensor.black_level_dn)
        low, high = isp.contrast_stretch.output_range_frac if isp.contrast_stretch is not None else (0.0, 1.0)
        self._lut = tone_lut(
            isp.tone_curve if "isp.tone" in steps else "linear",
            isp.gamma,
            output_low_frac=low,
            output_high_frac=high,
        )
        self._site_gains = None
        self._site_gains_for = None

    def _linear_mosaic(self, raw_dn: np.ndarray) -> np.ndarray:
        """Black level, white balance and scaling to the 16-bit linear code, on the mosaic."""
        sensor = self.sensor
        if self.mono:
            gains = np.float32(self._scale)
        else:
            wb = self.isp.white_balance
            if "isp.white_balance" not in self.steps:
                rgb = np.ones(3)
            elif wb.mode == "fixed":
                rgb = np.array(wb.gains_rgb, np.float64)
            else:
                rgb = grey_world_gains(
                    raw_dn, sensor.cfa, sensor.black_level_dn, white_level_dn=float(sensor.white_level_dn)
                )
            # The smallest gain is 1, so every channel of a saturated site reaches full scale and clips
            # to white (a green-normalised gain below 1 would tint highlights).
            rgb = rgb / np.min(rgb)
            self.white_balance_gains = rgb
            key = tuple(np.round(rgb, 6))
            if key != self._site_gains_for:
                height, width = raw_dn.shape
                self._site_gains = cfa_gain_image(rgb * self._scale, sensor.cfa, height, width)
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

    def process(self, raw_dn: np.ndarray) -> np.ndarray:
        """(H, W) uint16 raw → (H, W, 3) uint8 RGB (a mono camera's grey in all three)."""
        isp, steps = self.isp, self.steps
        linear = self._linear_mosaic(raw_dn)
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
        if "isp.denoise" in steps:
            out = denoise(out, isp.denoise_strength)
        if "isp.sharpen" in steps:
            out = sharpen(out, isp.sharpen_amount, isp.sharpen_radius_px)
        return out
