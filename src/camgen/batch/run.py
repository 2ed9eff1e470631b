"""Run compiled batch jobs on a local process pool or a Ray cluster: resumable, retried, interruptible.

Both executors run the same `render_job`, so they write the same bytes; the skip, retry, record and summary
logic is shared (`run_batch` talks to a `JobExecutor`; both are in `camgen.batch.executor`). Each worker
process opens one OpenGL `Renderer` on its first job and keeps it for the rest (a context per process; the
pool's workers are forked from a fork server that has imported what a job needs, not from the batch process,
so no worker inherits the parent's OpenGL or thread state, and none spends seconds importing). A job whose
directory already holds a manifest that `verify` passes, for the same job hash and the same frames, is
skipped. Anything else is rendered again: `execute` clears stale files and writes the manifest last,
so a job that was killed half-way never looks complete. With ``resume`` (``camgen batch --resume``) a job
that a stopped batch, a failed try or a killed worker left unfinished is continued from its cameras'
checkpoints instead (`execute`'s resume: the same bytes as a render never stopped), and a try that stops or
fails keeps its checkpoints for the next.

Stopping: SIGINT (Ctrl-C, to this process or its whole process group) or SIGTERM (a service manager's
stop) stops the batch within seconds, not after the running renders. The parent alone decides: pool
workers ignore SIGINT, and the parent sends each worker SIGTERM, on which the worker unwinds its job
(its temporary ``.partial`` files are deleted, no manifest is written) and exits; one still alive after
`STOP_GRACE_S` is killed. At a batch's end the pool's idle workers end on its end-of-work message; one that
has not within `STOP_GRACE_S` is stopped the same way (a worker killed at that moment can take the pool's queue
lock with it, which the others then wait for: `PoolExecutor._shut_down`). A batch killed outright (SIGKILL)
cannot stop its workers: each stops itself, as on SIGTERM, when it sees the batch process end. The interrupted
jobs are recorded as such and a rerun renders them again. In a batch that resumes, the stopped workers keep
their jobs' ``.partial`` folders (checkpoints, spools, video segments) and so does the parent for a killed
one; a rerun with ``resume`` continues each from its last checkpoint.
"""

from __future__ import annotations

import json
import signal
import threading
import time
from collections.abc import Callable, Collection, Hashable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import camgen
from camgen.batch.executor import (
    STOP_GRACE_S,
    JobExecutor,
    JobResult,
    error_text,
    first_frames,
    init_pool_worker,
    pool_context,
    render_job,
    start_pool_server,
)
from camgen.batch.expand import BatchJob
from camgen.errors import ConfigError
from camgen.io.files import write_text_atomic
from camgen.io.manifest import JOB_NAME, read_manifest, verify
from camgen.job import Job
from camgen.plan.execute import discard_unfinished, job_directory_name, rendered_record

BATCH_MANIFEST_NAME = "dataset.json"
"""The dataset-level record in the output directory. Not manifest.json: `camgen verify OUT` would take a
directory with a manifest.json in it for a single job directory."""
README_NAME = "DATASET.md"

Status = Literal["done", "skipped", "failed", "interrupted"]


@dataclass(frozen=True)
class JobOutcome:
    """What became of one job. seconds: wall time of its last attempt in the worker (0 when skipped)."""

    batch: BatchJob
    job_id: str
    directory: Path | None
    """The job's directory; None for a job that did not compile (it has none)."""
    status: Status
    frames: int = 0
    seconds: float = 0.0
    attempts: int = 0
    error: str | None = None
    resumed_frames: int = 0
    """Of `frames`, those taken over from the checkpoints of a stopped or failed try instead of rendered."""


@dataclass(frozen=True)
class BatchSummary:
    outcomes: list[JobOutcome]
    """One per job, in the order the jobs were given."""
    wall_s: float
    stop_signal: int | None
    """The signal that stopped the batch (signal.SIGINT or signal.SIGTERM); None when it ran to the end."""
    executor: str = "local"
    """Where the jobs ran: "local" (a process pool) or "ray"."""

    @property
    def interrupted(self) -> bool:
        return self.stop_signal is not None

    def count(self, status: Status) -> int:
        return sum(outcome.status == status for outcome in self.outcomes)

    @property
    def frames(self) -> int:
        return sum(outcome.frames for outcome in self.outcomes if outcome.status == "done")

    @property
    def rendered_frames(self) -> int:
        """The done jobs' frames rendered in this run (`frames` less those resumed from checkpoints)."""
        return sum(outcome.frames - outcome.resumed_frames for outcome in self.outcomes if outcome.status == "done")

    @property
    def ok(self) -> bool:
        return not self.interrupted and all(o.status in ("done", "skipped") for o in self.outcomes)


