"""The distortion + lateral-CA remap: direction, margin convention, per-channel maps and exact ids; the
interpolated maps against Newton on every pixel."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.optics.projection import LensInversionError, distort_points
from camgen.optics.remap import (
    LensGeometry,
    LensMapCache,
    check_inside,
    fit_source_spline,
    lens_maps,
    remap_image,
    remap_nearest,
    source_grid_px,
    source_points_px,
)

K = ((400.0, 0.0, 159.5), (0.0, 410.0, 119.5), (0.0, 0.0, 1.0))
BARREL = (-0.3, 0.08, 0.001, -0.0008, 0.0, 0.0, 0.0, 0.0)


def _geometry(distortion=BARREL, ca_scales=(1.0,), margin=(40, 30, 40, 30)) -> LensGeometry:
    return LensGeometry(K, distortion, ca_scales, 320, 240, margin)


def _blob_image(centres_px: np.ndarray, width: int, height: int, sigma_px: float = 1.2) -> np.ndarray:
    u, v = np.meshgrid(np.arange(width), np.arange(height))
    image = np.zeros((height, width), np.float64)
    for cu, cv in centres_px:
        image += np.exp(-((u - cu) ** 2 + (v - cv) ** 2) / (2 * sigma_px**2))
    return image.astype(np.float32)


def _centroid(image: np.ndarray, near: np.ndarray, radius: int = 5) -> np.ndarray:
    u0, v0 = np.round(near).astype(int)
    window = image[v0 - radius : v0 + radius + 1, u0 - radius : u0 + radius + 1].astype(np.float64)
    v, u = np.mgrid[v0 - radius : v0 + radius + 1, u0 - radius : u0 + radius + 1]
    return np.array([(window * u).sum(), (window * v).sum()]) / window.sum()


def test_zero_lens_is_the_identity():
    image = np.random.default_rng(0).random((240, 320, 3), dtype=np.float32)
    maps = lens_maps(_geometry(distortion=(0.0,) * 8, margin=(0, 0, 0, 0)))
    np.testing.assert_array_equal(remap_image(image, maps), image)


def test_a_point_lands_where_cv2_project_points_puts_it():
    """Blobs drawn at pinhole positions in the margin render come out at their distorted positions."""
    geometry = _geometry()
    left, top, right, bottom = geometry.margin_px
    u, v = np.meshgrid(np.linspace(12, 308, 9), np.linspace(12, 228, 7))
    undistorted = np.column_stack([u.ravel(), v.ravel()]) + 0.37  # sub-pixel, blobs ≥ 27 px apart
    render = _blob_image(undistorted + np.array([left, top]), 320 + left + right, 240 + top + bottom)
    maps = lens_maps(geometry)
    check_inside(maps, render.shape[1], render.shape[0], support_px=1)
    out = remap_image(np.repeat(render[..., None], 3, axis=2), maps)[..., 1]
    expected = distort_points(undistorted, np.array(K), BARREL)
    measured = np.array([_centroid(out, p) for p in expected])
    # Linear resampling of a σ = 1.2 px blob moves its centroid by up to ≈ 0.04 px (the interpolant's
    # phase error); a wrong direction, margin or half-pixel convention moves it by ≥ 0.5 px.
    assert np.max(np.hypot(*(measured - expected).T)) < 0.08


def test_lateral_ca_maps_are_the_green_map_magnified_about_the_principal_point():
    scales = (1.002, 1.0, 0.997)
    geometry = _geometry(ca_scales=scales)
    maps = lens_maps(geometry)
    cx, cy = K[0][2], K[1][2]
    points = np.array([[0.0, 0.0], [319.0, 239.0], [200.0, 17.0]])
    green = _geometry(ca_scales=(1.0,))
    left, top = geometry.margin_px[:2]
    for channel, scale in enumerate(scales):
        shrunk = np.column_stack([cx + (points[:, 0] - cx) / scale, cy + (points[:, 1] - cy) / scale])
        (expected,) = source_points_px(green, shrunk)
        rows, cols = points[:, 1].astype(int), points[:, 0].astype(int)
        got = np.column_stack([maps.map_x[channel][rows, cols] - left, maps.map_y[channel][rows, cols] - top])
        np.testing.assert_allclose(got, expected, atol=2e-4)  # float32 maps


def test_geometric_passes_keep_exact_values():
    geometry = _geometry()
    maps = lens_maps(geometry)
    ids = np.random.default_rng(2).integers(0, 2**32 - 1, size=(300, 400), dtype=np.uint32)
    out = remap_nearest(ids, maps)
    assert out.dtype == np.uint32 and out.shape == (240, 320)
    assert set(np.unique(out)) <= set(np.unique(ids))
    rows, cols = maps.nearest_index
    assert np.all(np.abs(rows - maps.map_y[1 % len(maps.map_y)]) <= 0.5)
    assert np.all(np.abs(cols - maps.map_x[0]) <= 0.5)
    assert np.array_equal(out, ids[rows, cols])  # each pixel the value at its row and column, not a neighbour's
    depth_rgb = np.random.default_rng(3).random((300, 400, 3), np.float32)  # channels ride along
    assert np.array_equal(remap_nearest(depth_rgb, maps), depth_rgb[rows, cols])
    wider = np.random.default_rng(4).random((300, 410), np.float32)  # another render width: its own index
    assert np.array_equal(remap_nearest(wider, maps), wider[rows, cols])
    assert np.array_equal(remap_nearest(ids, maps), ids[rows, cols])


def test_a_render_narrower_than_the_maps_is_refused():
    """The flat index reads row r, column c at r·W + c: a render narrower than the columns the map reads would
    take them from the next row without a word (indexing by row and column raised IndexError), so it is
    refused with both widths."""
    maps = lens_maps(_geometry())
    needed = int(maps.nearest_index[1].max()) + 1
    narrow = np.zeros((300, needed - 1), np.float32)
    with pytest.raises(ValueError, match=rf"column {needed - 1}.* {needed - 1} px wide"):
        remap_nearest(narrow, maps)
    assert remap_nearest(np.zeros((300, needed), np.float32), maps).shape == (240, 320)  # just wide enough


def test_a_margin_too_small_for_the_lens_is_caught():
    maps = lens_maps(_geometry(margin=(5, 5, 5, 5)))
    with pytest.raises(ValueError, match="reads left/above the render"):
        check_inside(maps, 330, 250, support_px=1)


def test_cache_returns_the_same_maps_and_drops_the_oldest():
    cache = LensMapCache(capacity=2)
    a, b, c = _geometry(), _geometry(distortion=(-0.1,) + (0.0,) * 7), _geometry(distortion=(0.1,) + (0.0,) * 7)
    first = cache.get(a)
    assert cache.get(a) is first
    cache.get(b)
    cache.get(c)
    assert cache.get(a) is not first


K_OFFSET = ((380.0, 0.0, 171.3), (0.0, 395.0, 108.8), (0.0, 0.0, 1.0))
"""Non-square pixels and a principal point off the image centre."""
LENSES = {
    "strong barrel": BARREL,
    "pincushion": (0.25, 0.05, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    "tangential": (-0.05, 0.0, 0.01, -0.008, 0.0, 0.0, 0.0, 0.0),
    "rational": (-0.25, 0.06, 0.0005, 0.0005, 0.01, 0.08, 0.02, 0.005),
    "zero, CA only": (0.0,) * 8,
}


@pytest.mark.parametrize("size", [(320, 240), (333, 251)])
@pytest.mark.parametrize("camera_matrix", [K, K_OFFSET], ids=["centred", "offset"])
@pytest.mark.parametrize("ca_scales", [(1.0,), (1.002, 1.0, 0.997)], ids=["mono", "lateral CA"])
@pytest.mark.parametrize("lens", LENSES)
def test_interpolated_maps_match_newton_on_every_pixel(lens, ca_scales, camera_matrix, size):
    geometry = LensGeometry(camera_matrix, LENSES[lens], ca_scales, *size, (40, 30, 40, 30))
    spline = fit_source_spline(geometry)
    assert spline is not None  # the interpolated path, not the per-pixel fallback
    fast = source_grid_px(geometry)
    exact = source_grid_px(geometry, exact=True)
    assert len(fast) == len(exact) == len(ca_scales)
    error_px = max(float(np.max(np.abs(f - e))) for f, e in zip(fast, exact, strict=True))
    assert error_px <= 1e-3
    assert error_px <= 1.25 * spline.check_error_px + 1e-9  # the check sees the worst error (SPLINE_ERROR_MAX_PX)
    maps, reference = lens_maps(geometry), lens_maps(geometry, exact=True)
    for name in ("map_x", "map_y"):
        for got, expected in zip(getattr(maps, name), getattr(reference, name), strict=True):
            assert got.dtype == np.float32 and got.shape == size[::-1]
            np.testing.assert_allclose(got, expected, rtol=0, atol=1e-3 + 1e-4)  # + float32 rounding
    fx, fy = camera_matrix[0][0], camera_matrix[1][1]
    np.testing.assert_allclose(
        maps.undistorted_normalized, reference.undistorted_normalized, rtol=0, atol=1e-3 / min(fx, fy)
    )
    for got, expected in zip(maps.nearest_index, reference.nearest_index, strict=True):
        assert got.dtype == np.int32 and np.mean(got != expected) < 1e-4  # differs only at half-pixel ties


def test_near_the_fold_the_check_refines_the_nodes_then_falls_back_to_newton():
    """k1 = −0.3 folds over at distorted radius 0.703; the closer the corner, the steeper the inverse
    there and the denser the nodes must be, until no spacing passes and every pixel is solved."""
    fold = (-0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    steps = []
    for focal_px in (600.0, 400.0, 350.0, 300.0):  # corner at normalised radius 0.33, 0.50, 0.57, 0.66
        camera_matrix = ((focal_px, 0.0, 159.5), (0.0, focal_px, 119.5), (0.0, 0.0, 1.0))
        geometry = LensGeometry(camera_matrix, fold, (1.002, 1.0, 0.997), 320, 240, (0, 0, 0, 0))
        spline = fit_source_spline(geometry)
        steps.append(None if spline is None else spline.node_step_px)
        fast, exact = source_grid_px(geometry), source_grid_px(geometry, exact=True)
        for f, e in zip(fast, exact, strict=True):
            if spline is None:
                np.testing.assert_array_equal(f, e)
            else:
                assert np.max(np.abs(f - e)) <= 1e-3
    assert steps == [16.0, 8.0, 4.0, None]


def test_a_lens_the_nodes_cannot_invert_falls_back_to_the_per_pixel_error():
    """Nodes beyond the fold fail; the per-pixel path then names the pixel that cannot be inverted."""
    geometry = LensGeometry(
        ((250.0, 0.0, 159.5), (0.0, 250.0, 119.5), (0.0, 0.0, 1.0)),
        (-0.3,) + (0.0,) * 7,
        (1.0,),
        320,
        240,
        (0, 0, 0, 0),
    )
    assert fit_source_spline(geometry) is None
    with pytest.raises(LensInversionError, match="cannot be inverted at pixel"):
        lens_maps(geometry)
