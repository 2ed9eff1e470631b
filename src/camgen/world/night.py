"""Night: street lamps by luminous flux, the night sky's skyglow, and the camera's infrared night mode.

Street lamps (`lamp` lights). A lamp is a spot light with the renderer's beam shape (glTF
KHR_lights_punctual, `camgen.render`): I(θ) = I₀ for θ ≤ θᵢ, I₀·s(θ)² with
s = (cos θ − cos θₒ)/(cos θᵢ − cos θₒ) for θᵢ < θ < θₒ, and 0 beyond the cone θₒ (θᵢ = 0.8 θₒ). Its
luminous flux is Φ = ∫ I dω = 2π I₀ ∫ s² d(cos θ), which in closed form is

    Φ = 2π I₀ [(1 − cos θᵢ) + (cos θᵢ − cos θₒ)/3],

so a lamp of flux Φ (lumens leaving the luminaire: the lamp's flux times the light output ratio) has
I₀ = Φ / (2π [(1 − cos θᵢ) + (cos θᵢ − cos θₒ)/3]). Under it a horizontal surface receives
E = I(θ)·cos θ / d² (the inverse-square cosine law). A street lantern's light leaves within about
70° of the downward vertical (EN 13201-2's G-classes cap the intensity above 70–90°; the CIE 115
"Type II/III" lateral distributions are asymmetric and not modelled here: the beam is round).

Night sky. Without the sun, the sky's luminance is natural airglow and starlight, 174 µcd/m² at the
zenith (22.0 mag/arcsec²), plus artificial skyglow: Falchi et al. 2016, "The new world atlas of
artificial night sky brightness", Sci. Adv. 2: e1600377 (natural background 174 µcd/m²; their classes
by artificial/natural ratio), and Kyba et al. 2015, "Worldwide variations in artificial skyglow", Sci.
Rep. 5: 8409 (clear-sky zenith brightness in cities about 17–18.5 mag/arcsec², i.e. 4–17 mcd/m²; an
overcast city sky up to ten times that). `NIGHT_SKY_LUMINANCE_CD_M2` takes one value per class; a
uniform sky of luminance L gives a horizontal surface E = π·L (0.5 mlx natural, 31 mlx urban), the
0.001–0.1 lx that moonless rural to urban nights measure on the ground.

Night mode. Below `night_mode.switch_lux` a surveillance camera removes its IR-cut filter, turns its
stream monochrome and switches on an 850 nm illuminator. The illuminator of radiant intensity I_e
(W/sr) irradiates a surface at distance d and incidence θ with E_e = I_e·cos θ / d² W/m²; a Lambertian
surface of NIR reflectance ρ returns L_e = ρ·E_e/π W/(m²·sr). The sensor counts photons: at 850 nm one
joule is λ/(hc) = 4.28·10¹⁸ photons, while `camgen.sensor.exposure` counts a lumen-second as 4.09·10¹⁵
photons of 555 nm, so one W of 850 nm light counts as `NIR_LM_EQUIVALENT_PER_W` ≈ 1046 lumens would,
times the sensor's QE at 850 nm relative to its visible QE (`sensor.qe_850nm_rel`). Without the
IR-cut filter the colour filters all pass 850 nm about equally (their dyes are transparent there: see
any Sony STARVIS spectral-response figure, e.g. the IMX291/IMX327 datasheets, where R, G and B meet
above 800 nm at about 30–40 % of the green peak), which is why the stream is shown monochrome.
"""

from __future__ import annotations

import math

import numpy as np

SPOT_FULL_INTENSITY_FRACTION = 0.8
"""θᵢ / θₒ of the renderer's spot and lamp beams (full intensity within 80 % of the cone)."""

SPEED_OF_LIGHT_M_S = 299_792_458.0
LUMINOUS_EFFICACY_LM_PER_W = 683.0
CANDELA_FREQUENCY_HZ = 540e12
"""The candela's definition: 683 lm/W at 540 THz, the photons `camgen.sensor.exposure` counts."""


def beam_solid_angle_sr(cone_half_angle_rad: float, inner_fraction: float = SPOT_FULL_INTENSITY_FRACTION) -> float:
    """Ω = Φ / I₀ of the renderer's beam shape, sr: 2π [(1 − cos θᵢ) + (cos θᵢ − cos θₒ)/3]."""
    outer = float(cone_half_angle_rad)
    if not 0 < outer < math.pi / 2:
        raise ValueError(f"the cone's half angle must lie in (0, π/2) rad, got {outer}")
    cos_i, cos_o = math.cos(inner_fraction * outer), math.cos(outer)
    return 2 * math.pi * ((1 - cos_i) + (cos_i - cos_o) / 3)


def peak_intensity_cd(flux_lm: float, cone_half_angle_rad: float) -> float:
    """I₀ of a lamp whose beam (the renderer's shape, half angle θₒ) carries `flux_lm` lumens, cd."""
    return float(flux_lm) / beam_solid_angle_sr(cone_half_angle_rad)


def beam_intensity_cd(peak_cd: float, off_axis_rad: np.ndarray | float, cone_half_angle_rad: float) -> np.ndarray:
    """I(θ) of the renderer's beam shape, cd, for angles θ from the beam's axis (any shape)."""
    cos_i = math.cos(SPOT_FULL_INTENSITY_FRACTION * cone_half_angle_rad)
    cos_o = math.cos(cone_half_angle_rad)
    s = np.clip((np.cos(np.asarray(off_axis_rad, dtype=np.float64)) - cos_o) / (cos_i - cos_o), 0.0, 1.0)
    return peak_cd * s * s


