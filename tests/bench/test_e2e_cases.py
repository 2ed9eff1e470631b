"""The end-to-end bench's per-frame figures: the warm-up left out, the finish shared out over the timed frames."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from camgen.bench.e2e_cases import cpu_per_frame_ms, timed_per_frame


def test_the_warm_up_is_left_out_and_the_finish_shared_out():
    result = SimpleNamespace(
        frame_wall_s=[9.0, 1.0, 2.0],
        frame_cpu_s=[15.0, 1.5, 3.5],
        stage_frames=[{"render": 8.0}, {"render": 0.6, "io.video": 0.2}, {"render": 1.4, "io.video": 0.3}],
        finish_s={"io.video": 0.6},
        finish_cpu_s=0.9,
    )
    frame_ms, stage_ms = timed_per_frame(result)
    # two timed frames of three: they take 2/3 of the finish
    assert frame_ms == pytest.approx(1e3 * (1.0 + 2.0 + 0.4) / 2)
    assert stage_ms == pytest.approx({"render": 1e3 * 2.0 / 2, "io.video": 1e3 * (0.5 + 0.4) / 2})
    assert cpu_per_frame_ms(result) == pytest.approx(1e3 * (1.5 + 3.5 + 0.6) / 2)


def test_a_one_frame_render_times_its_only_frame():
    result = SimpleNamespace(
        frame_wall_s=[2.0], frame_cpu_s=[3.0], stage_frames=[{"render": 1.5}], finish_s={}, finish_cpu_s=0.5
    )
    assert timed_per_frame(result) == (pytest.approx(2000.0), {"render": pytest.approx(1500.0)})
    assert cpu_per_frame_ms(result) == pytest.approx(3500.0)
