"""Progress of long commands where no one watches a terminal (a log file, CI, a batch system).

rich's bar draws only on a terminal; elsewhere it writes nothing until the command ends, so a log stays
empty for the length of a render. `ProgressLines` prints plain lines there instead, flushed at once: one each
time another `PROGRESS_STEP_FRAC` of the work is done, one from a timer whenever `PROGRESS_INTERVAL_S` pass
without a line (one frame or one job can take minutes), and a last one when the work ends or is stopped::

    render walk: 6/10 frames (60 %), 3.1 frames/s, elapsed 0:00:02, ETA 0:00:01
    batch: 3/8 jobs (38 %), 12.5 frames/s, elapsed 0:01:02, ETA 0:01:43
"""

from __future__ import annotations

import datetime
import math
import threading
import time
from types import TracebackType
from typing import Self

from rich.console import Console

PROGRESS_INTERVAL_S = 10.0
"""A line at least this often, s, even when no unit of work has ended since the last."""
PROGRESS_STEP_FRAC = 0.1
"""A line each time this fraction of the total more is done."""


def duration_text(seconds: float) -> str:
    """H:MM:SS, as rich's progress columns write a duration."""
    return str(datetime.timedelta(seconds=round(seconds)))


class ProgressLines:
    """Plain progress lines on `console`, for output that is not a terminal. A context manager: its timer
    runs inside the ``with`` block, and leaving the block prints the last line.

    Parameters
    ----------
    console : Console
        Where the lines go (the command's stderr console).
    label : str
        What each line starts with ("render walk", "batch").
    total : int
        Units of work, ≥ 0.
    unit : str
        Their name, plural ("frames", "jobs"). With "frames", each unit counts as one frame for frames/s.
    interval_s : float
        A line after this many seconds without one, s (> 0).
    step_frac : float
        A line each time this fraction of `total` more is done (0 < step_frac ≤ 1).
    """

    def __init__(
        self,
        console: Console,
        label: str,
        total: int,
        unit: str,
        *,
        interval_s: float = PROGRESS_INTERVAL_S,
        step_frac: float = PROGRESS_STEP_FRAC,
    ) -> None:
        self._console = console
        self._label = label
        self._total = total
        self._unit = unit
        self._interval_s = interval_s
        self._step = max(1, math.ceil(total * step_frac))
        self._next_step = self._step
        self._done = 0
        self._timed = 0
        self._frames = 0
        self._started = self._last_line = time.monotonic()
        self._shown = -1
        """`_done` at the last line (-1: no line yet)."""
        self._lock = threading.Lock()
        self._stopped = threading.Event()
        self._timer = threading.Thread(target=self._tick, name="progress-lines", daemon=True)

    def __enter__(self) -> Self:
        self._timer.start()
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, traceback: TracebackType | None
    ) -> None:
        self._stopped.set()
        self._timer.join()
        with self._lock:
            if self._shown != self._done:
                self._print()

    def advance(self, count: int = 1, *, frames: int | None = None, timed: bool = True) -> None:
        """Count `count` more units done, holding `frames` frames (None: `count`, for a unit of frames).
        timed=False: units that took no work (jobs skipped as already complete), left out of the ETA's rate."""
        with self._lock:
            self._done += count
            self._timed += count if timed else 0
            self._frames += (count if self._unit == "frames" else 0) if frames is None else frames
            if self._done >= self._next_step:
                self._next_step = (self._done // self._step + 1) * self._step
                self._print()

    def line(self) -> str:
        """The progress line for now."""
        elapsed_s = time.monotonic() - self._started
        percent = 100 * self._done / self._total if self._total else 100
        fps = self._frames / elapsed_s if elapsed_s > 0 else 0.0
        rate = self._timed / elapsed_s if elapsed_s > 0 else 0.0
        remaining = max(self._total - self._done, 0)
        eta = duration_text(remaining / rate) if rate > 0 else ("0:00:00" if remaining == 0 else "–")
        return (
            f"{self._label}: {self._done}/{self._total} {self._unit} ({percent:.0f} %), {fps:.1f} frames/s, "
            f"elapsed {duration_text(elapsed_s)}, ETA {eta}"
        )

    def _print(self) -> None:
        self._console.print(self.line(), markup=False, highlight=False, soft_wrap=True)
        self._shown = self._done
        self._last_line = time.monotonic()

    def _tick(self) -> None:
        while True:
            with self._lock:
                due_in_s = self._last_line + self._interval_s - time.monotonic()
                if due_in_s <= 0:
                    self._print()
                    due_in_s = self._interval_s
            if self._stopped.wait(due_in_s):
                return
