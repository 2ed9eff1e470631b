"""Occlusion of a sight line by the scene's environment meshes: exact ray tests against boxes,
cylinders, spheres and one-sided planes in each mesh's own frame, Möller–Trumbore against the
triangles of mesh files and of procedural props (`camgen.props`; a crown or a bush by its convex hull,
`PropModel.occluder_triangles`).

A sight line is the segment from the camera centre to a point; it is blocked when it enters a mesh
before it reaches the point (less `END_MARGIN_M`, so a point lying on a surface — the ground on its
plane — is not hidden by that surface). Entering only: a camera inside a closed solid sees through it,
as the renderer does (its faces are culled from inside, `camgen.config.placement`). Planes and
checkerboards block from their front (+Z) side only, as they are drawn, and not a point lying up to
`SURFACE_LAYER_M` under the plane of their face: such a point is on that surface (a road laid 1 cm over
the ground plane) or just beside its edge. Cylinders are exact circles (the renderer's facets lie inside them by at
most r·(1 − cos(π/sections))).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from camgen.config.kerbs import kerb_names
from camgen.config.placement import local_bounds, placement
from camgen.config.scene import BoxMesh, CheckerboardMesh, CylinderMesh, FileMesh, PlaneMesh, Scene, SphereMesh
from camgen.props import placed_props
from camgen.world.kerbs import kerb_geometry

END_MARGIN_M = 1e-3
"""A hit this close to the point itself does not hide it, m."""
SURFACE_LAYER_M = 0.05
"""A point at most this far under the plane of a face lies on that surface (or beside its edge) and is
not hidden by it, m: roads and markings are drawn a little above the ground they cover (intersection_two_
cameras: 1.0 and 1.1 cm) to keep the depth test from mixing them, and a camera sees the road at those
points (the render's depth there is 1 cm / sin(elevation) short of the ground's, the point's own
surface). 5 cm: more than such layers, less than a kerb (15 cm) or anything one stands under."""
BOUNDS_MARGIN_M = 1e-6
"""Slack of the bounding-box test that picks the segments to test against a mesh, m."""
INSIDE_TOLERANCE_M = 1e-6
"""A point this close to a solid's face counts as inside it (the ground under a box), m."""
TRIANGLE_CHUNK = 2_000_000
"""Most ray–triangle pairs tested at once (memory)."""


@dataclass(frozen=True)
class Occluder:
    """One environment mesh, in its own frame."""

    name: str
    kind: str
    """box, cylinder, sphere, plane or triangles."""
    T_mesh_from_world: np.ndarray
    """(4, 4)."""
    half_extent_m: np.ndarray
    """(3,) half sizes: a box's; (r, r, h/2) of a cylinder; (r, r, r) of a sphere; (hx, hy, 0) of a plane."""
    triangles_m: np.ndarray | None = None
    """(T, 3, 3) vertices in the mesh frame, m (mesh files, already scaled)."""
    entering_only: bool = False
    """Triangles wound outward (counter-clockwise seen from outside) that hide only where a sight line
    enters through their front, as the renderer culls back faces: a procedural prop, so a camera mounted
    inside a lamp post's column sees out of it. Mesh files, whose winding is the user's, hide both ways."""


def scene_occluders(scene: Scene, file_triangles_m: Mapping[str, np.ndarray] | None = None) -> list[Occluder]:
    """The occluders of a scene's environment; `file_triangles_m` maps a mesh file's path (as written)
    to its triangles (T, 3, 3) in the file's units (the mesh's `scale` is applied here)."""
    occluders = []
    for mesh in scene.environment.meshes:
        T = np.linalg.inv(placement(mesh))
        if isinstance(mesh, FileMesh):
            if not file_triangles_m or mesh.path not in file_triangles_m:
                raise ValueError(f"the triangles of mesh file {mesh.path!r} were not given")
            triangles = np.asarray(file_triangles_m[mesh.path], dtype=np.float64) * mesh.scale
            occluders.append(Occluder(mesh.name, "triangles", T, np.zeros(3), triangles))
            continue
        kind = {
            BoxMesh: "box",
            CylinderMesh: "cylinder",
            SphereMesh: "sphere",
            PlaneMesh: "plane",
            CheckerboardMesh: "plane",
        }[type(mesh)]
        occluders.append(Occluder(mesh.name, kind, T, local_bounds(mesh)[1]))
    for prop in placed_props(scene.environment, scene_seed=scene.seed):  # leafy parts by their hull
        T = np.linalg.inv(prop.T_world_from_prop)
        triangles = prop.model.occluder_triangles()
        occluders.append(Occluder(prop.name, "triangles", T, np.zeros(3), triangles, entering_only=True))
    for kerb, name in zip(scene.environment.kerbs, kerb_names(scene.environment.kerbs), strict=True):
        swept = kerb_geometry(kerb)  # in world coordinates, wound outward and open only along the road
        triangles = swept.vertices_m.astype(np.float64)[swept.faces]
        occluders.append(Occluder(name, "triangles", np.eye(4), np.zeros(3), triangles, entering_only=True))
    return occluders


