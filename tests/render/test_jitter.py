"""Motion sub-frames that carry the supersampling (`jittered_samples`): the counts, times and
sub-pixel positions that make a static pixel's average exactly the s×s box average."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.optics.motion_blur import sub_frame_offsets
from camgen.render.renderer import View
from camgen.render.sequence import jittered_samples, shifted


@pytest.mark.parametrize(("samples", "s"), [(2, 2), (5, 2), (8, 2), (9, 3), (10, 3), (3, 4)])
def test_every_sub_pixel_position_is_used_equally_often(samples, s):
    jittered = jittered_samples(samples, s)
    count = len(jittered)
    assert count % s**2 == 0 and samples <= count < samples + s**2
    times = np.array([t for t, _, _ in jittered])
    np.testing.assert_allclose(times, sub_frame_offsets(count))  # evenly spread, centred on the frame time
    positions = [(dx, dy) for _, dx, dy in jittered]
    grid = {((i + 0.5) / s - 0.5, (j + 0.5) / s - 0.5) for i in range(s) for j in range(s)}
    assert set(positions) == grid
    assert all(positions.count(p) == count // s**2 for p in grid)
    # Each run of s² consecutive times covers the whole grid (time and area stratified together).
    for start in range(0, count, s**2):
        assert set(positions[start : start + s**2]) == grid


def test_the_shifted_view_samples_the_box_average_positions_of_the_scaled_view():
    """Pixel u of the view shifted by d sees the ray of the scaled view's sub-pixel at u + d."""
    K = np.array([[800.0, 0, 319.5], [0, 800.0, 239.5], [0, 0, 1]])
    view = View(K, np.eye(4), 640, 480)
    fine = view.scaled(2)
    for (a, b), d in zip(
        [(0, 0), (1, 0), (0, 1), (1, 1)],
        [(-0.25, -0.25), (0.25, -0.25), (-0.25, 0.25), (0.25, 0.25)],
        strict=True,
    ):
        moved = shifted(view, *d)
        u, v = 100, 50
        ray_1x = np.linalg.solve(moved.K_px, [u, v, 1.0])
        ray_2x = np.linalg.solve(fine.K_px, [2 * u + a, 2 * v + b, 1.0])
        np.testing.assert_allclose(ray_1x, ray_2x, atol=1e-12)
