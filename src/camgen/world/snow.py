"""Snow: a seeded population of falling aggregate flakes, their short streaks in the exposure, the haze of
the far ones. The population, the streaks and the haze are rain's (`camgen.world.rain`: `particles_in_box`,
`streak_coverage`, Koschmieder's law); what differs is the particles and the light they send.

**Sizes** (sourced). Gunn & Marshall (1958, "The distribution with size of aggregate snowflakes",
J. Meteor. 15, 452–461) fit the snow that reaches the ground with an exponential in the *melted* diameter
d of the flakes (the drop a flake melts into), for the liquid-water-equivalent rate R in mm/h:

    N(d) = N0 exp(−Λ d),   N0 = 3800 R^−0.87 m⁻³ mm⁻¹,   Λ = 2.55 R^−0.48 mm⁻¹

Sekhon & Srivastava (1970, "Snow size spectra and radar reflectivity", J. Atmos. Sci. 27, 299–307, whose
abstract was read) confirm the form in melted diameter with N0 = 2500 R^−0.94, Λ = 2.29 R^−0.45: their
N0/Λ⁴ (the moment that carries the water) is 0.89–1.15 of Gunn & Marshall's over 0.5–2 mm/h (1.27 at 0.3,
0.75 at 5). A check of the coefficients that needs no source: with the flakes' own fall speeds (below) the
distribution carries 0.84 R of water at R = 0.3 mm/h, 1.02 R at 1 mm/h, 1.14 R at 2 and 1.33 R at 5
(`melted_rate_mm_h`): the published pair is self-consistent where most snowfalls are.

**Flake diameter from melted diameter** (sourced). An aggregate's bulk density falls as it grows,
ρ_s = C3 / D (Holroyd 1971; the form Rasmussen et al. 1999 use): C3 = 0.017 g cm⁻² for dry snow, 0.072
g cm⁻² for wet or rimed snow (Rasmussen et al. 1999, J. Appl. Meteor. 38, 1542–1563, §4). Mass
conservation, ρ_w d³ = ρ_s D³, gives D = √(ρ_w d³ / C3): a 1 mm drop is a dry flake of 2.4 mm, a 2 mm
drop one of 6.9 mm.

**Fall speeds** (sourced). Dry: Locatelli & Hobbs (1974, "Fall speeds and masses of solid precipitation
particles", J. Geophys. Res. 79, 2185–2197, table 1), aggregates of unrimed radiating assemblages of
dendrites, v = 0.8 D^0.16 m/s (D the flake's largest dimension in mm, measured over 2–10 mm: 0.89 m/s at
2 mm, 1.16 m/s at 10 mm). Wet: 2 m/s, the value Rasmussen et al. (1999) take for wet or rimed
aggregates ("typically fall twice as fast", after Magono & Nakamura 1965). A flake class shares one
speed, its mean diameter's.

**Number of wet flakes** (estimate). Gunn & Marshall measured dry aggregates. A wet snowfall of the same
rate carries its water on flakes falling twice as fast, so camgen thins the spectrum by the ratio of the
two speeds (N0 × 1/2); not a measured spectrum.

**Visibility** (sourced). Rasmussen et al. (1999, eq. 13) derive, for an exponential spectrum of
flakes of density C3/D falling at V_t and extinction efficiency 2 (Koschmieder, V = 3.912/β):

    V = 1.3 C3 V_t / (ρ_w S)        (cgs: S the liquid-equivalent rate in cm/s, V in cm)

i.e. V = 796 m / R for dry snow (C3 = 0.017 g cm⁻², V_t = 1 m/s) and 6.74 km / R for wet (0.072 g cm⁻²,
2 m/s), R in mm/h: 0.40 km and 3.4 km at 2 mm/h. (The paper quotes 0.3 and 2.6 km at 2 mm/h; its
observations scatter by a factor of 3–10 in visibility at one rate.) Rain of 1 mm/h leaves 10.7 km
(`camgen.world.rain.rain_visibility_m`): a snowfall of the same rate is 13 times thicker. The Gunn–Marshall
flakes' own geometric extinction, β = (π/2)∫D² N dd, gives 785 m at 1 mm/h of dry snow (2 % from the
relation; 10 % at 5 mm/h): the drawn flakes and the haze agree.

**Light** (estimate from first principles, not a measured flake radiance). A flake is a loose aggregate of
ice that scatters nearly all the light it intercepts, in all directions, and refracts no image of its
surroundings (unlike a drop, `camgen.world.rain`): it is taken as an isotropic scatterer of albedo
FLAKE_ALBEDO. In the radiance L_sky of the sky above and L_ground of the ground below and a sun of
illuminance E_sun its radiance is

    L_flake = ω [ (L_sky + L_ground)/2 + E_sun / (4π) ]

brighter than a grey road under an overcast sky, darker than that sky (flakes against the sky look grey in
real footage); a lamp adds ω E/(4π) with its own E = I(θ)/d² at the flake (the glittering cone of flakes
under a street lamp). Real aggregates scatter forwards more than backwards, so a flake between the camera
and a lamp or the sun is brighter than this, one lit from behind the camera darker. In the camera's own IR
illuminator (night mode) a flake at z metres sees E = I(θ)/z² from
straight behind the camera, and a Lambertian sphere seen at zero phase has radiance (2/3) ρ E / π (its
geometric albedo is 2/3 of its reflectance): the bright specks near the lens of IR night footage.

**Not modelled.** Flakes drift with the scene's mean wind (`environment.wind`: speed and direction) but not
with its gusts, and do not flutter or tumble (a real dendrite aggregate wanders by centimetres as it
falls); the streak ignores the camera's own motion in the exposure; nothing shadows the flakes (a flake under
a roof is lit as in the open) and the lamps' pools on the ground do not light them; flakes are round soft
spots, not dendrite shapes; no snow settles on the ground or on the lens.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from camgen.world.fog import KOSCHMIEDER_CONSTANT
from camgen.world.rain import particles_in_box

SnowKind = Literal["dry", "wet"]

GUNN_MARSHALL_N0_PER_M3_MM = 3800.0
"""N0 = 3800 R^−0.87 m⁻³ mm⁻¹ (Gunn & Marshall 1958), R in mm/h of melted water."""
GUNN_MARSHALL_N0_EXPONENT = -0.87
GUNN_MARSHALL_LAMBDA_PER_MM = 2.55
"""Λ = 2.55 R^−0.48 mm⁻¹ (Gunn & Marshall 1958: 25.5 R^−0.48 cm⁻¹), of the melted diameter."""
GUNN_MARSHALL_LAMBDA_EXPONENT = -0.48

DENSITY_SIZE_G_CM2 = {"dry": 0.017, "wet": 0.072}
"""C3 of ρ_s = C3 / D, g cm⁻² (Rasmussen et al. 1999 §4, after Holroyd 1971): dry snow, wet or rimed snow."""
FALL_SPEED_MEAN_M_S = {"dry": 1.0, "wet": 2.0}
"""V_t of Rasmussen et al. (1999): the mean fall speed of dry and of wet or rimed aggregates, m/s."""
LOCATELLI_HOBBS_COEFFICIENT = 0.8
LOCATELLI_HOBBS_EXPONENT = 0.16
"""v = 0.8 D^0.16 m/s, D in mm: aggregates of unrimed radiating assemblages of dendrites (Locatelli & Hobbs 1974)."""

WATER_DENSITY_G_CM3 = 1.0
RASMUSSEN_CONSTANT = KOSCHMIEDER_CONSTANT / 3.0
"""The 1.3 of Rasmussen et al.'s eq. 13: ln 50 / 3 (Koschmieder's 3.912 over the 3 of β = 3 S / (C3 V_t))."""

MELTED_MIN_MM = 0.5
"""Smaller flakes (a dry flake under 0.9 mm) are not drawn: their streaks are faint; they are in the haze."""
MELTED_MAX_MM = 4.0
"""Larger melted diameters (a dry flake over 19 mm) are under 1 % of the drawn flakes up to 3 mm/h (5 % at
10 mm/h)."""
MELTED_STEP_MM = 0.25
"""Width of a melted-diameter class; its flakes share one flake diameter and one speed."""

FLAKE_ALBEDO = 0.9
"""ω, the share of the light falling on a flake's disc π/4 D² that it scatters (an estimate): ice absorbs little
light below 0.9 µm, visible or the illuminator's 850 nm (pure snow's visible albedo is 0.96–0.99, Warren &
Wiscombe 1980, J. Atmos. Sci. 37, 2734–2745, whose abstract was read; Warren 1982, Rev. Geophys. 20, 67–89),
so a flake loses mostly what passes between its branches; 0.9, fresh snow's albedo, is taken for both."""
LAMBERT_SPHERE_GEOMETRIC_ALBEDO = 2.0 / 3.0
"""A Lambertian sphere's radiance at zero phase angle over a flat Lambertian disc's (its geometric albedo over
its reflectance)."""

