"""`camgen.plan.writer.FrameWriter`: frames' writes in order in one thread, at most `depth` frames behind, a
failed write's exception raised in the caller (the same object), the frames behind it dropped, `stop` quiet,
per-frame stage records in the writer's thread and the caller's waits timed as ``io.wait``."""

from __future__ import annotations

import threading
import time

import pytest

from camgen.plan.timing import StageClock
from camgen.plan.writer import WAIT_STAGE, FrameWriter


class DiskFullError(OSError):
    pass


def writer_threads() -> list[threading.Thread]:
    return [thread for thread in threading.enumerate() if thread.name == "camgen-frame-writer"]


def test_frames_are_written_in_order_in_another_thread():
    written, threads = [], set()

    def writes(index):
        def run(clock):
            with clock("io.files"):
                time.sleep(0.002 * (index % 3))  # uneven frames: the order must not follow their lengths
            written.append(index)
            threads.add(threading.get_ident())

        return run

    writer = FrameWriter(StageClock())
    for index in range(20):
        writer.submit(writes(index))
    writer.close()
    assert written == list(range(20))
    assert threads and threading.get_ident() not in threads
    assert len(writer.frames) == 20 and all(set(record) == {"io.files"} for record in writer.frames)
    assert writer_threads() == []


def test_at_most_depth_frames_wait_unwritten():
    """The third frame is not handed over while two are unwritten: the caller waits, timed as io.wait."""
    release, started = threading.Event(), threading.Event()

    def blocked(clock):
        started.set()
        release.wait(5)

    clock = StageClock()
    writer = FrameWriter(clock, depth=2)
    writer.submit(blocked)
    writer.submit(lambda clock: None)
    handed = threading.Event()

    def third():
        writer.submit(lambda clock: None)
        handed.set()

    caller = threading.Thread(target=third)
    caller.start()
    assert started.wait(5)
    assert not handed.wait(0.2)  # both slots taken: it waits
    release.set()
    assert handed.wait(5)
    caller.join(5)
    writer.close()
    assert len(writer.frames) == 3
    clock.end_frame()
    assert clock.frames[-1][WAIT_STAGE] > 0.1  # the third submit's wait (its own thread, the same clock)


def test_a_failed_write_is_raised_in_the_caller_and_the_frames_behind_it_are_dropped():
    error = DiskFullError(28, "No space left on device", "frames/000001.png")
    written = []

    def writes(index):
        def run(clock):
            if index == 1:
                raise error
            written.append(index)

        return run

    writer = FrameWriter(StageClock())
    with pytest.raises(DiskFullError) as raised:
        for index in range(50):
            writer.submit(writes(index))
        writer.drain()
    assert raised.value is error  # the very exception: its type, message and file name as the write raised them
    assert written[0] == 0 and 1 not in written and len(written) <= 2  # at most the frames already handed over
    with pytest.raises(DiskFullError):
        writer.check()  # it stays raised: no later drain or submit hides it
    writer.stop()  # quiet while unwinding
    assert writer_threads() == []


def test_the_last_frames_failed_write_is_raised_by_drain():
    writer = FrameWriter(StageClock())
    writer.submit(lambda clock: None)

    def fails(clock):
        raise DiskFullError(28, "No space left on device")

    writer.submit(fails)
    with pytest.raises(DiskFullError, match="No space left on device"):
        writer.close()
    writer.stop()
    assert writer_threads() == []


def test_stop_drops_frames_not_started_and_waits_for_the_one_being_written():
    release, started = threading.Event(), threading.Event()
    done = []

    def first(clock):
        started.set()
        release.wait(5)
        done.append(0)

    writer = FrameWriter(StageClock())
    writer.submit(first)
    writer.submit(lambda clock: done.append(1))
    assert started.wait(5)
    threading.Timer(0.1, release.set).start()
    writer.stop()
    assert done == [0]  # the one being written finished, the one waiting never ran
    assert writer_threads() == []


def test_a_serial_writer_writes_at_once_on_the_callers_clock():
    clock, order = StageClock(), []
    writer = FrameWriter(clock, threaded=False)

    def writes(clock):
        with clock("io.video"):
            order.append(threading.get_ident())

    writer.submit(writes)
    assert order == [threading.get_ident()]  # written before submit returned, in this thread
    writer.close()
    clock.end_frame()
    assert set(clock.frames[0]) == {"io.video"} and writer.frames == []
    with pytest.raises(DiskFullError):
        writer.submit(lambda clock: (_ for _ in ()).throw(DiskFullError(28, "No space left on device")))


def test_depth_below_one_is_refused():
    with pytest.raises(ValueError, match="depth must be ≥ 1 frame, got 0"):
        FrameWriter(StageClock(), depth=0)
