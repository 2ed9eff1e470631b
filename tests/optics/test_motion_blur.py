"""Sub-frame sampling of the exposure."""

from __future__ import annotations

import numpy as np

from camgen.optics.motion_blur import sub_frame_count, sub_frame_offsets


def test_count_keeps_sub_frames_at_most_a_step_apart_and_is_bounded():
    assert sub_frame_count(0.4) == 1  # under the threshold: sharp
    assert sub_frame_count(0.6) == 2
    assert sub_frame_count(16.7) == 17
    assert sub_frame_count(16.7, step_px=2.0) == 9
    assert sub_frame_count(1e4) == 32
    assert sub_frame_count(float("nan")) == 1


def test_offsets_are_centred_and_evenly_spread():
    for n in (1, 2, 7, 32):
        offsets = sub_frame_offsets(n)
        assert len(offsets) == n and abs(offsets.mean()) < 1e-15
        assert np.all(np.abs(offsets) < 0.5)
        np.testing.assert_allclose(np.diff(offsets), 1 / n)
