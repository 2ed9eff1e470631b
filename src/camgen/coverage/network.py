"""Coverage of every camera on a plane, and the network's figures: area at each DORI class, by how many
cameras (overlap for hand-off), blind spots, and the regions of interest."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from camgen.config.scene import Region
from camgen.coverage.density import centred_densities, densities, in_image
from camgen.coverage.dori import DORI_CLASSES, DORI_THRESHOLDS_PX_M, NOT_SEEN, class_index, class_name, dori_class
from camgen.coverage.grid import Grid
from camgen.coverage.occlusion import Occluder, inside_solids, on_ground, sight_blocked
from camgen.coverage.views import CameraView, EptzReach, PtzReach

BLIND_SPOTS_LISTED = 10
"""The largest blind spots are listed in the report."""


@dataclass(frozen=True)
class CameraCoverage:
    """One camera's view of a plane; arrays are (ny, nx), densities NaN where the point is not seen."""

    name: str
    uv_px: np.ndarray
    """(ny, nx, 2) distorted pixel position of each point (NaN where not imaged)."""
    in_view: np.ndarray
    """The point's distorted projection lands inside the image."""
    visible: np.ndarray
    """In view and not hidden by a mesh."""
    ground_px_m: np.ndarray
    vertical_px_m: np.ndarray
    across_px_m: np.ndarray
    person_px_m: np.ndarray
    dori: np.ndarray
    """int8 class index (0 below detect or not seen … 4 identify)."""


PTZ_REACH_RULE = (
    "a point is reached when the head can centre it (pan and tilt within range) and no mesh hides it; wide is "
    "the lens at 1×, tele at zoom_max_x, both with the point at the image centre"
)
EPTZ_REACH_RULE = (
    "virtual PTZ: a point is reached when the sensor images it and no mesh hides it (some window holds it); "
    "wide is the stream at zoom 1, tele at zoom_max_x: the sensor's px/m × stream width / window width, at "
    "most the sensor's own"
)


@dataclass(frozen=True)
class ReachCoverage:
    """Where a PTZ head can centre a point (unhidden), and the class it sees it at at wide and tele zoom."""

    name: str
    zoom_max_x: float
    reached: np.ndarray
    person_wide_px_m: np.ndarray
    person_tele_px_m: np.ndarray
    dori_wide: np.ndarray
    dori_tele: np.ndarray
    zoom_needed_x: np.ndarray
    """(4, ny, nx): the zoom each class needs there (threshold / density at wide, at least 1); NaN where
    the lens cannot reach it or the head cannot aim there."""
    rule: str = ""
    """How reached and the zooms are judged (the report's words)."""


@dataclass(frozen=True)
class PlaneCoverage:
    grid: Grid
    site: np.ndarray
    """(ny, nx) cells over a ground plane (every cell when the scene has none) and not inside a solid (a
    building's footprint): the area the figures count."""
    cameras: tuple[CameraCoverage, ...]
    reaches: tuple[ReachCoverage, ...]


def camera_coverage(grid: Grid, view: CameraView, occluders: Sequence[Occluder]) -> CameraCoverage:
    """`view`'s coverage of the grid: in view through the lens (distortion included), not occluded, densities."""
    points = grid.points_m()
    uv, dens = densities(points, grid.height_m, view)
    in_view = in_image(uv, view.width_px, view.height_px)
    visible = in_view.copy()
    visible[in_view] = ~sight_blocked(view.centre_m, points[in_view], occluders)
    shape = grid.shape

    def seen(values):
        return np.where(visible, values, np.nan).reshape(shape)

    person = seen(dens.person_px_m)
    return CameraCoverage(
        name=view.name,
        uv_px=uv.reshape(*shape, 2),
        in_view=in_view.reshape(shape),
        visible=visible.reshape(shape),
        ground_px_m=seen(dens.ground_px_m),
        vertical_px_m=seen(dens.vertical_px_m),
        across_px_m=seen(dens.across_px_m),
        person_px_m=person,
        dori=dori_class(person),
    )


def reach_coverage(grid: Grid, reach: PtzReach, occluders: Sequence[Occluder]) -> ReachCoverage:
    """Where the PTZ head reaches on the grid: aimable and unhidden; densities at wide (1×) and tele."""
    points = grid.points_m()
    ok, wide = centred_densities(points, grid.height_m, reach, 1.0)
    ok[ok] = ~sight_blocked(reach.position_m, points[ok], occluders)
    shape = grid.shape
    person_wide = np.where(ok, wide.person_px_m, np.nan)
    person_tele = person_wide * reach.zoom_max_x
    with np.errstate(invalid="ignore", divide="ignore"):
        needed = np.maximum(np.array(DORI_THRESHOLDS_PX_M)[:, None] / person_wide[None], 1.0)
    needed = np.where(needed <= reach.zoom_max_x * (1 + 1e-12), needed, np.nan)
    return ReachCoverage(
        name=reach.name,
        zoom_max_x=reach.zoom_max_x,
        reached=ok.reshape(shape),
        person_wide_px_m=person_wide.reshape(shape),
        person_tele_px_m=person_tele.reshape(shape),
        dori_wide=dori_class(person_wide).reshape(shape),
        dori_tele=dori_class(person_tele).reshape(shape),
        zoom_needed_x=needed.reshape(len(DORI_CLASSES), *shape),
        rule=PTZ_REACH_RULE,
    )