SNOW_KEY = 0x534E4F57
"""Seeds snow's population apart from rain's of the same seed ('SNOW')."""


def gunn_marshall_n0_per_m3_mm(rate_mm_h: float, kind: SnowKind = "dry") -> float:
    """N0 of the melted-diameter spectrum, m⁻³ mm⁻¹: Gunn & Marshall's 3800 R^−0.87 for dry snow, times
    1/2 for wet snow (module docstring: "Number of wet flakes", an estimate)."""
    thinning = FALL_SPEED_MEAN_M_S["dry"] / FALL_SPEED_MEAN_M_S[kind]
    return GUNN_MARSHALL_N0_PER_M3_MM * rate_mm_h**GUNN_MARSHALL_N0_EXPONENT * thinning


def gunn_marshall_lambda_per_mm(rate_mm_h: float) -> float:
    """Λ = 2.55 R^−0.48 mm⁻¹ of the melted diameter (Gunn & Marshall 1958), R in mm/h."""
    return GUNN_MARSHALL_LAMBDA_PER_MM * rate_mm_h**GUNN_MARSHALL_LAMBDA_EXPONENT


def flake_density_per_m3(rate_mm_h: float, melted_lo_mm: float, melted_hi_mm: float, kind: SnowKind = "dry") -> float:
    """Flakes per m³ whose melted diameters lie in [lo, hi] mm: N0/Λ (e^−Λ·lo − e^−Λ·hi)."""
    lam = gunn_marshall_lambda_per_mm(rate_mm_h)
    n0 = gunn_marshall_n0_per_m3_mm(rate_mm_h, kind)
    return n0 / lam * (math.exp(-lam * melted_lo_mm) - math.exp(-lam * melted_hi_mm))