def _entering_s(kind: str, half: np.ndarray, o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Segment parameter s (N,) where o + s·d first enters the shape from outside; inf where it does not."""
    n = len(d)
    with np.errstate(divide="ignore", invalid="ignore"):
        if kind == "box":
            t1 = (-half - o) / d
            t2 = (half - o) / d
            near = np.nanmax(np.minimum(t1, t2), axis=1)
            far = np.nanmin(np.maximum(t1, t2), axis=1)
            # A ray parallel to a slab outside it never enters.
            outside_parallel = np.any((d == 0) & (np.abs(o) > half), axis=1)
            # near < far: a segment that only touches the box (a camera mounted on its face, looking away
            # along it) does not enter it.
            hit = (near < far) & ~outside_parallel & (near >= 0)
            return np.where(hit, near, np.inf)
        if kind == "sphere":
            a = np.einsum("ij,ij->i", d, d)
            b = 2.0 * d @ o
            c = float(o @ o) - half[0] ** 2
            disc = b * b - 4 * a * c
            s = (-b - np.sqrt(disc)) / (2 * a)
            return np.where((disc >= 0) & (c > 0) & (s >= 0), s, np.inf)
        if kind == "cylinder":
            r, hz = half[0], half[2]
            a = d[:, 0] ** 2 + d[:, 1] ** 2
            b = 2.0 * (o[0] * d[:, 0] + o[1] * d[:, 1])
            c = o[0] ** 2 + o[1] ** 2 - r * r
            disc = b * b - 4 * a * c
            side = (-b - np.sqrt(disc)) / (2 * a)
            z_side = o[2] + side * d[:, 2]
            side = np.where((disc >= 0) & (c > 0) & (side >= 0) & (np.abs(z_side) <= hz), side, np.inf)
            if abs(o[2]) <= hz:
                return side
            cap_z = hz if o[2] > hz else -hz
            cap = (cap_z - o[2]) / d[:, 2]
            xy = o[:2] + cap[:, None] * d[:, :2]
            cap = np.where((cap >= 0) & (np.einsum("ij,ij->i", xy, xy) <= r * r), cap, np.inf)
            return np.minimum(side, cap)
        if kind == "plane":
            if o[2] <= 0:  # seen from behind: not drawn
                return np.full(n, np.inf)
            s = -o[2] / d[:, 2]
            xy = o[:2] + s[:, None] * d[:, :2]
            inside = (np.abs(xy[:, 0]) <= half[0]) & (np.abs(xy[:, 1]) <= half[1])
            return np.where((s >= 0) & inside, s, np.inf)
    raise ValueError(f"unknown occluder kind {kind!r}")


def _triangles_s(triangles: np.ndarray, o: np.ndarray, d: np.ndarray, *, entering_only: bool = False) -> np.ndarray:
    """Nearest s (N,) where o + s·d crosses any triangle (Möller & Trumbore 1997): from either side, or,
    `entering_only`, through its front (det > 0: d against the counter-clockwise normal)."""
    v0, e1, e2 = triangles[:, 0], triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]
    best = np.full(len(d), np.inf)
    step = max(1, TRIANGLE_CHUNK // max(1, len(triangles)))
    tvec = o - v0  # (T, 3)
    qvec = np.cross(tvec, e1)  # (T, 3)
    for start in range(0, len(d), step):
        dd = d[start : start + step]
        pvec = np.cross(dd[:, None, :], e2[None])  # (n, T, 3)
        det = np.einsum("ntk,tk->nt", pvec, e1)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            u = np.einsum("ntk,tk->nt", pvec, tvec) * inv
            v = np.einsum("nk,tk->nt", dd, qvec) * inv
            s = np.einsum("tk,tk->t", e2, qvec)[None] * inv
        facing = det > 1e-15 if entering_only else np.abs(det) > 1e-15
        hit = facing & (u >= 0) & (v >= 0) & (u + v <= 1) & (s >= 0)
        best[start : start + step] = np.where(hit, s, np.inf).min(axis=1, initial=np.inf)
    return best


def world_bounds_m(occluder: Occluder) -> tuple[np.ndarray, np.ndarray]:
    """The world axis-aligned box (lo (3,), hi (3,)) holding the occluder: its local box's (or its
    triangles') corners carried into the world."""
    if occluder.kind == "triangles":
        local = occluder.triangles_m.reshape(-1, 3)
    else:
        half = occluder.half_extent_m
        local = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
    T_world_from_mesh = np.linalg.inv(occluder.T_mesh_from_world)
    world = local @ T_world_from_mesh[:3, :3].T + T_world_from_mesh[:3, 3]
    return world.min(axis=0), world.max(axis=0)


def _entries(origin_m: np.ndarray, targets_m: np.ndarray, occluders: Sequence[Occluder]):
    """For each occluder: (it, the indices of the segments origin → target whose bounding box meets its
    world bounding box, s in [0, 1] where each of those first enters it, inf where it does not)."""
    origin = np.asarray(origin_m, dtype=np.float64)
    targets = np.asarray(targets_m, dtype=np.float64).reshape(-1, 3)
    columns = [np.ascontiguousarray(targets[:, axis]) for axis in range(3)]
    lows = [np.minimum(c, origin[axis]) for axis, c in enumerate(columns)]
    highs = [np.maximum(c, origin[axis]) for axis, c in enumerate(columns)]
    for occluder in occluders:
        lo, hi = world_bounds_m(occluder)
        meets = np.ones(len(targets), dtype=bool)
        for axis in range(3):
            meets &= highs[axis] >= lo[axis] - BOUNDS_MARGIN_M
            meets &= lows[axis] <= hi[axis] + BOUNDS_MARGIN_M
        near = np.flatnonzero(meets)
        if len(near) == 0:
            continue
        R, t = occluder.T_mesh_from_world[:3, :3], occluder.T_mesh_from_world[:3, 3]
        o = R @ origin + t
        d = (targets[near] - origin) @ R.T
        if occluder.kind == "triangles":
            s = _triangles_s(occluder.triangles_m, o, d, entering_only=occluder.entering_only)
        else:
            s = _entering_s(occluder.kind, occluder.half_extent_m, o, d)
        yield occluder, near, np.where(s <= 1.0, s, np.inf)


def sight_blocked(origin_m: np.ndarray, targets_m: np.ndarray, occluders: Sequence[Occluder]) -> np.ndarray:
    """Whether a mesh hides each target (N, 3) from `origin_m` (3,): bool (N,)."""
    targets = np.asarray(targets_m, dtype=np.float64).reshape(-1, 3)
    length = np.linalg.norm(targets - np.asarray(origin_m, dtype=np.float64), axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        s_end = 1.0 - END_MARGIN_M / length
    blocked = np.zeros(len(targets), dtype=bool)
    for occluder, near, s in _entries(origin_m, targets, occluders):
        hit = s < s_end[near]
        if occluder.kind == "plane":
            hit &= ~lies_under_face(targets[near], occluder)
        blocked[near] |= hit
    return blocked


def lies_under_face(points_m: np.ndarray, plane: Occluder) -> np.ndarray:
    """Whether each point (N, 3) lies within `SURFACE_LAYER_M` under the plane of a face (or on it): bool (N,).
    Inside the face's outline the point is on that surface; just beside it, a sight line can cross the
    layer's edge only in its last few centimetres (1 cm / tan(elevation)), which is no occlusion either."""
    z = points_m @ plane.T_mesh_from_world[2, :3] + plane.T_mesh_from_world[2, 3]
    return (z <= 0.0) & (z >= -SURFACE_LAYER_M)


def inside_solids(points_m: np.ndarray, occluders: Sequence[Occluder]) -> np.ndarray:
    """Whether each point (N, 3) lies inside (or on) a box, cylinder or sphere: bool (N,)."""
    points = np.asarray(points_m, dtype=np.float64).reshape(-1, 3)
    inside = np.zeros(len(points), dtype=bool)
    tol = INSIDE_TOLERANCE_M
    for occluder in occluders:
        local = points @ occluder.T_mesh_from_world[:3, :3].T + occluder.T_mesh_from_world[:3, 3]
        half = occluder.half_extent_m
        if occluder.kind == "box":
            inside |= np.all(np.abs(local) <= half + tol, axis=1)
        elif occluder.kind == "cylinder":
            inside |= (np.hypot(local[:, 0], local[:, 1]) <= half[0] + tol) & (np.abs(local[:, 2]) <= half[2] + tol)
        elif occluder.kind == "sphere":
            inside |= np.linalg.norm(local, axis=1) <= half[0] + tol
    return inside


GROUND_TOLERANCE_M = 1e-6


def on_ground(points_m: np.ndarray, occluders: Sequence[Occluder]) -> np.ndarray | None:
    """Whether each point (N, 3) lies above a ground plane (a plane or board at z = 0 facing up): bool (N,);
    None when the scene has no ground plane (then every point counts as ground)."""
    points = np.asarray(points_m, dtype=np.float64).reshape(-1, 3)
    over = None
    for occluder in occluders:
        R, t = occluder.T_mesh_from_world[:3, :3], occluder.T_mesh_from_world[:3, 3]
        position = -R.T @ t
        if occluder.kind != "plane" or R[2, 2] < 1 - 1e-9 or abs(position[2]) > GROUND_TOLERANCE_M:
            continue
        local = points.copy()
        local[:, 2] = 0.0
        local = local @ R.T + t
        half = occluder.half_extent_m
        inside = (np.abs(local[:, 0]) <= half[0] + 1e-9) & (np.abs(local[:, 1]) <= half[1] + 1e-9)
        over = inside if over is None else over | inside
    return over