def frames_of(job: Job, frame_count: int | None) -> int:
    """Frames a render of `job` writes, over all its cameras, for the first `frame_count` (None: all)."""
    return len(job.cameras) * (job.frame_count if frame_count is None else min(frame_count, job.frame_count))


def is_complete(job: Job, job_dir: Path, frame_count: int | None) -> bool:
    """Whether `job_dir` holds a finished, unmodified render of `job` and of these frames."""
    manifest, _ = read_manifest(job_dir)
    expected = rendered_record([camera.name for camera in job.cameras], first_frames(job, frame_count))
    if manifest is None or manifest.get("rendered") != expected:
        return False
    try:
        recorded = json.loads((job_dir / JOB_NAME).read_text(encoding="utf-8")).get("job_id")
    except (OSError, ValueError, AttributeError):
        return False
    return recorded == job.job_id and not verify(job_dir)


class PoolExecutor:
    """Jobs on a local process pool of `workers` processes, forked from the fork server
    (`camgen.batch.executor.pool_context`), which starts now if it is not running."""

    name = "local"

    def __init__(self, workers: int) -> None:
        start_pool_server()
        self._pool = ProcessPoolExecutor(max_workers=workers, mp_context=pool_context(), initializer=init_pool_worker)

    def submit(
        self,
        job_json: str,
        out_dir: str,
        frames: int | None,
        scene_path: str,
        resume: bool,
        checkpoint_frames: int | None,
    ) -> Future:
        # The pool starts a worker in submit: it asks the fork server for one, and the first waits until the
        # server has imported (`start_pool_server`). SIGINT stays blocked meanwhile, so that a Ctrl-C does not
        # cut the pool's bookkeeping short, and a server started again here (one that died) starts with it
        # blocked, as its workers then do. (Here, the signal waits for the mask to be restored.)
        unblocked = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            return self._pool.submit(render_job, job_json, out_dir, frames, scene_path, resume, checkpoint_frames)
        except BrokenProcessPool as exc:  # a worker died hard (out of memory, a crash in the driver)
            failed: Future = Future()
            failed.set_exception(exc)
            return failed
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, unblocked)

    def wait(self, handles: Collection[Future]) -> list[Future]:
        return list(wait(handles, return_when=FIRST_COMPLETED).done)

    def result(self, handle: Future) -> JobResult | None:
        return None if handle.cancelled() else _result(handle)

    def cancel(self, handles: Collection[Future]) -> None:
        # shutdown() would wait for the running renders (minutes each) and for the calls already queued to
        # the workers, which cancel_futures cannot reach; so the workers are stopped at once instead.
        self._shut_down(stop_now=True)

    def close(self) -> None:
        self._shut_down(stop_now=False)

    def _shut_down(self, *, stop_now: bool) -> None:
        """Shut the pool down and wait, boundedly, until its manager thread has ended: every worker has ended,
        every future is settled (a running one failed if its worker was stopped), the queues are freed.

        The pool's own shutdown(wait=True) sends each worker an end-of-work message through the call queue and
        joins them without a timeout. An idle worker waits in the queue holding its read lock (the others wait
        for that lock); one killed then, once the pool no longer watches for dead workers (a worker's death
        found as the last result comes in, or during the shutdown), takes the lock with it, and the others,
        hence the pool, the batch and the interpreter's exit, which joins the manager thread, wait for ever.
        So a worker still alive `STOP_GRACE_S` after the shutdown (at once with `stop_now`) is stopped:
        SIGTERM (an idle worker ends at once, a working one unwinds its job) and, `STOP_GRACE_S` later, SIGKILL.
        The pool has no public handle on its processes or its thread before Python 3.14 (terminate_workers)."""
        pool = self._pool
        workers = list((pool._processes or {}).values())
        manager, results = pool._executor_manager_thread, pool._result_queue
        pool.shutdown(wait=False, cancel_futures=True)  # wakes the manager thread; the pool lets go of all three
        if manager is not None:  # None: no worker ever started, or the pool was shut down before (a cancel)
            if not stop_now:
                manager.join(STOP_GRACE_S)  # each worker ends on its end-of-work message
            for stop in ("terminate", "kill"):
                if not manager.is_alive():
                    break
                # Signals only: the manager thread joins the workers, and a second reader of a worker's exit
                # status (the fork server's pipe) could take half of it.
                for worker in workers:
                    getattr(worker, stop)()
                manager.join(STOP_GRACE_S)
            manager.join()  # every worker has ended or been killed: the pool's last joins return
        if results is not None:
            results.close()


