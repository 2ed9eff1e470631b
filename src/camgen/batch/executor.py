"""Between `run_batch` and where its jobs run: the `JobExecutor` interface each executor implements, and
`render_job`, what every executor runs in its worker for one job.

`camgen.batch.run` schedules jobs (skip, retry, record, stop) through a `JobExecutor`; the local process
pool (`camgen.batch.run.PoolExecutor`) and Ray (`camgen.batch.ray_executor.RayExecutor`) implement it,
and both run the same `render_job`, so they write the same bytes. The executors import this module and
nothing of `run`; `run` imports the Ray executor only when a batch asks for it.

A worker process opens one OpenGL `Renderer` on its first job and keeps it for the rest (a context per
process). The local pool's workers are forked from a fork server (`pool_context`) that has imported what a
job needs (`POOL_PRELOAD_MODULES`) and nothing more: no OpenGL context, no thread of its own at the fork, so
a worker starts in milliseconds instead of seconds of imports, without inheriting the batch's state. A pool
worker's signals (`init_pool_worker`): SIGINT is ignored (the parent decides), SIGTERM unwinds the running
job, deleting its temporary files (or, in a batch that resumes, keeping its checkpoints for the next run),
and ends the worker, as does the end of the batch process, however it ends (`_stop_with_parent`).
"""

from __future__ import annotations

import multiprocessing
import multiprocessing.connection
import multiprocessing.forkserver
import multiprocessing.resource_tracker
import os
import signal
import threading
import time
import traceback
from collections.abc import Collection, Hashable
from pathlib import Path
from typing import Protocol

from camgen.job import Job

STOP_GRACE_S = 5.0
"""After a stop, how long a worker has to unwind its job (deleting its temporary files) before it is killed."""

JobResult = tuple[int, float, str | None, int]
"""What `render_job` returns: (frames written, seconds, error text or None, frames of those taken over from a
stopped render's checkpoints instead of rendered)."""


def first_frames(job: Job, frame_count: int | None) -> range | None:
    """The frames a render of the first `frame_count` frames of `job` draws (None: all of them)."""
    return None if frame_count is None or frame_count >= job.frame_count else range(frame_count)


class JobExecutor(Protocol):
    """Where jobs run: submit `render_job` calls, wait for some to finish, read their results, cancel.

    Handles are whatever the executor returns from `submit` (a Future, a Ray ObjectRef); they must be hashable.
    """

    name: str
    """Recorded in dataset.json: "local" or "ray"."""

    def submit(
        self,
        job_json: str,
        out_dir: str,
        frames: int | None,
        scene_path: str,
        resume: bool,
        checkpoint_frames: int | None,
    ) -> Hashable:
        """Start `render_job` with these arguments; return its handle."""
        ...

    def wait(self, handles: Collection[Hashable]) -> list[Hashable]:
        """Block until at least one of `handles` has finished; return those that have."""
        ...

    def result(self, handle: Hashable) -> JobResult | None:
        """(frames, seconds, error, resumed frames) of a finished job, or None if it was cancelled or interrupted.
        A worker that died counts as the job's error."""
        ...

    def cancel(self, handles: Collection[Hashable]) -> None:
        """After a stop: stop `handles`, the running ones included, within about `STOP_GRACE_S`, and wait until
        each has settled, so `result` no longer blocks."""
        ...

    def close(self) -> None: ...


def error_text(exc: BaseException) -> str:
    """The exception's type and the last line of its message."""
    lines = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {lines[-1]}" if lines else type(exc).__name__


_worker_renderer = None
"""The worker process's one Renderer, opened on its first job and kept until the process ends."""
_in_job = False
"""Whether this worker process is rendering a job now."""


class _WorkerStop(BaseException):
    """Raised in a pool worker by SIGTERM while it renders a job: unwinding the job deletes its temporary files.
    Not an Exception, so that `_render` does not report it as the job's error."""


POOL_PRELOAD_MODULES = (
    "camgen.plan.execute",
    "camgen.render.renderer",
    "camgen.render.sequence",
    "camgen.io.video",
    "camgen.actors",
    "camgen.vehicles",
    "camgen.props",
)
"""What the local pool's fork server imports, in this order, before it forks a worker: what `render_job`
imports for the usual scenes (people, vehicles, props, a video), and under it numpy, SciPy, OpenCV,
colour-science (with its plotting and matplotlib: 1.9 s alone), pyrender and PyAV, which a spawned worker
spent about 3 s importing before its first job. camgen's modules come first: `camgen.render.gl` chooses
PyOpenGL's EGL platform before PyOpenGL is imported (pyrender first would have made it GLX). The imports
load the EGL libraries but open no display and no context, and start no Python thread; the only threads
they start are OpenBLAS's (numpy's, SciPy's and OpenCV's copies), which OpenBLAS stops before every fork
and starts again in the worker, as many, at its first BLAS call (tests/batch/test_pool_workers.py)."""


def pool_context() -> multiprocessing.context.BaseContext:
    """The local pool's "forkserver" start: a worker is forked from a server process started (once per batch
    process) by `start_pool_server`, which has imported `POOL_PRELOAD_MODULES`, and not from the batch
    process, whose threads (a progress display, the pool's own) and their locks a fork would copy."""
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(list(POOL_PRELOAD_MODULES))
    return context


