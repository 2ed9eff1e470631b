"""`camgen.render.renderer._grid_points` (the sky and far ground at the pixels behind glass, one by one): any
number of pixels, each the value `_grid_interpolated` gives it over the whole view, bit for bit. OpenCV's
remap refuses an image 32767 pixels or more on a side, and the pixels behind a near bus's windows are more
than that in one column."""

from __future__ import annotations

import numpy as np

from camgen.render.renderer import View, _grid_interpolated, _grid_points, _grid_rays

WIDTH_PX, HEIGHT_PX = 320, 200  # 64 000 pixels: more than remap takes in one column


def _view() -> View:
    K_px = np.array([[250.0, 0.0, 159.5], [0.0, 250.0, 99.5], [0.0, 0.0, 1.0]])
    return View(K_px=K_px, T_world_from_cam=np.eye(4), width_px=WIDTH_PX, height_px=HEIGHT_PX)


def test_more_pixels_than_remap_takes_in_one_column_are_the_whole_views_values():
    view = _view()
    us, vs, _ = _grid_rays(view, 8)
    nodes = np.ascontiguousarray(np.random.default_rng(5).random((len(vs), len(us), 3), dtype=np.float32))
    whole = _grid_interpolated(nodes, us, vs, view)
    rows, cols = np.nonzero(np.ones((HEIGHT_PX, WIDTH_PX), bool))
    order = np.random.default_rng(6).permutation(len(rows))  # any order, as the glass pixels come
    rows, cols = rows[order], cols[order]
    points = _grid_points(nodes, us, vs, rows, cols)
    assert points.shape == (WIDTH_PX * HEIGHT_PX, 3)
    np.testing.assert_array_equal(points, whole[rows, cols])


def test_few_and_no_pixels():
    view = _view()
    us, vs, _ = _grid_rays(view, 8)
    nodes = np.ascontiguousarray(np.random.default_rng(7).random((len(vs), len(us), 3), dtype=np.float32))
    whole = _grid_interpolated(nodes, us, vs, view)
    rows, cols = np.array([0, 199, 57]), np.array([319, 0, 101])
    np.testing.assert_array_equal(_grid_points(nodes, us, vs, rows, cols), whole[rows, cols])
    assert _grid_points(nodes, us, vs, rows[:0], cols[:0]).shape == (0, 3)
