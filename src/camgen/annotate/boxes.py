"""Boxes of objects in an image: from the instance pass (visible) and from the geometry (amodal).

Box convention (COCO's): pixel (u, v) covers [u, u + 1) × [v, v + 1), so a box is (x0, y0, x1, y1)
in pixel-edge coordinates and a mask covering columns u_min…u_max spans x0 = u_min, x1 = u_max + 1.
A projected point at OpenCV pixel position p (centres at integers, DESIGN.md) lies at p + ½ there.

The amodal box is the projection of the object's surface through the same lens model as the pixels
(`camgen.optics.projection.project_points`: Brown–Conrady, the output camera matrix). Straight edges
bow under distortion, so the surface's edges are sampled densely (`edge_samples`), not just its
corners: under strong barrel distortion the extreme point of an edge lies between its ends.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from camgen.optics.projection import project_points

Box = tuple[float, float, float, float]


@dataclass(frozen=True)
class MaskBox:
    box: Box
    """(x0, y0, x1, y1), pixel edges."""
    pixels: int


def mask_boxes(instance_id: np.ndarray, ids=None) -> dict[int, MaskBox]:
    """Tight box and pixel count of every id (> 0) in an (H, W) instance image, or of `ids` only (those
    with no pixel are left out), in ascending id order.

    One pass over the image for all ids together, then work on their pixels only: the image is read a
    few times whatever the number of ids, instead of a full-frame mask per id.
    """
    wanted = np.unique(instance_id if ids is None else np.asarray(list(ids), dtype=np.int64))
    wanted = wanted[wanted > 0]
    if wanted.size == 0:
        return {}
    width = instance_id.shape[1]
    flat = instance_id.ravel()
    candidates = np.flatnonzero((flat >= int(wanted[0])) & (flat <= int(wanted[-1])))  # raster order
    values = flat[candidates]
    label = np.searchsorted(wanted, values)  # each value lies within wanted's range: a valid index
    wanted_pixel = wanted[label] == values
    candidates, label = candidates[wanted_pixel], label[wanted_pixel].astype(np.min_scalar_type(len(wanted)))
    if label.size == 0:
        return {}
    order = np.argsort(label, kind="stable")  # each id's pixels together, still in raster order
    candidates, label = candidates[order], label[order]
    starts = np.flatnonzero(np.concatenate([[True], label[1:] != label[:-1]]))
    ends = np.append(starts[1:], label.size)
    rows, cols = np.divmod(candidates, width)  # rows ascend within each id's pixels
    col_low, col_high = np.minimum.reduceat(cols, starts), np.maximum.reduceat(cols, starts)
    return {
        int(wanted[label[start]]): MaskBox(
            (float(c0), float(rows[start]), float(c1 + 1), float(rows[end - 1] + 1)), int(end - start)
        )
        for start, end, c0, c1 in zip(starts, ends, col_low, col_high, strict=True)
    }


def edge_samples(vertices_m: np.ndarray, edges: np.ndarray, per_edge: np.ndarray | int) -> np.ndarray:
    """Points along mesh edges: each edge (i, j) sampled at `per_edge` + 1 evenly spaced points (ends
    included). vertices_m (V, 3), edges (E, 2) int, per_edge (E,) or a scalar; returns (N, 3)."""
    counts = np.broadcast_to(np.asarray(per_edge, dtype=np.int64), (len(edges),))
    starts, ends = vertices_m[edges[:, 0]], vertices_m[edges[:, 1]]
    index = np.repeat(np.arange(len(edges)), counts + 1)
    offsets = np.arange(len(index)) - np.repeat(np.cumsum(counts + 1) - (counts + 1), counts + 1)
    t = offsets / np.repeat(counts, counts + 1)
    return starts[index] + t[:, None] * (ends[index] - starts[index])


def unique_edges(faces: np.ndarray) -> np.ndarray:
    """The distinct edges (E, 2) of triangles (F, 3)."""
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    return np.unique(edges, axis=0)


def amodal_box(
    vertices_world_m: np.ndarray,
    edges: np.ndarray,
    T_world_from_cam: np.ndarray,
    K_px: np.ndarray,
    distortion,
    *,
    step_px: float = 0.25,
    max_per_edge: int = 4096,
) -> Box | None:
    """Unclipped box of a mesh's projection (pixel edges), or None if no part of it is imaged.

    Each edge is sampled so that neighbouring samples lie at most about `step_px` apart on the image
    (from its ends' projected length); the surface's silhouette is made of such edges and vertices.
    Points behind the camera or beyond the lens' fold radius are not imaged and are left out.
    """
    ends_px, _ = project_points(vertices_world_m, T_world_from_cam, K_px, distortion)
    length = np.linalg.norm(ends_px[edges[:, 0]] - ends_px[edges[:, 1]], axis=1)
    length = np.where(np.isfinite(length), length, max_per_edge * step_px)
    per_edge = np.clip(np.ceil(length / step_px), 1, max_per_edge).astype(np.int64)
    points_px, _ = project_points(edge_samples(vertices_world_m, edges, per_edge), T_world_from_cam, K_px, distortion)
    return _box_of_pixels(points_px)


def points_box(points_world_m: np.ndarray, T_world_from_cam: np.ndarray, K_px: np.ndarray, distortion) -> Box | None:
    """Unclipped box (pixel edges) of the projections of points, or None if none is imaged: the
    amodal box of a mesh whose edges are short enough that its vertices bound its silhouette."""
    return _box_of_pixels(project_points(points_world_m, T_world_from_cam, K_px, distortion)[0])


def _box_of_pixels(points_px: np.ndarray) -> Box | None:
    """The box (pixel edges) of the imaged (finite) OpenCV pixel positions among `points_px`."""
    x, y = points_px[:, 0], points_px[:, 1]
    if not np.isfinite(points_px).all():
        imaged = np.isfinite(x) & np.isfinite(y)
        x, y = x[imaged], y[imaged]
    if x.size == 0:
        return None
    # Each coordinate reduced on its own: numpy's min/max over axis 0 of an (N, 2) array is some 30×
    # slower for the dense meshes of people (tens of thousands of vertices).
    return float(x.min() + 0.5), float(y.min() + 0.5), float(x.max() + 0.5), float(y.max() + 0.5)


def clip_box(box: Box, width_px: int, height_px: int) -> Box | None:
    """The part of a box inside the image [0, W] × [0, H], or None when nothing is inside."""
    x0, y0 = max(box[0], 0.0), max(box[1], 0.0)
    x1, y1 = min(box[2], float(width_px)), min(box[3], float(height_px))
    return (x0, y0, x1, y1) if x1 > x0 and y1 > y0 else None


def box_area(box: Box | None) -> float:
    return 0.0 if box is None else max(box[2] - box[0], 0.0) * max(box[3] - box[1], 0.0)


def truncation(box: Box, width_px: int, height_px: int) -> float:
    """Fraction of the amodal box's area outside the image (0 = wholly inside)."""
    area = box_area(box)
    return 0.0 if area == 0 else 1.0 - box_area(clip_box(box, width_px, height_px)) / area
