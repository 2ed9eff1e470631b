"""One sensor: its fixed patterns and per-site constants, and a raw frame from the light it receives.

`SensorModel.build` precomputes, once per camera, everything that does not change from frame to frame
(fixed patterns from the serial, the QE of each site, the per-channel noise scale, the dark current at
the operating temperature); `SensorModel.capture` then turns a frame's irradiance into raw DN with
explicit `rng` (`camgen.sensor.noise`).
"""

from __future__ import annotations

from concurrent.futures import Executor
from dataclasses import dataclass

import numpy as np

from camgen.config.profile import Noise, Sensor
from camgen.sensor.cfa import cfa_site_values
from camgen.sensor.characteristics import dark_current_e_per_s
from camgen.sensor.exposure import gain_linear
from camgen.sensor.fixed_pattern import FixedPattern, fixed_pattern
from camgen.sensor.noise import Adc, TemporalNoise, sample_raw

NOISE_TERM_OFF = {
    "shot": ("shot_noise", False),
    "prnu": ("prnu_pct", 0.0),
    "dsnu": ("dsnu_e", 0.0),
    "row_fpn": ("row_fpn_e", 0.0),
    "column_fpn": ("column_fpn_e", 0.0),
    "dark_current": ("dark_current_e_per_s", 0.0),
    "hot_pixels": ("hot_pixel_fraction", 0.0),
    "dead_pixels": ("dead_pixel_fraction", 0.0),
    "read": ("read_noise_e", 0.0),
    "blooming": ("blooming", False),
}
"""Each switchable term of the sensor model: the `Noise` key that sets it, and the value that turns it off."""
NOISE_TERMS = tuple(NOISE_TERM_OFF)
"""Switchable terms of the sensor model (the plan's `sensor.noise` stage lists those it keeps)."""


def noise_term_is_on(noise: Noise, term: str) -> bool:
    """Whether the profile's `noise` has `term` switched on (its key differs from the off value)."""
    key, off = NOISE_TERM_OFF[term]
    return getattr(noise, key) != off


def noise_with_terms(noise: Noise, terms: frozenset[str] | set[str]) -> Noise:
    """The profile's noise with every term not in `terms` switched off."""
    unknown = set(terms) - set(NOISE_TERMS)
    if unknown:
        raise ValueError(f"unknown noise term(s) {sorted(unknown)}; the terms are {', '.join(NOISE_TERMS)}")
    return noise.model_copy(update=dict(value for term, value in NOISE_TERM_OFF.items() if term not in terms))


def _per_site(values_rgb: tuple[float, float, float], cfa: str, height: int, width: int) -> np.ndarray | float:
    """One value per site, or a float32 scalar when the three channels agree (saves a pass per frame)."""
    if len(set(values_rgb)) == 1:
        return float(np.float32(values_rgb[0]))
    return cfa_site_values(values_rgb, cfa, height, width)


@dataclass(frozen=True)
class SensorModel:
    """A sensor with its fixed patterns, ready to capture frames."""

    sensor: Sensor
    noise: Noise
    """The profile's noise with the terms the plan left out switched off."""
    pattern: FixedPattern
    electrons_per_photon: np.ndarray | float
    """QE × (1 + PRNU) per site (0 at dead pixels), (H, W) float32, or a scalar for a uniform sensor."""
    noise_scale: np.ndarray | float
    """Temporal-noise multiplier per site (the profile's per-channel scale), or a scalar."""
    dark_e_per_s: np.ndarray | float
    """Dark current of each site at the operating temperature, e⁻/s."""
    gaussian_above_e: float

    @classmethod
    def build(
        cls,
        sensor: Sensor,
        serial: int,
        *,
        terms: frozenset[str] | set[str] = frozenset(NOISE_TERMS),
        gaussian_above_e: float = 20.0,
    ) -> SensorModel:
        """Precompute the model of the physical sensor `serial` of this type with these noise terms."""
        noise = noise_with_terms(sensor.noise, terms)
        height, width = sensor.height_px, sensor.width_px
        pattern = fixed_pattern(noise, height, width, serial)
        qe = sensor.quantum_efficiency
        scale = noise.channel_scale
        if sensor.cfa == "mono":
            # A mono site sums the three bands, each with its own QE: the caller weights them
            # (photon_rate = Σ η_c·Φ_c), so the site's own factor is the response alone.
            qe_site: np.ndarray | float = 1.0
            scale_site: np.ndarray | float = scale.g
        else:
            qe_site = _per_site((qe.r, qe.g, qe.b), sensor.cfa, height, width)
            scale_site = _per_site((scale.r, scale.g, scale.b), sensor.cfa, height, width)
        per_photon = qe_site if pattern.response is None else pattern.response * np.float32(qe_site)
        temperature_factor = dark_current_e_per_s(
            1.0, sensor.temperature_c, noise.dark_current_reference_c, noise.dark_current_doubling_c
        )
        if pattern.dark_current_e_per_s is not None:
            dark = pattern.dark_current_e_per_s * np.float32(temperature_factor)
        else:
            dark = noise.dark_current_e_per_s * temperature_factor
        return cls(
            sensor=sensor,
            noise=noise,
            pattern=pattern,
            electrons_per_photon=per_photon,
            noise_scale=scale_site,
            dark_e_per_s=dark,
            gaussian_above_e=gaussian_above_e,
        )

    def capture(
        self,
        photon_rate: np.ndarray,
        *,
        exposure_time_s: float,
        gain_db: float = 0.0,
        rng: np.random.Generator,
        electrons_per_photon=None,
        executor: Executor | None = None,
    ) -> np.ndarray:
        """Raw DN (H, W) uint16 of one exposure.

        Parameters
        ----------
        photon_rate : (H, W) float32
            Photons per second arriving at each site; for a mono sensor the QE-weighted sum over the
            bands, Σ η_c·Φ_c (or, with `electrons_per_photon` given, any
            linear quantity that factor turns into electrons per second).
        exposure_time_s : float
        gain_db : float
            Analog gain, dB; multiplies the system gain K.
        rng : numpy.random.Generator
        electrons_per_photon : (H, W) float32 or float, optional
            Replaces the model's QE × (1 + PRNU): pass a product with further per-site factors
            (vignetting, the camera equation's constant) to save a multiplication per frame.
        executor : Executor, optional
            Parallel row bands (see `camgen.sensor.noise.sample_electrons`).
        """
        sensor, noise = self.sensor, self.noise
        return sample_raw(
            photon_rate,
            per_unit=self.electrons_per_photon if electrons_per_photon is None else electrons_per_photon,
            exposure_time_s=exposure_time_s,
            dark_e_per_s=self.dark_e_per_s,
            offset_e=self.pattern.offset_e,
            noise=TemporalNoise(
                read_noise_e=noise.read_noise_e,
                noise_scale=self.noise_scale,
                shot_noise=noise.shot_noise,
                gaussian_above_e=self.gaussian_above_e,
                read_noise_tail_dof=noise.read_noise_tail_dof,
                full_well_e=sensor.full_well_e,
                blooming=noise.blooming,
            ),
            adc=Adc(
                gain_dn_per_e=sensor.conversion_gain_dn_per_e * gain_linear(gain_db),
                black_level_dn=sensor.black_level_dn,
                bit_depth=sensor.bit_depth,
            ),
            rng=rng,
            executor=executor,
        )
