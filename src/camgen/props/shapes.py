"""Closed meshes a prop is made of: boxes, tapered cylinders (frusta), cones and lumpy, noise-displaced
blobs, each a `PropPart` with its colour and near-infrared reflectance per vertex.

Every part is a closed, consistently wound surface on its own (watertight once coincident vertices are
merged); a prop is a union of such parts, which may interpenetrate (a trunk reaching into its crown).
Hard parts are split along edges sharper than `CREASE_RAD` so that boxes shade flat and cylinders round;
organic parts (crowns, bushes) keep one smooth normal per vertex.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import trimesh

CREASE_RAD = math.radians(40.0)
"""Edges between faces meeting at more than this angle shade hard (a box's edges, a cylinder's rims)."""
ROUND_SECTIONS = 16
"""Sides of a round post, trunk or bin: at 16 a circle's outline departs from the polygon by 2 %."""


@dataclass
class PropPart:
    """Triangles of one part in the prop's frame (x forward, y left, z up, origin on the ground)."""

    name: str
    vertices_m: np.ndarray
    """(V, 3) float64."""
    normals: np.ndarray
    """(V, 3) unit vertex normals."""
    faces: np.ndarray
    """(F, 3) int64, counter-clockwise seen from outside."""
    colours_rgb: np.ndarray
    """(V, 3) linear visible reflectance."""
    nir_reflectance: np.ndarray
    """(V,) reflectance at 850 nm."""
    flutter_groups: np.ndarray | None = None
    """(V,) int: the group each vertex flutters with as one (a twig's leaves, `camgen.props.foliage`); None:
    each vertex on its own (`camgen.props.sway`)."""


def _hard(name: str, mesh: trimesh.Trimesh, rgb, nir: float) -> PropPart:
    shaded = trimesh.graph.smooth_shade(mesh, angle=CREASE_RAD, facet_minarea=None)
    n = len(shaded.vertices)
    return PropPart(
        name,
        np.array(shaded.vertices, dtype=np.float64),
        np.array(shaded.vertex_normals, dtype=np.float64),
        np.asarray(shaded.faces, dtype=np.int64),
        np.tile(np.asarray(rgb, dtype=np.float64), (n, 1)),
        np.full(n, float(nir)),
    )


def box(name: str, size_m, centre_m, rgb, nir: float, *, rotation: np.ndarray | None = None) -> PropPart:
    """A box of extents `size_m` centred on `centre_m` (turned by the 3×3 `rotation` about its centre)."""
    T = np.eye(4)
    if rotation is not None:
        T[:3, :3] = rotation
    T[:3, 3] = centre_m
    mesh = trimesh.creation.box(extents=size_m, transform=T)
    # every triangle its own three vertices: flat faces, without smooth_shade's cost (2 ms a box)
    vertices = np.asarray(mesh.vertices, dtype=np.float64)[mesh.faces].reshape(-1, 3)
    n = len(vertices)
    return PropPart(
        name,
        vertices,
        np.repeat(np.asarray(mesh.face_normals, dtype=np.float64), 3, axis=0),
        np.arange(n, dtype=np.int64).reshape(-1, 3),
        np.tile(np.asarray(rgb, dtype=np.float64), (n, 1)),
        np.full(n, float(nir)),
    )


def frustum_mesh(
    r0_m: float, r1_m: float, z0_m: float, z1_m: float, sections: int = ROUND_SECTIONS, bands: int = 1
) -> trimesh.Trimesh:
    """A closed tapered cylinder about the z axis from radius `r0_m` at `z0_m` to `r1_m` at `z1_m`, its side
    cut into `bands` equal bands (more rings, so that a bent trunk curves: `camgen.props.sway`)."""
    a = np.linspace(0.0, 2 * math.pi, sections, endpoint=False)
    ring = np.column_stack([np.cos(a), np.sin(a)])
    f = np.arange(bands + 1) / bands
    vertices = np.vstack(
        [np.column_stack([(r0_m + (r1_m - r0_m) * t) * ring, np.full(sections, z0_m + (z1_m - z0_m) * t)]) for t in f]
        + [[(0.0, 0.0, z0_m), (0.0, 0.0, z1_m)]]
    )
    i = np.arange(sections)
    j = (i + 1) % sections
    bottom, top = (bands + 1) * sections, (bands + 1) * sections + 1
    sides = []
    for k in range(bands):
        low, high = k * sections, (k + 1) * sections
        sides += [np.column_stack([low + i, low + j, high + j]), np.column_stack([low + i, high + j, high + i])]
    last = bands * sections
    faces = np.vstack(
        [
            *sides,
            np.column_stack([np.full(sections, bottom), j, i]),
            np.column_stack([np.full(sections, top), last + i, last + j]),
        ]
    )
    return trimesh.Trimesh(vertices, faces, process=False)


def frustum(
    name: str, r0_m: float, r1_m: float, z0_m: float, z1_m: float, rgb, nir: float, *, offset_m=(0, 0), bands: int = 1
) -> PropPart:
    mesh = frustum_mesh(r0_m, r1_m, z0_m, z1_m, bands=bands)
    mesh.vertices[:, :2] += np.asarray(offset_m, dtype=np.float64)
    return _hard(name, mesh, rgb, nir)


def limb(name: str, start_m, end_m, r0_m: float, r1_m: float, rgb, nir: float, sections: int = 6) -> PropPart:
    """A closed tapered cylinder (a branch) from `start_m` (radius `r0_m`) to `end_m` (radius `r1_m`), with
    `sections` sides (a branch a few pixels across needs few)."""
    start, end = np.asarray(start_m, dtype=np.float64), np.asarray(end_m, dtype=np.float64)
    axis = end - start
    length = float(np.linalg.norm(axis))
    mesh = frustum_mesh(r0_m, r1_m, 0.0, length, sections=sections)
    z = axis / length
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    R = np.column_stack([x, np.cross(z, x), z])
    mesh.vertices = np.asarray(mesh.vertices) @ R.T + start
    return _hard(name, mesh, rgb, nir)


