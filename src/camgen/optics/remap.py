"""Distortion and lateral chromatic aberration as one resampling of the margin-rendered pinhole image.

For every output (sensor) pixel the map holds where its light comes from in the pinhole render: the
distorted position is first un-magnified per colour channel (lateral CA: channel c is the green
image magnified by s_c about the principal point), then undistorted by Newton's method with a
checked residual (`camgen.optics.projection.undistort_points`), then shifted by the render margin.
Each channel is resampled once, through its own map; geometric passes (depth, instance ids) use the
green map with nearest-neighbour lookup, so they keep exact values.

Newton's method on every pixel costs seconds per 1080p frame, and a zooming PTZ camera needs new maps
every frame, so the maps interpolate the exact inverse instead (`fit_source_spline`): Newton on a grid
of nodes a few pixels apart, a bicubic spline through them, and a check of the spline against Newton
between the nodes; the maps stay within 1e-3 px of Newton on every pixel, and where the check fails
even on the finest grid, every pixel is solved (``lens_maps(..., exact=True)`` always does).

Maps are pure functions of (K, distortion, CA scales, output size, margin); `LensMapCache` keeps them
per camera and zoom step.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Iterator
from dataclasses import dataclass, field, replace

import cv2
import numpy as np
from scipy.interpolate import BSpline, make_interp_spline

from camgen.optics.projection import INVERSE_RESIDUAL_MAX_PX, LensInversionError, undistort_points

INTERPOLATIONS = {
    "nearest": cv2.INTER_NEAREST,
    "linear": cv2.INTER_LINEAR,
    "cubic": cv2.INTER_CUBIC,
    "lanczos": cv2.INTER_LANCZOS4,
}
SUPPORT_PX = {"nearest": 1, "linear": 1, "cubic": 2, "lanczos": 4}
"""Pixels an interpolation reads beyond the sample position (the render margin must hold them)."""
NODE_STEPS_PX = (16.0, 8.0, 4.0)
"""Node spacings the source spline tries, coarsest first (the next where its check fails)."""
SPLINE_ERROR_MAX_PX = 5e-4
"""Largest accepted error of the source spline at its check points, px. Over every pixel the error
was at most 1.21× its largest value at them (650 random lenses, |k1| ≤ 0.8, images of 49–640 px;
1.11× for the lenses of tests/optics/test_remap.py), so the maps stay within 1e-3 px of Newton with
a factor 1.6 to spare."""
ROWS_PER_BLOCK = 32
"""Output rows evaluated at once: keeps the float64 temporaries in cache (at 1080p with lateral CA,
57 ms against 73 ms for whole-frame arrays; 16 to 32 rows alike)."""


@dataclass(frozen=True)
class LensGeometry:
    """What the remap depends on. `ca_scales` are per output channel (1 for green, or one entry for
    monochrome); `margin_px` is (left, top, right, bottom) of the pinhole render."""

    K_px: tuple[tuple[float, ...], ...]
    distortion: tuple[float, ...]
    ca_scales: tuple[float, ...]
    width_px: int
    height_px: int
    margin_px: tuple[int, int, int, int]

    @property
    def K(self) -> np.ndarray:
        return np.array(self.K_px, dtype=np.float64)


@dataclass(frozen=True)
class LensMaps:
    """Source coordinates in the pinhole render, px, float32 (H, W) per channel."""

    map_x: tuple[np.ndarray, ...]
    map_y: tuple[np.ndarray, ...]
    nearest_index: tuple[np.ndarray, np.ndarray]
    """Row and column (int32, (H, W)) of the nearest render pixel through the reference (green) map."""
    undistorted_normalized: np.ndarray
    """(H, W, 2) float64: the undistorted ray (x, y) = (X/Z, Y/Z) of each output pixel (green)."""
    _flat_index: dict[int, np.ndarray] = field(default_factory=dict, compare=False, repr=False)

    def nearest_flat_index(self, render_width_px: int) -> np.ndarray:
        """`nearest_index` as one index (intp, (H, W)) into the render raveled at `render_width_px`, kept per
        width: `np.take` through it is ~3× faster than indexing by row and column (1080p, 16 → 5 ms)."""
        flat = self._flat_index.get(render_width_px)
        if flat is None:
            rows, cols = self.nearest_index
            if int(cols.max()) >= render_width_px:  # its pixels would come from the next row, without a word
                raise ValueError(
                    f"the lens map reads render column {int(cols.max())}, but the render is {render_width_px} px "
                    "wide: pass the render-size passes (output plus margin) the maps were made for"
                )
            flat = rows.astype(np.intp) * render_width_px + cols
            self._flat_index[render_width_px] = flat
        return flat


def output_grid_px(width_px: int, height_px: int) -> np.ndarray:
    """Pixel centres (H, W, 2) of an image, OpenCV convention."""
    u, v = np.meshgrid(np.arange(width_px, dtype=np.float64), np.arange(height_px, dtype=np.float64))
    return np.stack([u, v], axis=-1)


def border_points_px(width_px: int, height_px: int, step_px: float = 8.0) -> np.ndarray:
    """Points (N, 2) along the outer pixel edges of an image, at most `step_px` apart, corners included."""
    xs = np.append(np.arange(-0.5, width_px - 0.5, step_px), width_px - 0.5)
    ys = np.append(np.arange(-0.5, height_px - 0.5, step_px), height_px - 0.5)
    top = np.stack([xs, np.full_like(xs, -0.5)], -1)
    bottom = np.stack([xs, np.full_like(xs, height_px - 0.5)], -1)
    left = np.stack([np.full_like(ys, -0.5), ys], -1)
    right = np.stack([np.full_like(ys, width_px - 0.5), ys], -1)
    return np.concatenate([top, bottom, left, right])


def source_overshoot_px(geometry: LensGeometry, points_px: np.ndarray | None = None) -> tuple[float, ...]:
    """How far (left, top, right, bottom), px, the pinhole positions that `points_px` (default: the
    frame border) sample through the lens lie beyond the frame's outer pixel edges; 0 where inside.

    The render margin is this plus the interpolation's support. Raises `LensInversionError` where the
    lens cannot be inverted.
    """
    W, H = geometry.width_px, geometry.height_px
    points = border_points_px(W, H) if points_px is None else points_px
    sources = np.concatenate(source_points_px(geometry, points))
    low, high = sources.min(axis=0), sources.max(axis=0)
    return tuple(max(0.0, float(x)) for x in (-0.5 - low[0], -0.5 - low[1], high[0] - (W - 0.5), high[1] - (H - 0.5)))


def _reference_channel(ca_scales: tuple[float, ...]) -> int:
    """The channel with the least lateral CA (green): its map also serves depth, ids and vignetting."""
    return int(np.argmin([abs(s - 1.0) for s in ca_scales]))


def source_points_px(
    geometry: LensGeometry,
    points_px: np.ndarray,
    *,
    residual_max_px: float = INVERSE_RESIDUAL_MAX_PX,
) -> tuple[np.ndarray, ...]:
    """For output pixel positions (..., 2), the pinhole-render positions each channel samples
    (without the margin shift): one (..., 2) array per entry of `geometry.ca_scales`."""
    K = geometry.K
    cx, cy = K[0, 2], K[1, 2]
    points = np.asarray(points_px, dtype=np.float64)
    reference = _reference_channel(geometry.ca_scales)
    order = [reference] + [i for i in range(len(geometry.ca_scales)) if i != reference]
    sources: dict[int, np.ndarray] = {}
    for channel in order:
        scale = geometry.ca_scales[channel]
        magnified = np.stack([cx + (points[..., 0] - cx) / scale, cy + (points[..., 1] - cy) / scale], axis=-1)
        sources[channel] = undistort_points(
            magnified,
            K,
            geometry.distortion,
            residual_max_px=residual_max_px,
            initial_px=sources.get(reference),  # the reference solution is a close start
        )
    return tuple(sources[c] for c in range(len(geometry.ca_scales)))


def _magnified_axes_px(geometry: LensGeometry) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    """Per channel, the x of each output column and the y of each output row (px) un-magnified by its
    CA scale about the principal point, as `source_points_px` does: still a tensor-product grid."""
    K = geometry.K
    cx, cy = K[0, 2], K[1, 2]
    u = np.arange(geometry.width_px, dtype=np.float64)
    v = np.arange(geometry.height_px, dtype=np.float64)
    return tuple((cx + (u - cx) / scale, cy + (v - cy) / scale) for scale in geometry.ca_scales)


@dataclass(frozen=True)
class SourceSpline:
    """The green inverse (distorted → pinhole position, px) as a not-a-knot bicubic spline through its
    Newton solutions at nodes `node_step_px` apart (`fit_source_spline`)."""

    knots_x_px: np.ndarray = field(repr=False)
    knots_y_px: np.ndarray = field(repr=False)
    coefficients_px: np.ndarray = field(repr=False)
    """(nx, ny, 2): B-spline coefficients of the pinhole position (x, y)."""
    node_step_px: float
    check_error_px: float = np.inf
    """Largest |spline − Newton| at the check points (every cell's centre and edge midpoints), px;
    ∞ until checked."""

    @classmethod
    def through(cls, x_px: np.ndarray, y_px: np.ndarray, sources_px: np.ndarray, node_step_px: float) -> SourceSpline:
        """The spline through `sources_px` (ny, nx, 2) at the nodes `x_px` × `y_px`, not yet checked."""
        along_y = make_interp_spline(y_px, sources_px, k=3, axis=0)
        along_x = make_interp_spline(x_px, along_y.c, k=3, axis=1)
        return cls(along_x.t, along_y.t, along_x.c, node_step_px)

    def _across(self, x_px: np.ndarray) -> np.ndarray:
        """The spline's coefficients interpolated along x, (ny, 2·len(x)): each component's row whole."""
        nx, ny = self.coefficients_px.shape[:2]
        across = BSpline.design_matrix(x_px, self.knots_x_px, 3) @ self.coefficients_px.reshape(nx, ny * 2)
        return across.reshape(len(x_px), ny, 2).transpose(1, 2, 0).reshape(ny, 2 * len(x_px))

    def row_blocks(self, x_px: np.ndarray, y_px: np.ndarray, rows: int = ROWS_PER_BLOCK) -> Iterator[np.ndarray]:
        """The spline on the grid `x_px` × `y_px`, `rows` of `y_px` at a time: (rows, len(x), 2) each.

        Two sparse products with the B-spline design matrices (four non-zeros a row), By·C·Bxᵀ. A
        block is a view of a (rows, 2, len(x)) array, so each component's rows are contiguous.
        """
        across = self._across(x_px)
        along_y = BSpline.design_matrix(y_px, self.knots_y_px, 3)
        for start in range(0, len(y_px), rows):
            block = along_y[start : start + rows] @ across
            yield block.reshape(block.shape[0], 2, len(x_px)).transpose(0, 2, 1)

    def __call__(self, x_px: np.ndarray, y_px: np.ndarray) -> np.ndarray:
        """The spline on the grid `x_px` × `y_px`: (len(y), len(x), 2)."""
        return next(self.row_blocks(x_px, y_px, rows=len(y_px)))


def fit_source_spline(
    geometry: LensGeometry,
    *,
    residual_max_px: float = INVERSE_RESIDUAL_MAX_PX,
    error_max_px: float = SPLINE_ERROR_MAX_PX,
) -> SourceSpline | None:
    """The lens's inverse as a bicubic spline over every channel's un-magnified output grid, checked
    against Newton's method.

    Parameters
    ----------
    geometry : LensGeometry
        K, distortion, CA scales and output size (the margin plays no part).
    residual_max_px : float
        Largest accepted residual of Newton's inverse at the nodes and check points, px.
    error_max_px : float
        Largest accepted |spline − Newton| at the check points, px.

    Returns
    -------
    SourceSpline or None
        The spline of the coarsest spacing of `NODE_STEPS_PX` that passes the check; None where none
        does, where a node or check point cannot be inverted (`LensInversionError`: the per-pixel path
        then says where), or where an axis has room for fewer than four nodes (a cubic's support).

    Notes
    -----
    Newton (`undistort_points`, residual checked) on a grid spanning the un-magnified output positions
    of every channel, first and last rows and columns included (nothing is extrapolated), at half the
    node spacing h; the not-a-knot bicubic spline through every second point (the nodes); its error at
    the other points, every cell's centre and edge midpoints, where an interpolating spline's error
    peaks. Over every pixel the error was measured at most 1.21× the largest at the check points (see
    `SPLINE_ERROR_MAX_PX`), so the default keeps every pixel within 1e-3 px of Newton. The error falls
    as h⁴, so each finer spacing cuts it about 16×; near a fold-over the inverse steepens and no
    spacing may pass.

    A cubic spline reproduces linear functions exactly, so the spline of the source position is the
    identity plus the spline of its smooth displacement. Channel c's source is the green inverse at
    its un-magnified position (`_magnified_axes_px`), so all channels share one spline.
    """
    axes = _magnified_axes_px(geometry)
    x_low, x_high = min(x[0] for x, _ in axes), max(x[-1] for x, _ in axes)
    y_low, y_high = min(y[0] for _, y in axes), max(y[-1] for _, y in axes)
    for step_px in NODE_STEPS_PX:
        nx = int(np.ceil((x_high - x_low) / step_px)) + 1
        ny = int(np.ceil((y_high - y_low) / step_px)) + 1
        if min(nx, ny) < 4:
            return None
        check_x, check_y = np.linspace(x_low, x_high, 2 * nx - 1), np.linspace(y_low, y_high, 2 * ny - 1)
        try:
            exact = undistort_points(
                np.stack(np.meshgrid(check_x, check_y), axis=-1),
                geometry.K,
                geometry.distortion,
                residual_max_px=residual_max_px,
            )
        except LensInversionError:
            return None
        spline = SourceSpline.through(check_x[::2], check_y[::2], exact[::2, ::2], step_px)
        error_px = float(np.max(np.abs(spline(check_x, check_y) - exact)))
        if error_px <= error_max_px:
            return replace(spline, check_error_px=error_px)
    return None


def _source_blocks(
    geometry: LensGeometry, *, exact: bool, residual_max_px: float
) -> Iterator[tuple[int, tuple[np.ndarray, ...]]]:
    """(first row, per-channel sources (rows, W, 2)) of every output pixel, a block of rows at a time:
    from `fit_source_spline`, or from Newton on every pixel where `exact` or where no spline passes."""
    spline = None if exact else fit_source_spline(geometry, residual_max_px=residual_max_px)
    if spline is None:
        grid = output_grid_px(geometry.width_px, geometry.height_px)
        yield 0, source_points_px(geometry, grid, residual_max_px=residual_max_px)
        return
    channels = [spline.row_blocks(x, y) for x, y in _magnified_axes_px(geometry)]
    yield from zip(range(0, geometry.height_px, ROWS_PER_BLOCK), zip(*channels, strict=True), strict=True)


def source_grid_px(
    geometry: LensGeometry, *, exact: bool = False, residual_max_px: float = INVERSE_RESIDUAL_MAX_PX
) -> tuple[np.ndarray, ...]:
    """Where every output pixel of each channel samples the pinhole render, px, without the margin
    shift: one (H, W, 2) float64 array per entry of `geometry.ca_scales`.

    Exactly the positions `lens_maps` casts to its maps (with the same `exact` and `residual_max_px`):
    `source_points_px` of the whole output grid, interpolated unless `exact`.
    """
    blocks = [sources for _, sources in _source_blocks(geometry, exact=exact, residual_max_px=residual_max_px)]
    return tuple(np.concatenate(channel) for channel in zip(*blocks, strict=True))


def lens_maps(
    geometry: LensGeometry, *, exact: bool = False, residual_max_px: float = INVERSE_RESIDUAL_MAX_PX
) -> LensMaps:
    """Build the per-channel inverse maps (see the module docstring).

    Parameters
    ----------
    geometry : LensGeometry
        K, distortion, CA scales, output size and render margin.
    exact : bool
        Solve every pixel by Newton's method instead of interpolating: the reference, about 20–30×
        slower at 1080p (BENCHMARKS.md).
    residual_max_px : float
        Largest accepted residual of Newton's inverse, px (`undistort_points`).

    Returns
    -------
    LensMaps
        float32 (H, W) maps per channel, shifted by the margin; the nearest render pixel and the
        undistorted rays through the reference channel.

    Raises
    ------
    LensInversionError
        Where an output pixel cannot be inverted.

    Notes
    -----
    By default the sources come from `fit_source_spline`, within 1e-3 px of Newton on every pixel
    and channel before the cast to float32 (which adds at most 6.1e-5 px below 2048 px); where no
    spline passes its check, from Newton on every pixel. Rows are built `ROWS_PER_BLOCK` at a time.
    """
    K = geometry.K
    left, top, _, _ = geometry.margin_px
    shape = (geometry.height_px, geometry.width_px)
    channels = len(geometry.ca_scales)
    maps_x = tuple(np.empty(shape, np.float32) for _ in range(channels))
    maps_y = tuple(np.empty(shape, np.float32) for _ in range(channels))
    rows, cols = np.empty(shape, np.int32), np.empty(shape, np.int32)
    undistorted = np.empty((*shape, 2))
    reference = _reference_channel(geometry.ca_scales)
    for start, sources in _source_blocks(geometry, exact=exact, residual_max_px=residual_max_px):
        block = slice(start, start + sources[0].shape[0])
        for map_x, map_y, source in zip(maps_x, maps_y, sources, strict=True):
            np.add(source[..., 0], left, out=map_x[block], casting="unsafe")
            np.add(source[..., 1], top, out=map_y[block], casting="unsafe")
        ref = sources[reference]
        rows[block] = np.floor(ref[..., 1] + top + 0.5)
        cols[block] = np.floor(ref[..., 0] + left + 0.5)
        for axis in (0, 1):
            np.subtract(ref[..., axis], K[axis, 2], out=undistorted[block, :, axis])
            undistorted[block, :, axis] /= K[axis, axis]
    return LensMaps(maps_x, maps_y, (rows, cols), undistorted)


def check_inside(maps: LensMaps, render_width_px: int, render_height_px: int, support_px: int) -> None:
    """Raise ValueError if a map reads outside the render (the plan's margin is too small)."""
    for mx, my in zip(maps.map_x, maps.map_y, strict=True):
        low_x, high_x, low_y, high_y = mx.min(), mx.max(), my.min(), my.max()
        if low_x < support_px - 1 or low_y < support_px - 1:
            raise ValueError(f"the lens map reads left/above the render: min ({low_x:.2f}, {low_y:.2f}) px")
        if high_x > render_width_px - support_px or high_y > render_height_px - support_px:
            raise ValueError(
                f"the lens map reads right/below the {render_width_px}×{render_height_px} render: "
                f"max ({high_x:.2f}, {high_y:.2f}) px"
            )


def remap_image(image: np.ndarray, maps: LensMaps, interpolation: str = "linear") -> np.ndarray:
    """Resample a (H, W, C) float32 radiance image through the per-channel maps.

    One resampling per channel. Interpolation undershoot (cubic, Lanczos ringing at bright edges) is
    clipped at zero: radiance is non-negative.
    """
    flag = INTERPOLATIONS[interpolation]
    channels = len(maps.map_x)
    if image.ndim != 3 or (channels == 3 and image.shape[2] != 3):
        raise ValueError(f"expected an (H, W, 3) image for a colour lens map, got {image.shape}")
    if channels == 1:
        out = cv2.remap(image, maps.map_x[0], maps.map_y[0], flag, borderMode=cv2.BORDER_REPLICATE)
        out = out.reshape(out.shape[0], out.shape[1], -1)
    else:
        out = np.empty((*maps.map_x[0].shape, 3), np.float32)
        for c in range(3):
            out[..., c] = cv2.remap(
                np.ascontiguousarray(image[..., c]), maps.map_x[c], maps.map_y[c], flag, borderMode=cv2.BORDER_REPLICATE
            )
    if interpolation in ("cubic", "lanczos"):
        np.maximum(out, 0.0, out=out)
    return out


def remap_nearest(image: np.ndarray, maps: LensMaps) -> np.ndarray:
    """Exact values of the nearest render pixel through the reference map (depth, instance ids)."""
    flat = maps.nearest_flat_index(image.shape[1])
    return np.take(image.reshape(-1, *image.shape[2:]), flat, axis=0)


class LensMapCache:
    """Maps per lens geometry (one per camera and zoom step), least recently used dropped first."""

    def __init__(self, capacity: int = 8):
        self.capacity = capacity
        self._maps: OrderedDict[LensGeometry, LensMaps] = OrderedDict()

    def get(self, geometry: LensGeometry) -> LensMaps:
        if geometry in self._maps:
            self._maps.move_to_end(geometry)
            return self._maps[geometry]
        maps = lens_maps(geometry)
        self._maps[geometry] = maps
        while len(self._maps) > self.capacity:
            self._maps.popitem(last=False)
        return maps


@dataclass(frozen=True)
class MosaicMap:
    """Where each photosite's light comes from in the channel-stacked render (`stack_channels`).

    A colour site reads only its own CFA channel, so distortion, lateral CA and the CFA sampling are
    one resampling of H·W samples (a third of resampling three full channels): site (v, u) of
    channel c reads the stacked image at (map_x, map_y) = (x_c, y_c + c·H_render).
    """

    map_x: np.ndarray
    map_y: np.ndarray
    exact: bool
    """The map only crops (no lens geometry): nearest-pixel lookup is exact and cheapest."""


def mosaic_map(
    maps: LensMaps | None,
    channel_index: np.ndarray | None,
    *,
    width_px: int,
    height_px: int,
    margin_px: tuple[int, int, int, int],
    render_height_px: int,
) -> MosaicMap:
    """The photosite map of an output frame.

    Parameters
    ----------
    maps : LensMaps or None
        The lens maps (one or three channels); None when no lens stage resamples (a pure crop).
    channel_index : (H, W) uint8 or None
        The CFA channel of each site (`camgen.sensor.cfa.cfa_channel_index`); None for a single plane
        (a mono sensor).
    width_px, height_px, margin_px, render_height_px
        Output size, the render margin (left, top, right, bottom) and the render height.
    """
    if maps is None:
        left, top, _, _ = margin_px
        u, v = np.meshgrid(np.arange(width_px, dtype=np.float32), np.arange(height_px, dtype=np.float32))
        map_x, map_y = u + left, v + top
        if channel_index is not None:
            map_y = map_y + channel_index.astype(np.float32) * render_height_px
        return MosaicMap(map_x, map_y, exact=True)
    if channel_index is None or len(maps.map_x) == 1:
        map_x, map_y = maps.map_x[0], maps.map_y[0]
        if channel_index is not None:
            map_y = map_y + channel_index.astype(np.float32) * render_height_px
        return MosaicMap(map_x, map_y, exact=False)
    map_x = np.choose(channel_index, maps.map_x).astype(np.float32)
    map_y = np.choose(channel_index, maps.map_y) + channel_index.astype(np.float32) * render_height_px
    return MosaicMap(map_x, map_y.astype(np.float32), exact=False)


STACKED_ROWS_MAX = 32766
"""`cv2.remap` reads sources of fewer than 32 767 rows (SHRT_MAX): the channel stack must fit."""


def stack_channels(image: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """(H, W, C) float32 → (C·H, W): the channels one above the other (the layout `MosaicMap` reads).

    `out`, when given, is reused (it must have that shape); `cv2.split` writes into it directly.
    """
    height, width, channels = image.shape
    if out is None or out.shape != (channels * height, width):
        out = np.empty((channels * height, width), np.float32)
    cv2.split(image, [out[c * height : (c + 1) * height] for c in range(channels)])
    return out


def remap_mosaic(stacked: np.ndarray, mosaic: MosaicMap, interpolation: str = "linear") -> np.ndarray:
    """(H, W) float32 light at each photosite from the channel-stacked render (or a single plane).

    Cubic and Lanczos undershoot is clipped at zero, as in `remap_image`.
    """
    flag = cv2.INTER_NEAREST if mosaic.exact else INTERPOLATIONS[interpolation]
    out = cv2.remap(stacked, mosaic.map_x, mosaic.map_y, flag, borderMode=cv2.BORDER_REPLICATE)
    if not mosaic.exact and interpolation in ("cubic", "lanczos"):
        np.maximum(out, 0.0, out=out)
    return out