def start_pool_server() -> None:
    """Start the local pool's fork server now, if it is not running, and return at once (it imports
    `POOL_PRELOAD_MODULES` in the background, about 3 s, while this process goes on); the pool's first worker
    waits for it. It ends when the batch process and every worker forked from it have ended.

    SIGINT is blocked while the server starts: a signal mask outlives exec and fork, so the server and
    every worker forked from it start with SIGINT blocked, until `init_pool_worker` ignores it; a Ctrl-C
    while the server imports or a worker starts up does not end either with a traceback. multiprocessing's
    resource tracker is started first: starting it (on the server's way) unblocks SIGINT in the caller."""
    pool_context()
    multiprocessing.resource_tracker.ensure_running()
    blocked = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        multiprocessing.forkserver.ensure_running()
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, blocked)


def init_pool_worker() -> None:
    """A pool worker's signals: SIGINT is the parent's to act on (Ctrl-C reaches the whole process group, and
    the parent then stops the workers); SIGTERM stops the worker. SIGINT was blocked until now (see
    `start_pool_server`); a SIGTERM before now ended the worker at once, before it had written anything."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _stop_worker)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    _stop_with_parent()


def _stop_with_parent() -> None:
    """Stop this worker, as SIGTERM does, when the batch process that started it ends, however it ends: a batch
    killed with SIGKILL runs no handler, and its workers must not go on rendering as orphans.

    The worker's parent process is the fork server, not the batch, and the server outlives the batch until
    its last worker has ended, so the kernel's parent-death signal (prctl PR_SET_PDEATHSIG) cannot tell.
    Instead a thread waits on `multiprocessing.parent_process().sentinel`, a pipe whose other end only the
    batch process holds: it reads as ended when the batch has ended, at once if it already had. The thread
    then sends SIGTERM to the main thread, whose handler unwinds the job (or ends an idle worker); the
    thread starts with SIGINT and SIGTERM blocked, so that it takes none sent to the process."""
    parent = multiprocessing.parent_process()
    if parent is None:
        return
    main_thread = threading.main_thread().ident

    def watch() -> None:
        multiprocessing.connection.wait([parent.sentinel])
        signal.pthread_kill(main_thread, signal.SIGTERM)

    unblocked = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        threading.Thread(target=watch, name="camgen-batch-watch", daemon=True).start()
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, unblocked)


def _stop_worker(signum: int, frame) -> None:
    if _in_job:
        # One stop is enough: a second SIGTERM must not cut short the unwinding that deletes the job's files
        # (the parent's SIGKILL after `STOP_GRACE_S` still ends a worker that does not unwind).
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        raise _WorkerStop
    os._exit(128 + signum)


def render_job(
    job_json: str,
    out_dir: str,
    frames: int | None,
    scene_path: str,
    resume: bool = False,
    checkpoint_frames: int | None = None,
) -> JobResult:
    """Runs in a worker: render one job; returns (frames, seconds, error text or None, resumed frames). A pool
    worker stopped by SIGTERM exits from here, once the job has unwound (the pool's loop would go on to the next
    job).

    resume: continue the job from the checkpoints a stopped or failed try left (`execute`'s resume), and keep
    this try's if it stops or fails too; a job directory whose manifest is of this job but whose files no longer
    pass `verify` (`run_batch` did not skip it) is rendered again from the start instead. checkpoint_frames:
    `execute`'s (None: its default); a resumed try must use the interval of the try it continues."""
    global _in_job
    try:
        _in_job = True
        try:
            return _render(job_json, out_dir, frames, scene_path, resume, checkpoint_frames)
        finally:
            _in_job = False
    except _WorkerStop:  # also when SIGTERM lands in the inner finally, before _in_job is False
        os._exit(128 + signal.SIGTERM)


def _render(
    job_json: str, out_dir: str, frames: int | None, scene_path: str, resume: bool, checkpoint_frames: int | None
) -> JobResult:
    global _worker_renderer
    from camgen.plan.execute import execute, finished_render
    from camgen.render.renderer import Renderer

    started = time.perf_counter()
    try:
        if _worker_renderer is None:
            _worker_renderer = Renderer()
        job = Job.from_json(job_json)
        chosen = first_frames(job, frames)
        results = execute(
            job,
            out_dir,
            renderer=_worker_renderer,
            frames=chosen,
            resolve_path=Path(scene_path).resolve().parent.joinpath,
            # execute refuses to resume over a finished render's manifest; one that is here although the job was
            # not skipped no longer verifies, and is rendered again.
            resume=resume and finished_render(job, out_dir, frames=chosen) is None,
            checkpoint_frames=checkpoint_frames,
        )
    except Exception as exc:  # reported to the parent as this job's error, with the traceback's last frame
        stack = traceback.extract_tb(exc.__traceback__)
        where = f" (at {Path(stack[-1].filename).name}:{stack[-1].lineno})" if stack else ""
        return 0, time.perf_counter() - started, error_text(exc) + where, 0
    frames_done = sum(result.frames for result in results)
    return frames_done, time.perf_counter() - started, None, sum(result.resumed_frames for result in results)
