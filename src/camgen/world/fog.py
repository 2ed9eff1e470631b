"""Fog and haze: Koschmieder's law on each pixel's distance.

A homogeneous atmosphere of extinction coefficient β transmits t = exp(−β d) of the light of a surface
d metres away and adds the light it scatters towards the camera along the way (Koschmieder 1924,
"Theorie der horizontalen Sichtweite", Beitr. Phys. freien Atm. 12; Middleton 1952, *Vision through
the atmosphere*):

    L = L0 t + L_air (1 − t),     t = exp(−3.912 d / V)

with V the visual range: the distance at which a black object's contrast against the horizon sky falls
to 2 % (ln 50 = 3.912). The WMO's meteorological optical range uses a 5 % threshold instead
(WMO-No. 8, 2018, §9.1), MOR = ln 20 / ln 50 V = 0.766 V.

The airlight L_air is the luminance of an infinitely deep atmosphere, which is what the horizon sky
is: camgen takes the sky's radiance at the horizon in the pixel's azimuth (`camgen.world.sky`; for a
uniform sky its one luminance), so fog glows brighter towards the sun under a clear sky. The sky
itself (no surface: d = ∞) becomes airlight. Two simplifications: the fog layer has no top (a sky
pixel high above the horizon in light haze would, in nature, keep some of its blue), and the airlight
comes from daylight only (lamps lighting the fog at night are not modelled).
"""

from __future__ import annotations

import numpy as np

KOSCHMIEDER_CONSTANT = float(np.log(50.0))
"""ln(1/0.02) = 3.912: β·V for a 2 % contrast threshold (Koschmieder 1924)."""


def transmittance(distance_m: np.ndarray, visibility_m: float) -> np.ndarray:
    """t = exp(−3.912 d / V) of paths `distance_m` long (any shape; +inf gives 0) through air of
    visual range `visibility_m`."""
    return np.exp(-KOSCHMIEDER_CONSTANT * np.asarray(distance_m, dtype=np.float64) / visibility_m)


def apply_fog(radiance: np.ndarray, distance_m: np.ndarray, airlight: np.ndarray, visibility_m: float) -> np.ndarray:
    """L0 t + L_air (1 − t): `radiance` (H, W, 3) seen through `distance_m` (H, W) of fog, with the
    airlight `airlight` (3,) or (H, W, 3) in the same units; float32 out."""
    t = np.exp(np.float32(-KOSCHMIEDER_CONSTANT / visibility_m) * np.asarray(distance_m, dtype=np.float32))
    airlight = np.asarray(airlight, dtype=np.float32)
    # L0 t + L_air (1 − t) = L_air + (L0 − L_air) t, in place; the sky (d = ∞, t = 0) becomes L_air.
    out = np.subtract(radiance, airlight, dtype=np.float32)
    out *= t[..., None]
    out += airlight
    return out
