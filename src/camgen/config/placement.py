"""Where meshes and cameras stand: a mesh's bounds in its own frame, its placement in the world and the
corners of a placed box (`local_bounds`, `placement`, `box_corners`; plan and render use them too), and
checks of each camera's position against the meshes that no pixel can make up for.

The renderer draws a mesh's front faces only (back-face culling, `render.scene_graph._material`). A plane
or checkerboard is one-sided: seen from behind it vanishes, so a camera under the ground would film the
actors' undersides through the ground and the ground truth would mark them visible. Such a camera is
refused. A camera inside a closed solid (box, cylinder, sphere) sees through it, since the solid's faces
point outward and are culled from inside: right for a housing modelled around the camera, wrong for a
camera placed in a wall by mistake or a room modelled as a box, so it is a warning, not an error.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping

import numpy as np

from camgen.config.scene import BoxMesh, CheckerboardMesh, CylinderMesh, FileMesh, PlaneMesh, Scene, SphereMesh
from camgen.errors import ConfigError, ConfigWarning, Problem
from camgen.motion.pose import T_world_from_cam, rotation_xyz_deg

BEHIND_TOLERANCE_M = 1e-6
"""A camera this close to a plane counts as on it, not behind it (float round-off of the placement)."""


Bounds = tuple[np.ndarray, np.ndarray]


def local_bounds(shape, file_bounds: Mapping[str, Bounds] | None = None) -> Bounds:
    """Axis-aligned bounds of a mesh in its own frame, before its placement."""
    if isinstance(shape, BoxMesh):
        half = np.array(shape.size_m) / 2
        return -half, half
    if isinstance(shape, CylinderMesh):
        half = np.array([shape.radius_m, shape.radius_m, shape.height_m / 2])
        return -half, half
    if isinstance(shape, SphereMesh):
        return -np.full(3, shape.radius_m), np.full(3, shape.radius_m)
    if isinstance(shape, PlaneMesh):
        half = np.array([shape.size_m[0] / 2, shape.size_m[1] / 2, 0.0])
        return -half, half
    if isinstance(shape, CheckerboardMesh):
        border = shape.border_width_m
        half = np.array([s * shape.square_size_m / 2 + border for s in shape.squares] + [0.0])
        return -half, half
    if isinstance(shape, FileMesh):
        if not file_bounds or shape.path not in file_bounds:
            raise ConfigError(f"the bounds of mesh file {shape.path!r} were not loaded; use camgen.config.load_scene")
        low, high = file_bounds[shape.path]
        return np.asarray(low) * shape.scale, np.asarray(high) * shape.scale
    raise TypeError(f"unknown shape {type(shape).__name__}")


def placement(shape) -> np.ndarray:
    """T_world_from_mesh of a placed shape (rotation about X, Y, Z, then the offset)."""
    return T_world_from_cam(shape.position_m, rotation_xyz_deg(shape.rotation_deg))


def is_level_plane(mesh) -> bool:
    """Whether `mesh` is a plane lying level and facing up: its rotation keeps local +Z on world +Z (a turn about
    Z only)."""
    if not isinstance(mesh, PlaneMesh):
        return False
    rx, ry, _ = (math.remainder(angle, 360.0) for angle in mesh.rotation_deg)
    return abs(rx) < 1e-6 and abs(ry) < 1e-6


def largest_level_plane(meshes, min_area_m2: float = 0.0) -> PlaneMesh | None:
    """The largest of `meshes` that `is_level_plane` and covers at least `min_area_m2`, or None."""
    level = [m for m in meshes if is_level_plane(m) and m.size_m[0] * m.size_m[1] >= min_area_m2]
    return max(level, key=lambda mesh: mesh.size_m[0] * mesh.size_m[1], default=None)


def box_corners(low: np.ndarray, high: np.ndarray, T_world_from_local: np.ndarray) -> np.ndarray:
    """The 8 world-frame corners (8, 3) of an axis-aligned local box."""
    i = np.arange(8)
    local = np.stack(
        [
            np.where(i & 1, high[0], low[0]),
            np.where(i >> 1 & 1, high[1], low[1]),
            np.where(i >> 2 & 1, high[2], low[2]),
        ],
        axis=-1,
    )
    return local @ T_world_from_local[:3, :3].T + T_world_from_local[:3, 3]


def _local(position_m, mesh) -> np.ndarray:
    """A world point in the mesh's own frame (before its placement)."""
    T_world_from_mesh = placement(mesh)
    return T_world_from_mesh[:3, :3].T @ (np.asarray(position_m, dtype=np.float64) - T_world_from_mesh[:3, 3])


def _inside(local_m: np.ndarray, mesh) -> bool:
    x, y, z = local_m
    if isinstance(mesh, BoxMesh):
        return bool(np.all(np.abs(local_m) < local_bounds(mesh)[1]))
    if isinstance(mesh, CylinderMesh):
        return x * x + y * y < mesh.radius_m**2 and abs(z) < mesh.height_m / 2
    if isinstance(mesh, SphereMesh):
        return float(local_m @ local_m) < mesh.radius_m**2
    return False