def flake_diameter_mm(melted_diameter_mm, kind: SnowKind = "dry") -> np.ndarray:
    """D = √(ρ_w d³ / C3) mm: the flake whose bulk density C3/D holds the water of a drop of d mm."""
    d_cm = np.asarray(melted_diameter_mm, dtype=np.float64) * 0.1
    return np.sqrt(WATER_DENSITY_G_CM3 * d_cm**3 / DENSITY_SIZE_G_CM2[kind]) * 10.0


def fall_speed_m_s(flake_diameter_mm, kind: SnowKind = "dry") -> np.ndarray:
    """A flake's fall speed, m/s: 0.8 D^0.16 for dry aggregates (Locatelli & Hobbs 1974), 2 m/s for wet
    ones (Rasmussen et al. 1999)."""
    diameter = np.asarray(flake_diameter_mm, dtype=np.float64)
    if kind == "wet":
        return np.full(diameter.shape, FALL_SPEED_MEAN_M_S["wet"])
    return LOCATELLI_HOBBS_COEFFICIENT * diameter**LOCATELLI_HOBBS_EXPONENT


def melted_classes(rate_mm_h: float, kind: SnowKind = "dry") -> tuple[np.ndarray, np.ndarray]:
    """(melted_diameters_mm, densities_per_m3) of the classes MELTED_MIN_MM…MELTED_MAX_MM in steps of
    MELTED_STEP_MM: each class's mean melted diameter under the spectrum and its flakes per m³."""
    edges = np.arange(MELTED_MIN_MM, MELTED_MAX_MM + 1e-9, MELTED_STEP_MM)
    lam = gunn_marshall_lambda_per_mm(rate_mm_h)
    lo, hi = edges[:-1], edges[1:]
    a, b = np.exp(-lam * lo), np.exp(-lam * hi)
    density = gunn_marshall_n0_per_m3_mm(rate_mm_h, kind) / lam * (a - b)
    mean = (a * (lo + 1 / lam) - b * (hi + 1 / lam)) / (a - b)  # ∫ d e^−Λd / ∫ e^−Λd over the class
    return mean, density


def melted_rate_mm_h(rate_mm_h: float, kind: SnowKind = "dry") -> float:
    """The liquid-water rate the whole spectrum (0 to ∞) carries at the flakes' fall speeds, mm/h:
    ρ_w (π/6) ∫ d³ v(D(d)) N(d) dd — equal to `rate_mm_h` where the published coefficients are consistent."""
    lam = gunn_marshall_lambda_per_mm(rate_mm_h)
    d = np.linspace(0.0, 40.0 / lam, 20001)[1:]
    integrand = d**3 * fall_speed_m_s(flake_diameter_mm(d, kind), kind) * np.exp(-lam * d)
    flux_mm3_m2_s = math.pi / 6 * gunn_marshall_n0_per_m3_mm(rate_mm_h, kind) * float(np.trapezoid(integrand, d))
    return flux_mm3_m2_s * 1e-9 * 1e3 * 3600.0  # mm³ of water per m² per s → mm/h


