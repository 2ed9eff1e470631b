"""Each prop type: its dimensions drawn from an identity seed within cited real ranges, and its parts.

The prop's frame: x forward (`heading_deg`), y left, z up, origin on the ground at the prop's foot. A
bench faces −y (its backrest on the +y side); a fence runs from x = 0 to its length; a lamp's bracket
reaches along +x; a sign's plate faces +x.

Sources of the ranges (overall heights in `camgen.config.props.PROP_HEIGHT_RANGE_M`):

- Street trees: 5–15 m tall at maturity for small to medium street species, stem 0.2–0.5 m across at
  breast height, crown spread about half the height (Trees & Design Action Group, "Trees in Hard
  Landscapes", 2014, species tables); clear stem over footways 2.0–3.0 m (BS 8545:2014 and BS 3936-1
  nursery stock: clear stem ≥ 1.8–2.0 m; highway practice keeps 2.4 m over footways). Conifers: crown
  from 0.5–1.5 m, spread 0.35–0.5 of the height.
- Leaves: canopy reflectance ≈ 0.04–0.06 red, 0.08–0.12 green, 0.02–0.04 blue in the visible and
  0.45–0.5 at 850 nm (the red edge; Gates, Keegan, Schleter & Weidner 1965, Appl. Opt. 4: 11;
  Jacquemoud & Baret 1990, PROSPECT, Remote Sens. Environ. 34: 75; ECOSTRESS library green
  vegetation). Conifer needles reflect less in the NIR, 0.35–0.4. Bark ≈ 0.3–0.4 at 850 nm.
- Shrubs and hedges: 0.5–2 m high, 0.6–1.2 m deep.
- Benches: seat 0.45–0.475 m high, 0.40–0.45 m deep, backrest top 0.75–0.9 m (BS 8300-1:2018, seating;
  DfT "Inclusive Mobility" 2021, seat height about 450–475 mm), 1.5–2.0 m long.
- Litter bins: street bins of 80–120 L stand 0.9–1.0 m high and 0.4–0.6 m across (manufacturers'
  catalogues for UK councils).
- Bollards: 0.9–1.0 m high, 0.1–0.2 m across (DfT "Inclusive Mobility" 2021 and BS 8300-1:2018: about
  1.0 m high, at least 0.1 m across, with a contrasting band near the top).
- Lamp columns: nominal heights 4, 5, 6, 8, 10 and 12 m (BS EN 40-2:2004), bracket outreach 0.5–1.5 m,
  column 0.14–0.19 m across at the base tapering to 76 mm at the top; an LED lantern 0.5–0.8 m long.
- Signs: the plate's lower edge 2.1 m over a footway, 2.3–2.5 m where cyclists pass (DfT Traffic Signs
  Manual, chapter 1, 2018); posts of 76 or 89 mm tube; plates 0.45–0.9 m (circles 0.6 or 0.75 m).
- Fences and railings: 1.0–2.0 m high (BS 1722 series), posts at 3 m centres at most, bars at most 0.1 m apart
  (BS 6180:2011, barriers in and about buildings).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import trimesh

from camgen.config.props import PROP_HEIGHT_RANGE_M
from camgen.props.foliage import (
    BUSH_LARGEST_CARD_M2,
    BUSH_LEAF_AREA_INDEX,
    BUSH_LEAF_CARD_AREA_M2,
    CROWN_GAP_FRACTION,
    LEAF_CARD_AREA_M2,
    envelope_of,
    leaf_area_m2,
    leafy_volume,
    line_envelopes,
)
from camgen.props.shapes import PropPart, blob, box, frustum, limb, lumpy_cone, rot_x

PROP_TYPE_KEYS = {"tree": 1, "bush": 2, "bench": 3, "bin": 4, "bollard": 5, "lamp_post": 6, "sign": 7, "fence": 8}
"""Each type's key in the seed sequence, so one seed draws different streams for different types."""

