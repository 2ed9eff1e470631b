"""Stage timing: per-frame records that add up, and the shares `camgen render` prints."""

from __future__ import annotations

import itertools

import pytest

from camgen.plan.timing import StageClock, shares_text, stage_sums


def test_stage_clock_records_each_frame_and_its_wall_time():
    ticks = itertools.count(0.0, 0.5)  # every reading is 0.5 s after the one before
    cpu_ticks = itertools.count(0.0, 0.75)  # read at creation and at each frame's end
    clock = StageClock(clock=lambda: next(ticks), cpu_clock=lambda: next(cpu_ticks))  # creation reads 0.0
    with clock("render"):  # 0.5 → 1.0
        pass
    with clock("sensor"):  # 1.5 → 2.0
        pass
    with clock("render"):  # 2.5 → 3.0
        pass
    clock.end_frame()  # 3.5
    with clock("isp"):  # 4.0 → 4.5
        pass
    clock.end_frame()  # 5.0
    assert clock.frames == [{"render": 1.0, "sensor": 0.5}, {"isp": 0.5}]
    assert clock.frame_wall_s == [3.5, 1.5]
    assert clock.frame_cpu_s == [0.75, 0.75]
    assert stage_sums(clock.frames) == {"render": 1.0, "sensor": 0.5, "isp": 0.5}


def test_a_stage_that_raises_is_still_timed():
    ticks = itertools.count(0.0, 1.0)
    clock = StageClock(clock=lambda: next(ticks))
    with pytest.raises(RuntimeError), clock("render"):
        raise RuntimeError("draw failed")
    clock.end_frame()
    assert clock.frames == [{"render": 1.0}]


def test_shares_put_small_stages_and_untimed_time_into_other():
    seconds = {"render": 6.0, "sensor": 2.0, "isp": 0.05}
    assert shares_text(seconds, 10.0) == "render 60 %, sensor 20 %, other 20 %"
    assert stage_sums([{"a": 1.0}, {"a": 2.0, "b": 1.0}]) == {"a": 3.0, "b": 1.0}
    assert shares_text({}, 0.0) == ""


def test_a_frames_cpu_time_counts_every_thread_of_the_process():
    """Two threads each busy for 0.3 s of CPU during one frame: the frame's CPU time holds both (≥ 0.5 s), as a
    frame's counts the rasterizer's, the writer's and the encoder's threads."""
    import threading
    import time

    def busy(seconds: float) -> None:
        end = time.thread_time() + seconds
        while time.thread_time() < end:
            pass

    clock = StageClock()
    threads = [threading.Thread(target=busy, args=(0.3,)) for _ in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    clock.end_frame()
    assert clock.frame_cpu_s[0] >= 0.5
