"""Rain: a seeded population of falling drops, their streaks in the exposure, the haze of the far ones,
and wet ground.

Drop sizes follow Marshall & Palmer (1948, "The distribution of raindrops with size", J. Meteor. 5,
165–166):

    N(D) = N0 exp(−Λ D),   N0 = 8000 m⁻³ mm⁻¹,   Λ = 4.1 R^−0.21 mm⁻¹     (R the rain rate, mm/h)

so a cubic metre holds N0/Λ (e^−Λ·D_lo − e^−Λ·D_hi) drops of diameter D_lo…D_hi. Drops fall at their
terminal speed, measured by Gunn & Kinzer (1949, "The terminal velocity of fall for water droplets in
stagnant air", J. Meteor. 6, 243–248) and fitted by Atlas, Srivastava & Sekhon (1973, "Doppler radar
characteristics of precipitation at vertical incidence", Rev. Geophys. 11, 1–35):

    v(D) = 9.65 − 10.3 exp(−0.6 D)   m/s   (D in mm; 4.0 m/s at 1 mm, 8.1 m/s at 3 mm)

Rain rates by intensity (AMS Glossary of Meteorology, "rain"; WMO-No. 8 (2018) Vol. I §14.2.1):
light up to 2.5 mm/h, moderate 2.5–7.6 mm/h, heavy above 7.6 mm/h.

**Streaks.** A drop moves during the exposure T and smears into a streak v·T long, which a camera
images as v·T·f/z pixels for a drop z metres ahead falling across the view. Garg & Nayar (2004,
"Detection and removal of rain from videos", CVPR; 2007, "Vision and rain", IJCV 75, 3–27) show that a
pixel the streak crosses sees the drop for only τ of the exposure (τ ≈ D_px / v_px, the time the drop's
image takes to pass the pixel) and its background the rest:

    L = (1 − α) L_background + α L_drop,    α = (area the drop's image covers in the pixel) × τ / T

Summed along a streak α carries the drop's whole image area, π/4·(D f/z)² px², spread over its
length: `streak_coverage` splats exactly that along each projected streak. A drop, a wide-angle lens,
refracts the light of about 165° of the environment (Garg & Nayar 2007, §3), so its radiance L_drop is
the environment's mean over a wide field, not its background's: camgen takes the mean of the horizon
sky and of the frame (`drop_radiance`).

**Population.** Drops live in a frame of their own: a drop of speed v at height z at time t has the
fall-invariant height s = z + v t. Space (x, y, s) is cut into cubic cells CELL_M on a side; each
cell and diameter class draws its drops (Poisson count, uniform positions) from a generator seeded by
(seed, class, cell), so any region at any time is reproduced exactly, a drop keeps its x, y and s from
frame to frame (it falls by v·Δt between frames) and no drop is stored. Diameters are binned into
classes of DIAMETER_STEP_MM; a class's drops share its Marshall–Palmer mean diameter and that
diameter's speed.

**Haze.** Drops beyond STREAK_RANGE_M are not drawn: their streaks are faint (at 15 m a 3 mm drop
covers α ≈ 0.004 of a pixel for T = 20 ms, f = 1500 px) and many per pixel, so they act as a uniform
extinction. For drops much larger than the wavelength the extinction efficiency is 2 (van de Hulst 1957,
*Light scattering by small particles*, §8.22), so β = (π/2)∫D² N(D) dD = π N0 / Λ³ (in mm² per m³),
which under Marshall–Palmer is

    β = 3.65·10⁻⁴ R^0.63 m⁻¹,   V = 3.912 / β ≈ 10.7 km · R^−0.63

(3.9 km at 5 mm/h, 1.4 km at 25 mm/h) — Koschmieder's law (`camgen.world.fog`) with this visual
range, over the part of each pixel's distance beyond STREAK_RANGE_M.

**Not modelled.** Drops fall straight down (no wind); the streak ignores the camera's own motion during
the exposure (a panning PTZ); drops nearer than NEAR_M or imaged wider than DROP_IMAGE_MAX_PX (out of
focus) are left out rather than blurred; lamps do not light the drops (at night they show the dark
environment's mean); no splashes, no drops on the lens or its dome.

**Wet ground.** A water film darkens a rough surface (light that the film reflects back inside is
absorbed again: Lekner & Dorf 1988, "Why some things are darker when wet", Appl. Opt. 27, 1278–1280;
Twomey, Bohren & Mergenthaler 1986, Appl. Opt. 25, 431–437 measure 0.5–0.7 of the dry reflectance for
soils, sand and asphalt-like materials) and smooths it: WET_ALBEDO_FACTOR and WET_ROUGHNESS_FACTOR.

**Reflections in the wet road.** Over the wet surface lies a film of water whose own surface mirrors the
scene: the share `water_fresnel` of the light reaching it from the mirror direction is reflected (Fresnel's
equations for unpolarised light at water's refractive index, 1.333: 2 % looking straight down, 6 % at
60° from the vertical, 13 % at 70°, 35 % at 80°, 80 % at 88°, so a road seen at a grazing angle mirrors the sky brightly
while the road under the camera barely does), and the rest (1 − F) reaches the road beneath, which is
shaded as before. The film is not flat: rain's ripples and the road's texture tilt it, which spreads each
mirrored ray (`WATER_FILM_SLOPE_RAD`): a tilt δ in the plane of incidence turns the reflected ray by 2δ,
a tilt across it by 2δ·cos θᵢ, so at a grazing angle a reflection is smeared up and down far more than
sideways — the vertical streaks of lamps and lit windows on a wet street.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from camgen.config.placement import largest_level_plane

MARSHALL_PALMER_N0_PER_M3_MM = 8000.0
"""N0 of Marshall & Palmer (1948), m⁻³ mm⁻¹."""

RAIN_RATE_LIGHT_MAX_MM_H = 2.5
RAIN_RATE_MODERATE_MAX_MM_H = 7.6
"""AMS Glossary of Meteorology ("rain"), WMO-No. 8 §14.2.1: light < 2.5, moderate 2.5–7.6, heavy > 7.6 mm/h."""

DIAMETER_MIN_MM = 1.0
"""Smaller drops are not drawn as streaks: a 0.5 mm drop (v = 2.1 m/s) covers α ≈ 0.007/z of a pixel at z m
(T = 1/50 s, f = 1500 px), invisible beyond a metre or so; they are in the haze beyond STREAK_RANGE_M."""
DIAMETER_MAX_MM = 6.0
"""Larger drops break up (Pruppacher & Klett 1997, *Microphysics of clouds and precipitation*); Marshall–Palmer
gives them ≪ 1 % of drops."""
DIAMETER_STEP_MM = 0.5
"""Width of a diameter class; its drops share one speed (v varies by ≤ 1.2 m/s across a class above 1 mm)."""
CELL_M = 4.0
"""Edge of a population cell in (x, y, s), m."""
STREAK_RANGE_M = 15.0
"""Drops are drawn as streaks up to this distance from the camera, m; the rest is haze."""
NEAR_M = 0.3
"""Drops nearer than this are not drawn (out of focus for a surveillance camera), m."""
DROP_IMAGE_MAX_PX = 3.0
"""Drops whose image is wider than this (very near, out of focus, blurred over many pixels) are not drawn."""
SAMPLE_ALPHA_MAX = 0.01
"""Most coverage one sample of a streak may put on a pixel: a faint streak (a small or far drop) is sampled
more sparsely than one sample per pixel, down to one sample at its middle, so that a frame's cost follows
the rain's light rather than its number of drops (hundreds of thousands within 15 m); at full contrast
1 % is 2.5 steps of 8 bits, and a drop's contrast against its background is usually well under full."""
SAMPLES_MAX = 256
"""Most samples along one streak (a streak longer than this many pixels is sampled more sparsely)."""