def check_options(
    *, workers: int, retries: int, executor: str, address: str | None, checkpoint_frames: int | None = None
) -> None:
    """ConfigError for run options `run_batch` cannot take (the CLI checks them before expanding)."""
    if workers < 1:
        raise ConfigError(f"--workers must be ≥ 1, got {workers}")
    if retries < 0:
        raise ConfigError(f"--retries must be ≥ 0, got {retries}")
    if executor not in ("local", "ray"):
        raise ConfigError(f"--executor must be local or ray, got {executor!r}")
    if address is not None and executor != "ray":
        raise ConfigError(f"--address {address} is for --executor ray; add --executor ray or leave it out")
    bad = isinstance(checkpoint_frames, bool) or not isinstance(checkpoint_frames, int | None)
    if bad or (checkpoint_frames is not None and checkpoint_frames < 1):
        # Checked here, before any worker starts, rather than by every job's `execute` in its worker.
        raise ConfigError(f"checkpoint_frames must be an integer ≥ 1 (or None), got {checkpoint_frames!r}")


def run_batch(
    jobs: Sequence[tuple[BatchJob, Job | str]],
    out_dir: str | Path,
    *,
    workers: int,
    retries: int,
    frames: int | None = None,
    description: str = "",
    on_event: Callable[[JobOutcome], None] | None = None,
    executor: Literal["local", "ray"] = "local",
    address: str | None = None,
    resume: bool = False,
    checkpoint_frames: int | None = None,
) -> BatchSummary:
    """Render each (batch job, compiled job) into ``out_dir/<scene>-<hash8>/`` with `workers` processes.

    A job given as an error text instead of a Job (it did not compile: a missing mesh file, a drawn
    value its scene rejects) is reported as failed with that text; the others go on.

    frames: render only the first N frames of each job (None: all). description: the dataset's, for
    DATASET.md. executor: "local", a process pool on this machine, or "ray", one Ray task per job on the
    cluster at `address` (None: a local Ray with `workers` CPUs); with Ray, `out_dir` and the scenes must be
    on a filesystem every node shares. A job that raises is tried again up
    to `retries` times, then reported as failed with its error; the others go on. A failed try leaves no files,
    a worker that died included (`camgen.plan.execute.discard_unfinished`). on_event(outcome) is
    called in this process as each job is skipped, done or failed. SIGINT or SIGTERM (or a KeyboardInterrupt)
    stops the batch within about `STOP_GRACE_S`: the running jobs are stopped, their partial files deleted,
    and what completed is returned (`stop_signal` set). The dataset record and DATASET.md are written at the
    end, atomically, in every case.

    resume: a job that is not complete is continued from the checkpoints an earlier stopped batch, failed try
    or killed worker left (`camgen.plan.execute.execute`'s resume), and nothing unfinished is deleted: a stop
    keeps the running jobs' ``.partial`` folders, a failed try keeps its checkpoints and the retry (or a later
    batch with resume) continues from them. Jobs without checkpoints render from their first frame; the bytes
    are those of a batch never stopped. checkpoint_frames: frames between a camera's checkpoints (None:
    `execute`'s default); it sets where the video is segmented, so a resumed batch must use the interval of
    the batch it resumes (a checkpoint of another interval is discarded and its camera rendered again).
    """
    check_options(
        workers=workers, retries=retries, executor=executor, address=address, checkpoint_frames=checkpoint_frames
    )
    out_dir = Path(out_dir)
    started = time.perf_counter()
    outcomes: dict[int, JobOutcome] = {}
    attempts = [0] * len(jobs)
    runner: JobExecutor | None = None
    running: dict[Hashable, int] = {}
    stop_signal: int | None = None

    def record(index: int, frames_done: int, seconds: float, error: str | None, resumed_frames: int) -> None:
        batch, job = jobs[index]
        status: Status = "failed" if error is not None else "done"
        directory = out_dir / job_directory_name(job)
        outcomes[index] = JobOutcome(
            batch, job.job_id, directory, status, frames_done, seconds, attempts[index], error, resumed_frames
        )
        if on_event is not None:
            on_event(outcomes[index])

    def discard(index: int) -> None:
        """Delete what an unfinished try of job `index` left (`discard_unfinished`), unless the batch resumes:
        then it is where the next try continues from."""
        if resume:
            return
        job = jobs[index][1]
        discard_unfinished(job, out_dir / job_directory_name(job))

    def submit(index: int) -> None:
        batch, job = jobs[index]
        attempts[index] += 1
        # Absolute paths: a Ray worker's working directory is not ours.
        handle = runner.submit(
            job.to_json(), str(out_dir.resolve()), frames, str(batch.scene_path.resolve()), resume, checkpoint_frames
        )
        running[handle] = index

    with _StopSignals() as signals:
        try:
            pending = []
            for index, (batch, job) in enumerate(jobs):
                if isinstance(job, str):
                    outcomes[index] = JobOutcome(batch, "", None, "failed", error=job)
                    if on_event is not None:
                        on_event(outcomes[index])
                    continue
                job_dir = out_dir / job_directory_name(job)
                if is_complete(job, job_dir, frames):
                    outcomes[index] = JobOutcome(batch, job.job_id, job_dir, "skipped", frames=frames_of(job, frames))
                    if on_event is not None:
                        on_event(outcomes[index])
                else:
                    pending.append(index)
            if pending:
                if executor == "ray":
                    from camgen.batch.ray_executor import RayExecutor

                    runner = RayExecutor(workers=workers, address=address)
                else:
                    runner = PoolExecutor(min(workers, len(pending)))
                for index in pending:
                    submit(index)
                while running:
                    for handle in runner.wait(running):
                        index = running.pop(handle)
                        result = runner.result(handle)
                        if result is None:  # a Ray task stopped by a Ctrl-C that reached its worker
                            raise KeyboardInterrupt
                        if result[2] is not None:
                            # A job that raised deleted its files as it unwound (kept them, if it resumes); a worker
                            # that died hard (out of memory, a crash in the driver; the pool then fails its other jobs
                            # too) did not.
                            discard(index)
                        if result[2] is not None and attempts[index] <= retries:
                            submit(index)
                        else:
                            record(index, *result)
            signals.disarm()  # the jobs are over: a signal now no longer cuts the shutdown or the record short
        except KeyboardInterrupt:
            stop_signal = signals.signum or signal.SIGINT
            if runner is not None:
                runner.cancel(running)
                # Jobs that were running may have finished before they were stopped; what they wrote counts.
                for handle, index in running.items():
                    result = runner.result(handle)
                    if result is not None and result[2] is None:
                        record(index, *result)
                    else:
                        # A worker that did not unwind within the grace period was killed in the middle of
                        # its job (a long draw or encode): its temporary files are deleted here instead (kept, for
                        # their checkpoints, if the batch resumes).
                        discard(index)
        finally:
            if runner is not None:
                runner.close()
    summary = BatchSummary(
        [
            outcomes.get(index)
            or (
                JobOutcome(batch, "", None, "failed", error=job)  # stopped before the scan reached it
                if isinstance(job, str)
                else JobOutcome(
                    batch, job.job_id, out_dir / job_directory_name(job), "interrupted", attempts=attempts[index]
                )
            )
            for index, (batch, job) in enumerate(jobs)
        ],
        time.perf_counter() - started,
        stop_signal,
        executor,
    )
    write_batch_record(summary, out_dir, frames, description)
    return summary


