"""Reflections in a wet road (`camgen.world.rain`: "Reflections in the wet road").

A wet scene's ground (`camgen.world.rain.ground_is_wet`: rain, or `environment.wet`) lies under a film of water that
mirrors what stands on it. The mirror image is drawn, not guessed from the frame: the scene seen by the
camera reflected in the ground's plane (its height h: `camgen.world.rain.wet_ground_height_m`, the largest level
plane facing up; `mirrored_view`: the pose times the reflection z → 2h − z, an improper pose, which the
renderer draws with its triangles' winding reversed), leaving out what lies flat
on the ground (the road and its markings, which would hide everything under the mirror), with the sky and
the fog of the reflected rays. A pixel of the frame that shows the wet ground (`wet_pixels`: its point
within `WET_SURFACE_TOLERANCE_M` of the ground's height, or the ground continued to the horizon) then
takes (1 − F)·L + F·R: L what the draw shaded there, R the mirror image at that pixel spread by the film's
ripples (`film_blur`: one Gaussian over the frame, its width across taken at the wet pixels' median angle of
incidence), F the water's Fresnel reflectance at the pixel's angle of incidence
(`camgen.world.rain.water_fresnel`). A planar mirror seen through the camera's own pixels needs no
search: the reflected ray through pixel u of the mirrored view is the camera's ray through u after the
bounce, so R at u is what u reflects.

The film's spread is applied on a grid coarser than the frame, a sample every `mirror_step_px` pixels each way
(a fraction of the spread, which blurs finer detail away); each sample is the mean of the mirror drawn at
the frame's pixels over its block (`block_view`, `block_means`), not the mirror seen through the block's
middle alone, which would catch a small bright object (a lamp, a headlight, a lit window) whole or miss it:
its reflection came out up to 1.8 times too bright, or not at all, and flickered as it moved. The mirror is
drawn at the frame time (no motion blur of its own: the spread is wider than a sub-frame's smear), with shadow
maps fitted to the frame's view (`ShadowFit`; the same cascades as the frame's where the mirrored camera's far
plane is the frame's, as in the examples, where the farthest point the scene reaches lies on the ground).
Not modelled: the IR illuminator's light in the mirror (night mode), puddles (the film covers the ground
evenly), reflections in wet walls, cars or glass.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from camgen.config.placement import box_corners
from camgen.render.renderer import View
from camgen.world.rain import WATER_FILM_SLOPE_RAD, water_fresnel

WET_SURFACE_TOLERANCE_M = 0.03
"""A pixel whose point lies within this height of the wet ground takes its reflection: the road planes a
few mm over the ground (an intersection's roads at 10 and 11 mm), paint on them, and the lowest 3 cm of a
tyre, whose mirror image is its own continuation."""
MIRROR_SAMPLES_PER_SIGMA = 3.0
"""The film's spread is applied on a grid of this many samples per standard deviation of it (each way; at
least one a pixel), each sample its block's mean (`block_means`): the Gaussian then varies little between
samples (< 6 % of its peak), so the spread mirror is the same as one spread at every pixel to within that."""


def mirrored_view(view: View, height_m: float) -> View:
    """`view` reflected in the level plane z = `height_m`: the camera under the ground, looking up at
    the mirror image; its pixel u sees along the camera's ray through u after the bounce. Its pose is
    improper (determinant −1)."""
    reflection = np.diag([1.0, 1.0, -1.0, 1.0])
    reflection[2, 3] = 2.0 * height_m
    return View(view.K_px, reflection @ view.T_world_from_cam, view.width_px, view.height_px)


@dataclass(frozen=True)
class WetViewGeometry:
    """What the reflection of a view depends on besides its frame (kept while the view holds)."""

    key: tuple
    """`View.key` of the view."""
    rise_per_m: np.ndarray
    """(H, W) float32: the world z the ray through each pixel rises per metre of camera z."""
    fresnel: np.ndarray
    """(H, W) float32: the water's reflectance at each pixel's angle of incidence on the ground."""
    cos_incidence: np.ndarray
    """(H, W) float32: cos θᵢ of each pixel's ray against the ground's normal (+z)."""


def view_geometry(view: View) -> WetViewGeometry:
    """Each pixel's ray's rise, angle of incidence on level ground and water reflectance there."""
    K_inv = np.linalg.inv(view.K_px)
    R = view.T_world_from_cam[:3, :3] @ K_inv
    u = np.arange(view.width_px, dtype=np.float64)[None, :]
    v = np.arange(view.height_px, dtype=np.float64)[:, None]
    x = R[0, 0] * u + (R[0, 1] * v + R[0, 2])
    y = R[1, 0] * u + (R[1, 1] * v + R[1, 2])
    z = R[2, 0] * u + (R[2, 1] * v + R[2, 2])
    cos_incidence = np.abs(z) / np.sqrt(x * x + y * y + z * z)
    return WetViewGeometry(
        view.key(),
        z.astype(np.float32),
        water_fresnel(cos_incidence).astype(np.float32),
        cos_incidence.astype(np.float32),
    )


def wet_pixels(
    view: View, depth_m: np.ndarray, height_m: float, far_ground_m: float | None, rise_per_m: np.ndarray | None = None
) -> np.ndarray:
    """(H, W) bool: the pixels that show the wet ground: a surface point within `WET_SURFACE_TOLERANCE_M` of
    `height_m` (from the camera-z `depth_m`), or no surface (+inf) along a ray going down where the ground
    continues to the horizon at `far_ground_m` (None: it does not). `rise_per_m`: `view_geometry`'s."""
    rise = view_geometry(view).rise_per_m if rise_per_m is None else rise_per_m
    camera_z_m = float(view.T_world_from_cam[2, 3])
    finite = np.isfinite(depth_m)
    with np.errstate(invalid="ignore"):
        offset_m = np.abs(depth_m * rise + np.float32(camera_z_m - height_m))
    wet = finite & (offset_m <= WET_SURFACE_TOLERANCE_M)
    if far_ground_m is not None and camera_z_m > far_ground_m:
        wet |= ~finite & (rise < 0)
    return wet


