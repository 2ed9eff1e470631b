"""A scene's coverage: every plane, every camera, the network's and the regions' figures, as a JSON
report and plain arrays (`camgen coverage` writes them)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from camgen.config.profile import Profile
from camgen.config.scene import Scene
from camgen.coverage.density import PERSON_HEIGHT_M
from camgen.coverage.dori import DORI_CLASSES, DORI_THRESHOLDS_PX_M
from camgen.coverage.grid import make_grid, region_masks, region_problems, site_extent_m
from camgen.coverage.network import (
    PlaneCoverage,
    camera_figures,
    network_figures,
    plane_coverage,
    reach_figures,
    region_figures,
)
from camgen.coverage.occlusion import Occluder, scene_occluders
from camgen.coverage.views import CameraView, eptz_reach, home_view, ptz_reach
from camgen.errors import ConfigError, Problem

FACE_HEIGHT_M = 1.6


@dataclass(frozen=True)
class SceneCoverage:
    scene: Scene
    views: tuple[CameraView, ...]
    occluders: tuple[Occluder, ...]
    extent_m: tuple[float, float, float, float]
    planes: tuple[PlaneCoverage, ...]
    region_masks: tuple[tuple[np.ndarray, ...], ...]
    """Per plane, per region: (ny, nx) cells inside the region."""
    ptz_reach: bool


def check_settings(cell_m: float, heights_m: Sequence[float]) -> None:
    """The grid's settings: a located error (naming the option) for each bad one."""
    problems = []
    if not cell_m > 0:
        problems.append(Problem(("--cell-m",), f"must be > 0 m, got {cell_m:g}; give the grid's cell size, e.g. 0.25"))
    for height in heights_m:
        if not 0 <= height <= 10:
            problems.append(Problem(("--height-m",), f"must be 0–10 m (the ground or a person's face), got {height:g}"))
    if problems:
        raise ConfigError(problems)


def scene_coverage(
    scene: Scene,
    profiles: Mapping[str, Profile],
    *,
    cell_m: float = 0.25,
    heights_m: Sequence[float] = (0.0,),
    with_ptz_reach: bool = False,
    file_bounds=None,
    file_triangles_m: Mapping[str, np.ndarray] | None = None,
) -> SceneCoverage:
    """Every camera's coverage of the scene's ground (and other planes), at its home view, and for PTZ
    heads with `with_ptz_reach` what the head reaches. Raises ConfigError for bad settings or regions
    (key paths from the scene, to be located by the caller)."""
    check_settings(cell_m, heights_m)
    extent = site_extent_m(scene, file_bounds)
    problems = region_problems(scene, extent)
    if problems:
        raise ConfigError(problems)
    views = tuple(home_view(camera, profiles[camera.name]) for camera in scene.cameras)
    reaches = (
        tuple(
            r
            for camera in scene.cameras
            if (r := ptz_reach(camera, profiles[camera.name]) or eptz_reach(camera, profiles[camera.name])) is not None
        )
        if with_ptz_reach
        else ()
    )
    occluders = tuple(scene_occluders(scene, file_triangles_m))
    planes, masks = [], []
    for height in dict.fromkeys(float(h) for h in heights_m):
        grid = make_grid(extent, cell_m, height)
        planes.append(plane_coverage(grid, views, reaches, occluders))
        masks.append(tuple(region_masks(scene, grid)))
    return SceneCoverage(scene, views, occluders, extent, tuple(planes), tuple(masks), with_ptz_reach)


def _stack(arrays, shape, dtype):
    return np.stack(arrays).astype(dtype) if arrays else np.zeros((0, *shape), dtype)


def classes_with_reach(plane: PlaneCoverage, zoom: str) -> np.ndarray:
    """Each camera's class, a PTZ head's raised to what it reaches at `zoom` (wide or tele) aimed there."""
    reach = {r.name: r for r in plane.reaches}
    return _stack(
        [
            np.maximum(c.dori, getattr(reach[c.name], f"dori_{zoom}")) if c.name in reach else c.dori
            for c in plane.cameras
        ],
        plane.grid.shape,
        np.int8,
    )


