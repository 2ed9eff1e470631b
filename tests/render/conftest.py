"""Helpers for the rendering tests (their OpenGL context, `renderer`, is tests/conftest.py's)."""

from __future__ import annotations

import numpy as np

from camgen.config.scene import Scene


def scene_from(**document) -> Scene:
    """A Scene from keyword arguments, with one placeholder camera unless cameras are given."""
    document.setdefault("duration_s", 1.0)
    document.setdefault("cameras", [{"name": "cam", "profile": "unused", "mount": {"position_m": [0.0, 0.0, 1.0]}}])
    return Scene.model_validate(document)


def look_at(position_m, target_m) -> np.ndarray:
    """T_world_from_cam of an OpenCV camera at `position_m` looking at `target_m`, image up ≈ world +Z."""
    position, target = np.asarray(position_m, float), np.asarray(target_m, float)
    z = target - position
    z /= np.linalg.norm(z)
    x = np.cross(z, [0.0, 0.0, 1.0])
    if np.linalg.norm(x) < 1e-9:
        x = np.array([1.0, 0.0, 0.0])
    x /= np.linalg.norm(x)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    T[:3, 3] = position
    return T


def camera_matrix(fx: float, fy: float, cx: float, cy: float) -> np.ndarray:
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def lit_wall_radiance(
    renderer,
    texture: dict,
    size_m: tuple[float, float, float],
    sun_azimuth_deg: float,
    sun_elevation_deg: float,
    f_px: float,
    distance_m: float,
    relief: bool,
    size_px: tuple[int, int] = (640, 480),
):
    """The green radiance (float64) of a textured wall's +x face (a box 1 m thick standing on the ground, its face
    at x = 0.5, y across, z up; texture u = y + half its length, v = z) seen square-on from `distance_m` through a
    `f_px` pinhole at half its height, under a sun alone; without its normal map unless `relief`. Returns
    (radiance, View)."""
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph

    wall = {"type": "box", "name": "wall", "size_m": list(size_m), "position_m": [0, 0, size_m[2] / 2]}
    sun = {"type": "sun", "illuminance_lux": 50000, "azimuth_deg": sun_azimuth_deg, "elevation_deg": sun_elevation_deg}
    scene = scene_from(
        environment={"ground_to_horizon": False, "meshes": [{**wall, "material": {"texture": texture}}]}, lights=[sun]
    )
    graph = build_scene_graph(scene)
    if not relief:
        for primitive in graph.environment_nodes[0].mesh.primitives:
            primitive.material.normalTexture = None
    width, height = size_px
    middle = (0.5, 0.0, size_m[2] / 2)
    view = View(
        camera_matrix(f_px, f_px, (width - 1) / 2, (height - 1) / 2),
        look_at((0.5 + distance_m, 0.0, middle[2]), middle),
        width,
        height,
    )
    return renderer.draw(graph, view, ("radiance",)).radiance[..., 1].astype(np.float64), view
