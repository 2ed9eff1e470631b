"""Boxes of objects in an image (`camgen.annotate.boxes`): `mask_boxes`, which finds every id's box and
pixel count in one pass over the image, against each id's own full-frame mask; `points_box`'s box of
the imaged points against the box of the finite points taken one by one."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.annotate.boxes import mask_boxes, points_box


def reference_boxes(instance_id: np.ndarray, ids) -> dict[int, tuple[tuple[float, ...], int]]:
    """Each id's (box in pixel edges, pixel count) from its own mask over the whole image."""
    out = {}
    for value in ids:
        rows, cols = np.nonzero(instance_id == value)
        if value > 0 and rows.size:
            box = (float(cols.min()), float(rows.min()), float(cols.max() + 1), float(rows.max() + 1))
            out[int(value)] = (box, rows.size)
    return out


def found(instance_id: np.ndarray, ids=None) -> dict[int, tuple[tuple[float, ...], int]]:
    return {key: (value.box, value.pixels) for key, value in mask_boxes(instance_id, ids).items()}


def test_an_id_whose_pixels_reach_the_four_edges_of_the_image_gets_the_whole_image():
    # Id 3 has a pixel at each corner only, id 2 a block between them: a box taken from where an id's
    # pixels start (or from a window around its bulk) would cut id 3's short.
    instance = np.zeros((7, 9), np.uint32)
    instance[2:5, 3:6] = 2
    for row, col in ((0, 0), (0, 8), (6, 0), (6, 8)):
        instance[row, col] = 3
    assert found(instance, [2, 3]) == {2: ((3.0, 2.0, 6.0, 5.0), 9), 3: ((0.0, 0.0, 9.0, 7.0), 4)}


def test_every_id_of_a_random_image_matches_its_own_mask():
    rng = np.random.default_rng(7)
    for _ in range(50):
        shape = (int(rng.integers(1, 40)), int(rng.integers(1, 40)))
        instance = rng.integers(0, 9, size=shape).astype(np.uint32)
        instance[rng.random(shape) < 0.6] = 0
        ids = [int(i) for i in rng.integers(0, 12, size=int(rng.integers(0, 6)))]  # 0, absent and repeated ids
        assert found(instance, ids) == reference_boxes(instance, ids)
        assert found(instance) == reference_boxes(instance, np.unique(instance))


def test_ids_inside_the_range_asked_for_but_not_asked_for_are_left_out():
    instance = np.array([[1, 2, 3], [4, 5, 6]], np.uint32)
    assert found(instance, [2, 6]) == {2: ((1.0, 0.0, 2.0, 1.0), 1), 6: ((2.0, 1.0, 3.0, 2.0), 1)}
    assert found(instance, [0]) == {} and found(instance, []) == {} and found(np.zeros((3, 3), np.uint32)) == {}


def test_many_ids_and_a_view_that_is_not_contiguous():
    rng = np.random.default_rng(3)
    instance = rng.integers(0, 700, size=(60, 80)).astype(np.uint32)  # more ids than a byte labels
    view = instance.T[5:70:2]
    ids = range(0, 800, 3)
    assert found(view, ids) == reference_boxes(view, ids)


def test_points_box_leaves_out_points_not_imaged():
    K = np.array([[100.0, 0.0, 50.0], [0.0, 100.0, 40.0], [0.0, 0.0, 1.0]])
    T = np.eye(4)
    points = np.array([[0.1, 0.2, 1.0], [-0.3, 0.1, 2.0], [0.2, -0.1, -1.0], [0.0, 0.0, 4.0]])  # one behind
    box = points_box(points, T, K, np.zeros(5))
    imaged = points[points[:, 2] > 0]
    u = 100.0 * imaged[:, 0] / imaged[:, 2] + 50.0 + 0.5
    v = 100.0 * imaged[:, 1] / imaged[:, 2] + 40.0 + 0.5
    assert box == pytest.approx((u.min(), v.min(), u.max(), v.max()), abs=1e-12)
    assert points_box(points[2:3], T, K, np.zeros(5)) is None


def test_a_point_with_one_coordinate_not_finite_is_not_imaged():
    from camgen.annotate.boxes import _box_of_pixels

    points = np.array([[1.0, 2.0], [np.inf, -50.0], [-60.0, np.nan], [3.0, 5.0]])
    assert _box_of_pixels(points) == (1.5, 2.5, 3.5, 5.5)
    assert _box_of_pixels(points[1:3]) is None