class _StopSignals:
    """While the batch runs (inside ``with``), the first SIGINT or SIGTERM raises KeyboardInterrupt in the main
    thread and is kept in `signum`; later ones, and any after `disarm`, are ignored, so that stopping (workers
    stopped, record written) is not cut short. A signal this process ignores (SIGINT in a job started with
    ``&``) stays ignored; outside the main thread, where Python cannot set handlers, nothing changes.

    The signal is kept here, not in the exception, because a blocking call in a library may turn the
    exception into a KeyboardInterrupt of its own (Ray's ``ray.wait`` does)."""

    def __init__(self) -> None:
        self.signum: int | None = None
        self._armed = True
        self._previous: dict[int, Callable | int | None] = {}

    def disarm(self) -> None:
        self._armed = False

    def _stop(self, signum: int, frame) -> None:
        if self._armed:
            self._armed = False
            self.signum = signum
            raise KeyboardInterrupt

    def __enter__(self) -> _StopSignals:
        if threading.current_thread() is threading.main_thread():
            self._previous = {signum: signal.getsignal(signum) for signum in (signal.SIGINT, signal.SIGTERM)}
            for signum, handler in self._previous.items():
                if handler is not signal.SIG_IGN:
                    signal.signal(signum, self._stop)
        return self

    def __exit__(self, *exc_info) -> None:
        for signum, handler in self._previous.items():
            if handler is not None:  # None: a handler set outside Python, which cannot be put back
                signal.signal(signum, handler)


