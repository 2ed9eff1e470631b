"""Derived sensor figures (EMVA 1288 release 4.0, section 4): saturation, dark noise, dynamic range."""

from __future__ import annotations

import math


def dark_current_e_per_s(
    reference_e_per_s: float, temperature_c: float, reference_c: float, doubling_c: float
) -> float:
    """Dark current at `temperature_c`: I(T) = I(T_ref)·2^((T − T_ref)/T_double), e⁻/s."""
    return reference_e_per_s * 2.0 ** ((temperature_c - reference_c) / doubling_c)


def saturation_e(
    full_well_e: float, conversion_gain_dn_per_e: float, black_level_dn: float, bit_depth: int, gain_db: float = 0.0
) -> tuple[float, str]:
    """Electrons at which the raw output saturates, and what limits it ('full well' or 'ADC').

    The ADC clips at 2^bits − 1 DN; with gain G = 10^(dB/20) one electron gives K·G DN. This is the
    clip level; EMVA 1288's μ_e.sat (the variance peak) lies a few shot-noise σ below it.
    """
    adc_limit_e = (2**bit_depth - 1 - black_level_dn) / (conversion_gain_dn_per_e * 10 ** (gain_db / 20))
    if adc_limit_e < full_well_e:
        return adc_limit_e, "ADC"
    return full_well_e, "full well"


def temporal_dark_noise_e(
    read_noise_e: float, dark_current_e_per_s_: float, exposure_time_s: float, conversion_gain_dn_per_e: float
) -> float:
    """σ_d: read noise, dark-current shot noise and quantisation (1/12 DN²) in electrons rms."""
    quantisation_e2 = (1.0 / conversion_gain_dn_per_e) ** 2 / 12.0
    return math.sqrt(read_noise_e**2 + dark_current_e_per_s_ * exposure_time_s + quantisation_e2)


def dynamic_range_db(saturation_e_: float, dark_noise_e: float) -> float:
    """DR = 20·log10(μ_e,sat / σ_d) in dB (DESIGN.md; EMVA 1288 eq. 36 in dB)."""
    return 20.0 * math.log10(saturation_e_ / dark_noise_e)