LEAF_RGB = ((0.045, 0.085, 0.025), (0.06, 0.10, 0.03), (0.05, 0.08, 0.035), (0.07, 0.095, 0.03))
"""Linear canopy albedos of broadleaf crowns (module docstring): fresh to olive greens."""
LEAF_NIR = (0.45, 0.5)
BUSH_CORE_SCALE = 0.7
"""A bush's dark core: its outline shrunk by this about its foot."""
BUSH_CORE_SHADE = 0.5
"""The core's albedo over the leaves' (the inside of a bush gets little of the sky's light)."""
CONIFER_RGB = ((0.03, 0.055, 0.03), (0.035, 0.06, 0.035))
CONIFER_NIR = (0.35, 0.4)
BARK_RGB = (0.10, 0.08, 0.06)
BARK_NIR = 0.35
WOOD_RGB = (0.22, 0.12, 0.06)
"""Weathered hardwood slats."""
WOOD_NIR = 0.5
PAINT_RGB = {"black": (0.03, 0.03, 0.03), "green": (0.02, 0.07, 0.04), "grey": (0.15, 0.15, 0.16)}
PAINT_NIR = {"black": 0.05, "green": 0.25, "grey": 0.2}
"""Street furniture paints: carbon-black stays near 0.05 at 850 nm; green and grey paints reflect more
in the NIR than in the red (`camgen.world.night.default_nir_reflectance`)."""
GALVANISED_RGB = (0.30, 0.30, 0.32)
GALVANISED_NIR = 0.35
STAINLESS_RGB = (0.55, 0.55, 0.56)
SIGN_RGB = {
    "blue": (0.02, 0.08, 0.40),
    "red": (0.50, 0.03, 0.03),
    "white": (0.75, 0.75, 0.75),
    "yellow": (0.70, 0.50, 0.03),
}
LANTERN_GLASS_RGB = (0.6, 0.6, 0.6)
BAND_RGB = (0.8, 0.8, 0.8)
"""A bollard's retro-reflective band."""
SIGN_HEIGHT_OVER_PLATE_M = (2.1, 2.5)
LAMP_HEIGHTS_M = (4.0, 5.0, 6.0, 8.0, 10.0, 12.0)
"""BS EN 40-2 nominal column heights."""


