"""How much light the sun and the sky give for a sun elevation: the IES daylight availability model,
and the zenith luminance of a CIE sky (`camgen.world.sky`) that gives the model's sky illuminance.

IES RP-21 "Recommended practice for the calculation of daylight availability" (J. Illum. Eng. Soc. 13:4,
381–392, 1984), as reproduced in the IESNA Lighting Handbook (9th ed., 2000, §8 "Daylighting"):

    E_xt = E_sc (1 + 0.034 cos(2π (J − 2) / 365))     extraterrestrial illuminance, E_sc = 127.5 klx
    E_dn = E_xt exp(−c m),  m = 1 / sin α             direct normal illuminance at sun elevation α
    E_kh = A + B sin^C α                              horizontal illuminance from the sky alone, klx

with J the day of the year and, per sky condition,

    sky            c (extinction)   A      B      C
    clear          0.21             0.8    15.5   0.5
    partly cloudy  0.80             0.3    45.0   1.0
    overcast       (no sun)         0.3    21.0   1.0     (Krochmann & Seidl 1974)

These are mean design values: the handbook warns that an instant's measurement may be half or twice
them. camgen's `uniform` sky takes the clear sky's numbers.

Zenith luminance: the horizontal illuminance of a sky of luminance L(Z, χ) = L_z·ℓ(Z, χ) is
E_kh = L_z ∫ ℓ cos Z dω over the hemisphere, so L_z = E_kh / ∫ ℓ cos Z dω with ℓ the CIE standard
general sky's relative luminance (`camgen.world.sky.relative_luminance`) for the sun's position. The
sky drawn behind the scene then holds exactly the illuminance that lights it. For the CIE overcast
sky the integral is 7π/9 (Moon & Spencer's L = L_z (1 + 2 cos Z)/3), for a uniform sky π.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from camgen.world.sky import relative_luminance

SOLAR_ILLUMINANCE_CONSTANT_LUX = 127_500.0
"""E_sc, the sun's illuminance outside the atmosphere at 1 AU (IES RP-21, 1984)."""

EXTINCTION = {"clear": 0.21, "partly_cloudy": 0.80, "uniform": 0.21}
"""Luminous atmospheric extinction coefficient c per sky (IES RP-21, 1984); an overcast sky has no sun."""

SKY_ILLUMINANCE_KLX = {
    "clear": (0.8, 15.5, 0.5),
    "partly_cloudy": (0.3, 45.0, 1.0),
    "overcast": (0.3, 21.0, 1.0),
    "uniform": (0.8, 15.5, 0.5),
}
"""(A, B, C) of E_kh = A + B sin^C α in klx per sky (IES RP-21, 1984)."""


def extraterrestrial_illuminance_lux(day_of_year: np.ndarray | int) -> np.ndarray:
    """E_xt: the sun's normal illuminance above the atmosphere on day `day_of_year` (1 = 1 January), lux."""
    return SOLAR_ILLUMINANCE_CONSTANT_LUX * (1.0 + 0.034 * np.cos(2 * math.pi * (np.asarray(day_of_year) - 2) / 365.0))


def direct_normal_illuminance_lux(elevation_deg: np.ndarray | float, day_of_year: int, sky: str) -> np.ndarray:
    """E_dn: the sun's illuminance on a surface facing it, lux; 0 for an overcast sky and a sun at or
    below the horizon."""
    elevation = np.asarray(elevation_deg, dtype=np.float64)
    if sky not in EXTINCTION:
        return np.zeros_like(elevation)
    sin_alpha = np.sin(np.radians(np.maximum(elevation, 0.0)))
    with np.errstate(divide="ignore"):
        air_mass = np.where(sin_alpha > 0, 1.0 / np.maximum(sin_alpha, 1e-12), np.inf)
    return extraterrestrial_illuminance_lux(day_of_year) * np.exp(-EXTINCTION[sky] * air_mass)


def sky_horizontal_illuminance_lux(elevation_deg: np.ndarray | float, sky: str) -> np.ndarray:
    """E_kh: the illuminance the sky alone (no sun) gives a horizontal surface, lux; the model holds
    for a sun at or above the horizon (A at α = 0)."""
    a, b, c = SKY_ILLUMINANCE_KLX[sky]
    sin_alpha = np.sin(np.radians(np.maximum(np.asarray(elevation_deg, dtype=np.float64), 0.0)))
    return 1000.0 * (a + b * sin_alpha**c)


@lru_cache(maxsize=256)
def _horizontal_integral(sky: str, sun_elevation_deg: float) -> float:
    """∫ ℓ cos Z dω over the sky hemisphere (sr), ℓ = L / L_z of the CIE sky (midpoint rule, 0.5° cells)."""
    if sky == "uniform":
        return math.pi
    step = math.radians(0.5)
    zenith = (np.arange(180) + 0.5) * step
    azimuth = (np.arange(720) + 0.5) * step
    Z, A = np.meshgrid(zenith, azimuth, indexing="ij")
    directions = np.stack([np.sin(Z) * np.cos(A), np.sin(Z) * np.sin(A), np.cos(Z)], axis=-1)
    el = math.radians(sun_elevation_deg)
    sun = np.array([math.cos(el), 0.0, math.sin(el)])
    ell = relative_luminance(directions, sun, sky)
    return float(np.sum(ell * np.cos(Z) * np.sin(Z)) * step * step)


def sky_horizontal_illuminance_from_zenith_lux(zenith_cd_m2: float, sun_elevation_deg: float, sky: str) -> float:
    """The illuminance, lux, that the CIE sky `sky` ("uniform": one luminance everywhere) with zenith luminance
    `zenith_cd_m2` gives a horizontal surface with the sun at `sun_elevation_deg`: L_z·∫ ℓ cos Z dω (the inverse
    of `zenith_luminance_cd_m2`)."""
    return zenith_cd_m2 * _horizontal_integral(sky, round(float(max(sun_elevation_deg, 0.0)), 2))


def zenith_luminance_cd_m2(sky_illuminance_lux: float, sun_elevation_deg: float, sky: str) -> float:
    """L_z of the CIE sky `sky` (`camgen.world.sky`; "uniform": one luminance everywhere) whose
    horizontal illuminance is `sky_illuminance_lux` with the sun at `sun_elevation_deg`, cd/m²."""
    return sky_illuminance_lux / sky_horizontal_illuminance_from_zenith_lux(1.0, sun_elevation_deg, sky)