def report(coverage: SceneCoverage, scene_name: str) -> dict:
    """The JSON report."""
    scene = coverage.scene
    names = [v.name for v in coverage.views]
    planes = []
    for plane, masks in zip(coverage.planes, coverage.region_masks, strict=True):
        grid = plane.grid
        classes = _stack([c.dori for c in plane.cameras], grid.shape, np.int8)
        visible = _stack([c.visible for c in plane.cameras], grid.shape, bool)
        entry = {
            "height_m": grid.height_m,
            "cells": list(grid.shape),
            "network": network_figures(classes, visible, plane.site, grid),
            "regions": region_figures(scene.regions, masks, classes, plane.site, grid, names),
            "cameras": {c.name: camera_figures(c, plane.site, grid) for c in plane.cameras},
        }
        if coverage.ptz_reach:
            entry["ptz_reach"] = {r.name: reach_figures(r, plane.site, grid) for r in plane.reaches}
            entry["network_with_ptz_reach"] = {}
            for zoom in ("wide", "tele"):
                reach_classes = classes_with_reach(plane, zoom)
                entry["network_with_ptz_reach"][zoom] = {
                    "network": network_figures(reach_classes, visible, plane.site, grid),
                    "regions": region_figures(scene.regions, masks, reach_classes, plane.site, grid, names),
                }
        planes.append(entry)
    return {
        "scene": scene_name,
        "cell_m": coverage.planes[0].grid.cell_m,
        "extent_m": {"x": list(coverage.extent_m[:2]), "y": list(coverage.extent_m[2:])},
        "dori": {
            "standard": "IEC 62676-4:2014",
            "thresholds_px_m": dict(zip(DORI_CLASSES, DORI_THRESHOLDS_PX_M, strict=True)),
            "density_rule": f"min(vertical, across) px/m on a standing {PERSON_HEIGHT_M:g} m person (Jacobian "
            "of the distorted projection; see camgen.coverage.density)",
        },
        "cameras": [
            {
                "name": v.name,
                "position_m": [round(float(x), 4) for x in v.centre_m],
                "focal_length_mm": v.focal_length_mm,
                "image_px": [v.width_px, v.height_px],
                "view": "home (ptz pan/tilt/zoom)" if c.ptz is not None else "installed",
            }
            for v, c in zip(coverage.views, scene.cameras, strict=True)
        ],
        "planes": planes,
    }


def arrays(coverage: SceneCoverage) -> dict[str, np.ndarray]:
    """Plain arrays for `coverage.npz` (no objects: `numpy.load` reads them without pickle)."""
    out: dict[str, np.ndarray] = {
        "camera_names": np.array([v.name for v in coverage.views], dtype=str),
        "dori_classes": np.array(DORI_CLASSES, dtype=str),
        "dori_thresholds_px_m": np.array(DORI_THRESHOLDS_PX_M),
        "plane_heights_m": np.array([p.grid.height_m for p in coverage.planes]),
    }
    for k, plane in enumerate(coverage.planes):
        grid, cams, prefix = plane.grid, plane.cameras, f"plane{k}_"
        classes = _stack([c.dori for c in cams], grid.shape, np.int8)
        out |= {
            prefix + "x_m": grid.x_m,
            prefix + "y_m": grid.y_m,
            prefix + "site": plane.site,
            prefix + "visible": _stack([c.visible for c in cams], grid.shape, bool),
            prefix + "person_px_m": _stack([c.person_px_m for c in cams], grid.shape, np.float32),
            prefix + "ground_px_m": _stack([c.ground_px_m for c in cams], grid.shape, np.float32),
            prefix + "vertical_px_m": _stack([c.vertical_px_m for c in cams], grid.shape, np.float32),
            prefix + "dori": classes,
            prefix + "best_dori": classes.max(axis=0, initial=0),
            prefix + "camera_count_at_least": np.stack(
                [(classes >= i).sum(axis=0) for i in range(1, len(DORI_CLASSES) + 1)]
            ).astype(np.int16),
        }
        if coverage.ptz_reach:
            reaches = plane.reaches
            out |= {
                prefix + "reach_names": np.array([r.name for r in reaches], dtype=str),
                prefix + "reach_reached": _stack([r.reached for r in reaches], grid.shape, bool),
                prefix + "reach_dori_wide": _stack([r.dori_wide for r in reaches], grid.shape, np.int8),
                prefix + "reach_dori_tele": _stack([r.dori_tele for r in reaches], grid.shape, np.int8),
                prefix + "reach_zoom_needed_x": _stack(
                    [r.zoom_needed_x for r in reaches], (len(DORI_CLASSES), *grid.shape), np.float32
                ),
            }
    return out
