"""A camera's per-frame writes (issue 23, pipelining) in one background thread, in order, while the main
thread renders the next frame: the frame time approaches its slowest stage instead of the sum.

`camgen.plan.execute` hands each frame's writes (the video's encode, the frame files, the annotation lines
and images, camera.jsonl) to a `FrameWriter` as one callable, with arrays that nothing else writes into
again (copies of the renderer's passes and the pipeline's output). The writer runs the frames' callables one
after another in submission order, so the files, the spools and `CameraResult.files` come out as a serial
render writes them, byte for byte. What feeds the next frame (auto-exposure, the ISP's adapting state, the
scene graph's actors, OpenGL) stays in the main thread.

At most `depth` frames (`PIPELINE_FRAMES`) are handed over and not yet written: the main thread waits for a
slot before handing over another, so memory stays flat over a long sequence. `drain` waits until every
frame handed over is written (before a checkpoint, before the camera's files are finished). A write that
raises stops the writer: the frames behind it are dropped, and the main thread gets the same exception
object at its next `check`, `submit` or `drain`, so a full disk or a bad path reads as it does in a serial
render, at most `depth` frames later. `stop` (the main thread unwinding: an error, Ctrl-C, a batch worker's
SIGTERM) drops the frames not started, waits for the one being written, and raises nothing; the caller then
aborts what is half written (the video's temporary file) and deletes or keeps the folder as it would.

Timing: the writer's stages are timed in the writer thread on its own `StageClock`, one record per frame
handed over (`frames`), which the caller adds to the main thread's record of the same frame. The main
thread's waits for the writer are timed on the caller's clock as ``io.wait`` (`WAIT_STAGE`).

A `FrameWriter(threaded=False)` runs each frame's callable at once in the calling thread, on the caller's
clock: the serial render.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable

from camgen.plan.timing import StageClock

PIPELINE_FRAMES = 2
"""Frames handed to the writer and not yet written, at most (the one being written included). Two keep the
writer busy while the main thread renders (one frame written, the next ready) and hold two frames' arrays
(about 30 MB at 1080p with depth and ids)."""

WAIT_STAGE = "io.wait"
"""The caller's stage for the time it waits for the writer: a free slot, a drain. The wall time the overlap
did not hide: the writer, not the main thread, set the pace."""

FrameWrites = Callable[[StageClock], None]
"""One frame's writes: called with the clock to time its stages on."""


class FrameWriter:
    """Runs frames' writes in order in one background thread, at most `depth` frames behind (module docstring).

    Parameters
    ----------
    clock : StageClock
        The caller's clock: a serial writer (`threaded` False) times the writes on it; a threaded one keeps
        its own (`frames`).
    threaded : bool
        False runs each frame's writes at once in the calling thread.
    depth : int
        Frames handed over and not yet written, at most (≥ 1).
    """

    def __init__(self, clock: StageClock, *, threaded: bool = True, depth: int = PIPELINE_FRAMES):
        if depth < 1:
            raise ValueError(f"depth must be ≥ 1 frame, got {depth}")
        self.threaded, self.depth = threaded, depth
        self._caller_clock = clock
        self._clock = StageClock() if threaded else clock
        self._slots = threading.Semaphore(depth)
        self._tasks: queue.SimpleQueue[FrameWrites | None] = queue.SimpleQueue()
        self._error: BaseException | None = None
        self._stopping = False
        self._thread: threading.Thread | None = None

    @property
    def frames(self) -> list[dict[str, float]]:
        """Seconds per stage of each frame written by the thread, in submission order (a serial writer's
        stages are on the caller's clock: empty). Read after `drain` or `close`."""
        return self._clock.frames if self.threaded else []

    def check(self) -> None:
        """Raise the exception a write raised, if one did."""
        if self._error is not None:
            raise self._error

    def submit(self, writes: FrameWrites) -> None:
        """Hand over one frame's writes; waits while `depth` frames are still unwritten. Raises a failed
        write's exception instead of handing over."""
        self.check()
        if not self.threaded:
            writes(self._clock)
            return
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name="camgen-frame-writer", daemon=True)
            self._thread.start()
        with self._caller_clock(WAIT_STAGE):
            self._slots.acquire()
        if self._error is not None:
            self._slots.release()
            self.check()
        self._tasks.put(writes)

    def drain(self) -> None:
        """Wait until every frame handed over is written; raise a failed write's exception."""
        if self.threaded:
            with self._caller_clock(WAIT_STAGE):
                for _ in range(self.depth):
                    self._slots.acquire()
            for _ in range(self.depth):
                self._slots.release()
        self.check()

    def close(self) -> None:
        """`drain`, then end the thread."""
        self.drain()
        self._end()

    def stop(self) -> None:
        """Drop the frames not started, wait for the one being written and end the thread; raises nothing
        (for a caller that is unwinding)."""
        self._stopping = True
        self._end()

    def _end(self) -> None:
        if self._thread is None:
            return
        self._tasks.put(None)
        # A join without a timeout is interruptible too, but a loop keeps a second Ctrl-C responsive.
        while self._thread.is_alive():
            self._thread.join(0.1)
        self._thread = None

    def _run(self) -> None:
        clock = self._clock
        while True:
            writes = self._tasks.get()
            if writes is None:
                return
            try:
                if self._error is None and not self._stopping:
                    writes(clock)
            except BaseException as error:  # handed to the main thread, which raises it
                self._error = error
            finally:
                clock.end_frame()
                self._slots.release()