@dataclass
class PropModel:
    """Everything drawn of one prop, in its own frame, and the dimensions drawn for it."""

    type: str
    seed: int
    parts: list[PropPart]
    height_m: float
    roughness: float = 0.8
    metallic: float = 0.0
    dims: dict[str, float] = field(default_factory=dict)
    """Named dimensions, m (trunk_diameter_m, seat_height_m, …), for tests and metadata."""
    envelope: list[PropPart] = field(default_factory=list)
    """Closed surfaces the leaves of a crown or bush fill (`camgen.props.foliage`); not drawn."""

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(vertices (V, 3), normals (V, 3), faces (F, 3), colours (V, 3), NIR (V,)) of all parts as one."""
        offsets = np.cumsum([0] + [len(p.vertices_m) for p in self.parts])
        return (
            np.concatenate([p.vertices_m for p in self.parts]),
            np.concatenate([p.normals for p in self.parts]),
            np.concatenate([p.faces + o for p, o in zip(self.parts, offsets, strict=False)]),
            np.concatenate([p.colours_rgb for p in self.parts]),
            np.concatenate([p.nir_reflectance for p in self.parts]),
        )

    def occluder_triangles(self) -> np.ndarray:
        """(T, 3, 3) triangles, in the prop's frame, that stand in for it in sight-line tests
        (`camgen.coverage.occlusion`): its hard parts as drawn, and its leafy parts (a crown's leaves or
        a conifer's lumps, a bush) as one convex hull, a small share of their triangles; the hull fills
        the gaps between leaves too, which the render sees through (a crown hides 73–89 % of what lies
        behind it, `camgen.props.foliage.CROWN_POROSITY_RANGE`: a sight line is taken as blocked)."""
        hard = [p.vertices_m[p.faces] for p in self.parts if not p.name.startswith(ORGANIC_PARTS)]
        leafy = [p.vertices_m for p in self.parts if p.name.startswith(ORGANIC_PARTS)]
        if leafy:
            hull = trimesh.convex.convex_hull(np.concatenate(leafy))
            hard.append(np.asarray(hull.vertices)[hull.faces])
        return np.concatenate(hard)


ORGANIC_PARTS = ("crown", "foliage")
"""Name prefixes of the leafy parts, which `PropModel.occluder_triangles` replaces by their convex hull and
`camgen.props.sway` makes flutter: a broadleaf crown's leaves ("crown"), a conifer's lumps ("crown_<k>"), a
bush's leaves ("foliage") and its dark core ("foliage_core")."""
LEAF_CARD_PARTS = ("crown", "foliage")
"""Names of the parts made of two-sided leaf cards (`camgen.props.foliage`), open sheets unlike every other part."""


def _height(kind: str, rng: np.random.Generator, pinned: float | None) -> float:
    low, high = PROP_HEIGHT_RANGE_M[kind]
    drawn = float(rng.uniform(low, high))
    return drawn if pinned is None else float(pinned)


def _fit_height(parts: list[PropPart], bottom_m: float, top_m: float, span_of: list[PropPart] | None = None) -> None:
    """Stretch the parts' z span (or that of `span_of`, the same stretch applied to all) onto [bottom_m, top_m]
    (a crown's top at the tree's height)."""
    measured = parts if span_of is None else span_of
    low = min(float(p.vertices_m[:, 2].min()) for p in measured)
    high = max(float(p.vertices_m[:, 2].max()) for p in measured)
    scale = (top_m - bottom_m) / (high - low)
    for p in parts:
        p.vertices_m[:, 2] = bottom_m + (p.vertices_m[:, 2] - low) * scale
        p.normals[:, 2] /= scale
        p.normals /= np.linalg.norm(p.normals, axis=1, keepdims=True)


def _tree(rng, height_m, form, length_m) -> PropModel:
    H = _height("tree", rng, height_m)
    trunk_d = float(np.clip(0.2 + 0.3 * (H - 5.0) / 10.0 + rng.uniform(-0.05, 0.05), 0.2, 0.5))
    if form == "conifer":
        crown_base = float(rng.uniform(0.5, 1.5))
        crown_r = float(rng.uniform(0.35, 0.5) * H / 2)
        rgb = CONIFER_RGB[rng.integers(len(CONIFER_RGB))]
        nir = float(rng.uniform(*CONIFER_NIR))
        trunk = frustum("trunk", trunk_d / 2, trunk_d / 4, 0.0, crown_base + 0.5 * (H - crown_base), BARK_RGB, BARK_NIR)
        tiers = int(rng.integers(2, 4))
        parts = [trunk]
        span = H - crown_base
        for k in range(tiers):
            z0 = crown_base + span * k / (tiers + 1)
            radius = crown_r * (1.0 - 0.22 * k)
            parts.append(
                lumpy_cone(
                    f"crown_{k}", radius, z0, H if k == tiers - 1 else z0 + span * 0.62, rgb=rgb, nir=nir, rng=rng
                )
            )
        return PropModel(
            "tree", 0, parts, H, roughness=0.9,
            dims={"height_m": H, "trunk_diameter_m": trunk_d, "crown_base_m": crown_base, "crown_radius_m": crown_r},
        )  # fmt: skip
    crown_base = float(min(rng.uniform(2.0, 3.0), 0.45 * H))
    crown_h = H - crown_base
    crown_r = float(np.clip(rng.uniform(0.22, 0.32) * H, 0.4 * crown_h / 2, 1.3 * crown_h / 2))
    rgb = LEAF_RGB[rng.integers(len(LEAF_RGB))]
    nir = float(rng.uniform(*LEAF_NIR))
    centre_z = crown_base + crown_h / 2
    parts = [frustum("trunk", trunk_d / 2, trunk_d / 3, 0.0, centre_z + 0.2 * crown_h, BARK_RGB, BARK_NIR)]
    lumps = int(rng.integers(4, 8))
    for k in range(lumps):
        if k == 0:
            offset = np.zeros(3)
            size = np.array([0.75 * crown_r, 0.75 * crown_r, 0.42 * crown_h])
        else:
            direction = rng.normal(size=3) * (1.0, 1.0, 0.6)
            direction /= np.linalg.norm(direction)
            offset = direction * (0.45 * crown_r, 0.45 * crown_r, 0.3 * crown_h)
            size = rng.uniform(0.45, 0.6) * np.array([crown_r, crown_r, 0.8 * crown_h / 2])
        parts.append(
            blob(
                f"crown_{k}",
                size,
                offset + np.array([0.0, 0.0, centre_z]),
                roughness=0.12,
                exponent=2.0,
                rgb=rgb,
                nir=nir,
                rng=rng,
                subdivisions=3,
            )
        )
    crown = parts[1:]
    bottom = min(float(p.vertices_m[:, 2].min()) for p in crown)
    _fit_height(crown, bottom, H)
    lines = line_envelopes([(p.vertices_m, p.faces) for p in crown])
    envelope = lines[0][0]
    gap_fraction = float(rng.uniform(*CROWN_GAP_FRACTION))
    leaves = leafy_volume(
        "crown", envelope, gap_fraction=gap_fraction, gap_envelopes=lines, card_area_m2=LEAF_CARD_AREA_M2,
        centre_m=(0.0, 0.0, centre_z),
        radii_m=(crown_r, crown_r, crown_h / 2), rgb=rgb, nir=nir, rng=rng,
    )  # fmt: skip
    _fit_height([leaves, *crown], float(leaves.vertices_m[:, 2].min()), H, span_of=[leaves])
    leaf_area = leaf_area_m2(leaves)  # as drawn, after the stretch
    lai = leaf_area / envelope.projected_area_m2
    trunk_top = centre_z + 0.2 * crown_h
    branches = []
    for k in range(int(rng.integers(4, 8))):
        z0 = crown_base + rng.uniform(0.0, 0.7) * (trunk_top - crown_base)
        azimuth = 2 * math.pi * (k + rng.uniform(-0.3, 0.3)) / 6
        start = np.array([0.0, 0.0, z0])
        end = np.array([crown_r * math.cos(azimuth), crown_r * math.sin(azimuth), z0 + rng.uniform(0.3, 0.6) * crown_h])
        # out to 0.5–0.8 of the way to the envelope's edge along its line, so that no bare branch sticks out
        steps = start + np.linspace(0.0, 1.0, 41)[:, None] * (end - start)
        inside = envelope.contains(steps)
        last = int(np.flatnonzero(inside)[-1]) if inside.any() else 0
        reach = rng.uniform(0.5, 0.8) * last / 40
        if reach * np.linalg.norm(end - start) < 0.3:
            continue
        r0 = 0.25 * trunk_d * (1.0 - 0.5 * (z0 - crown_base) / max(trunk_top - crown_base, 1e-9))
        branches.append(limb("branch", start, start + reach * (end - start), r0, 0.3 * r0, BARK_RGB, BARK_NIR))
    return PropModel(
        "tree", 0, [parts[0], *branches, leaves], H, roughness=0.9, envelope=crown,
        dims={"height_m": H, "trunk_diameter_m": trunk_d, "crown_base_m": crown_base, "crown_radius_m": crown_r,
              "leaf_area_index": lai, "leaf_area_m2": leaf_area, "crown_gap_fraction": gap_fraction,
              "crown_projected_area_m2": envelope.projected_area_m2},
    )  # fmt: skip


def _bush(rng, height_m, form, length_m) -> PropModel:
    H = _height("bush", rng, height_m)
    L = float(rng.uniform(0.8, 2.5)) if length_m is None else float(length_m)
    depth = float(rng.uniform(0.6, 1.2))
    rgb = LEAF_RGB[rng.integers(len(LEAF_RGB))]
    nir = float(rng.uniform(*LEAF_NIR))
    subdivisions = 3 if L < 6 else 4
    outline = blob(
        "foliage", (L / 2, depth / 2, H / 2), (L / 2, 0.0, H / 2 - 0.03), roughness=0.06, exponent=4.0,
        rgb=rgb, nir=nir, rng=rng, subdivisions=subdivisions,
    )  # fmt: skip
    _fit_height([outline], -0.03, H)
    # The dense inside, where little light reaches: a darker core the leaves cover (the outline shrunk
    # about its foot's middle), so that a bush hides what lies behind it but shows a ragged, leafy surface.
    foot = np.array([L / 2, 0.0, -0.03])
    core = PropPart(
        "foliage_core",
        foot + BUSH_CORE_SCALE * (outline.vertices_m - foot),
        outline.normals.copy(),
        outline.faces.copy(),
        outline.colours_rgb * BUSH_CORE_SHADE,
        outline.nir_reflectance.copy(),
    )
    lai = float(rng.uniform(*BUSH_LEAF_AREA_INDEX))
    envelope = envelope_of([(outline.vertices_m, outline.faces)])
    inner = envelope_of([(core.vertices_m, core.faces)])
    leaf_area = lai * envelope.projected_area_m2
    leaves = leafy_volume(
        "foliage", envelope, leaf_area, card_area_m2=BUSH_LEAF_CARD_AREA_M2, centre_m=(L / 2, 0.0, H / 2),
        radii_m=(L / 2, depth / 2, H / 2), rgb=rgb, nir=nir, rng=rng, exclude=inner.contains,
        largest_card_m2=BUSH_LARGEST_CARD_M2,
    )  # fmt: skip
    _fit_height([leaves, core, outline], -0.03, H, span_of=[leaves])
    leaf_area = leaf_area_m2(leaves)  # as drawn, after the stretch
    lai = leaf_area / envelope.projected_area_m2
    return PropModel(
        "bush", 0, [core, leaves], H, roughness=0.9, envelope=[outline],
        dims={"height_m": H, "length_m": L, "depth_m": depth, "leaf_area_index": lai, "leaf_area_m2": leaf_area,
              "crown_projected_area_m2": envelope.projected_area_m2},
    )  # fmt: skip


def _paint(rng) -> str:
    return ("black", "green", "grey")[int(rng.integers(3))]


def _bench(rng, height_m, form, length_m) -> PropModel:
    top = _height("bench", rng, height_m)
    L = float(rng.uniform(1.5, 2.0))
    seat_h = float(rng.uniform(0.45, 0.475))
    depth = float(rng.uniform(0.40, 0.45))
    wooden = bool(rng.random() < 0.6)
    paint = _paint(rng)
    seat_rgb, seat_nir = (WOOD_RGB, WOOD_NIR) if wooden else (PAINT_RGB[paint], PAINT_NIR[paint])
    frame_rgb, frame_nir = PAINT_RGB["black"], PAINT_NIR["black"]
    slab = 0.05
    parts = [box("seat", (L, depth, slab), (0.0, 0.0, seat_h - slab / 2), seat_rgb, seat_nir)]
    tilt = math.radians(10.0)
    thickness = 0.04
    # the tilted backrest's top edge at `top`: seat + 0.06 m gap + its height and thickness turned by the tilt
    back_h = (top - seat_h - 0.06 - math.sin(tilt) * thickness / 2) / math.cos(tilt)
    parts.append(
        box(
            "backrest", (L, thickness, back_h),
            (0.0, depth / 2 - 0.02 + math.sin(tilt) * back_h / 2, seat_h + 0.06 + math.cos(tilt) * back_h / 2),
            seat_rgb, seat_nir, rotation=rot_x(tilt),
        )
    )  # fmt: skip
    for x in (-0.42 * L, 0.0, 0.42 * L) if L > 1.8 else (-0.42 * L, 0.42 * L):
        parts.append(box("leg", (0.06, depth, seat_h - slab), (x, 0.0, (seat_h - slab) / 2), frame_rgb, frame_nir))
        back_leg = top - 0.02
        parts.append(box("back_leg", (0.06, 0.05, back_leg), (x, depth / 2, back_leg / 2), frame_rgb, frame_nir))
    return PropModel(
        "bench", 0, parts, top, roughness=0.7,
        dims={"height_m": top, "seat_height_m": seat_h, "length_m": L, "seat_depth_m": depth},
    )  # fmt: skip


def _bin(rng, height_m, form, length_m) -> PropModel:
    H = _height("bin", rng, height_m)
    D = float(rng.uniform(0.4, 0.6))
    paint = _paint(rng)
    rgb, nir = PAINT_RGB[paint], PAINT_NIR[paint]
    lid = 0.07
    parts = [
        frustum("body", 0.46 * D, D / 2 - 0.01, 0.0, H - lid, rgb, nir),
        frustum("lid", D / 2, 0.42 * D, H - lid, H, rgb, nir),
        frustum("aperture", D / 2 - 0.005, D / 2 - 0.005, H - lid - 0.16, H - lid - 0.04, PAINT_RGB["black"], 0.05),
    ]
    return PropModel("bin", 0, parts, H, roughness=0.6, dims={"height_m": H, "diameter_m": D})


def _bollard(rng, height_m, form, length_m) -> PropModel:
    H = _height("bollard", rng, height_m)
    D = float(rng.uniform(0.1, 0.2))
    steel = bool(rng.random() < 0.3)
    rgb, nir = (STAINLESS_RGB, 0.55) if steel else (PAINT_RGB["black"], PAINT_NIR["black"])
    cap = 0.3 * D
    parts = [
        frustum("column", D / 2, D / 2, 0.0, H - cap, rgb, nir),
        frustum("cap", D / 2, 0.25 * D, H - cap, H, rgb, nir),
    ]
    if not steel:
        parts.append(frustum("band", D / 2 + 0.002, D / 2 + 0.002, H - cap - 0.12, H - cap - 0.05, BAND_RGB, 0.8))
    return PropModel(
        "bollard", 0, parts, H, roughness=0.35 if steel else 0.6, metallic=1.0 if steel else 0.0,
        dims={"height_m": H, "diameter_m": D},
    )  # fmt: skip


def _lamp_post(rng, height_m, form, length_m) -> PropModel:
    H = float(LAMP_HEIGHTS_M[int(rng.integers(len(LAMP_HEIGHTS_M)))]) if height_m is None else float(height_m)
    base_d = float(rng.uniform(0.14, 0.19))
    top_d = 0.076
    outreach = float(rng.uniform(0.5, 1.5))
    lantern_l = float(rng.uniform(0.5, 0.8))
    arm = 0.06
    parts = [
        frustum("column", base_d / 2, top_d / 2, 0.0, H - arm / 2, GALVANISED_RGB, GALVANISED_NIR),
        box("bracket", (outreach, arm, arm), (outreach / 2, 0.0, H - arm / 2), GALVANISED_RGB, GALVANISED_NIR),
        box(
            "lantern",
            (lantern_l, 0.28, 0.10),
            (outreach + lantern_l / 2 - 0.1, 0.0, H - 0.05),
            GALVANISED_RGB,
            GALVANISED_NIR,
        ),
        box(
            "diffuser",
            (lantern_l - 0.12, 0.2, 0.02),
            (outreach + lantern_l / 2 - 0.1, 0.0, H - 0.105),
            LANTERN_GLASS_RGB,
            0.6,
        ),
    ]
    return PropModel(
        "lamp_post", 0, parts, H, roughness=0.5, metallic=0.5,
        dims={"height_m": H, "base_diameter_m": base_d, "outreach_m": outreach, "lantern_length_m": lantern_l},
    )  # fmt: skip


def _sign(rng, height_m, form, length_m) -> PropModel:
    lower = float(rng.uniform(*SIGN_HEIGHT_OVER_PLATE_M))
    circle = bool(rng.random() < 0.5)
    plate = float((0.6, 0.75)[int(rng.integers(2))]) if circle else float(rng.uniform(0.45, 0.9))
    if height_m is not None:  # keep the plate (smaller if it must be), move its lower edge
        lower = max(float(height_m) - plate, SIGN_HEIGHT_OVER_PLATE_M[0])
        if lower + plate > height_m:
            circle, plate = False, float(height_m) - lower
    H = lower + plate
    post_d = float((0.076, 0.089)[int(rng.integers(2))])
    colour = tuple(SIGN_RGB)[int(rng.integers(len(SIGN_RGB)))]
    rgb = SIGN_RGB[colour]
    parts = [frustum("post", post_d / 2, post_d / 2, 0.0, H - 0.02, GALVANISED_RGB, GALVANISED_NIR)]
    x = post_d / 2 + 0.01
    if circle:
        disc = frustum("plate", plate / 2, plate / 2, -0.01, 0.01, rgb, float(rgb[0]))
        disc.vertices_m[:] = disc.vertices_m[:, [2, 0, 1]] + (x, 0.0, lower + plate / 2)
        disc.normals[:] = disc.normals[:, [2, 0, 1]]
        parts.append(disc)
    else:
        parts.append(box("plate", (0.02, plate, plate), (x, 0.0, lower + plate / 2), rgb, float(rgb[0])))
    return PropModel(
        "sign", 0, parts, H, roughness=0.4,
        dims={"height_m": H, "plate_lower_edge_m": lower, "plate_size_m": plate, "post_diameter_m": post_d},
    )  # fmt: skip


def _fence(rng, height_m, form, length_m) -> PropModel:
    H = _height("fence", rng, height_m)
    L = float(rng.uniform(4.0, 10.0)) if length_m is None else float(length_m)
    bays = max(1, math.ceil(L / float(rng.uniform(2.5, 3.0))))  # posts at ≤ 3 m centres
    paint = _paint(rng)
    rgb, nir = PAINT_RGB[paint], PAINT_NIR[paint]
    post, rail, bar = 0.06, 0.04, 0.02
    parts = [box("post", (post, post, H), (x, 0.0, H / 2), rgb, nir) for x in np.linspace(0.0, L, bays + 1)]
    for z in (0.1, H - 0.06):
        parts.append(box("rail", (L, rail, rail), (L / 2, 0.0, z), rgb, nir))
    bar_gap = 0.1
    count = math.ceil(L / (bar + bar_gap))
    for x in (np.arange(count) + 0.5) * (L / count):
        parts.append(box("bar", (bar, bar, H - 0.1), (x, 0.0, (H - 0.1) / 2 + 0.05), rgb, nir))
    return PropModel(
        "fence", 0, parts, H, roughness=0.6,
        dims={"height_m": H, "length_m": L, "post_spacing_m": L / bays, "bar_gap_m": L / count - bar},
    )  # fmt: skip


BUILDERS = {
    "tree": _tree,
    "bush": _bush,
    "bench": _bench,
    "bin": _bin,
    "bollard": _bollard,
    "lamp_post": _lamp_post,
    "sign": _sign,
    "fence": _fence,
}


def build_prop(
    kind: str, seed: int, *, form: str | None = None, height_m: float | None = None, length_m: float | None = None
) -> PropModel:
    """The prop of type `kind` that identity `seed` draws (a pinned height or length replaces the drawn one)."""
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(PROP_TYPE_KEYS[kind],)))
    model = BUILDERS[kind](rng, height_m, form, length_m)
    model.seed = seed
    return model
