"""The coverage figures (matplotlib, PNG, written atomically): the best DORI class over the site plan with
the cameras, their frusta and the regions; and each camera's image plane coloured by pixel density."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from camgen.config.placement import box_corners, local_bounds, placement
from camgen.config.scene import CylinderMesh, FileMesh, PlaneMesh
from camgen.coverage.dori import DORI_CLASSES, DORI_THRESHOLDS_PX_M
from camgen.coverage.frustum import footprint_m, image_plane_density
from camgen.coverage.report import SceneCoverage
from camgen.io.files import atomic_path

DPI = 110
CLASS_COLOURS = ("#d9d9d9", "#fde725", "#5ec962", "#21918c", "#3b528b")
"""below detect (seen or not), detect, observe, recognise, identify."""


def _figure(width_in: float, height_in: float):
    from matplotlib.figure import Figure  # no pyplot: no global state, no display backend

    figure = Figure(figsize=(width_in, height_in), dpi=DPI, layout="constrained")
    return figure, figure.add_subplot()


def _save(figure, path: Path) -> Path:
    with atomic_path(path) as tmp:
        figure.savefig(tmp, format="png", metadata={"Software": None})
    return path


def plot_site(coverage: SceneCoverage, plane_index: int, path: Path, *, zoom: str | None = None) -> Path:
    """Best class over the site plan (off-site cells white), meshes from above, each camera with its frame's
    footprint on the plane, and the regions of interest with their required class."""
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Circle, Patch, Polygon

    from camgen.coverage.report import classes_with_reach

    plane = coverage.planes[plane_index]
    grid = plane.grid
    classes = (
        classes_with_reach(plane, zoom)
        if zoom
        else np.stack([c.dori for c in plane.cameras])
        if plane.cameras
        else np.zeros((0, *grid.shape), np.int8)
    )
    best = classes.max(axis=0, initial=0).astype(float)
    best[~plane.site] = np.nan
    x0, x1, y0, y1 = coverage.extent_m
    aspect = (y1 - y0) / max(x1 - x0, 1e-9)
    figure, ax = _figure(7.5, max(3.5, min(9.0, 6.2 * aspect + 1.0)))
    cmap = ListedColormap(CLASS_COLOURS).with_extremes(bad="white")
    half = grid.cell_m / 2
    ax.imshow(
        best,
        origin="lower",
        extent=(grid.x_m[0] - half, grid.x_m[-1] + half, grid.y_m[0] - half, grid.y_m[-1] + half),
        cmap=cmap,
        norm=BoundaryNorm(np.arange(-0.5, 5.5), cmap.N),
        interpolation="nearest",
    )
    for mesh in coverage.scene.environment.meshes:
        if isinstance(mesh, PlaneMesh) or isinstance(mesh, FileMesh):
            continue
        corners = box_corners(*local_bounds(mesh), placement(mesh))
        if corners[:, 2].max() <= grid.height_m and grid.height_m > 0:
            continue
        style = {"facecolor": "#444444", "edgecolor": "black", "alpha": 0.55, "lw": 0.6}
        if isinstance(mesh, CylinderMesh) and mesh.rotation_deg[:2] == (0.0, 0.0):
            ax.add_patch(Circle(mesh.position_m[:2], mesh.radius_m, **style))
        else:
            ax.add_patch(Polygon(_hull(corners[:, :2]), closed=True, **style))
    range_m = float(np.hypot(x1 - x0, y1 - y0))
    for k, view in enumerate(coverage.views):
        colour = f"C{k % 10}"
        outline = footprint_m(view, grid.height_m, range_m)
        ax.add_patch(Polygon(outline, closed=True, fill=False, edgecolor=colour, lw=1.2))
        cx, cy = view.centre_m[:2]
        ax.plot([cx], [cy], marker="^", color=colour, markeredgecolor="black", ms=9)
        ax.annotate(view.name, (cx, cy), textcoords="offset points", xytext=(5, 5), fontsize=8, color="black")
    for region in coverage.scene.regions:
        polygon = np.array(region.polygon_m)
        ax.add_patch(Polygon(polygon, closed=True, fill=False, edgecolor="black", lw=1.4, ls="--"))
        cx, cy = polygon.mean(axis=0)
        ax.text(cx, cy, f"{region.name}\n({region.required_class})", fontsize=7, ha="center", va="center")
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    what = f", PTZ heads aimed at each point at {zoom} zoom" if zoom else ""
    ax.set_title(f"best IEC 62676-4 class at z = {grid.height_m:g} m{what}", fontsize=10)
    labels = ["below detect"] + [f"{n} ≥ {t:g} px/m" for n, t in zip(DORI_CLASSES, DORI_THRESHOLDS_PX_M, strict=True)]
    handles = [Patch(facecolor=c, edgecolor="black", label=lab) for c, lab in zip(CLASS_COLOURS, labels, strict=True)]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    return _save(figure, path)


def plot_image_plane(coverage: SceneCoverage, camera_index: int, plane_height_m: float, path: Path) -> Path:
    """One camera's image: the person density (px/m, log colour scale) where each pixel's ray meets the
    plane, hatched grey where a mesh hides it or the ray never meets it, with the class boundaries drawn."""
    from matplotlib.colors import LogNorm

    view = coverage.views[camera_index]
    u, v, density, hidden = image_plane_density(view, coverage.occluders, plane_height_m)
    figure, ax = _figure(7.0, 7.0 * view.height_px / view.width_px + 0.9)
    shown = np.where(hidden, np.nan, density)
    image = ax.imshow(
        shown,
        extent=(u[0], u[-1], v[-1], v[0]),
        norm=LogNorm(vmin=5, vmax=1000),
        cmap="viridis",
        interpolation="nearest",
    )
    ax.imshow(np.where(hidden, 1.0, np.nan), extent=(u[0], u[-1], v[-1], v[0]), cmap="Greys", vmin=0, vmax=3, alpha=0.8)
    # The class edges are drawn on the plane's density field, through what hides it, so that a thin
    # occluder (a kerb, a post) does not break them into fragments.
    field = np.ma.masked_invalid(density)
    if field.count():
        contours = ax.contour(u, v, field, levels=list(DORI_THRESHOLDS_PX_M), colors="white", linewidths=0.8)
        ax.clabel(contours, fmt={t: n for t, n in zip(DORI_THRESHOLDS_PX_M, DORI_CLASSES, strict=True)}, fontsize=7)
    ax.set_xlim(-0.5, view.width_px - 0.5)
    ax.set_ylim(view.height_px - 0.5, -0.5)
    ax.set_xlabel("u (px)")
    ax.set_ylabel("v (px)")
    ax.set_title(
        f"{view.name}: person density where the image meets z = {plane_height_m:g} m (grey: hidden or sky)",
        fontsize=9,
    )
    figure.colorbar(image, ax=ax, label="px/m", shrink=0.8)
    return _save(figure, path)


def _hull(points: np.ndarray) -> np.ndarray:
    """Convex hull (Andrew's monotone chain) of 2-D points, counter-clockwise."""
    pts = sorted(map(tuple, np.round(points, 9)))
    if len(pts) <= 2:
        return np.array(pts)

    def half(sequence):
        chain: list[tuple] = []
        for p in sequence:
            while len(chain) >= 2 and _cross(chain[-2], chain[-1], p) <= 0:
                chain.pop()
            chain.append(p)
        return chain[:-1]

    return np.array(half(pts) + half(reversed(pts)))


def _cross(o, a, b) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