WET_ALBEDO_FACTOR = 0.6
"""Wet over dry reflectance of a rough ground (0.5–0.7: Twomey et al. 1986; Lekner & Dorf 1988)."""
WET_ROUGHNESS_FACTOR = 0.35
"""Wet over dry roughness: a dry asphalt's 0.8–0.9 becomes 0.28–0.32, the 0.2–0.4 of a wet road's glossy
lobe (measured wet-asphalt BRDFs are far sharper than dry ones; a film of standing water would be a mirror,
the water film's own mirror reflection is added on top: `water_fresnel`, `camgen.render.wet`)."""

WATER_REFRACTIVE_INDEX = 1.333
"""Refractive index of water for visible light (1.333 at 589 nm and 20 °C: CRC Handbook of Chemistry and
Physics; 1.331–1.337 over 400–700 nm)."""
WATER_FILM_SLOPE_RAD = 0.008
"""RMS tilt of the water film's surface on a wet road, rad (≈ 0.5°): rain's ripples and the asphalt's
macrotexture under a thin film. Not a measured value: no published slope statistics of films on roads
were found (Cox & Munk 1954 measure wind-driven sea slopes of 0.1–0.2 rad, far rougher than a film
between kerbs). A mirror image is spread by σ = 2·0.008·f px up and down (16 px at f = 1000 px) and
less across; the broad glossy highlight of each lamp on the wet asphalt itself is the shader's
(WET_ROUGHNESS_FACTOR). At 0.02 rad a lantern's mirror image on the night street became a saturated
disc 150 px across."""


