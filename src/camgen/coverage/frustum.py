"""What a camera's image covers: the footprint of its frame on a plane (for the site plan), and the
pixel density over its image plane (rays from pixels through the inverse lens model to the ground)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from camgen.coverage.density import densities
from camgen.coverage.occlusion import Occluder, sight_blocked
from camgen.coverage.views import CameraView
from camgen.optics.projection import undistort_points

FOOTPRINT_POINTS_PER_EDGE = 24


def frame_outline_px(width_px: int, height_px: int, per_edge: int = FOOTPRINT_POINTS_PER_EDGE) -> np.ndarray:
    """Points (4·per_edge, 2) around the image's outer pixel edges in order: top, right, bottom, left."""
    t = np.linspace(0.0, 1.0, per_edge, endpoint=False)
    right, bottom = width_px - 0.5, height_px - 0.5
    edges = [
        np.stack([-0.5 + t * width_px, np.full_like(t, -0.5)], -1),
        np.stack([np.full_like(t, right), -0.5 + t * height_px], -1),
        np.stack([right - t * width_px, np.full_like(t, bottom)], -1),
        np.stack([np.full_like(t, -0.5), bottom - t * height_px], -1),
    ]
    return np.concatenate(edges)


def pixel_rays_world(view: CameraView, pixels_px: np.ndarray) -> np.ndarray:
    """Unit world directions (N, 3) of the rays that land on distorted pixels (N, 2) (the lens inverted,
    `camgen.optics.projection.undistort_points`)."""
    K = view.K_px
    pinhole = undistort_points(pixels_px, K, view.distortion)
    x = (pinhole[:, 0] - K[0, 2] - K[0, 1] * (pinhole[:, 1] - K[1, 2]) / K[1, 1]) / K[0, 0]
    y = (pinhole[:, 1] - K[1, 2]) / K[1, 1]
    cam = np.stack([x, y, np.ones_like(x)], -1)
    world = cam @ view.T_world_from_cam[:3, :3].T
    return world / np.linalg.norm(world, axis=1, keepdims=True)


def footprint_m(view: CameraView, plane_height_m: float, range_m: float) -> np.ndarray:
    """Outline (M, 2) of the image frame on the plane z = `plane_height_m`, x y in m: each border pixel's
    ray meets the plane, or, looking above it or farther than `range_m` (horizontally), stops at that range."""
    border = frame_outline_px(view.width_px, view.height_px)
    rays = pixel_rays_world(view, border)
    centre = view.centre_m
    horizontal = np.hypot(rays[:, 0], rays[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (plane_height_m - centre[2]) / rays[:, 2]
        s_range = range_m / horizontal
    s = np.where((s > 0) & np.isfinite(s), np.minimum(s, s_range), s_range)
    return centre[:2] + s[:, None] * rays[:, :2]


def image_plane_density(
    view: CameraView, occluders: Sequence[Occluder], plane_height_m: float, samples_across: int = 96
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Person density over the image: (u (nu,), v (nv,), density (nv, nu) px/m, hidden (nv, nu) bool).

    Each sampled pixel's ray meets the plane z = `plane_height_m`; the density is that of the point it
    meets (NaN where the ray never meets the plane); hidden marks rays that enter a mesh first."""
    u = np.linspace(-0.5, view.width_px - 0.5, samples_across)
    v = np.linspace(-0.5, view.height_px - 0.5, max(2, round(samples_across * view.height_px / view.width_px)))
    uu, vv = np.meshgrid(u, v)
    pixels = np.stack([uu.ravel(), vv.ravel()], -1)
    rays = pixel_rays_world(view, pixels)
    centre = view.centre_m
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (plane_height_m - centre[2]) / rays[:, 2]
    meets = np.isfinite(s) & (s > 0)
    points = centre + np.where(meets, s, 1.0)[:, None] * rays
    _, dens = densities(points, plane_height_m, view)
    person = np.where(meets, dens.person_px_m, np.nan)
    hidden = ~meets
    hidden[meets] = sight_blocked(centre, points[meets], occluders)
    return u, v, person.reshape(uu.shape), hidden.reshape(uu.shape)