def eptz_reach_coverage(grid: Grid, reach: EptzReach, occluders: Sequence[Occluder]) -> ReachCoverage:
    """Where a virtual PTZ reaches on the grid: every point its sensor sees, unhidden; the stream's
    densities there at zoom 1 (wide) and zoom_max_x (tele), and the digital zoom each class needs (none
    where even the sensor's own px/m fall short: zooming further only interpolates)."""
    sensor = camera_coverage(grid, reach.sensor, occluders)
    native = sensor.person_px_m.ravel()
    person_wide = native * reach.detail_scale(1.0)
    person_tele = native * reach.detail_scale(reach.zoom_max_x)
    thresholds = np.array(DORI_THRESHOLDS_PX_M)[:, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        needed = np.maximum(thresholds * reach.full_window_width_px / (reach.output_width_px * native[None]), 1.0)
        needed = np.where((native[None] >= thresholds) & (needed <= reach.zoom_max_x * (1 + 1e-12)), needed, np.nan)
    shape = grid.shape
    return ReachCoverage(
        name=reach.name,
        zoom_max_x=reach.zoom_max_x,
        reached=sensor.visible,
        person_wide_px_m=person_wide.reshape(shape),
        person_tele_px_m=person_tele.reshape(shape),
        dori_wide=dori_class(person_wide).reshape(shape),
        dori_tele=dori_class(person_tele).reshape(shape),
        zoom_needed_x=needed.reshape(len(DORI_CLASSES), *shape),
        rule=EPTZ_REACH_RULE,
    )


def plane_coverage(
    grid: Grid,
    views: Sequence[CameraView],
    reaches: Sequence[PtzReach | EptzReach],
    occluders: Sequence[Occluder],
) -> PlaneCoverage:
    """Every camera's coverage of one plane, and (for PTZ heads, mechanical or virtual) its reach."""
    points = grid.points_m()
    ground = on_ground(points, occluders)
    site = ~inside_solids(points, occluders) & (True if ground is None else ground)
    site = site.reshape(grid.shape)
    return PlaneCoverage(
        grid=grid,
        site=site,
        cameras=tuple(camera_coverage(grid, view, occluders) for view in views),
        reaches=tuple(
            eptz_reach_coverage(grid, reach, occluders)
            if isinstance(reach, EptzReach)
            else reach_coverage(grid, reach, occluders)
            for reach in reaches
        ),
    )


def _components(mask: np.ndarray, grid: Grid) -> list[dict]:
    """Connected areas (8-neighbour) of a mask, largest first: area and centroid."""
    labels, count = ndimage.label(mask, structure=np.ones((3, 3)))
    if count == 0:
        return []
    index = np.arange(1, count + 1)
    cells = ndimage.sum(mask, labels, index)
    centres = ndimage.center_of_mass(mask, labels, index)
    order = np.argsort(-cells)[:BLIND_SPOTS_LISTED]
    step = grid.cell_m
    return [
        {
            "area_m2": float(cells[k] * grid.cell_area_m2),
            "centroid_m": [
                round(float(grid.x_m[0] + centres[k][1] * step), 3),
                round(float(grid.y_m[0] + centres[k][0] * step), 3),
            ],
        }
        for k in order
    ]


def network_figures(classes: np.ndarray, visible: np.ndarray, site: np.ndarray, grid: Grid) -> dict:
    """Area at each class (at least that class), by how many cameras reach it, overlap for hand-off and
    blind spots.

    Parameters
    ----------
    classes : (cameras, ny, nx) int8
        Each camera's DORI class index at each cell.
    visible : (cameras, ny, nx) bool
        Each camera sees the cell (in view, not hidden), at any density.
    site : (ny, nx) bool
        The cells that count (inside the site, outside solids).
    """
    area = grid.cell_area_m2
    best = classes.max(axis=0, initial=NOT_SEEN) if len(classes) else np.zeros(grid.shape, np.int8)
    site_m2 = float(site.sum() * area)
    by_class, by_cameras = {}, {}
    for k, name in enumerate(DORI_CLASSES, 1):
        count = (classes >= k).sum(axis=0) if len(classes) else np.zeros(grid.shape, int)
        at_least = site & (best >= k)
        by_class[name] = {"area_m2": float(at_least.sum() * area), "share": _share(at_least.sum(), site.sum())}
        by_cameras[name] = {
            label: float((site & selector(count)).sum() * area)
            for label, selector in (
                ("0", lambda c: c == 0),
                ("1", lambda c: c == 1),
                ("2", lambda c: c == 2),
                ("3+", lambda c: c >= 3),
            )
        }
    detect_count = (classes >= 1).sum(axis=0) if len(classes) else np.zeros(grid.shape, int)
    detected = site & (detect_count >= 1)
    handoff = site & (detect_count >= 2)
    seen_any = visible.any(axis=0) if len(visible) else np.zeros(grid.shape, bool)
    blind = site & (best == NOT_SEEN)
    return {
        "site_area_m2": site_m2,
        "area_at_least_class": by_class,
        "area_by_camera_count_m2": by_cameras,
        "handoff_overlap": {
            "area_m2": float(handoff.sum() * area),
            "share_of_detected": _share(handoff.sum(), detected.sum()),
            "rule": "cells seen at detect class or better by at least 2 cameras",
        },
        "blind": {
            "area_m2": float(blind.sum() * area),
            "share": _share(blind.sum(), site.sum()),
            "unseen_area_m2": float((site & ~seen_any).sum() * area),
            "below_detect_area_m2": float((site & seen_any & (best == NOT_SEEN)).sum() * area),
            "rule": "cells no camera sees at detect class or better",
            "largest": _components(blind, grid),
        },
    }


def _share(part, whole) -> float | None:
    return float(part) / float(whole) if whole else None


def region_figures(
    regions: Sequence[Region], masks: Sequence[np.ndarray], classes: np.ndarray, site: np.ndarray, grid: Grid, names
) -> list[dict]:
    """Per region: its area, the best class reached in it, the share of it meeting its required class and
    the share seen so by two cameras (hand-off), and which cameras reach the class there."""
    best = classes.max(axis=0, initial=NOT_SEEN) if len(classes) else np.zeros(grid.shape, np.int8)
    out = []
    for region, mask in zip(regions, masks, strict=True):
        cells = mask & site
        required = class_index(region.required_class)
        meeting = cells & (best >= required)
        count = (classes >= required).sum(axis=0) if len(classes) else np.zeros(grid.shape, int)
        out.append(
            {
                "name": region.name,
                "required_class": region.required_class,
                "area_m2": float(cells.sum() * grid.cell_area_m2),
                "best_class": class_name(int(best[cells].max(initial=NOT_SEEN))),
                "share_meeting_required": _share(meeting.sum(), cells.sum()),
                "share_handoff_at_required": _share((cells & (count >= 2)).sum(), cells.sum()),
                "cameras_reaching_required": [
                    name for name, c in zip(names, classes, strict=True) if bool((cells & (c >= required)).any())
                ],
            }
        )
    return out


def camera_figures(coverage: CameraCoverage, site: np.ndarray, grid: Grid) -> dict:
    """One camera's area in view, visible, at each class, and its density range."""
    area = grid.cell_area_m2
    seen = coverage.visible & site
    person = coverage.person_px_m[seen]
    return {
        "in_view_area_m2": float((coverage.in_view & site).sum() * area),
        "visible_area_m2": float(seen.sum() * area),
        "occluded_area_m2": float((coverage.in_view & ~coverage.visible & site).sum() * area),
        "area_at_least_class_m2": {
            name: float((seen & (coverage.dori >= k)).sum() * area) for k, name in enumerate(DORI_CLASSES, 1)
        },
        "person_density_px_m": _range(person),
        "ground_density_px_m": _range(coverage.ground_px_m[seen]),
    }


def reach_figures(reach: ReachCoverage, site: np.ndarray, grid: Grid) -> dict:
    area = grid.cell_area_m2
    cells = reach.reached & site
    return {
        "zoom_max_x": reach.zoom_max_x,
        "reached_area_m2": float(cells.sum() * area),
        "area_at_least_class_m2": {
            zoom: {name: float((cells & (dori >= k)).sum() * area) for k, name in enumerate(DORI_CLASSES, 1)}
            for zoom, dori in (("wide", reach.dori_wide), ("tele", reach.dori_tele))
        },
        "rule": reach.rule,
    }


def _range(values: np.ndarray) -> dict | None:
    values = values[np.isfinite(values)]
    if not values.size:
        return None
    return {
        "min": round(float(values.min()), 3),
        "median": round(float(np.median(values)), 3),
        "max": round(float(values.max()), 3),
    }