def ground_is_wet(environment) -> bool:
    """Whether a scene's ground is wet: its `environment.wet`, or while it rains when that is left out."""
    return environment.rain is not None if environment.wet is None else bool(environment.wet)


def wet_ground_height_m(environment) -> float | None:
    """The height of the wet ground whose water film mirrors the scene (`camgen.render.wet`), m: the largest level
    plane facing up among `environment.meshes` when the ground is wet (`ground_is_wet`); None for a dry ground
    or one without such a plane (nothing is mirrored then, and the plan draws nothing for it)."""
    if not ground_is_wet(environment):
        return None
    ground = largest_level_plane(environment.meshes)
    return None if ground is None else float(ground.position_m[2])


def water_fresnel(cos_incidence: np.ndarray, n: float = WATER_REFRACTIVE_INDEX) -> np.ndarray:
    """Reflectance of a smooth water surface for unpolarised light arriving at angle θᵢ from its normal
    (`cos_incidence` = cos θᵢ, 0–1): the mean of Fresnel's s and p reflectances,
    r_s = (cos θᵢ − n cos θₜ)/(cos θᵢ + n cos θₜ), r_p = (n cos θᵢ − cos θₜ)/(n cos θᵢ + cos θₜ),
    sin θₜ = sin θᵢ / n (Born & Wolf, *Principles of Optics*, §1.5.2). 0.020 at normal incidence, 1 at grazing."""
    cos_i = np.clip(np.asarray(cos_incidence, np.float64), 0.0, 1.0)
    cos_t = np.sqrt(1.0 - (1.0 - cos_i * cos_i) / (n * n))
    r_s = (cos_i - n * cos_t) / (cos_i + n * cos_t)
    r_p = (n * cos_i - cos_t) / (n * cos_i + cos_t)
    return 0.5 * (r_s * r_s + r_p * r_p)


def marshall_palmer_lambda_per_mm(rate_mm_h: float) -> float:
    """Λ = 4.1 R^−0.21 mm⁻¹ of Marshall & Palmer (1948) for a rain rate R in mm/h."""
    return 4.1 * rate_mm_h**-0.21


def drop_density_per_m3(rate_mm_h: float, diameter_lo_mm: float, diameter_hi_mm: float) -> float:
    """Drops per m³ with diameters in [lo, hi] mm: N0/Λ (e^−Λ·lo − e^−Λ·hi) (Marshall & Palmer 1948)."""
    lam = marshall_palmer_lambda_per_mm(rate_mm_h)
    return MARSHALL_PALMER_N0_PER_M3_MM / lam * (math.exp(-lam * diameter_lo_mm) - math.exp(-lam * diameter_hi_mm))


def terminal_speed_m_s(diameter_mm):
    """v = 9.65 − 10.3 exp(−0.6 D) m/s for a drop of diameter D mm (Atlas et al. 1973's fit to Gunn &
    Kinzer 1949); any shape."""
    return 9.65 - 10.3 * np.exp(-0.6 * np.asarray(diameter_mm, dtype=np.float64))