def smooth_noise(directions: np.ndarray, *, rng: np.random.Generator, waves: int = 7, scale: float = 1.0) -> np.ndarray:
    """A smooth random field on points or unit directions (N, 3): a sum of `waves` plane waves of random
    direction, phase and frequency 1.5–4.5 / `scale` with amplitudes ∝ 1/frequency, normalised to unit
    standard deviation over the points given. Shape (N,)."""
    axes = rng.normal(size=(waves, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    frequency = rng.uniform(1.5, 4.5, size=waves) / scale
    phase = rng.uniform(0, 2 * math.pi, size=waves)
    field = (np.cos((directions @ axes.T) * frequency + phase) / frequency).sum(axis=1)
    spread = field.std()
    return (field - field.mean()) / spread if spread > 0 else field


def blob(
    name: str,
    radii_m,
    centre_m,
    *,
    roughness: float,
    exponent: float,
    rgb,
    nir: float,
    rng: np.random.Generator,
    subdivisions: int = 2,
    colour_variation: float = 0.3,
) -> PropPart:
    """A lumpy closed blob: an icosphere mapped onto a superellipsoid of semi-axes `radii_m` (`exponent` 2
    an ellipsoid, 4 a rounded box) and displaced along each direction by `roughness` × a smooth random
    field (with a finer one, a third as strong, for clumps of leaves); its colour varies by
    `colour_variation` with another field (lighter at the top), its NIR reflectance by a tenth of that."""
    sphere = trimesh.creation.icosphere(subdivisions=subdivisions)
    d = np.asarray(sphere.vertices, dtype=np.float64)
    radii = np.asarray(radii_m, dtype=np.float64)
    superellipse = (np.abs(d) ** exponent).sum(axis=1) ** (-1.0 / exponent)
    # Large lumps, and a finer field a third as strong for clumps of leaves.
    bump = 1.0 + roughness * np.clip(
        smooth_noise(d, rng=rng) + 0.35 * smooth_noise(d, rng=rng, waves=12, scale=0.25), -3, 3
    )
    vertices = d * (superellipse * bump)[:, None] * radii + np.asarray(centre_m, dtype=np.float64)
    mesh = trimesh.Trimesh(vertices, np.asarray(sphere.faces), process=False)
    shade = 1.0 + colour_variation * np.clip(smooth_noise(d, rng=rng, scale=0.5) / 2.5, -1, 1) + 0.15 * d[:, 2]
    shade *= rng.uniform(0.92, 1.08, size=len(d))
    colours = np.clip(np.asarray(rgb, dtype=np.float64) * shade[:, None], 0.0, 1.0)
    nirs = np.clip(nir * (1.0 + 0.1 * (shade - 1.0)), 0.0, 1.0)
    return PropPart(
        name,
        vertices,
        np.array(mesh.vertex_normals, dtype=np.float64),
        np.asarray(mesh.faces, dtype=np.int64),
        colours,
        nirs,
    )


def lumpy_cone(
    name: str,
    radius_m: float,
    z0_m: float,
    z1_m: float,
    *,
    rgb,
    nir: float,
    rng: np.random.Generator,
    sections: int = 24,
    rings: int = 6,
) -> PropPart:
    """A closed cone from a ring of `radius_m` at `z0_m` to its apex at `z1_m`, its radius perturbed by a
    smooth random field (±20 %) so that its outline is not a straight-sided triangle."""
    a = np.linspace(0.0, 2 * math.pi, sections, endpoint=False)
    t = np.linspace(0.0, 1.0, rings, endpoint=False)
    ring = np.column_stack([np.cos(a), np.sin(a)])
    points = np.concatenate([np.column_stack([ring, np.full(sections, ti)]) for ti in t])
    wobble = 1.0 + 0.2 * np.clip(smooth_noise(points * (2.0, 2.0, 4.0), rng=rng) / 2.5, -1, 1)
    radius = radius_m * (1.0 - points[:, 2]) ** 0.9 * wobble
    sides = np.column_stack([points[:, 0] * radius, points[:, 1] * radius, z0_m + (z1_m - z0_m) * points[:, 2]])
    vertices = np.vstack([sides, [(0.0, 0.0, z1_m), (0.0, 0.0, z0_m)]])
    apex, base = len(sides), len(sides) + 1
    faces = []
    for r in range(rings - 1):
        for s in range(sections):
            i, j = r * sections + s, r * sections + (s + 1) % sections
            faces += [(i, j, j + sections), (i, j + sections, i + sections)]
    top = (rings - 1) * sections
    for s in range(sections):
        faces.append((top + s, top + (s + 1) % sections, apex))
        faces.append((base, (s + 1) % sections, s))
    mesh = trimesh.Trimesh(vertices, np.array(faces), process=False)
    n = len(vertices)
    shade = rng.uniform(0.85, 1.15, size=n) * (1.0 + 0.2 * (vertices[:, 2] - z0_m) / max(z1_m - z0_m, 1e-9))
    return PropPart(
        name,
        vertices,
        np.array(mesh.vertex_normals, dtype=np.float64),
        np.asarray(mesh.faces, dtype=np.int64),
        np.clip(np.asarray(rgb, dtype=np.float64) * shade[:, None], 0.0, 1.0),
        np.full(n, float(nir)),
    )


def rot_x(angle_rad: float) -> np.ndarray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
