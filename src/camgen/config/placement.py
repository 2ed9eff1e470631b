"""Where a camera stands relative to the scene's meshes: checks that no pixel can make up for.

The renderer draws a mesh's front faces only (back-face culling, `render.scene_graph._material`). A plane
or checkerboard is one-sided: seen from behind it vanishes, so a camera under the ground would film the
actors' undersides through the ground and the ground truth would mark them visible. Such a camera is
refused. A camera inside a closed solid (box, cylinder, sphere) sees through it, since the solid's faces
point outward and are culled from inside: right for a housing modelled around the camera, wrong for a
camera placed in a wall by mistake or a room modelled as a box, so it is a warning, not an error.
"""

from __future__ import annotations

import warnings

import numpy as np

from camgen.config.scene import BoxMesh, CheckerboardMesh, CylinderMesh, PlaneMesh, Scene, SphereMesh
from camgen.errors import ConfigWarning, Problem
from camgen.motion.pose import rotation_xyz_deg

BEHIND_TOLERANCE_M = 1e-6
"""A camera this close to a plane counts as on it, not behind it (float round-off of the placement)."""


def _local(position_m, mesh) -> np.ndarray:
    """A world point in the mesh's own frame (before its rotation about X, Y, Z and its offset)."""
    R_world_from_mesh = rotation_xyz_deg(mesh.rotation_deg)
    return R_world_from_mesh.T @ (np.asarray(position_m, dtype=np.float64) - np.asarray(mesh.position_m))


def _plane_half_extent_m(mesh: PlaneMesh | CheckerboardMesh) -> tuple[float, float]:
    if isinstance(mesh, PlaneMesh):
        return mesh.size_m[0] / 2, mesh.size_m[1] / 2
    border_m = mesh.border_width_m
    return tuple(s * mesh.square_size_m / 2 + border_m for s in mesh.squares)


def _inside(local_m: np.ndarray, mesh) -> bool:
    x, y, z = local_m
    if isinstance(mesh, BoxMesh):
        return bool(np.all(np.abs(local_m) < np.asarray(mesh.size_m) / 2))
    if isinstance(mesh, CylinderMesh):
        return x * x + y * y < mesh.radius_m**2 and abs(z) < mesh.height_m / 2
    if isinstance(mesh, SphereMesh):
        return float(local_m @ local_m) < mesh.radius_m**2
    return False


def camera_placement_problems(scene: Scene) -> tuple[list[Problem], list[Problem]]:
    """(errors, warnings) about each camera's position against the scene's meshes; key paths from the scene.

    Errors: a camera behind a one-sided plane or checkerboard, within its outline. Warnings: a camera
    inside a box, cylinder or sphere. Mesh files are not checked (whether one is closed is not known here).
    """
    errors: list[Problem] = []
    notes: list[Problem] = []
    for i, camera in enumerate(scene.cameras):
        key = ("cameras", i, "mount", "position_m")
        position_m = camera.mount.position_m
        shown = "[" + ", ".join(f"{v:g}" for v in position_m) + "]"
        for mesh in scene.environment.meshes:
            if isinstance(mesh, (PlaneMesh, CheckerboardMesh)):
                x, y, z = _local(position_m, mesh)
                half_x, half_y = _plane_half_extent_m(mesh)
                if z < -BEHIND_TOLERANCE_M and abs(x) <= half_x and abs(y) <= half_y:
                    errors.append(
                        Problem(
                            key,
                            f"puts camera {camera.name!r} {-z:.3g} m behind the {mesh.type} {mesh.name!r}, which "
                            "is opaque from its front (local +Z) side only: from behind, the camera would see "
                            "through it and the ground truth would mark what lies beyond as visible; move the "
                            "camera to its front side (above the ground: z > 0), or turn the plane with "
                            f"rotation_deg, or use a thin box, which is opaque from both sides; got {shown}",
                        )
                    )
            elif _inside(_local(position_m, mesh), mesh):
                notes.append(
                    Problem(
                        key,
                        f"puts camera {camera.name!r} inside the closed {mesh.type} {mesh.name!r} (got {shown}): "
                        f"the {mesh.type}'s faces point outward and are not drawn from inside, so the camera sees "
                        "through it as if it were not there; right for a housing around the camera, otherwise "
                        "move the camera out (a room around a camera is modelled with planes facing inward)",
                    )
                )
    return errors, notes


def warn_about(problems: list[Problem]) -> None:
    """Issue each problem as a `ConfigWarning` (the CLI prints them like errors, marked as warnings)."""
    for problem in problems:
        warnings.warn(ConfigWarning(problem), stacklevel=3)
