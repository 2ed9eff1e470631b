"""Procedural surface textures: asphalt, paving slabs, concrete, grass, gravel, brick and facades.

Each texture is a pure function of (type, seed, tile size) returning per-texel linear albedo (RGB,
relative to the surface's mean reflectance: its mean is 1), roughness and metallic maps (and, for
paving and brick, a normal map of their recessed joints) for one tile
that repeats across a surface (`camgen.render.scene_graph` maps it at the tile's size in metres and
lets the GPU filter it over mipmaps). Real pavements are not one grey: what a detector and a tracker
see on them is grain, joints, patches, stains and cracks at several scales.

Mean reflectances (`TYPICAL_ALBEDO_RGB`, linear RGB) used when a scene gives a texture but no colour:
- asphalt: 0.05 new, 0.10–0.18 aged (Pomerantz, Akbari et al. 2000, "The effect of pavements'
  temperatures on air temperatures in large cities", LBNL-43442); 0.11 here, a weathered car park.
- concrete and concrete paving: 0.35–0.40 new, 0.20–0.30 weathered (Levinson & Akbari 2002, "Effects of
  composition and exposure on the solar reflectance of Portland cement concrete", Cem. Concr. Res.
  32: 1679); 0.28 here.
- grass, gravel, brick: approximate visible reflectances of the kind spectral libraries list for
  them (a grass canopy reflects about 4–10 % in the visible, most in green; light gravel about a
  quarter; red clay brick about 0.3 in red, under 0.1 in blue); estimates, not measured for camgen.
Sizes: a brick is 215 × 65 mm with 10 mm joints (BS EN 771-1's UK work size); paving slabs 400 mm
square with 6 mm joints (BS 7263 flags, 400 × 400 or 600 × 600); a facade storey is 3 m high with
windows 1.2 m wide and 1.5 m tall, 0.9 m above the floor.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

TEXTURE_TYPES = ("asphalt", "paving", "concrete", "grass", "gravel", "brick", "facade")

TYPICAL_ALBEDO_RGB = {
    "asphalt": (0.11, 0.11, 0.105),
    "paving": (0.28, 0.265, 0.245),
    "concrete": (0.28, 0.27, 0.255),
    "grass": (0.05, 0.08, 0.035),
    "gravel": (0.24, 0.23, 0.21),
    "brick": (0.30, 0.13, 0.08),
    "facade": (0.32, 0.30, 0.27),
}
"""Mean linear reflectance of each surface (sources in the module docstring)."""

DEFAULT_TILE_M = {
    "asphalt": 8.0,
    "paving": 4.0,
    "concrete": 6.0,
    "grass": 4.0,
    "gravel": 2.0,
    "brick": 2.25,
    "facade": 12.0,
}
"""The size of one repeat of each texture, m: a whole number of its pattern's periods (10 bricks of
225 mm and 30 courses of 75 mm; 10 flags; 2 concrete bays; 4 window bays and storeys)."""

PATTERN_PERIOD_M = {"paving": 0.4, "concrete": 3.0, "brick": 0.45, "facade": 3.0}
"""A patterned texture's tile is rounded to a whole number of these (brick: 0.45 m holds 2 bricks of
225 mm and 6 courses of 75 mm, an even number, as running bond repeats every two courses)."""

TEXELS_PER_TILE = 1024
"""Texels along one side of a tile: 8 mm at 8 m, finer than a 1080p camera resolves on the ground
beyond 2 m."""


@dataclass(frozen=True)
class SurfaceMaps:
    """One tile of a texture: `albedo` (H, W, 3) float32, the reflectance relative to the surface's
    mean (1 on average over its main material: the bricks, not the mortar; the wall, not the windows);
    `roughness` and `metallic` (H, W) float32 in [0, 1]; `normal` (H, W, 3) float32 unit normals in
    the surface's frame (u, v, out: `normal_map_from_height`) or None for a flat surface. Row 0 is the
    tile's v = 0 edge."""

    albedo: np.ndarray
    roughness: np.ndarray
    metallic: np.ndarray
    tile_m: float
    normal: np.ndarray | None = None


