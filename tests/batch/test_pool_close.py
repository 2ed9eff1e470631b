"""The local pool closes within seconds even when a worker dies while it shuts down.

At a batch's end the pool's workers are idle in its call queue: one holds the queue's read lock while it waits
for a message, the others wait for that lock. Shutting down, the pool sends each an end-of-work message and
joins them. A worker killed then (a user's SIGKILL, the kernel's OOM killer) after the pool stopped watching
for dead workers takes the lock with it: the others wait for it for ever, and a pool that joins them without a
timeout (`concurrent.futures.ProcessPoolExecutor.shutdown`) never returns. Here the timing is made, not waited
for: the worker holding the lock is stopped (SIGSTOP) before the shutdown and killed once the end-of-work
messages are sent."""

from __future__ import annotations

import concurrent.futures.process as cf_process
import os
import signal
import threading
import time
from pathlib import Path

import camgen.batch.run as batch_run
from camgen.batch.run import PoolExecutor

GRACE_S = 1.0
"""`STOP_GRACE_S` for these tests, to keep them short."""
SETTLE_S = 120.0
"""How long the workers may take to start (the fork server imports for seconds on a loaded machine)."""


def main_thread_waits_in(pid: int) -> str:
    """Where the kernel has process `pid`'s main thread sleeping (``/proc/PID/wchan``): a pipe read, a futex."""
    return Path(f"/proc/{pid}/wchan").read_text()


def idle_workers(pool: PoolExecutor) -> tuple[int, list[int]]:
    """(the idle worker that holds the call queue's read lock, reading its pipe; the others, waiting for that
    lock), once every worker has started and is idle."""
    deadline = time.monotonic() + SETTLE_S
    while True:
        waits = {pid: main_thread_waits_in(pid) for pid in pool._pool._processes}
        readers = [pid for pid, where in waits.items() if "pipe" in where]
        lockers = [pid for pid, where in waits.items() if "futex" in where]
        if len(readers) == 1 and len(readers) + len(lockers) == len(waits):
            return readers[0], lockers
        assert time.monotonic() < deadline, f"the workers did not settle idle: {waits}"
        time.sleep(0.05)


def test_a_worker_killed_while_the_pool_shuts_down_does_not_hang_close(monkeypatch):
    monkeypatch.setattr(batch_run, "STOP_GRACE_S", GRACE_S)
    messages_sent = threading.Event()
    send_end_of_work = cf_process._ExecutorManagerThread.shutdown_workers

    def shutdown_workers(manager) -> None:
        send_end_of_work(manager)
        messages_sent.set()

    monkeypatch.setattr(cf_process._ExecutorManagerThread, "shutdown_workers", shutdown_workers)
    pool = PoolExecutor(2)
    calls = [pool._pool.submit(os.getpid) for _ in range(2)]  # each submit starts a worker, up to 2
    for call in calls:
        call.result(timeout=SETTLE_S)
    reader, lockers = idle_workers(pool)
    assert len(lockers) == 1
    os.kill(reader, signal.SIGSTOP)  # holding the lock, it cannot take its end-of-work message
    closing = threading.Thread(target=pool.close, name="close")
    closing.start()
    try:
        assert messages_sent.wait(SETTLE_S), "the pool did not send its workers their end-of-work messages"
        os.kill(reader, signal.SIGKILL)  # dies holding the read lock; the pool is no longer watching
        closing.join(3 * GRACE_S + 10.0)
        hung = closing.is_alive()
    finally:
        for pid in lockers:  # end a hang here instead of in pytest's exit
            if closing.is_alive():
                os.kill(pid, signal.SIGKILL)
        closing.join(30.0)
    assert not hung, "close() was still waiting for a worker that waits for a dead worker's lock"