def rain_extinction_per_m(rate_mm_h: float) -> float:
    """β = π N0 / Λ³ ·10⁻⁶ m⁻¹: the geometric-optics extinction (efficiency 2) of a Marshall–Palmer rain."""
    return math.pi * MARSHALL_PALMER_N0_PER_M3_MM / marshall_palmer_lambda_per_mm(rate_mm_h) ** 3 * 1e-6


def rain_visibility_m(rate_mm_h: float) -> float:
    """Koschmieder visual range 3.912/β of a rain of `rate_mm_h` alone (≈ 10.7 km · R^−0.63), m."""
    return math.log(50.0) / rain_extinction_per_m(rate_mm_h)


def diameter_classes(rate_mm_h: float) -> tuple[np.ndarray, np.ndarray]:
    """(diameters_mm, densities_per_m3) of the classes DIAMETER_MIN_MM…DIAMETER_MAX_MM in steps of
    DIAMETER_STEP_MM: each class's Marshall–Palmer mean diameter and its number of drops per m³."""
    edges = np.arange(DIAMETER_MIN_MM, DIAMETER_MAX_MM + 1e-9, DIAMETER_STEP_MM)
    lam = marshall_palmer_lambda_per_mm(rate_mm_h)
    lo, hi = edges[:-1], edges[1:]
    density = MARSHALL_PALMER_N0_PER_M3_MM / lam * (np.exp(-lam * lo) - np.exp(-lam * hi))
    # Mean of D e^{−ΛD} over [lo, hi] divided by the mean of e^{−ΛD}.
    a, b = np.exp(-lam * lo), np.exp(-lam * hi)
    mean = (a * (lo + 1 / lam) - b * (hi + 1 / lam)) / (a - b)
    return mean, density


_CELL_OFFSET = 1 << 30
_CUBE_CORNERS = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], np.float64)