def fbm(rng: np.random.Generator, size: int, octaves: int, base_cells: int, persistence: float = 0.5) -> np.ndarray:
    """Fractal value noise on a periodic (tileable) size × size grid, zero mean, unit standard
    deviation: octaves of bicubically upsampled random lattices, each twice as fine and
    `persistence` times as strong as the one before."""
    total = np.zeros((size, size), dtype=np.float32)
    amplitude = 1.0
    for k in range(octaves):
        cells = base_cells * 2**k
        if cells > size:
            break
        lattice = rng.standard_normal((cells, cells)).astype(np.float32)
        # Wrap the lattice before resizing so that the result tiles without a seam.
        padded = np.pad(lattice, 2, mode="wrap")
        scale = size / cells
        up = cv2.resize(padded, None, fx=scale, fy=scale, interpolation=cv2.INTER_CUBIC)
        offset = round(2 * scale)
        total += amplitude * up[offset : offset + size, offset : offset + size]
        amplitude *= persistence
    total -= total.mean()
    return total / max(float(total.std()), 1e-6)


@lru_cache(maxsize=16)
def surface_maps(kind: str, seed: int, tile_m: float | None = None, texels: int = TEXELS_PER_TILE) -> SurfaceMaps:
    """The maps of one tile of texture `kind` (one of `TEXTURE_TYPES`), drawn from `seed` (cached: a
    pure function, and a scene's surfaces share few textures)."""
    if kind not in TEXTURE_TYPES:
        raise ValueError(f"unknown texture {kind!r}; known: {', '.join(TEXTURE_TYPES)}")
    tile = DEFAULT_TILE_M[kind] if tile_m is None else float(tile_m)
    if kind in PATTERN_PERIOD_M:  # a whole number of periods, or the tile's edge would cut the pattern
        period = PATTERN_PERIOD_M[kind]
        tile = max(1, round(tile / period)) * period
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(TEXTURE_TYPES.index(kind),)))
    m_per_px = tile / texels
    maker = {
        "asphalt": _asphalt,
        "paving": _paving,
        "concrete": _concrete,
        "grass": _grass,
        "gravel": _gravel,
        "brick": _brick,
        "facade": _facade,
    }[kind]
    albedo, roughness, metallic, *height_m = maker(rng, texels, m_per_px)
    normal = normal_map_from_height(height_m[0], m_per_px) if height_m else None
    return SurfaceMaps(
        albedo.astype(np.float32), roughness.astype(np.float32), metallic.astype(np.float32), tile, normal
    )


def _blur_wrap(image: np.ndarray, sigma_px: float) -> np.ndarray:
    """A Gaussian blur of a tile that wraps around its edges (so the tile stays seamless)."""
    pad = math.ceil(3 * sigma_px) + 1
    padded = np.pad(image, pad, mode="wrap")
    return cv2.GaussianBlur(padded, (0, 0), sigma_px)[pad:-pad, pad:-pad]


def _grey(value: np.ndarray) -> np.ndarray:
    return np.repeat(value[..., None], 3, axis=2)


def _normalise(albedo: np.ndarray, where: np.ndarray | None = None) -> np.ndarray:
    mean = albedo[where].mean(axis=0) if where is not None else albedo.reshape(-1, 3).mean(axis=0)
    return np.clip(albedo / np.maximum(mean, 1e-6), 0.0, None)


def _cracks(rng: np.random.Generator, size: int, count: int, m_per_px: float) -> np.ndarray:
    """A mask (0…1) of thin, wandering cracks: random walks that turn a little at each step."""
    mask = np.zeros((size, size), dtype=np.float32)
    step_px = max(1.0, 0.02 / m_per_px)
    for _ in range(count):
        x, y = rng.uniform(0, size, 2)
        heading = rng.uniform(0, 2 * math.pi)
        points = []
        for _ in range(int(rng.uniform(0.8, 3.0) / (step_px * m_per_px))):
            heading += rng.normal(0, 0.25)
            x, y = (x + step_px * math.cos(heading)) % size, (y + step_px * math.sin(heading)) % size
            points.append((x, y))
        for (x0, y0), (x1, y1) in itertools.pairwise(points):
            if abs(x1 - x0) < size / 2 and abs(y1 - y0) < size / 2:  # not across the wrap
                cv2.line(mask, (int(x0), int(y0)), (int(x1), int(y1)), 1.0, 1, cv2.LINE_AA)
    return mask


