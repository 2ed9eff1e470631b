"""The sky's luminance and colour in every direction: the CIE standard general sky.

Luminance follows ISO 15469:2004 / CIE S 011/E:2003 ("Spatial distribution of daylight — CIE standard
general sky"): relative to the zenith, a sky element at zenith angle Z and angular distance χ from
the sun (at zenith angle Z_s) has

    L(Z, χ) / L_z = f(χ) φ(Z) / (f(Z_s) φ(0)),
    φ(Z) = 1 + a exp(b / cos Z) (φ = 1 at the horizon),
    f(χ) = 1 + c (exp(d χ) − exp(d π/2)) + e cos² χ,

with (a, b) the gradation group and (c, d, e) the indicatrix group of the sky type (Darula & Kittler
2002, "CIE general sky standard defining luminance distributions", eSim). Three types are offered:

- `overcast`: type 1, the CIE standard overcast sky (gradation I: a = 4, b = −0.7; indicatrix 1:
  c = 0, d = −1, e = 0), three times brighter at the zenith than at the horizon, no sun;
- `partly_cloudy`: type 7 (gradation III: a = 0, b = −1; indicatrix 3: c = 5, d = −2.5, e = 0.3),
  no gradation, a brighter circumsolar region;
- `clear`: type 12, the CIE standard clear sky, low turbidity (gradation V: a = −1, b = −0.32;
  indicatrix 4: c = 10, d = −3, e = 0.45): darkest about 90° from the sun, bright around it and
  towards the horizon.

Colour: daylight of a correlated colour temperature on the CIE daylight locus (CIE 15:2004), 6500 K
for overcast skies; a clear sky is bluest away from the sun and high up (zenith CCTs of clear skies
are 10 000–25 000 K; the horizon and the circumsolar sky are near 6500 K: Hernández-Andrés, Romero &
Lee 2001, "Colorimetric and spectroradiometric characteristics of narrow-field-of-view clear skylight
in Granada, Spain", JOSA A 18: 412). Here a clear sky's CCT falls from 12 000 K (high, away from the
sun) to 6500 K at the horizon and at the sun, a smooth approximation of those measurements.

Units: camgen's radiance, linear BT.709 RGB scaled so that 0.2126 R + 0.7152 G + 0.0722 B is the
luminance in cd/m² (`camgen.render.scene_graph`); `zenith_luminance_cd_m2` sets the scale.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

SKY_TYPES = {
    # name: (a, b, c, d, e)
    "overcast": (4.0, -0.70, 0.0, -1.0, 0.0),
    "partly_cloudy": (0.0, -1.0, 5.0, -2.5, 0.30),
    "clear": (-1.0, -0.32, 10.0, -3.0, 0.45),
}
LUMINANCE_WEIGHTS = np.array([0.2126, 0.7152, 0.0722])
HORIZON_CCT_K = 6500.0
CLEAR_ZENITH_CCT_K = 12000.0


def gradation(zenith_rad: np.ndarray, a: float, b: float) -> np.ndarray:
    """φ(Z) = 1 + a exp(b / cos Z), 1 at and below the horizon."""
    cos_z = np.cos(np.minimum(zenith_rad, math.pi / 2))
    with np.errstate(divide="ignore", over="ignore"):
        return np.where(cos_z > 1e-6, 1.0 + a * np.exp(b / np.maximum(cos_z, 1e-6)), 1.0)


def indicatrix(chi_rad: np.ndarray, c: float, d: float, e: float) -> np.ndarray:
    """f(χ) = 1 + c (exp(d χ) − exp(d π/2)) + e cos² χ."""
    return 1.0 + c * (np.exp(d * chi_rad) - math.exp(d * math.pi / 2)) + e * np.cos(chi_rad) ** 2


def relative_luminance(directions: np.ndarray, sun_direction: np.ndarray, sky: str) -> np.ndarray:
    """L / L_z of sky elements in world `directions` (…, 3), z up; `sun_direction` a unit vector
    towards the sun (any, for an overcast sky). Directions below the horizon get the horizon's."""
    a, b, c, d, e = SKY_TYPES[sky]
    unit = directions / np.linalg.norm(directions, axis=-1, keepdims=True)
    zenith = np.arccos(np.clip(unit[..., 2], 0.0, 1.0))
    chi = np.arccos(np.clip(unit @ sun_direction, -1.0, 1.0))
    sun_zenith = math.acos(min(1.0, max(0.0, float(sun_direction[2]))))
    norm = indicatrix(np.array(sun_zenith), c, d, e) * gradation(np.array(0.0), a, b)
    return indicatrix(chi, c, d, e) * gradation(zenith, a, b) / norm


@lru_cache(maxsize=4)
def _daylight_rgb_table() -> tuple[np.ndarray, np.ndarray]:
    """(CCTs K, linear BT.709 RGB (N, 3) of daylight of each CCT, luminance 1)."""
    import colour

    ccts = np.linspace(4000.0, 25000.0, 85)
    rgb = []
    for cct in ccts:
        xy = colour.temperature.CCT_to_xy_CIE_D(cct)
        XYZ = colour.xy_to_XYZ(xy)  # Y = 1
        rgb.append(colour.XYZ_to_RGB(XYZ, colour.RGB_COLOURSPACES["sRGB"], apply_cctf_encoding=False))
    rgb = np.array(rgb)
    rgb /= (rgb @ LUMINANCE_WEIGHTS)[:, None]
    return ccts, rgb


def daylight_rgb(cct_k: np.ndarray) -> np.ndarray:
    """Linear BT.709 RGB (…, 3) of daylight at correlated colour temperatures `cct_k`, luminance 1."""
    ccts, table = _daylight_rgb_table()
    flat = np.asarray(cct_k, dtype=np.float64).ravel()
    out = np.stack([np.interp(flat, ccts, table[:, k]) for k in range(3)], axis=-1)
    return out.reshape(*np.shape(cct_k), 3)


def sky_cct_k(directions: np.ndarray, sun_direction: np.ndarray, sky: str) -> np.ndarray:
    """Correlated colour temperature of the sky in `directions`, K (see the module docstring)."""
    if sky == "overcast":
        return np.full(directions.shape[:-1], HORIZON_CCT_K)
    unit = directions / np.linalg.norm(directions, axis=-1, keepdims=True)
    height = np.sqrt(np.clip(unit[..., 2], 0.0, 1.0))
    away = 1.0 - np.exp(-np.arccos(np.clip(unit @ sun_direction, -1.0, 1.0)) / 0.35)
    blue = CLEAR_ZENITH_CCT_K if sky == "clear" else 0.5 * (CLEAR_ZENITH_CCT_K + HORIZON_CCT_K)
    return HORIZON_CCT_K + (blue - HORIZON_CCT_K) * height * away


def sky_radiance(
    directions: np.ndarray, sun_direction: np.ndarray, sky: str, zenith_luminance_cd_m2: float
) -> np.ndarray:
    """Radiance (…, 3) of the sky in world `directions` (camgen's radiance units)."""
    luminance = zenith_luminance_cd_m2 * relative_luminance(directions, sun_direction, sky)
    return (luminance[..., None] * daylight_rgb(sky_cct_k(directions, sun_direction, sky))).astype(np.float32)