def _result(future: Future) -> JobResult:
    """(frames, seconds, error, resumed frames) of a finished task; a worker that died (the pool is then broken,
    after a stop too) counts as the job's error. Workers ignore SIGINT, so no job ends in a KeyboardInterrupt."""
    exc = future.exception()
    if exc is not None:  # a broken pool or an unpicklable result: the job failed, the batch goes on
        return 0, 0.0, error_text(exc), 0
    return future.result()


def write_batch_record(summary: BatchSummary, out_dir: Path, frames: int | None, description: str) -> None:
    """Write ``dataset.json`` (machine-readable) and ``DATASET.md`` (for people) into `out_dir`, atomically."""
    if not summary.outcomes:
        return
    dataset_path = summary.outcomes[0].batch.dataset_path
    record = {
        "camgen_version": camgen.__version__,
        "dataset": str(dataset_path),
        "frames_limit": frames,
        "executor": summary.executor,
        "interrupted": summary.interrupted,
        "jobs": [
            {
                "name": o.batch.name,
                "scene": str(o.batch.scene_path),
                "profile": o.batch.profile,
                "seed": o.batch.seed,
                "randomized": o.batch.randomized,
                "directory": None if o.directory is None else o.directory.name,
                "status": o.status,
                "job_id": o.job_id,
                "frames": o.frames,
                "seconds": round(o.seconds, 3),
                "attempts": o.attempts,
                "resumed_frames": o.resumed_frames,
                "error": o.error,
            }
            for o in summary.outcomes
        ],
    }
    write_text_atomic(out_dir / BATCH_MANIFEST_NAME, json.dumps(record, indent=1, ensure_ascii=False) + "\n")
    write_text_atomic(out_dir / README_NAME, dataset_markdown(summary, description, out_dir))


def dataset_markdown(summary: BatchSummary, dataset_description: str, out_dir: Path) -> str:
    """DATASET.md: what the dataset is, how many jobs ended how, a table of jobs, how to check the files."""
    dataset_path = summary.outcomes[0].batch.dataset_path
    counts = ", ".join(
        f"{summary.count(status)} {status}"
        for status in ("done", "skipped", "failed", "interrupted")
        if summary.count(status)
    )
    lines = [
        f"# Dataset {dataset_path.stem}",
        "",
        dataset_description or "(no description in the dataset file)",
        "",
        f"Generated by camgen {camgen.__version__} from `{dataset_path}`: {len(summary.outcomes)} jobs ({counts}).",
        "",
        "| job | directory | scene | profile | seed | frames | status |",
        "|---|---|---|---|---|---|---|",
    ]
    for o in summary.outcomes:
        profile = o.batch.profile or "(scene's own)"
        status = o.status if o.error is None else f"{o.status}: {o.error}"
        directory = "–" if o.directory is None else o.directory.name
        lines.append(
            f"| {o.batch.name} | {directory} | {o.batch.scene_path.name} | {profile} | {o.batch.seed} "
            f"| {o.frames if o.status in ('done', 'skipped') else '–'} | {status.replace('|', '/')} |"
        )
    lines += [
        "",
        "Each job directory holds a manifest.json with the SHA-256 of every file. To check them all:",
        "",
        f"    camgen verify {out_dir}",
        "",
    ]
    return "\n".join(lines)