def _asphalt(rng, size, m_per_px):
    grain = fbm(rng, size, 7, 8, 0.6)
    stones = (rng.random((size, size)) < 0.02).astype(np.float32)  # light aggregate showing through
    stones = _blur_wrap(stones, max(0.5, 0.004 / m_per_px))
    stones /= max(float(stones.max()), 1e-6)
    stains = fbm(rng, size, 3, 2, 0.5)  # oil and wear: large soft blotches
    albedo = 1.0 + 0.10 * grain + 0.45 * stones - 0.06 * np.clip(stains, 0, None)
    # Repair patches: darker (fresh) rectangles with crisp edges.
    for _ in range(rng.integers(0, 3)):
        w, h = (rng.uniform(0.6, 2.5, 2) / m_per_px).astype(int)
        x, y = rng.integers(0, size, 2)
        patch = np.zeros((size, size), dtype=bool)
        patch[:h, :w] = True
        albedo[np.roll(patch, (y, x), axis=(0, 1))] *= rng.uniform(0.85, 0.93)  # wrapping across the edge
    albedo *= 1.0 - 0.5 * _cracks(rng, size, int(rng.integers(2, 6)), m_per_px)
    roughness = np.clip(0.9 - 0.08 * stones + 0.02 * grain, 0.6, 1.0)
    return _normalise(_grey(albedo)), roughness, np.zeros((size, size))


def _slabs(rng, size, m_per_px, slab_m: float, joint_m: float, tint: float, bond: float = 0.0):
    """Per-texel (slab id tint, joint mask) of a grid of slabs; `bond` offsets every other row by that
    fraction of a slab (running bond for bricks)."""
    yy, xx = np.mgrid[0:size, 0:size].astype(np.float32) * m_per_px
    row = np.floor(yy / slab_m[1])
    x_shift = xx + (row % 2) * bond * slab_m[0]
    col = np.floor(x_shift / slab_m[0])
    in_x = x_shift - col * slab_m[0]
    in_y = yy - row * slab_m[1]
    joint = ((in_x < joint_m) | (in_y < joint_m)).astype(np.float32)
    count_x, count_y = round(size * m_per_px / slab_m[0]), round(size * m_per_px / slab_m[1])
    tints = 1.0 + tint * rng.standard_normal((max(count_y, 1), max(count_x, 1)))
    slab_tint = tints[(row.astype(int) % tints.shape[0]), (col.astype(int) % tints.shape[1])]
    return slab_tint.astype(np.float32), _blur_wrap(joint, 0.7)


JOINT_DEPTH_M = {"paving": 0.003, "brick": 0.003}
"""How far a joint lies below the face around it, m, for the normal map: a brick joint finished
weathered or bucket-handle sits a few millimetres behind the brick face (a raked one up to about 6 mm);
a flag's sand-filled joint settles a few millimetres below the flags. Estimates, not measured for
camgen; 3 mm against 2.2 mm (brick) and 3.9 mm (paving) texels tilts a joint's edges by 30–40°."""


def _paving(rng, size, m_per_px):
    tint, joint = _slabs(rng, size, m_per_px, (0.4, 0.4), 0.006, 0.06)
    grain = fbm(rng, size, 6, 16, 0.55)
    dirt = np.clip(fbm(rng, size, 3, 2, 0.5), 0, None)
    albedo = tint * (1.0 + 0.05 * grain - 0.05 * dirt) * (1.0 - 0.45 * joint)
    height_m = -JOINT_DEPTH_M["paving"] * joint
    return _normalise(_grey(albedo)), np.clip(0.85 + 0.05 * joint, 0, 1), np.zeros((size, size)), height_m


def _concrete(rng, size, m_per_px):
    grain = fbm(rng, size, 7, 8, 0.55)
    _, joint = _slabs(rng, size, m_per_px, (3.0, 3.0), 0.01, 0.0)
    albedo = (1.0 + 0.06 * grain) * (1.0 - 0.35 * joint) * (1.0 - 0.4 * _cracks(rng, size, 2, m_per_px))
    return _normalise(_grey(albedo)), np.full((size, size), 0.85), np.zeros((size, size))