def ground_illuminance_lux(
    peak_cd: float, cone_half_angle_rad: float, height_m: float, offset_m: np.ndarray | float
) -> np.ndarray:
    """E = I(θ)·cos θ / d² on the ground at horizontal distance `offset_m` from under a lamp aimed
    straight down from `height_m`, lux (cos θ = h/d, d² = h² + r²)."""
    r = np.asarray(offset_m, dtype=np.float64)
    d2 = height_m * height_m + r * r
    theta = np.arctan2(r, height_m)
    return beam_intensity_cd(peak_cd, theta, cone_half_angle_rad) * (height_m / np.sqrt(d2)) / d2


NATURAL_NIGHT_SKY_CD_M2 = 174e-6
"""Natural zenith luminance of a moonless clear night (airglow, zodiacal light, starlight): 22.0
mag/arcsec² (Falchi et al. 2016)."""

NIGHT_SKY_LUMINANCE_CD_M2 = {
    "natural": NATURAL_NIGHT_SKY_CD_M2,
    "rural": 2 * NATURAL_NIGHT_SKY_CD_M2,
    "suburban": 2e-3,
    "urban": 1e-2,
}
"""Zenith luminance of a clear moonless sky, cd/m², per setting: natural (no skyglow); rural (skyglow
equal to the natural sky, Falchi et al. 2016's limit of a sky with a visible Milky Way); suburban
(19.9 mag/arcsec²) and urban (18.1 mag/arcsec², the middle of Kyba et al. 2015's city readings)."""

NIGHT_SUN_MAX_ELEVATION_DEG = -12.0
"""A site may be a night scene once the sun is 12° below the horizon (nautical dusk): the sunlit sky
then gives about 0.01 lx (Seidelmann (ed.), Explanatory Supplement to the Astronomical Almanac, 1992,
§9.33; 3 lx at civil dusk, −6°), no more than the skyglow; between it and sunset the twilight sky,
which camgen does not model, would outshine it."""


def night_sky_illuminance_lux(sky_luminance_cd_m2: float) -> float:
    """E = π·L: the horizontal illuminance of a uniform sky of luminance L, lux."""
    return math.pi * sky_luminance_cd_m2


NIR_WAVELENGTH_NM = 850.0
NIR_LM_EQUIVALENT_PER_W = (
    LUMINOUS_EFFICACY_LM_PER_W * CANDELA_FREQUENCY_HZ * NIR_WAVELENGTH_NM * 1e-9 / SPEED_OF_LIGHT_M_S
)
"""Lumens of 540 THz light that give a sensor as many photons as one watt of 850 nm light (≈ 1046):
(λ/hc) / (1/(683 lm/W · h · 540 THz)) = 683 · 540 THz · λ / c; Planck's constant cancels."""


def nir_equivalent_intensity_cd(radiant_intensity_mw_sr: float, qe_850nm_rel: float) -> float:
    """The candela that, counted as `camgen.sensor.exposure` counts visible light, give the sensor as
    many photo-electrons as an 850 nm source of `radiant_intensity_mw_sr`, with QE `qe_850nm_rel` of
    the visible one: I_eq = I_e · 1046 lm/W · η₈₅₀."""
    return radiant_intensity_mw_sr * 1e-3 * NIR_LM_EQUIVALENT_PER_W * qe_850nm_rel


NIR_REFLECTANCE_BY_TEXTURE = {
    "asphalt": 0.14,
    "paving": 0.36,
    "concrete": 0.36,
    "grass": 0.45,
    "gravel": 0.32,
    "brick": 0.45,
    "facade": 0.38,
}
"""Reflectance at 850 nm of each procedural surface (`camgen.world.textures`), read off spectra of the
kind the ECOSTRESS spectral library (Meerdink et al. 2019, Remote Sens. Environ. 230: 111196; formerly
ASTER, Baldridge et al. 2009) holds: asphalt 0.10–0.18 (aged), concrete 0.3–0.45, green grass
0.4–0.5 (the red edge: leaves reflect half the NIR), red brick 0.4–0.5, limestone gravel 0.3–0.35.
Estimates to two digits, not measured for camgen."""

NIR_SKIN_REFLECTANCE = 0.6
"""Human skin at 850 nm: 0.5–0.65 for light to dark skin (melanin absorbs little there; Jacques 2013,
"Optical properties of biological tissues: a review", Phys. Med. Biol. 58: R37)."""


def default_nir_reflectance(color_rgb) -> np.ndarray:
    """The NIR reflectance of a surface whose only known property is its linear visible colour: its red
    reflectance, ρ₈₅₀ = R. Most pigments, dyes and
    minerals reflect at 850 nm at least what they reflect at the red end of the visible (the dyes turn
    transparent in the NIR; USGS splib07, Kokaly et al. 2017), so R is a floor; carbon-black paints and
    tyres stay near 0.05. Shape (..., 3) → (...)."""
    rgb = np.asarray(color_rgb, dtype=np.float64)
    return rgb[..., 0]


def luma_bt601(rgb: np.ndarray) -> np.ndarray:
    """Each pixel's BT.601 luma Y = 0.299 R + 0.587 G + 0.114 B of (..., 3) → (...), unrounded (an integer image's
    in float64)."""
    return rgb[..., 0] * 0.299 + rgb[..., 1] * 0.587 + rgb[..., 2] * 0.114


def monochrome(rgb: np.ndarray) -> np.ndarray:
    """The stream of a camera in night mode: each pixel's BT.601 luma (`luma_bt601`) in all three channels (what a
    camera's ISP sends with its saturation at zero), same dtype and shape."""
    y = luma_bt601(rgb)
    if np.issubdtype(rgb.dtype, np.integer):
        y = np.clip(np.rint(y), np.iinfo(rgb.dtype).min, np.iinfo(rgb.dtype).max)
    return np.repeat(y[..., None].astype(rgb.dtype), rgb.shape[-1], axis=-1)
