"""Kerbs: a precast concrete kerb's cross-section swept along a polyline, as a triangle mesh with texture
coordinates in metres (pure geometry; `camgen.render.scene_graph` draws it with `camgen.world.textures.
kerb_surface_maps`, whose joints fall every `unit_length_m` along the kerb). Sizes and their sources:
`camgen.config.kerbs`.

The profile is the part above the road of a half-battered kerb, BS EN 1340 / BS 7263-1 type HB2, 125 mm wide
and 255 mm deep, laid with an upstand (its top over the road): from the foot of its road face, a vertical face,
then a batter leaning back towards the footway, a small radius where the batter meets the top, the flat top,
and the back face down to the road's level again (the footway behind a kerb is usually level with its top and
hides the back face; a kerb standing alone shows it).

Frames: a kerb's polyline `along_m` is the foot of its road face on the road surface, in world (x, y), and the
road lies to its right walking along it (`road_side` flips it). In the profile, x runs back from the road
face (away from the road) and z up from the road surface. Texture coordinates: u is the distance along the
polyline from its first point walking with the road on the right (the last given point when `road_side` is
left), projected onto each segment; v the distance around the profile from the foot
of the road face; (u, v, outward normal) is right-handed on every face, as `camgen.render.scene_graph`'s normal
maps need. End caps take u across the kerb and v up.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from camgen.config.kerbs import (
    ARRIS_RADIUS_M,
    BATTER_RISE_M,
    BATTER_SETBACK_M,
    HB2_WIDTH_M,
    UNIT_LENGTH_M,
    UPSTAND_M,
    Kerb,
)

ARC_SEGMENTS = 4
"""Facets of the arris radius (each quarter of its 63° turn about 16°: its silhouette is smooth at a pixel)."""


@dataclass(frozen=True)
class KerbProfile:
    """A kerb's cross-section above the road, (x back from the road face, z up), m: `points` (P, 2) from the
    foot of the road face up over the top and down the back face, facets between consecutive points;
    `normals` (P − 1, 2, 2) the outward unit normal at each facet's two ends (equal on a flat facet, the
    circle's own on the arris's facets)."""

    points: np.ndarray
    normals: np.ndarray

    @property
    def arc_length_m(self) -> np.ndarray:
        """(P,) the distance around the profile from its first point to each point, m."""
        steps = np.hypot(*np.diff(self.points, axis=0).T)
        return np.concatenate([[0.0], np.cumsum(steps)])

    def area_m2(self) -> float:
        """Area of the cross-section closed along the road (z = 0), m² (shoelace formula)."""
        x, z = self.points[:, 0], self.points[:, 1]
        return float(abs(np.dot(x, np.roll(z, -1)) - np.dot(z, np.roll(x, -1))) / 2)


def kerb_profile(
    width_m: float = HB2_WIDTH_M,
    upstand_m: float = UPSTAND_M,
    batter_setback_m: float = BATTER_SETBACK_M,
    batter_rise_m: float = BATTER_RISE_M,
    arris_radius_m: float = ARRIS_RADIUS_M,
    arc_segments: int = ARC_SEGMENTS,
) -> KerbProfile:
    """The cross-section of a kerb `width_m` wide standing `upstand_m` over the road, its road face's top
    `batter_rise_m` battered back `batter_setback_m`, the arris between batter and top rounded to
    `arris_radius_m` (tangent to both). A batter of zero setback or rise is a square kerb."""
    h, s, r = upstand_m, batter_setback_m, batter_rise_m
    if s <= 0 or r <= 0:
        s, r = 0.0, 0.0
    foot, batter_foot, corner = np.array([0.0, 0.0]), np.array([0.0, h - r]), np.array([s, h])
    back_top, back_foot = np.array([width_m, h]), np.array([width_m, 0.0])
    # The corner where the road face's top part (its batter, or the whole face when unbattered) meets the top.
    face_foot = batter_foot if r > 0 else foot
    incoming = (corner - face_foot) / np.linalg.norm(corner - face_foot)
    outgoing = np.array([1.0, 0.0])
    turn = math.acos(float(np.clip(incoming @ outgoing, -1.0, 1.0)))  # the direction turns clockwise by this
    points, normals = [foot], []
    if r > 0:
        points.append(batter_foot)
        normals.append([[-1.0, 0.0], [-1.0, 0.0]])
    face_normal = np.array([-incoming[1], incoming[0]])  # outward: travel (dx, dz) turned by +90°
    if arris_radius_m > 0 and turn > 1e-9:
        tangent_m = arris_radius_m * math.tan(turn / 2)
        start, end = corner - tangent_m * incoming, corner + tangent_m * outgoing
        centre = end - np.array([0.0, arris_radius_m])
        a0 = math.atan2(*(start - centre)[::-1])
        angles = a0 - np.linspace(0.0, turn, arc_segments + 1)  # clockwise, from the face's normal to +z
        arc = centre + arris_radius_m * np.column_stack([np.cos(angles), np.sin(angles)])
        arc_normals = np.column_stack([np.cos(angles), np.sin(angles)])
        points.append(start)
        normals.append([face_normal, face_normal])
        points += list(arc[1:])
        normals += [[a, b] for a, b in itertools.pairwise(arc_normals)]
    else:
        points.append(corner)
        normals.append([face_normal, face_normal])
    points += [back_top, back_foot]
    normals += [[[0.0, 1.0], [0.0, 1.0]], [[1.0, 0.0], [1.0, 0.0]]]
    return KerbProfile(np.array(points, dtype=np.float64), np.array(normals, dtype=np.float64))


def profile_area_m2(
    width_m: float, upstand_m: float, batter_setback_m: float, batter_rise_m: float, arris_radius_m: float
) -> float:
    """The closed-form area of `kerb_profile`'s cross-section with a true circular arris, m²: the rectangle
    width·upstand less the batter's triangle ½·setback·rise less the fillet r²·(cot(α/2) − (π − α)/2) that
    rounding a corner of interior angle α = π − atan(rise / setback) takes off (α = π/2 unbattered)."""
    if batter_setback_m <= 0 or batter_rise_m <= 0:
        batter_setback_m, batter_rise_m = 0.0, 1.0  # a vertical road face
    area = width_m * upstand_m - batter_setback_m * batter_rise_m / 2
    alpha = math.pi - math.atan2(batter_rise_m, batter_setback_m)
    return area - arris_radius_m**2 * (1.0 / math.tan(alpha / 2) - (math.pi - alpha) / 2)


@dataclass(frozen=True)
class KerbMesh:
    """A kerb swept along its polyline, in world coordinates: `vertices_m` (V, 3), `normals` (V, 3) unit,
    `uv_m` (V, 2) texture coordinates in metres (module docstring), `faces` (F, 3) int32 counter-clockwise
    seen from outside."""

    vertices_m: np.ndarray
    normals: np.ndarray
    uv_m: np.ndarray
    faces: np.ndarray
    length_m: float
    """Length of the polyline, m."""


def polyline_length_m(along_m) -> float:
    """The length of a polyline (N, 2), m."""
    return float(np.hypot(*np.diff(np.asarray(along_m, dtype=np.float64), axis=0).T).sum())


def joint_positions_m(length_m: float, unit_length_m: float = UNIT_LENGTH_M) -> np.ndarray:
    """Distances along a kerb of `length_m` from its first point to each joint between its units, m: every
    `unit_length_m` from the first point (the last unit is cut to length)."""
    return np.arange(1, math.ceil(length_m / unit_length_m - 1e-9)) * unit_length_m


def kerb_mesh(along_m, profile: KerbProfile, *, road_side: str = "right", base_height_m: float = 0.0) -> KerbMesh:
    """Sweep `profile` along the polyline `along_m` ((N, 2), m; the foot of the road face, the road to its
    `road_side`), standing on the road surface at `base_height_m`: one strip of quads per profile facet and
    segment, mitred at the polyline's bends, and a flat cap at each end."""
    points = np.asarray(along_m, dtype=np.float64)
    if road_side == "left":  # walk it the other way, and the road is on the right
        points = points[::-1]
    steps = np.diff(points, axis=0)
    lengths = np.hypot(*steps.T)
    tangents = steps / lengths[:, None]
    backs = np.column_stack([-tangents[:, 1], tangents[:, 0]])  # left of travel: away from the road
    starts_s = np.concatenate([[0.0], np.cumsum(lengths)])
    # The offset of a profile point at x = 1 behind each polyline point: square at the ends, mitred between.
    offsets = np.empty((len(points), 2))
    offsets[0], offsets[-1] = backs[0], backs[-1]
    for i in range(1, len(points) - 1):
        mid = backs[i - 1] + backs[i]
        mid /= np.linalg.norm(mid)
        offsets[i] = mid / float(mid @ backs[i])
    px, pz = profile.points[:, 0], profile.points[:, 1] + base_height_m
    arc = profile.arc_length_m
    vertices, normals, uvs, faces = [], [], [], []

    def add_quad(corners, quad_normals, quad_uvs, outward):
        base = sum(len(v) for v in vertices)
        vertices.append(np.asarray(corners))
        normals.append(np.asarray(quad_normals))
        uvs.append(np.asarray(quad_uvs))
        order = [(0, 1, 2), (0, 2, 3)]
        c = np.asarray(corners)
        if np.cross(c[1] - c[0], c[2] - c[0]) @ outward < 0:
            order = [(0, 2, 1), (0, 3, 2)]
        faces.extend([(base + a, base + b, base + c_) for a, b, c_ in order])

    for j in range(len(points) - 1):
        t, back = tangents[j], backs[j]
        for k in range(len(px) - 1):
            corners, quad_normals, quad_uvs = [], [], []
            for end, a in ((0, k), (1, k), (1, k + 1), (0, k + 1)):
                i = j + end
                xy = points[i] + px[a] * offsets[i]
                corners.append((xy[0], xy[1], pz[a]))
                n2 = profile.normals[k, 0 if a == k else 1]
                quad_normals.append((*(n2[0] * back), n2[1]))
                quad_uvs.append((starts_s[j] + float((xy - points[j]) @ t), arc[a]))
            mean_normal = np.mean(quad_normals, axis=0)
            add_quad(corners, quad_normals, quad_uvs, mean_normal)
    # End caps: the profile closed along the road, fanned from its centroid (the profile is convex).
    for i, outward2 in ((0, -tangents[0]), (len(points) - 1, tangents[-1])):
        outward = np.array([*outward2, 0.0])
        u_axis = np.cross([0.0, 0.0, 1.0], outward)  # (u, v = z, outward) right-handed
        ring = np.column_stack([points[i] + np.outer(px, offsets[i]), pz])
        centre = ring.mean(axis=0)
        for a in range(len(ring)):
            b = (a + 1) % len(ring)
            tri = [centre, ring[a], ring[b]]
            base = sum(len(v) for v in vertices)
            vertices.append(np.asarray(tri))
            normals.append(np.tile(outward, (3, 1)))
            uvs.append(np.array([(float(p @ u_axis), float(p[2] - base_height_m)) for p in tri]))
            order = (0, 1, 2) if np.cross(tri[1] - tri[0], tri[2] - tri[0]) @ outward > 0 else (0, 2, 1)
            faces.append(tuple(base + o for o in order))
    return KerbMesh(
        vertices_m=np.concatenate(vertices).astype(np.float32),
        normals=np.concatenate(normals).astype(np.float32),
        uv_m=np.concatenate(uvs).astype(np.float32),
        faces=np.asarray(faces, dtype=np.int32),
        length_m=float(lengths.sum()),
    )


def kerb_geometry(kerb: Kerb) -> KerbMesh:
    """The mesh of a kerb of `camgen.config.kerbs`."""
    profile = kerb_profile(kerb.width_m, kerb.upstand_m, kerb.batter_setback_m, kerb.batter_rise_m, kerb.arris_radius_m)
    return kerb_mesh(kerb.along_m, profile, road_side=kerb.road_side, base_height_m=kerb.road_height_m)
