"""A naive reference of the post-render camera model: float64 numpy, exact Poisson, nothing fused.

Every stage is written as its equation on full arrays, in the textbook order (DESIGN.md "Sensor
model"), so that the fast path (`camgen.plan.camera_pipeline`) can be timed against it in the same run
and its statistics checked against it:

    RGB remap per channel (float64) → × relative illumination → CFA sampling → photons (camera
    equation) → Poisson(QE·(1 + PRNU)·Φ + dark·t) → full well with blooming → + offsets + N(0, σ_read²)
    → ADC (round, clip) → black level, white balance → bilinear demosaic (normalised convolution) →
    CCM → contrast stretch (np.percentile) → tone curve (colour-science, float) → 8 bit.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from camgen.config.profile import Profile
from camgen.isp.tone import tone_curve
from camgen.optics.remap import LensMaps
from camgen.sensor.cfa import cfa_channel_index
from camgen.sensor.exposure import gain_linear, photons_per_cd_m2_s
from camgen.sensor.fixed_pattern import FixedPattern


@dataclass(frozen=True)
class ReferenceCamera:
    profile: Profile
    pattern: FixedPattern
    dark_e_per_s: np.ndarray | float
    """Dark current per site at the operating temperature, e⁻/s."""

    def light_at_sites(self, radiance, maps: LensMaps | None, margin_px, vignetting) -> np.ndarray:
        """(H, W) float64 radiance at each photosite (mono: QE-weighted sum of the bands)."""
        sensor = self.profile.sensor
        radiance = radiance.astype(np.float64)
        if maps is None:
            left, top, _, _ = margin_px
            rgb = radiance[top : top + sensor.height_px, left : left + sensor.width_px]
        else:
            channels = []
            for c in range(3):
                k = c if len(maps.map_x) == 3 else 0
                channels.append(
                    cv2.remap(np.ascontiguousarray(radiance[..., c]), maps.map_x[k], maps.map_y[k], cv2.INTER_LINEAR)
                )
            rgb = np.stack(channels, -1)
        if vignetting is not None:
            rgb = rgb * vignetting[..., None]
        if sensor.cfa == "mono":
            qe = sensor.quantum_efficiency
            return rgb @ np.array([qe.r, qe.g, qe.b])
        index = cfa_channel_index(sensor.cfa, sensor.height_px, sensor.width_px)
        return np.take_along_axis(rgb, index[..., None].astype(np.intp), axis=2)[..., 0]

    def raw(self, light_cd_m2, *, f_number, exposure_time_s, gain_db, rng) -> np.ndarray:
        """Raw DN (H, W) uint16 from the light at each site."""
        sensor, noise = self.profile.sensor, self.profile.sensor.noise
        photons = light_cd_m2 * photons_per_cd_m2_s(sensor.pixel_pitch_um * sensor.pitch_y_um, f_number)
        photons = photons * exposure_time_s
        if sensor.cfa == "mono":
            qe = np.ones(light_cd_m2.shape)
        else:
            q = sensor.quantum_efficiency
            qe = np.array([q.r, q.g, q.b])[cfa_channel_index(sensor.cfa, *light_cd_m2.shape)]
        response = 1.0 if self.pattern.response is None else self.pattern.response.astype(np.float64)
        mean = qe * response * photons + self.dark_e_per_s * exposure_time_s
        scale = noise.channel_scale
        k = np.ones(light_cd_m2.shape)
        if sensor.cfa != "mono":
            k = np.array([scale.r, scale.g, scale.b])[cfa_channel_index(sensor.cfa, *light_cd_m2.shape)]
        else:
            k = k * scale.g
        signal = rng.poisson(mean).astype(np.float64) if noise.shot_noise else mean.copy()
        signal = mean + k * (signal - mean)
        excess = np.maximum(signal - sensor.full_well_e, 0.0)
        if noise.blooming:
            spill = np.zeros_like(excess)
            spill[1:] += excess[:-1] / 4
            spill[:-1] += excess[1:] / 4
            spill[:, 1:] += excess[:, :-1] / 4
            spill[:, :-1] += excess[:, 1:] / 4
            signal = signal + spill
        signal = np.minimum(signal, sensor.full_well_e)
        offset = 0.0 if self.pattern.offset_e is None else self.pattern.offset_e.astype(np.float64)
        electrons = signal + offset + k * rng.normal(0.0, noise.read_noise_e, signal.shape)
        dn = electrons * sensor.conversion_gain_dn_per_e * gain_linear(gain_db) + sensor.black_level_dn
        return np.clip(np.round(dn), 0, sensor.white_level_dn).astype(np.uint16)

    def isp(self, raw_dn, *, white_balance_rgb=(1.0, 1.0, 1.0)) -> np.ndarray:
        """(H, W, 3) uint8 from raw DN, float64 throughout."""
        sensor, isp = self.profile.sensor, self.profile.isp
        linear = (raw_dn.astype(np.float64) - sensor.black_level_dn) / (sensor.white_level_dn - sensor.black_level_dn)
        if sensor.cfa == "mono":
            rgb = np.repeat(linear[..., None], 3, axis=2)
        else:
            index = cfa_channel_index(sensor.cfa, *raw_dn.shape)
            linear = np.clip(linear * np.asarray(white_balance_rgb)[index], 0.0, 1.0)
            kernel = np.array([[0.25, 0.5, 0.25], [0.5, 1.0, 0.5], [0.25, 0.5, 0.25]])
            planes = []
            for c in range(3):
                mask = (index == c).astype(np.float64)
                num = cv2.filter2D(linear * mask, -1, kernel, borderType=cv2.BORDER_REFLECT)
                den = cv2.filter2D(mask, -1, kernel, borderType=cv2.BORDER_REFLECT)
                planes.append(num / den)
            rgb = np.stack(planes, -1) @ np.array(isp.ccm).T
        if isp.contrast_stretch is not None:
            lo, hi = np.percentile(linear, [isp.contrast_stretch.low_percentile, isp.contrast_stretch.high_percentile])
            low, high = isp.contrast_stretch.output_range_frac
        else:
            lo, hi, low, high = 0.0, 1.0, 0.0, 1.0
        stretched = np.clip((rgb - lo) / max(hi - lo, 1e-12), 0.0, 1.0)
        toned = low + (high - low) * tone_curve(stretched, isp.tone_curve, isp.gamma)
        return np.round(toned * 255.0).astype(np.uint8)