def film_spread_px(view: View, cos_incidence: float) -> tuple[float, float]:
    """(σ across, σ up and down) in pixels of the film's spread of a reflection seen at θᵢ: the reflected ray
    turns by 2δ for a tilt δ in the plane of incidence and by 2δ·cos θᵢ for one across it
    (`camgen.world.rain.WATER_FILM_SLOPE_RAD`), through the view's focal lengths."""
    spread_rad = 2.0 * WATER_FILM_SLOPE_RAD
    return float(view.K_px[0, 0] * spread_rad * cos_incidence), float(view.K_px[1, 1] * spread_rad)


def mirror_step_px(sigma_px: float) -> int:
    """Pixels of the frame per sample of the mirror on an axis whose spread is `sigma_px`."""
    return max(1, int(sigma_px / MIRROR_SAMPLES_PER_SIGMA))


def coarse_view(view: View, step_x_px: int, step_y_px: int) -> View:
    """`view` sampled every `step_x_px` × `step_y_px` of its pixels: sample (i, j) sees what the pixel at
    (i·step_x + (step_x − 1)/2, j·step_y + (step_y − 1)/2) sees (the middle of its block), the size rounded
    up so that the samples cover the view."""
    K = view.K_px.astype(np.float64).copy()
    K[0, :] /= step_x_px
    K[1, :] /= step_y_px
    K[0, 2] -= (step_x_px - 1) / (2.0 * step_x_px)
    K[1, 2] -= (step_y_px - 1) / (2.0 * step_y_px)
    K[2] = (0.0, 0.0, 1.0)
    width = -(-view.width_px // step_x_px)
    height = -(-view.height_px // step_y_px)
    return View(K, view.T_world_from_cam, width, height)


def block_view(view: View, step_x_px: int, step_y_px: int) -> View:
    """`view` grown at its right and bottom edges to whole blocks of `step_x_px` × `step_y_px` pixels (its own
    pixels where they were): block (i, j) holds the pixels whose middle `coarse_view`'s sample (i, j) sees."""
    coarse = coarse_view(view, step_x_px, step_y_px)
    return View(view.K_px, view.T_world_from_cam, coarse.width_px * step_x_px, coarse.height_px * step_y_px)


def block_means(image: np.ndarray, step_x_px: int, step_y_px: int) -> np.ndarray:
    """(h, w, 3) float32: the mean of each `step_x_px` × `step_y_px` block of `image` ((h·step_y, w·step_x, 3),
    `block_view`'s draw): the light over each sample's block of pixels, whose middle is the sample's
    (`coarse_view`)."""
    height, width = image.shape[0] // step_y_px, image.shape[1] // step_x_px
    if (step_x_px, step_y_px) == (1, 1):
        return np.ascontiguousarray(image, np.float32)
    # OpenCV's area resampling by whole factors: each output the mean of its block.
    return cv2.resize(np.ascontiguousarray(image, np.float32), (width, height), interpolation=cv2.INTER_AREA)


def film_blur(
    coarse: np.ndarray, steps_px: tuple[int, int], sigmas_px: tuple[float, float], size: tuple[int, int]
) -> np.ndarray:
    """The coarse mirror (h, w, 3; a sample every `steps_px` (x, y) pixels of the frame, `block_means`) spread by
    the film's Gaussian of `sigmas_px` (across, up and down; frame pixels) and brought to the frame's `size` (W, H)
    by bilinear interpolation between the samples' centres (edges held)."""
    step_x, step_y = steps_px
    sigma_x, sigma_y = sigmas_px[0] / step_x, sigmas_px[1] / step_y
    blurred = coarse
    if sigma_x > 0.05 or sigma_y > 0.05:
        blurred = cv2.GaussianBlur(
            np.ascontiguousarray(coarse, np.float32),
            (0, 0),
            sigmaX=max(sigma_x, 0.05),
            sigmaY=max(sigma_y, 0.05),
            borderType=cv2.BORDER_REPLICATE,
        )
    width, height = size
    if (step_x, step_y) == (1, 1):
        return np.ascontiguousarray(blurred[:height, :width], np.float32)
    # frame pixel u lies at sample coordinate (u − (step − 1)/2) / step (`coarse_view`)
    map_x = ((np.arange(width, dtype=np.float32) - (step_x - 1) / 2.0) / step_x)[None, :].repeat(height, 0)
    map_y = ((np.arange(height, dtype=np.float32) - (step_y - 1) / 2.0) / step_y)[:, None].repeat(width, 1)
    return cv2.remap(
        np.ascontiguousarray(blurred, np.float32), map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
    )


def flat_nodes(graph, height_m: float) -> set[int]:
    """id() of the environment nodes lying flat on the wet ground (their world box no higher than
    `WET_SURFACE_TOLERANCE_M` over it): the road and its paint, left out of the mirror."""
    scene = graph.scene
    flat = set()
    for node in graph.environment_nodes:
        corners = box_corners(*node.mesh.bounds, scene.get_pose(node))
        if corners[:, 2].max() <= height_m + WET_SURFACE_TOLERANCE_M:
            flat.add(id(node))
    return flat


def reflected_radiance(radiance: np.ndarray, mirror: np.ndarray, wet: np.ndarray, fresnel: np.ndarray) -> np.ndarray:
    """`radiance` (H, W, 3) with the film's reflection at the `wet` pixels: (1 − F)·L + F·R = L + F·(R − L),
    F the water's reflectance there (`fresnel`, (H, W)), R the spread `mirror` (H, W, 3)."""
    weight = np.where(wet, fresnel, np.float32(0.0))[..., None]
    return radiance + weight * (mirror - radiance)