def drops_in_box(
    low_m, high_m, time_s: float, rate_mm_h: float, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every drop inside the world box [low_m, high_m] (3,) at `time_s`, from the seeded population.

    Returns positions_m (N, 3) in the world, diameters_mm (N,) and speeds_m_s (N,). Deterministic in
    (seed, time_s, box); a drop found at t is found at t + Δt lowered by v·Δt (module docstring)."""
    diameters, densities = diameter_classes(rate_mm_h)
    speeds = terminal_speed_m_s(diameters)
    positions, classes = particles_in_box(low_m, high_m, time_s, densities, speeds, (seed,))
    return positions, diameters[classes], speeds[classes]


def particles_in_box(
    low_m,
    high_m,
    time_s: float,
    densities_per_m3: np.ndarray,
    speeds_m_s: np.ndarray,
    key: tuple[int, ...],
    drift_m_s: tuple[float, float] = (0.0, 0.0),
    planes: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Every particle inside the world box [low_m, high_m] (3,) at `time_s` of a seeded population of
    classes (`densities_per_m3` (C,) particles per m³ falling at `speeds_m_s` (C,)), all drifting
    horizontally at `drift_m_s` (x, y): rain's drops and snow's flakes (`camgen.world.snow`) alike.

    A particle of class c lives at a fixed point of the frame moving with its class, (x − u t, y − w t,
    z + v t), cut into cubic cells CELL_M on a side; each (class, cell) draws its Poisson count and uniform
    positions from a generator seeded by (*key, class, cell), so any region at any time is reproduced
    exactly and no particle is stored (module docstring, "Population"). `planes` (P, 4): (n, d) of half-spaces
    n·x + d ≥ 0 in the world (a view's frustum); a cell wholly outside one of them is not drawn, so that a
    caller who keeps only the particles inside them pays for the box's cells that reach in, and gets the same
    particles. Returns positions_m (N, 3) in the world and each particle's class index (N,) int8."""
    low_m, high_m = np.asarray(low_m, np.float64), np.asarray(high_m, np.float64)
    u_m_s, w_m_s = float(drift_m_s[0]), float(drift_m_s[1])
    positions, classes = [], []
    for c, (density, speed) in enumerate(zip(densities_per_m3, speeds_m_s, strict=True)):
        shift = np.array([-u_m_s * time_s, -w_m_s * time_s, speed * time_s])  # world → the class's frame
        lo, hi = low_m + shift, high_m + shift
        cells = [range(math.floor(lo[i] / CELL_M), math.floor(hi[i] / CELL_M) + 1) for i in range(3)]
        mean_count = density * CELL_M**3
        ijk = np.stack(np.meshgrid(*cells, indexing="ij"), axis=-1).reshape(-1, 3)
        if planes is not None:  # a cell is left out when its 8 corners all lie outside one plane
            corners = (ijk[:, None, :] + _CUBE_CORNERS) * CELL_M - shift  # (cells, 8, 3) in the world
            outside = corners @ planes[:, :3].T + planes[:, 3] < 0  # (cells, 8, planes)
            ijk = ijk[~np.any(np.all(outside, axis=1), axis=1)]
        for i, j, k in ijk.tolist():
            rng = np.random.default_rng((*key, c, i + _CELL_OFFSET, j + _CELL_OFFSET, k + _CELL_OFFSET))
            cell = rng.random((rng.poisson(mean_count), 3))
            cell += (i, j, k)
            cell *= CELL_M
            cell -= shift
            positions.append(cell)
            classes.append(np.full(len(cell), c, np.int8))
    if not positions:
        return np.zeros((0, 3)), np.zeros(0, np.int8)
    p, c = np.concatenate(positions), np.concatenate(classes)
    inside = np.all((p >= low_m) & (p <= high_m), axis=1)
    return p[inside], c[inside]


def streak_coverage(
    positions_cam_m: np.ndarray,
    diameters_mm: np.ndarray,
    fall_cam_m: np.ndarray,
    K_px: np.ndarray,
    depth_m: np.ndarray,
) -> np.ndarray:
    """(H, W) float32 α: the fraction of each pixel's exposure that rain drops cover it (Garg & Nayar 2007).

    positions_cam_m (N, 3): each drop at the middle of the exposure, camera frame (OpenCV); fall_cam_m
    (N, 3): its displacement over the whole exposure (v·T down, in the camera frame); K_px (3, 3);
    depth_m (H, W): camera z of the nearest surface (+inf for the sky) — a drop behind it is hidden.
    Each streak is sampled at n points evenly along it, every sample carrying 1/n of the drop's image
    area π/4 (D f / z)² and splatted bilinearly: n is about its length in pixels, or fewer when each
    sample would carry less than SAMPLE_ALPHA_MAX; the sum is clipped to 1. Drops imaged wider than
    DROP_IMAGE_MAX_PX are left out (`streak_layers`)."""
    return streak_layers(positions_cam_m, diameters_mm, fall_cam_m, K_px, depth_m)[0]


SPREAD_SHARP_PX = 0.5
"""A particle whose footprint σ (`streak_layers`' spread_px) is under this is splatted bilinearly, as a point."""
SPREAD_STEP = math.sqrt(2.0)
"""Ratio between the σ of successive blurred layers of `streak_layers` (a footprint takes its layer's σ:
at most 19 % wider or narrower)."""


def streak_layers(
    positions_cam_m: np.ndarray,
    diameters_mm: np.ndarray,
    fall_cam_m: np.ndarray,
    K_px: np.ndarray,
    depth_m: np.ndarray,
    *,
    image_max_px: float = DROP_IMAGE_MAX_PX,
    spread_px: np.ndarray | None = None,
    values: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray | None]:
    """(α, Σ α·value): `streak_coverage` for any falling particles (rain's drops, snow's flakes), with two
    options it leaves off.

    `spread_px` (N,): σ of each particle's footprint in pixels (its image, its defocus): the samples of a
    particle with σ ≥ SPREAD_SHARP_PX are splatted into a layer of their σ (in steps of SPREAD_STEP) that
    is then blurred by a Gaussian of that σ, which spreads each one's coverage without changing its sum;
    the depth test is at the sample's own pixel. Such a streak is sampled every σ pixels rather than every
    pixel. None: every sample is a point, as rain's.
    `values` (N,) or (N, K): a quantity per particle (its own radiance, or K of them: its colour); the second
    array, (H, W) or (H, W, K), is Σ α_i·value_i over the particles covering each pixel, scaled down with α
    where α is clipped to 1. None: None.
    `image_max_px`: particles imaged wider than this (their diameter at their depth) are left out."""
    height_px, width_px = depth_m.shape
    f_px = math.sqrt(abs(K_px[0, 0] * K_px[1, 1]))
    start, end = positions_cam_m - fall_cam_m / 2, positions_cam_m + fall_cam_m / 2
    keep = (start[:, 2] > NEAR_M) & (end[:, 2] > NEAR_M)
    keep &= diameters_mm * 1e-3 * f_px / positions_cam_m[:, 2].clip(NEAR_M) <= image_max_px
    start, end, diameters_mm = start[keep], end[keep], diameters_mm[keep]
    spread = None if spread_px is None else np.asarray(spread_px, np.float64)[keep]
    value = None if values is None else np.asarray(values, np.float64).reshape(len(keep), -1)[keep]
    coverage = np.zeros((height_px, width_px), np.float64)
    valued = None if values is None else np.zeros((height_px, width_px, value.shape[1]), np.float64)
    if len(start):
        padded_depth = np.full((height_px + 2, width_px + 2), -np.inf, np.float32)  # the border hides every splat
        padded_depth[1:-1, 1:-1] = depth_m
        x0, y0 = _project(start, K_px)
        x1, y1 = _project(end, K_px)
        # Streaks wholly outside the image (their bounding box, widened by 3σ, misses it) are not sampled.
        margin = 1.0 if spread is None else 1.0 + 3 * spread
        seen = (np.maximum(x0, x1) > -margin) & (np.minimum(x0, x1) < width_px - 1 + margin)
        seen &= (np.maximum(y0, y1) > -margin) & (np.minimum(y0, y1) < height_px - 1 + margin)
        length_px = np.hypot(x1 - x0, y1 - y0)[seen]
        start, end, diameters_mm = start[seen], end[seen], diameters_mm[seen]
        spread = None if spread is None else spread[seen]
        value = None if value is None else value[seen]
        if spread is None:
            layers = np.zeros(len(start), np.int64)
        else:  # 0 sharp; b ≥ 1 blurred by SPREAD_SHARP_PX·SPREAD_STEP^(b−1)
            steps = np.log(np.maximum(spread, SPREAD_SHARP_PX) / SPREAD_SHARP_PX) / math.log(SPREAD_STEP)
            layers = np.where(spread < SPREAD_SHARP_PX, 0, np.floor(steps + 0.5).astype(np.int64) + 1)
        unique = np.unique(layers)
        for b in unique:
            chosen = slice(None) if len(unique) == 1 else layers == b
            sigma_px = 0.0 if b == 0 else SPREAD_SHARP_PX * SPREAD_STEP ** (b - 1)
            parts = _splat_streaks(
                start[chosen],
                end[chosen],
                diameters_mm[chosen],
                length_px[chosen],
                None if value is None else value[chosen],
                sigma_px,
                K_px,
                padded_depth,
                f_px,
            )
            totals = [coverage] + ([] if valued is None else [valued[..., k] for k in range(valued.shape[2])])
            for total, image in zip(totals, [parts[0], *parts[1]], strict=True):
                if sigma_px > 0:
                    _add_blurred(total, image, sigma_px, parts[2])
                else:
                    total += image
    clipped = np.minimum(coverage, 1.0)
    if valued is not None:
        valued *= np.divide(clipped, coverage, out=np.ones_like(coverage), where=coverage > 1.0)[..., None]
        valued = valued.astype(np.float32)
        if np.ndim(values) == 1:
            valued = valued[..., 0]
    return clipped.astype(np.float32), valued


BLUR_TILE_PX = 256
"""`_add_blurred` blurs a layer tile by tile, only the tiles its splats reached."""


def _add_blurred(total: np.ndarray, image: np.ndarray, sigma_px: float, tiles: np.ndarray | None = None) -> None:
    """total += `image` blurred by a Gaussian of σ `sigma_px` (zero beyond the frame), computed over the
    BLUR_TILE_PX tiles of `image` that hold anything (`tiles` (T, 2), the (top, left) of each, when the
    caller knows them), each with a margin wider than OpenCV's kernel (its radius is 4σ): a sparse layer
    (a few flakes near the lens) costs its tiles, not the frame."""
    height_px, width_px = image.shape
    margin = math.ceil(4 * sigma_px) + 1
    if tiles is None:
        corners = [
            (top, left) for top in range(0, height_px, BLUR_TILE_PX) for left in range(0, width_px, BLUR_TILE_PX)
        ]
    else:
        corners = tiles.tolist()
    for top, left in corners:
        tile = image[top : top + BLUR_TILE_PX, left : left + BLUR_TILE_PX]
        if tiles is None and not tile.any():
            continue
        y0, x0 = max(top - margin, 0), max(left - margin, 0)
        y1, x1 = min(top + tile.shape[0] + margin, height_px), min(left + tile.shape[1] + margin, width_px)
        window = np.zeros((y1 - y0, x1 - x0))
        window[top - y0 : top - y0 + tile.shape[0], left - x0 : left - x0 + tile.shape[1]] = tile
        total[y0:y1, x0:x1] += cv2.GaussianBlur(window, (0, 0), sigma_px, borderType=cv2.BORDER_CONSTANT)


def _splat_streaks(
    start: np.ndarray,
    end: np.ndarray,
    diameters_mm: np.ndarray,
    length_px: np.ndarray,
    value: np.ndarray | None,
    sigma_px: float,
    K_px: np.ndarray,
    padded_depth: np.ndarray,
    f_px: float,
) -> tuple[np.ndarray, list[np.ndarray], np.ndarray | None]:
    """The (H, W) float64 sum of α of the samples of streaks from `start` to `end` (N, 3) splatted bilinearly
    as points and depth-tested at the pixels they reach (`streak_layers`), unclipped; the sums of α·value,
    one (H, W) per column of `value` (N, K) (none without); and with footprints (σ > 0) the (top, left) of
    the BLUR_TILE_PX tiles they reached (else None). Footprints of σ = `sigma_px` (0: points) set how densely
    each streak is sampled. `padded_depth`: the depth map with a border of −inf a pixel wide (which hides the
    splats that fall off the frame)."""
    height_px, width_px = padded_depth.shape[0] - 2, padded_depth.shape[1] - 2
    # Samples along each streak: one per pixel of its length (per σ of a spread one), or fewer where each
    # then still carries at most SAMPLE_ALPHA_MAX of a pixel (a faint streak's light is spread no less
    # evenly than it shows; a spread sample's light is shared by about 2πσ² pixels).
    middle_z = (start[:, 2] + end[:, 2]) / 2
    area_px2 = math.pi / 4 * (diameters_mm * 1e-3 * f_px / middle_z) ** 2
    if sigma_px == 0:
        n = np.minimum(np.ceil(length_px) + 1, np.ceil(area_px2 / SAMPLE_ALPHA_MAX))
    else:
        footprint_px2 = max(1.0, 2 * math.pi * sigma_px**2)
        n = np.minimum(
            np.ceil(length_px / max(sigma_px, 1.0)) + 1, np.ceil(area_px2 / footprint_px2 / SAMPLE_ALPHA_MAX)
        )
    n = np.clip(n, 1, SAMPLES_MAX).astype(np.int64)
    drop = np.repeat(np.arange(len(n)), n)
    first = np.cumsum(n) - n
    u = ((np.arange(len(drop)) - first[drop] + 0.5) / n[drop]).astype(np.float32)
    start32, delta32 = start.astype(np.float32), (end - start).astype(np.float32)
    points = start32[drop]
    points += u[:, None] * delta32[drop]
    inverse_z = 1.0 / points[:, 2]
    K32 = K_px.astype(np.float32)
    x = (points[:, 0] * K32[0, 0] + points[:, 1] * K32[0, 1]) * inverse_z + K32[0, 2]
    y = points[:, 1] * K32[1, 1] * inverse_z + K32[1, 2]
    # Each sample carries 1/n of the drop's image area at its own depth.
    scale = (diameters_mm * 1e-3 * f_px) ** 2 * (math.pi / 4) / n
    weight = scale.astype(np.float32)[drop] * inverse_z * inverse_z
    inside = (x > -1.0) & (x < width_px) & (y > -1.0) & (y < height_px)
    x, y, z, weight, drop = x[inside], y[inside], points[inside, 2], weight[inside], drop[inside]
    x0, y0 = np.floor(x), np.floor(y)
    fx, fy = x - x0, y - y0
    x0, y0 = x0.astype(np.int64), y0.astype(np.int64)
    # Bilinear splats onto the frame padded by a pixel on every side (x0, y0 ≥ −1 and x0 + 1, y0 + 1 ≤ W, H).
    padded_w = width_px + 2
    corner = (y0 + 1) * padded_w + (x0 + 1)  # (x0, y0) in the padded frame, whose origin is (−1, −1)
    indices = np.concatenate([corner, corner + 1, corner + padded_w, corner + padded_w + 1])
    weights = np.concatenate([(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy]) * np.tile(weight, 4)
    # The depth test, at each pixel a sample reaches: a drop behind that pixel's surface is hidden.
    front = np.tile(z, 4) < padded_depth.reshape(-1)[indices]
    indices, weights = indices[front], weights[front]
    sums = [np.bincount(indices, weights=weights, minlength=padded_depth.size)]
    if value is not None:
        for column in value.T:
            weighted = weights * np.tile(column[drop], 4)[front]
            sums.append(np.bincount(indices, weights=weighted, minlength=padded_depth.size))
    images = [flat.reshape(height_px + 2, padded_w)[1:-1, 1:-1] for flat in sums]
    tiles = None
    if sigma_px > 0:  # the BLUR_TILE_PX tiles the splats reached (a splat past the border failed the depth test)
        row, column = np.divmod(indices, padded_w)
        tiles = np.unique((row - 1) // BLUR_TILE_PX * padded_w + (column - 1) // BLUR_TILE_PX)
        tiles = np.column_stack(np.divmod(tiles, padded_w)) * BLUR_TILE_PX  # (top, left) of each
    return images[0], images[1:], tiles


def _project(points_cam_m: np.ndarray, K_px: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates (u, v) of (N, 3) camera-frame points (column arithmetic: a BLAS matmul with an
    inner size of 3 is slower, and slower still on a busy machine)."""
    inverse_z = 1.0 / points_cam_m[:, 2]
    u = (K_px[0, 0] * points_cam_m[:, 0] + K_px[0, 1] * points_cam_m[:, 1]) * inverse_z + K_px[0, 2]
    return u, K_px[1, 1] * points_cam_m[:, 1] * inverse_z + K_px[1, 2]


def apply_rain(radiance: np.ndarray, coverage: np.ndarray, drop_radiance: np.ndarray) -> np.ndarray:
    """(1 − α) L + α L_drop: `radiance` (H, W, 3) behind streaks of coverage α (H, W), the drops'
    radiance `drop_radiance` (3,) or (H, W, 3); float32 out."""
    drop = np.asarray(drop_radiance, np.float32)
    return (radiance + coverage[..., None] * (drop - radiance)).astype(np.float32)


def drop_radiance(horizon_sky: np.ndarray, radiance: np.ndarray) -> np.ndarray:
    """(3,) a drop's radiance: the mean of the horizon sky (`horizon_sky`, (3,) or (H, W, 3)) and of the
    frame's radiance (H, W, 3), a stand-in for the environment's mean over the drop's 165° field (Garg &
    Nayar 2007)."""
    horizon_sky, radiance = np.asarray(horizon_sky), np.asarray(radiance)
    # Every 4th pixel each way: the mean of a smooth wide field, at 1/16 of the cost.
    sky = (
        (horizon_sky[::4, ::4] if horizon_sky.ndim == 3 else horizon_sky).reshape(-1, 3).mean(axis=0, dtype=np.float64)
    )
    scene = radiance[::4, ::4].reshape(-1, 3).mean(axis=0, dtype=np.float64)
    return (0.5 * (sky + scene)).astype(np.float32)