def _grass(rng, size, m_per_px):
    blades = fbm(rng, size, 8, 32, 0.7)
    patches = fbm(rng, size, 3, 2, 0.5)
    # Dry and shaded blades: the red channel varies most (yellowing), so the lawn is not one green.
    albedo = np.stack(
        [1.0 + 0.3 * blades + 0.3 * patches, 1.0 + 0.22 * blades + 0.1 * patches, 1.0 + 0.25 * blades], axis=2
    )
    return _normalise(np.clip(albedo, 0.2, None)), np.full((size, size), 0.95), np.zeros((size, size))


def _gravel(rng, size, m_per_px):
    stones = fbm(rng, size, 4, int(size * m_per_px / 0.02), 0.5)  # 2 cm stones
    fine = fbm(rng, size, 3, 64, 0.5)
    tint = np.stack([1.0 + 0.05 * fbm(rng, size, 2, 4, 0.5)] * 3, axis=2)
    albedo = tint * _grey(1.0 + 0.2 * stones + 0.08 * fine)
    return _normalise(np.clip(albedo, 0.2, None)), np.full((size, size), 0.9), np.zeros((size, size))


def _brick(rng, size, m_per_px):
    tint, joint = _slabs(rng, size, m_per_px, (0.225, 0.075), 0.010, 0.10, bond=0.5)
    grain = fbm(rng, size, 5, 32, 0.5)
    brick = np.stack([tint * (1 + 0.06 * grain)] * 3, axis=2)
    mortar_rgb = np.array(TYPICAL_ALBEDO_RGB["concrete"]) / np.array(TYPICAL_ALBEDO_RGB["brick"])
    albedo = brick * (1 - joint[..., None]) + mortar_rgb * joint[..., None]
    height_m = -JOINT_DEPTH_M["brick"] * joint
    return _normalise(albedo, joint < 0.5), np.full((size, size), 0.9), np.zeros((size, size)), height_m


FACADE_STOREY_M = 3.0
WINDOW_W_M, WINDOW_H_M, SILL_M, WINDOW_PITCH_M = 1.2, 1.5, 0.9, 3.0
GLASS_ALBEDO = 0.15
"""Glass's share of the wall's mean reflectance (dark: the interior behind it), relative units."""


