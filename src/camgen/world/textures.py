"""Procedural surface textures: asphalt, paving slabs, concrete, grass, gravel, brick and facades.

Each texture is a pure function of (type, seed, tile size) returning per-texel linear albedo (RGB,
relative to the surface's mean reflectance: its mean is 1), roughness and metallic maps (and, for
paving and brick, a normal map of their recessed joints; for facades, of their recessed windows and doors) for
one tile
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
windows 1.2 m wide and 1.5 m tall, 0.9 m above the floor, and its ground storey has entrance doors (1.0 m
clear by 2.1 m, Approved Document M; `DOOR_CLEAR_W_M`), windows and doors set back `REVEAL_DEPTH_M`.
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
FRAME_M = 0.06
"""Width of a window's frame (and a glazed door panel's bead) as the texture paints it, m."""
GLASS_ALBEDO = 0.15
"""Glass's share of the wall's mean reflectance (dark: the interior behind it), relative units."""
FRAME_ALBEDO = 0.25
"""A window or door frame's reflectance relative to the wall's mean (dark-grey aluminium or uPVC)."""

DOOR_CLEAR_W_M = 1.0
"""Clear width of an entrance door's leaf, m: the effective clear width Approved Document M (vol. 2, 2015,
table 2.1) asks of an external door to a building the public uses in new work, 1000 mm (800–825 mm for
others), as BS 8300-2:2018 recommends for main entrances."""
DOOR_H_M = 2.1
"""Height of a door's leaf from the floor to the underside of its head frame, m: the UK's 1981 mm (6 ft 6 in)
leaf hung in a frame with its threshold, about 2.04–2.1 m clear; 2.1 m is the common door-set height."""
DOOR_FRAME_M = 0.07
"""Width of a door's frame at its sides and head, m (a 70 mm timber or aluminium door frame), so that the
opening in the wall is 1.14 × 2.17 m."""
DOOR_PANEL_M = (0.15, 0.5, 1.9)
"""A door's glazed vision panel: inset from the leaf's sides, bottom and top above the floor, m. Approved
Document M (vol. 2, 2015, 2.13) asks a vision panel over the zone of visibility 500–1500 mm above the floor;
entrance doors' panels commonly run higher."""
DOOR_EVERY_BAYS = 4
"""A ground storey has one entrance door per this many window bays (at least one per tile; a seeded bay, whose
ground-storey window the door replaces): an estimate for blocks of shops and flats, one entrance per 10–12 m."""
DOOR_RGB = (
    (0.02, 0.02, 0.02),
    (0.02, 0.03, 0.08),
    (0.02, 0.06, 0.03),
    (0.22, 0.03, 0.02),
    (0.05, 0.05, 0.055),
    (0.12, 0.06, 0.03),
)
"""Linear reflectances of a painted or stained door leaf drawn per door (black, navy, dark green, red, anthracite,
stained timber): estimates of common door colours."""
DOOR_ROUGHNESS = 0.45
"""A door leaf's glTF roughness: satin or gloss paint over timber or steel."""
REVEAL_DEPTH_M = 0.1
"""How far windows and doors sit back from the wall's face, m: the London Building Act of 1709 set sash boxes
back 4 in (0.10 m) behind the brickwork, and windows in today's cavity walls stand 50–100 mm behind the outer
leaf's face (estimates, not measured for camgen). The height map holds each opening's reveal as a splay as
wide as it is deep (a normal map cannot turn a face through 90°), so a low sun lights the reveal on its side
and leaves the other darker; the frame lies `REVEAL_DEPTH_M` deep and the glass `GLASS_SET_BACK_M` deeper."""
GLASS_SET_BACK_M = 0.03
"""How far glass sits behind the face of its frame or door leaf, m (a glazing bead's depth)."""