def snow_visibility_m(rate_mm_h: float, kind: SnowKind = "dry") -> float:
    """Visual range of snow alone, m (Rasmussen et al. 1999, eq. 13): 1.3 C3 V_t / (ρ_w S), S in cm/s;
    796 m / R dry, 6.74 km / R wet, R in mm/h."""
    rate_cm_s = rate_mm_h * 0.1 / 3600.0
    fall_speed_cm_s = FALL_SPEED_MEAN_M_S[kind] * 100.0
    visibility_cm = RASMUSSEN_CONSTANT * DENSITY_SIZE_G_CM2[kind] * fall_speed_cm_s / (WATER_DENSITY_G_CM3 * rate_cm_s)
    return visibility_cm * 0.01


def flake_extinction_per_m(rate_mm_h: float, kind: SnowKind = "dry") -> float:
    """β = (π/2) ∫ D(d)² N(d) dd · 10⁻⁶ m⁻¹ over the whole spectrum: the geometric-optics extinction
    (efficiency 2) of the flakes themselves, 3π N0 ρ_w / (C3 Λ⁴) in closed form."""
    lam = gunn_marshall_lambda_per_mm(rate_mm_h)
    c3_mm = DENSITY_SIZE_G_CM2[kind] * 10.0 / WATER_DENSITY_G_CM3  # D² = d³ / c3_mm, all in mm
    return 3 * math.pi * gunn_marshall_n0_per_m3_mm(rate_mm_h, kind) / (c3_mm * lam**4) * 1e-6


def flake_classes(rate_mm_h: float, kind: SnowKind = "dry") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(flake_diameters_mm, densities_per_m3, speeds_m_s) of the drawn classes (`melted_classes`)."""
    melted, densities = melted_classes(rate_mm_h, kind)
    diameters = flake_diameter_mm(melted, kind)
    return diameters, densities, fall_speed_m_s(diameters, kind)


def flakes_in_box(
    low_m,
    high_m,
    time_s: float,
    rate_mm_h: float,
    seed: int,
    kind: SnowKind = "dry",
    drift_m_s: tuple[float, float] = (0.0, 0.0),
    classes=None,
    planes: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every flake inside the world box [low_m, high_m] (3,) at `time_s`, from the seeded population,
    drifting at `drift_m_s` (the wind's (x, y), m/s); of the class indices `classes` of `flake_classes`
    only (default all: each class is its own population, so a caller may look for each in its own box);
    `planes`: half-spaces whose outside the caller does not need (`camgen.world.rain.particles_in_box`).

    Returns positions_m (N, 3), flake diameters_mm (N,) and speeds_m_s (N,). A flake found at t is found at
    t + Δt moved by (u Δt, w Δt, −v Δt) (`camgen.world.rain.particles_in_box`)."""
    diameters, densities, speeds = flake_classes(rate_mm_h, kind)
    found = []
    for c in range(len(diameters)) if classes is None else classes:
        positions, _ = particles_in_box(
            low_m, high_m, time_s, densities[c : c + 1], speeds[c : c + 1], (seed, SNOW_KEY, c), drift_m_s, planes
        )
        found.append((positions, np.full(len(positions), diameters[c]), np.full(len(positions), speeds[c])))
    if not found:
        return np.zeros((0, 3)), np.zeros(0), np.zeros(0)
    positions, diameters_mm, speeds_m_s = (np.concatenate(parts) for parts in zip(*found, strict=True))
    return positions, diameters_mm, speeds_m_s


def wind_drift_m_s(wind) -> tuple[float, float]:
    """(u, w) m/s of a `camgen.config.scene.Wind` (its mean speed towards direction_deg, counter-clockwise
    from +X); (0, 0) for None."""
    if wind is None:
        return 0.0, 0.0
    heading = math.radians(wind.direction_deg)
    return wind.speed_m_s * math.cos(heading), wind.speed_m_s * math.sin(heading)


def flake_radiance(sky_radiance, ground_radiance, sun_illuminance=0.0, albedo: float = FLAKE_ALBEDO) -> np.ndarray:
    """(3,) an isotropic scatterer's radiance: ω [(L_sky + L_ground)/2 + E_sun/(4π)] (module docstring),
    from the sky's radiance above (3,), the ground's below (3,) and the sun's illuminance normal to its
    beam (3,) or scalar, all in one unit system (cd/m² and lux in camgen's renderer)."""
    sky, ground = np.asarray(sky_radiance, np.float64), np.asarray(ground_radiance, np.float64)
    sun = np.asarray(sun_illuminance, np.float64)
    return (albedo * (0.5 * (sky + ground) + sun / (4 * math.pi))).astype(np.float32)


def illuminated_flake_radiance(illuminance, albedo: float = FLAKE_ALBEDO) -> np.ndarray:
    """A flake's radiance in a light from straight behind the camera of illuminance E (any shape):
    (2/3) ρ E / π, a Lambertian sphere at zero phase angle."""
    return LAMBERT_SPHERE_GEOMETRIC_ALBEDO * albedo * np.asarray(illuminance, np.float64) / math.pi