def _facade(rng, size, m_per_px):
    """A rendered or concrete wall with a grid of windows (texture v up the wall)."""
    grain = fbm(rng, size, 6, 16, 0.5)
    streaks = fbm(rng, size, 3, 4, 0.5)
    wall = 1.0 + 0.05 * grain - 0.05 * np.clip(streaks, 0, None)
    yy, xx = np.mgrid[0:size, 0:size].astype(np.float32) * m_per_px
    in_x = xx % WINDOW_PITCH_M
    in_y = yy % FACADE_STOREY_M
    x0 = (WINDOW_PITCH_M - WINDOW_W_M) / 2
    window = (in_x > x0) & (in_x < x0 + WINDOW_W_M) & (in_y > SILL_M) & (in_y < SILL_M + WINDOW_H_M)
    frame = window & ~((in_x > x0 + 0.06) & (in_x < x0 + WINDOW_W_M - 0.06)
                       & (in_y > SILL_M + 0.06) & (in_y < SILL_M + WINDOW_H_M - 0.06))  # fmt: skip
    glass = window & ~frame
    wall_only = ~window
    albedo = _normalise(_grey(wall), wall_only)
    lit = rng.random((int(size * m_per_px / FACADE_STOREY_M) + 1, int(size * m_per_px / WINDOW_PITCH_M) + 1))
    pane = GLASS_ALBEDO * (0.7 + 0.6 * lit[(yy // FACADE_STOREY_M).astype(int), (xx // WINDOW_PITCH_M).astype(int)])
    albedo[glass] = pane[glass][:, None]
    albedo[frame] = 0.25
    roughness = np.where(glass, 0.05, 0.85).astype(np.float32)
    return albedo, roughness, np.zeros((size, size))


def decode_srgb(encoded: np.ndarray) -> np.ndarray:
    """sRGB-encoded values in [0, 1] → linear values in [0, 1], float64 (IEC 61966-2-1)."""
    x = np.asarray(encoded, dtype=np.float64)
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def decode_srgb8(codes: np.ndarray) -> np.ndarray:
    """8-bit sRGB codes → linear values in [0, 1], float64 (IEC 61966-2-1; `encode_srgb8`'s inverse)."""
    return decode_srgb(np.asarray(codes, dtype=np.float64) / 255.0)


def encode_srgb8(linear: np.ndarray) -> np.ndarray:
    """Linear values in [0, 1] → 8-bit sRGB (IEC 61966-2-1), as glTF base-colour textures are stored."""
    x = np.clip(linear, 0.0, 1.0)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(srgb * 255).astype(np.uint8)


@dataclass(frozen=True)
class FileSurfaceMaps:
    """A file texture's maps (`camgen.config.scene.FileTexture`), row 0 the image's top (the tile's +v
    edge): `reflectance` (H, W, 3) float32 linear reflectance; `normal` (H, W, 3) float32 unit normals in
    the surface's frame (u, v, out), or None; `roughness` (H, W) float32, or None; `tile_m` (width,
    height) of one repeat."""

    reflectance: np.ndarray
    normal: np.ndarray | None
    roughness: np.ndarray | None
    tile_m: tuple[float, float]


def file_surface_maps(
    base_color_srgb: np.ndarray,
    tile_m: float | tuple[float, float],
    *,
    normal_packed: np.ndarray | None = None,
    roughness: np.ndarray | None = None,
    mean_rgb: tuple[float, float, float] | None = None,
) -> FileSurfaceMaps:
    """The maps of a texture read from files: the base colour (H, W, 3) sRGB-encoded in [0, 1] decoded to
    linear reflectance (IEC 61966-2-1), scaled per channel so that its mean is `mean_rgb` when given
    (None: the image's own mean); a tangent-space normal map packed as n / 2 + 0.5 (OpenGL's convention:
    green is +v, up the image) unpacked and renormalised; roughness as stored. A single `tile_m` is the
    width, the height following the image's aspect ratio (square texels)."""
    reflectance = decode_srgb(base_color_srgb)
    if mean_rgb is not None:
        mean = reflectance.reshape(-1, 3).mean(axis=0)
        reflectance = reflectance * np.where(mean > 0, np.asarray(mean_rgb) / np.maximum(mean, 1e-12), 0.0)
        reflectance += np.where(mean > 0, 0.0, np.asarray(mean_rgb))  # a black channel takes the mean itself
    height_px, width_px = reflectance.shape[:2]
    size = (float(tile_m), float(tile_m) * height_px / width_px) if np.isscalar(tile_m) else tuple(map(float, tile_m))
    normal = None
    if normal_packed is not None:
        normal = 2.0 * np.asarray(normal_packed, dtype=np.float64) - 1.0
        normal /= np.maximum(np.linalg.norm(normal, axis=2, keepdims=True), 1e-6)
        normal = normal.astype(np.float32)
    rough = None if roughness is None else np.clip(np.asarray(roughness, dtype=np.float32), 0.0, 1.0)
    return FileSurfaceMaps(np.clip(reflectance, 0.0, 1.0).astype(np.float32), normal, rough, size)


def normal_map_from_height(height_m: np.ndarray, m_per_texel: float) -> np.ndarray:
    """(H, W, 3) float32 unit normals, in the surface's frame (u along the columns, v along the rows, out
    of the surface), of a periodic height field (H, W) in metres: n ∝ (−∂h/∂u, −∂h/∂v, 1), the slopes
    by 3 × 3 Sobel kernels (central differences smoothed across, weights 1 2 1; divided by their gain of
    8 texels) with the tile wrapping around its edges."""
    padded = np.pad(np.asarray(height_m, dtype=np.float32), 1, mode="wrap")
    scale = 1.0 / (8.0 * m_per_texel)
    dh_du = cv2.Sobel(padded, cv2.CV_32F, 1, 0, ksize=3)[1:-1, 1:-1] * scale
    dh_dv = cv2.Sobel(padded, cv2.CV_32F, 0, 1, ksize=3)[1:-1, 1:-1] * scale
    normal = np.stack([-dh_du, -dh_dv, np.ones_like(dh_du)], axis=2)
    return (normal / np.linalg.norm(normal, axis=2, keepdims=True)).astype(np.float32)


def encode_normal8(normal: np.ndarray) -> np.ndarray:
    """Unit normals (…, 3) → 8-bit codes packed as n / 2 + 0.5, as normal maps store them."""
    return np.round((np.clip(normal, -1.0, 1.0) * 0.5 + 0.5) * 255).astype(np.uint8)