def _rect_mask(x: np.ndarray, y: np.ndarray, x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    return (x > x0) & (x < x1) & (y > y0) & (y < y1)


def _outside_m(x: np.ndarray, y: np.ndarray, x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    """How far each point lies outside the rectangle, by the larger of its two axes' distances (0 inside)."""
    return np.maximum(np.maximum(x0 - x, x - x1), np.maximum(np.maximum(y0 - y, y - y1), 0.0))


def facade_door_bays(rng: np.random.Generator, bays: int) -> np.ndarray:
    """The bays (sorted indices among `bays` across a tile) whose ground storey holds an entrance door:
    max(1, round(bays / DOOR_EVERY_BAYS)) distinct bays drawn by `rng`."""
    count = min(bays, max(1, round(bays / DOOR_EVERY_BAYS)))
    return np.sort(rng.choice(bays, size=count, replace=False))


def _facade(rng, size, m_per_px):
    """A rendered or concrete wall with a grid of windows and entrance doors in its ground storey (texture v up
    the wall, row 0 its foot), each opening recessed `REVEAL_DEPTH_M` in the height map."""
    grain = fbm(rng, size, 6, 16, 0.5)
    streaks = fbm(rng, size, 3, 4, 0.5)
    wall = 1.0 + 0.05 * grain - 0.05 * np.clip(streaks, 0, None)
    yy, xx = np.mgrid[0:size, 0:size].astype(np.float32) * m_per_px
    tile = size * m_per_px
    bays, storeys = round(tile / WINDOW_PITCH_M), round(tile / FACADE_STOREY_M)
    bay = np.minimum((xx // WINDOW_PITCH_M).astype(int), bays - 1)
    storey = np.minimum((yy // FACADE_STOREY_M).astype(int), storeys - 1)
    in_x = xx - bay * WINDOW_PITCH_M
    in_y = yy - storey * FACADE_STOREY_M
    door_bays = facade_door_bays(rng, bays)
    has_door = np.isin(bay, door_bays) & (storey == 0)

    x0 = (WINDOW_PITCH_M - WINDOW_W_M) / 2
    window_box = (x0, SILL_M, x0 + WINDOW_W_M, SILL_M + WINDOW_H_M)
    window = _rect_mask(in_x, in_y, *window_box) & ~has_door
    window_glass = window & _rect_mask(
        in_x, in_y, x0 + FRAME_M, SILL_M + FRAME_M, x0 + WINDOW_W_M - FRAME_M, SILL_M + WINDOW_H_M - FRAME_M
    )
    d0 = (WINDOW_PITCH_M - DOOR_CLEAR_W_M) / 2  # the leaf's left edge in its bay
    door_box = (d0 - DOOR_FRAME_M, 0.0, d0 + DOOR_CLEAR_W_M + DOOR_FRAME_M, DOOR_H_M + DOOR_FRAME_M)
    door_to_floor = (door_box[0], -1.0, *door_box[2:])  # its opening runs down through the floor
    door = _rect_mask(in_x, in_y, *door_to_floor) & has_door
    leaf = door & _rect_mask(in_x, in_y, d0, -1.0, d0 + DOOR_CLEAR_W_M, DOOR_H_M)
    inset, panel_bottom, panel_top = DOOR_PANEL_M
    panel = (d0 + inset, panel_bottom, d0 + DOOR_CLEAR_W_M - inset, panel_top)
    door_glass = leaf & _rect_mask(in_x, in_y, *panel)
    bead_box = (panel[0] - FRAME_M, panel[1] - FRAME_M, panel[2] + FRAME_M, panel[3] + FRAME_M)
    panel_bead = leaf & _rect_mask(in_x, in_y, *bead_box) & ~door_glass
    glass = window_glass | door_glass
    opening = window | door
    frame = (window & ~window_glass) | (door & ~leaf) | panel_bead

    albedo = _normalise(_grey(wall), ~opening)
    lit = rng.random((storeys, bays))
    pane = GLASS_ALBEDO * (0.7 + 0.6 * lit[storey, bay])
    albedo[glass] = pane[glass][:, None]
    albedo[frame] = FRAME_ALBEDO
    colours = np.asarray(DOOR_RGB)[rng.integers(0, len(DOOR_RGB), bays)] / np.asarray(TYPICAL_ALBEDO_RGB["facade"])
    painted = leaf & ~door_glass & ~panel_bead
    albedo[painted] = colours[bay[painted]]
    roughness = np.where(glass, 0.05, np.where(painted, DOOR_ROUGHNESS, 0.85)).astype(np.float32)

    # The wall's face at 0; each opening's reveal a splay down to its frame (`REVEAL_DEPTH_M`), glass deeper.
    outside_window = _outside_m(in_x, in_y, *window_box)
    outside_door = _outside_m(in_x, in_y, *door_to_floor)
    outside = np.where(has_door, outside_door, outside_window)
    height_m = -REVEAL_DEPTH_M * np.clip(1.0 - outside / REVEAL_DEPTH_M, 0.0, 1.0)
    height_m = np.where(glass, -REVEAL_DEPTH_M - GLASS_SET_BACK_M, height_m)
    return albedo, roughness, np.zeros((size, size)), height_m.astype(np.float32)


KERB_UNITS_PER_TILE = 4
"""Kerb units along one tile of a kerb's texture (`kerb_surface_maps`): 3.66 m of 914 mm units, 3.6 mm texels."""
KERB_JOINT_DEPTH_M = 0.003
"""How far a kerb's open joint lies behind the faces either side of it in the normal map, m: the joint is open
(no mortar), so deeper in fact; 3 mm tilts a joint's edges as a brick joint's are (`JOINT_DEPTH_M`)."""
KERB_JOINT_ALBEDO = 0.3
"""An open joint's reflectance relative to the kerb's mean: the shaded gap between two units."""


@lru_cache(maxsize=8)
def kerb_surface_maps(seed: int, unit_length_m: float, joint_m: float, texels: int = TEXELS_PER_TILE) -> SurfaceMaps:
    """One tile of a precast concrete kerb's texture (`camgen.world.kerbs`: u along the kerb from its first
    point, v around its profile): `KERB_UNITS_PER_TILE` units `unit_length_m` long, an open joint `joint_m`
    wide across the whole tile at u = 0 and every unit after (dark, `KERB_JOINT_ALBEDO`, and recessed
    `KERB_JOINT_DEPTH_M` in the normal map), each unit's own tint (± 4 %, as units cast on different days
    differ) over a fine concrete grain. The mean over the units (not the joints) is 1."""
    tile = KERB_UNITS_PER_TILE * unit_length_m
    m_per_px = tile / texels
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(len(TEXTURE_TYPES),)))
    u = np.arange(texels, dtype=np.float32) * m_per_px
    in_unit = np.mod(u, unit_length_m)
    joint_row = ((in_unit < joint_m / 2) | (in_unit > unit_length_m - joint_m / 2)).astype(np.float32)
    joint = _blur_wrap(np.tile(joint_row, (texels, 1)), 0.5)
    tints = 1.0 + 0.04 * rng.standard_normal(KERB_UNITS_PER_TILE)
    unit_tint = tints[np.minimum((u // unit_length_m).astype(int), KERB_UNITS_PER_TILE - 1)][None, :]
    grain = fbm(rng, texels, 7, 16, 0.55)
    stains = np.clip(fbm(rng, texels, 3, 4, 0.5), 0, None)
    concrete = unit_tint * (1.0 + 0.06 * grain - 0.05 * stains)
    albedo = concrete * (1.0 - joint) + KERB_JOINT_ALBEDO * joint
    albedo = _normalise(_grey(albedo), joint < 0.5)
    height_m = -KERB_JOINT_DEPTH_M * joint
    roughness = np.full((texels, texels), 0.85, dtype=np.float32)
    return SurfaceMaps(
        albedo.astype(np.float32),
        roughness,
        np.zeros((texels, texels), dtype=np.float32),
        tile,
        normal_map_from_height(height_m, m_per_px),
    )


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
