"""Wall time per stage of a render, frame by frame: where a camera's time goes.

The executor and the camera pipeline wrap each stage in ``with clock("stage"):``; `end_frame` closes a
frame. Benchmarks read the per-frame records (the first frame carries the one-off costs: lens maps,
the scene upload, auto-exposure's convergence), and `camgen render` prints the shares.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager


class StageClock:
    """Seconds spent in each named stage, accumulated per frame and in total."""

    def __init__(
        self, clock: Callable[[], float] = time.perf_counter, cpu_clock: Callable[[], float] = time.process_time
    ):
        self._clock, self._cpu_clock = clock, cpu_clock
        self._current: dict[str, float] = {}
        self._frame_start, self._frame_cpu_start = clock(), cpu_clock()
        self.frames: list[dict[str, float]] = []
        """One record per finished frame: stage → seconds spent in it during that frame."""
        self.frame_wall_s: list[float] = []
        """Wall time of each finished frame, s: from the end of the one before (or the clock's creation)."""
        self.frame_cpu_s: list[float] = []
        """CPU time of the whole process during each finished frame, s (`time.process_time`: every thread's,
        OpenGL's rasterizer threads, the writer's and the encoder's included). Over the wall time: how many cores
        the frame kept busy; on n cores a frame cannot take less wall time than its CPU time ÷ n."""

    @contextmanager
    def __call__(self, stage: str) -> Iterator[None]:
        start = self._clock()
        try:
            yield
        finally:
            self._current[stage] = self._current.get(stage, 0.0) + self._clock() - start

    def add(self, stage: str, seconds: float) -> None:
        """Count `seconds` spent in `stage` during this frame elsewhere (another thread timed them)."""
        self._current[stage] = self._current.get(stage, 0.0) + seconds

    def end_frame(self) -> None:
        now, cpu_now = self._clock(), self._cpu_clock()
        self.frames.append(self._current)
        self.frame_wall_s.append(now - self._frame_start)
        self.frame_cpu_s.append(cpu_now - self._frame_cpu_start)
        self._current, self._frame_start, self._frame_cpu_start = {}, now, cpu_now


def stage_sums(frames: list[dict[str, float]]) -> dict[str, float]:
    """Seconds per stage summed over frame records, in the order stages first appear."""
    total: dict[str, float] = {}
    for record in frames:
        for stage, seconds in record.items():
            total[stage] = total.get(stage, 0.0) + seconds
    return total


def shares_text(seconds: dict[str, float], total_s: float, smallest_pct: float = 1.0) -> str:
    """`render 61 %, sensor 12 %, …`: each stage's share of `total_s`, largest first; stages under
    `smallest_pct` and the time outside every stage are summed as `other`."""
    if total_s <= 0:
        return ""
    parts, other = [], total_s - sum(seconds.values())
    for stage, s in sorted(seconds.items(), key=lambda item: -item[1]):
        if 100 * s / total_s >= smallest_pct:
            parts.append(f"{stage} {100 * s / total_s:.0f} %")
        else:
            other += s
    if 100 * other / total_s >= smallest_pct:
        parts.append(f"other {100 * other / total_s:.0f} %")
    return ", ".join(parts)