def cameras_behind_planes(scene: Scene) -> list[Problem]:
    """A camera behind a one-sided plane or checkerboard, within its outline: an error each (key paths from
    the scene)."""
    problems = []
    for i, camera in enumerate(scene.cameras):
        for mesh in scene.environment.meshes:
            if not isinstance(mesh, (PlaneMesh, CheckerboardMesh)):
                continue
            x, y, z = _local(camera.mount.position_m, mesh)
            half_x, half_y, _ = local_bounds(mesh)[1]
            if z < -BEHIND_TOLERANCE_M and abs(x) <= half_x and abs(y) <= half_y:
                problems.append(
                    Problem(
                        ("cameras", i, "mount", "position_m"),
                        f"puts camera {camera.name!r} {-z:.3g} m behind the {mesh.type} {mesh.name!r}, which "
                        "is opaque from its front (local +Z) side only: from behind, the camera would see "
                        "through it and the ground truth would mark what lies beyond as visible; move the "
                        "camera to its front side (above the ground: z > 0), or turn the plane with "
                        f"rotation_deg, or use a thin box, which is opaque from both sides; got "
                        f"{_shown(camera.mount.position_m)}",
                    )
                )
    return problems


def cameras_inside_solids(scene: Scene) -> list[Problem]:
    """A camera inside a box, cylinder or sphere: a warning each (key paths from the scene). Mesh files are
    not checked (whether one is closed is not known here)."""
    problems = []
    for i, camera in enumerate(scene.cameras):
        for mesh in scene.environment.meshes:
            if _inside(_local(camera.mount.position_m, mesh), mesh):
                problems.append(
                    Problem(
                        ("cameras", i, "mount", "position_m"),
                        f"puts camera {camera.name!r} inside the closed {mesh.type} {mesh.name!r} (got "
                        f"{_shown(camera.mount.position_m)}): the {mesh.type}'s faces point outward and are not "
                        "drawn from inside, so the camera sees through it as if it were not there; right for a "
                        "housing around the camera, otherwise move the camera out (a room around a camera is "
                        "modelled with planes facing inward)",
                    )
                )
    return problems


def _shown(position_m) -> str:
    return "[" + ", ".join(f"{v:g}" for v in position_m) + "]"


SKY_AMBIENT_RATIO_MAX = 3.0
"""How far the light a scene's ambient term gives may stray from what its visible sky sheds (`sky_light_problems`)
before a warning: the ambient term stands for the sky's light less what buildings and trees hide, plus the ground's
bounce, which can take it some way from the open sky's own; a factor of 3 between them is already a sky that shows
three times brighter than the light it gives, and no site does more than that by accident."""


def sky_light_problems(scene: Scene) -> list[Problem]:
    """A visible sky whose luminance and the ambient light that stands for its light on the scene disagree by more
    than `SKY_AMBIENT_RATIO_MAX`: a warning (key paths from the scene). The renderer shows the sky at its luminance
    (`environment.sky_luminance_cd_m2`, the zenith's of the CIE sky `environment.sky`) but lights the scene with the
    ambient light's illuminance; the sky sheds L_z·∫ ℓ cos Z dω on the ground (`camgen.world.daylight`). Far
    apart, people and vehicles lit by the ambient light film as silhouettes against the sky, or the sky as a dark
    backdrop to a bright street. A scene with `environment.site` takes both from one model and is not checked."""
    from camgen.config.scene import AmbientLight, SunLight
    from camgen.world.daylight import sky_horizontal_illuminance_from_zenith_lux

    environment = scene.environment
    if environment.site is not None or environment.sky_luminance_cd_m2 <= 0:
        return []
    ambient = [(i, light) for i, light in enumerate(scene.lights) if isinstance(light, AmbientLight)]
    suns = [light for light in scene.lights if isinstance(light, SunLight)]
    elevation_deg = suns[0].elevation_deg if suns else 45.0
    shed_lux = sky_horizontal_illuminance_from_zenith_lux(
        environment.sky_luminance_cd_m2, elevation_deg, environment.sky
    )
    given_lux = sum(light.illuminance_lux for _, light in ambient)
    if shed_lux <= 0 or (given_lux > 0 and 1 / SKY_AMBIENT_RATIO_MAX <= given_lux / shed_lux <= SKY_AMBIENT_RATIO_MAX):
        return []
    where = ("lights", ambient[0][0], "illuminance_lux") if ambient else ("environment", "sky_luminance_cd_m2")
    sky = f"a {environment.sky} sky" + (f", the sun at {elevation_deg:g}°" if environment.sky != "uniform" else "")
    given = f"the ambient light gives {_lux(given_lux)} lx" if ambient else "no ambient light gives any"
    zenith_for_given = environment.sky_luminance_cd_m2 * given_lux / shed_lux
    return [
        Problem(
            where,
            f"{given}, but the sky the frames show (environment.sky_luminance_cd_m2 "
            f"{environment.sky_luminance_cd_m2:g} cd/m², {sky}) sheds {_lux(shed_lux)} lx on the ground"
            + (f", {shed_lux / given_lux:.2g}× as much" if given_lux > 0 else "")
            + ": people and vehicles lit by the ambient light film as silhouettes against such a sky (or a dim sky "
            f"frames a bright street); give the ambient light about {_lux(shed_lux)} lx, or the sky about "
            f"{zenith_for_given:.3g} cd/m², or set environment.site, which takes both from one daylight model",
        )
    ]


def _lux(value: float) -> str:
    return f"{value:.3g}" if value < 1000 else f"{value:,.0f}"


def warn_about(problems: list[Problem]) -> None:
    """Issue each problem as a `ConfigWarning` (the CLI prints them like errors, marked as warnings)."""
    for problem in problems:
        warnings.warn(ConfigWarning(problem), stacklevel=3)
