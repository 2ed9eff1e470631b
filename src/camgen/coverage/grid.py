"""The ground grid coverage is computed on, the site it covers, and regions of interest on it."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from camgen.config.placement import box_corners, local_bounds, placement
from camgen.config.scene import FileMesh, Scene
from camgen.errors import ConfigError, Problem

MARGIN_WITHOUT_MESHES_M = 20.0
"""A scene without environment meshes is covered this far around its cameras, m."""


@dataclass(frozen=True)
class Grid:
    """Cell centres of a horizontal plane: x (nx,), y (ny,) m, at `height_m`; arrays are (ny, nx)."""

    x_m: np.ndarray
    y_m: np.ndarray
    cell_m: float
    height_m: float

    @property
    def shape(self) -> tuple[int, int]:
        return len(self.y_m), len(self.x_m)

    @property
    def cell_area_m2(self) -> float:
        return self.cell_m * self.cell_m

    def points_m(self) -> np.ndarray:
        """(ny·nx, 3) cell centres, row-major over (y, x)."""
        x, y = np.meshgrid(self.x_m, self.y_m)
        return np.stack([x.ravel(), y.ravel(), np.full(x.size, self.height_m)], -1)


def site_extent_m(scene: Scene, file_bounds=None) -> tuple[float, float, float, float]:
    """(x_min, x_max, y_min, y_max) of the environment meshes seen from above (the site plan); around the
    cameras when the scene has none."""
    corners = [
        box_corners(*local_bounds(mesh, file_bounds), placement(mesh))
        for mesh in scene.environment.meshes
        if not isinstance(mesh, FileMesh) or file_bounds
    ]
    if corners:
        xy = np.concatenate(corners)[:, :2]
        return float(xy[:, 0].min()), float(xy[:, 0].max()), float(xy[:, 1].min()), float(xy[:, 1].max())
    xy = np.array([c.mount.position_m[:2] for c in scene.cameras])
    m = MARGIN_WITHOUT_MESHES_M
    return float(xy[:, 0].min() - m), float(xy[:, 0].max() + m), float(xy[:, 1].min() - m), float(xy[:, 1].max() + m)


def make_grid(extent_m: Sequence[float], cell_m: float, height_m: float) -> Grid:
    """Cells of `cell_m` covering the extent (cell centres half a cell inside its edges)."""
    x_min, x_max, y_min, y_max = extent_m
    nx = max(1, int(np.ceil((x_max - x_min) / cell_m - 1e-9)))
    ny = max(1, int(np.ceil((y_max - y_min) / cell_m - 1e-9)))
    x = x_min + (np.arange(nx) + 0.5) * cell_m
    y = y_min + (np.arange(ny) + 0.5) * cell_m
    return Grid(x_m=x, y_m=y, cell_m=float(cell_m), height_m=float(height_m))


def inside_polygon(points_xy: np.ndarray, polygon_xy: np.ndarray) -> np.ndarray:
    """Even–odd rule: whether each point (N, 2) lies inside the polygon (M, 2) (implicitly closed)."""
    points = np.asarray(points_xy, dtype=np.float64).reshape(-1, 2)
    poly = np.asarray(polygon_xy, dtype=np.float64)
    x, y = points[:, 0:1], points[:, 1:2]
    x1, y1 = poly[:, 0], poly[:, 1]
    x2, y2 = np.roll(x1, -1), np.roll(y1, -1)
    crosses = (y1 > y) != (y2 > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_at = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
    return (np.count_nonzero(crosses & (x < x_at), axis=1) % 2) == 1


def region_problems(scene: Scene, extent_m: Sequence[float]) -> list[Problem]:
    """A region reaching outside the site plan: a problem each (key paths from the scene)."""
    x_min, x_max, y_min, y_max = extent_m
    problems = []
    for i, region in enumerate(scene.regions):
        for k, (x, y) in enumerate(region.polygon_m):
            if not (x_min - 1e-9 <= x <= x_max + 1e-9 and y_min - 1e-9 <= y <= y_max + 1e-9):
                problems.append(
                    Problem(
                        ("regions", i, "polygon_m", k),
                        f"puts a corner of region {region.name!r} at [{x:g}, {y:g}], outside the site "
                        f"(x {x_min:g}…{x_max:g} m, y {y_min:g}…{y_max:g} m: the environment meshes seen from "
                        "above); move it inside, or extend the ground",
                    )
                )
                break
    return problems


def region_masks(scene: Scene, grid: Grid) -> list[np.ndarray]:
    """Cells (ny, nx) whose centres lie inside each region; a region no cell centre falls in is an error
    (the cell is too coarse for it)."""
    points = grid.points_m()[:, :2]
    masks, problems = [], []
    for i, region in enumerate(scene.regions):
        mask = inside_polygon(points, np.array(region.polygon_m)).reshape(grid.shape)
        if not mask.any():
            problems.append(
                Problem(
                    ("regions", i, "polygon_m"),
                    f"of region {region.name!r} holds no cell centre of the {grid.cell_m:g} m grid; give a "
                    "smaller --cell-m, or a larger region",
                )
            )
        masks.append(mask)
    if problems:
        raise ConfigError(problems)
    return masks
