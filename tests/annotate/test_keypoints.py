"""Keypoint visibility (`camgen.annotate.keypoints.keypoint_visibility`) given the person's own depth in
a window of the image only (its box, where the annotator draws it alone) flags each keypoint as the
whole image's own depth does: +inf outside the window."""

from __future__ import annotations

import numpy as np

from camgen.annotate.keypoints import keypoint_visibility

WIDTH_PX, HEIGHT_PX = 40, 30
K = np.array([[20.0, 0.0, 19.5], [0.0, 20.0, 14.5], [0.0, 0.0, 1.0]])


def test_own_depth_in_a_window_flags_keypoints_as_the_whole_image_does():
    rng = np.random.default_rng(5)
    # The person's own surface: camera z 4-6 m over the window's pixels, +inf elsewhere.
    col0, row0, col1, row1 = 12, 8, 25, 22
    window = rng.uniform(4.0, 6.0, (row1 - row0, col1 - col0)).astype(np.float32)
    window[rng.random(window.shape) < 0.3] = np.inf  # pixels of the window it does not cover
    whole = np.full((HEIGHT_PX, WIDTH_PX), np.inf, np.float32)
    whole[row0:row1, col0:col1] = window
    instance = np.ones((HEIGHT_PX, WIDTH_PX), np.uint32)  # nothing else covers it: its own body decides
    # Keypoints at every pixel of the image, at depths in front of, within and behind its surface: inside
    # the window, across its edges, outside it and on the image's border.
    rows, cols = np.mgrid[0:HEIGHT_PX, 0:WIDTH_PX]
    z = rng.uniform(3.5, 6.5, rows.size)
    u, v = cols.ravel().astype(float), rows.ravel().astype(float)
    points = np.stack([(u - K[0, 2]) / K[0, 0] * z, (v - K[1, 2]) / K[1, 1] * z, z], axis=1)
    T = np.eye(4)

    reference = keypoint_visibility(points, T, K, np.zeros(5), instance, 1, WIDTH_PX, HEIGHT_PX, own_depth_m=whole)
    flags = keypoint_visibility(
        points, T, K, np.zeros(5), instance, 1, WIDTH_PX, HEIGHT_PX, own_depth_m=window, own_depth_at_px=(col0, row0)
    )
    np.testing.assert_array_equal(flags, reference)
    assert {1.0, 2.0} <= set(reference[:, 2])  # some hidden by its own body, some seen
    # Without the window's place the same depths would stand at the image's top-left: other flags.
    misplaced = keypoint_visibility(points, T, K, np.zeros(5), instance, 1, WIDTH_PX, HEIGHT_PX, own_depth_m=window)
    assert not np.array_equal(misplaced, reference)
