"""A batch stopped mid-run and resumed ends byte for byte as an uninterrupted run, with no duplicate or
partial outputs. A stop signal (SIGINT to the whole process group, as a terminal's Ctrl-C sends it; SIGINT or
SIGTERM to the batch process alone, as a service manager's stop does) ends the batch within seconds, its
workers with it, leaking nothing; SIGKILL of one worker process fails the jobs the broken pool lost. The
interrupted batch runs as its own process (`python -m camgen.cli.main batch …`)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from camgen.batch.dataset_files import CARD_PLOTS_DIR
from camgen.cli.main import main
from tests.batch.conftest import make_dataset
from tests.batch.test_run import job_files, statuses

pytestmark = pytest.mark.opengl

DATASET = """\
description: four jobs of ten frames, long enough to be interrupted
scenes: [scenes/walk.yaml]
profiles: [small, wide]
seeds: {start: 0, count: 2}
combine: product
"""
WORKERS = ["--workers", "2"]
TIMEOUT_S = 120
STOP_BOUND_S = 10.0
"""A stopped batch, its workers included, must have exited within this. A correctness bound, not a benchmark:
it takes about 1 s; before the workers were stopped, the batch waited for the renders they had started."""


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory) -> dict[str, bytes]:
    workspace = tmp_path_factory.mktemp("uninterrupted")
    dataset = make_dataset(workspace, DATASET)
    assert main(["batch", str(dataset), "-o", str(workspace / "out"), *WORKERS]) == 0
    return job_files(workspace / "out")


def start_batch(dataset: Path, out: Path) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "camgen.cli.main", "batch", str(dataset), "-o", str(out), *WORKERS],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,  # its own process group, to signal as a terminal would
        # A test run started in the background (`make test &`) has SIGINT ignored, and a child
        # inherits that: Python then installs no KeyboardInterrupt handler and Ctrl-C would be lost.
        preexec_fn=_default_sigint,
    )


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def wait_for(condition, what: str) -> None:
    deadline = time.monotonic() + TIMEOUT_S
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.05)


def finished_jobs(out: Path) -> int:
    return len(list(out.glob("*/manifest.json"))) if out.is_dir() else 0


def children_of(pid: int) -> dict[int, bytes]:
    """`pid`'s child processes and their command lines (the pool's workers, multiprocessing's resource tracker)."""
    children = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            cmdline = (entry / "cmdline").read_bytes().replace(b"\0", b" ")
        except (OSError, IndexError, ValueError):
            continue
        if ppid == pid:
            children[int(entry.name)] = cmdline
    return children


def workers_of(pid: int) -> list[int]:
    """The pool's worker processes: the children of `pid`'s fork server (`pid`'s children are that server and
    multiprocessing's resource tracker)."""
    servers = [child for child, cmdline in children_of(pid).items() if b"multiprocessing.forkserver" in cmdline]
    return [worker for server in servers for worker in children_of(server)]


def descendants_of(pid: int) -> list[int]:
    """`pid`'s children (the fork server, the resource tracker) and the pool's workers."""
    return [*children_of(pid), *workers_of(pid)]


def is_running(pid: int) -> bool:
    """Whether process `pid` exists and is not a zombie (one that has exited, not yet reaped)."""
    try:
        return (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return False


def assert_unfinished_jobs_hold_no_files(out: Path) -> None:
    """A job directory without a manifest holds no file at all: the job's files are written at its end, and a
    worker stopped mid-job deletes the temporary ones it was writing (``.partial``)."""
    for job_dir in (path for path in out.iterdir() if path.is_dir() and path.name != CARD_PLOTS_DIR):
        if not (job_dir / "manifest.json").exists():
            files = [path.relative_to(out).as_posix() for path in job_dir.rglob("*") if path.is_file()]
            assert not files, f"an unfinished job left files: {files}"


def resume_and_compare(dataset: Path, out: Path, uninterrupted: dict[str, bytes]) -> None:
    assert main(["batch", str(dataset), "-o", str(out), *WORKERS]) == 0
    assert job_files(out) == uninterrupted
    assert set(statuses(out).values()) <= {"done", "skipped"}
    leftovers = [p.name for p in out.rglob("*") if ".partial" in p.name]
    assert not leftovers, f"partial files left: {leftovers}"
    assert main(["verify", str(out)]) == 0


def rendering(out: Path) -> bool:
    """Whether a job is being written: a worker has a temporary (``.partial``) file open."""
    return out.is_dir() and any(out.rglob("*.partial*"))


def stop_batch(tmp_path: Path, signum: int, *, to_group: bool, after: Callable[[Path], bool], what: str) -> Path:
    """Start the batch, send `signum` to its process group or to it alone once `after(out)` (`what`), and check
    that it ended within STOP_BOUND_S, workers and all, with the exit code of that signal, leaking nothing and
    leaving no unfinished job's files; returns the dataset's path."""
    dataset = make_dataset(tmp_path, DATASET)
    out = tmp_path / "out"
    process = start_batch(dataset, out)
    wait_for(lambda: after(out) and len(workers_of(process.pid)) == 2, f"{what} and two workers")
    children = descendants_of(process.pid)
    signalled = time.monotonic()
    (os.killpg if to_group else os.kill)(process.pid, signum)
    try:
        # communicate returns at the end of the pipes, which every child inherited: all of them have exited.
        _, stderr = process.communicate(timeout=STOP_BOUND_S)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        for child in children:
            if is_running(child):
                os.kill(child, signal.SIGKILL)
        process.communicate()
        name = signal.Signals(signum).name
        raise AssertionError(f"the batch was still running {STOP_BOUND_S:g} s after {name}") from None
    assert time.monotonic() - signalled < STOP_BOUND_S
    assert process.returncode == 128 + signum, stderr.decode()
    wait_for(lambda: not any(is_running(child) for child in children), "the batch's child processes to end")
    assert b"Traceback" not in stderr
    assert b"leaked" not in stderr, stderr.decode()  # multiprocessing's resource tracker on lost semaphores
    assert finished_jobs(out) < 4, "the batch finished before it was interrupted; make the jobs longer"
    assert "interrupted" in statuses(out).values()
    assert_unfinished_jobs_hold_no_files(out)
    return dataset


@pytest.mark.parametrize(
    ("signum", "to_group"),
    # Ctrl-C to the whole group is the slow variant (`make test-slow`); SIGTERM to the batch alone must be
    # passed on to the workers by the batch itself, the harder case.
    [pytest.param(signal.SIGINT, True, marks=pytest.mark.slow), (signal.SIGTERM, False)],
    ids=["ctrl-c-to-the-group", "sigterm-to-the-batch-alone"],
)
def test_a_stop_signal_ends_the_batch_in_seconds_and_resume_gives_the_uninterrupted_dataset(
    tmp_path, uninterrupted, signum, to_group
):
    out = tmp_path / "out"
    dataset = stop_batch(tmp_path, signum, to_group=to_group, after=lambda out: finished_jobs(out) >= 1, what="a job")
    resume_and_compare(dataset, out, uninterrupted)
    assert "skipped" in statuses(out).values()  # the jobs done before the signal were not rendered again


def test_sigint_to_the_batch_alone_mid_render_ends_it_in_seconds(tmp_path):
    # Resuming after it is the SIGTERM case's: the batch stops the same way after either signal. Here the
    # signal comes while jobs are being written, whose temporary files the stopped workers then delete.
    stop_batch(tmp_path, signal.SIGINT, to_group=False, after=rendering, what="a job being written")


def pending_signals(pid: int) -> int:
    """The signals sent to process `pid` and not yet delivered (a stopped process's), as a bit mask."""
    status = (Path("/proc") / str(pid) / "status").read_text()
    return int(next(line.split()[1] for line in status.splitlines() if line.startswith("ShdPnd:")), 16)


def kill_a_worker_before_the_jobs_end(batch: int, out: Path) -> bool:
    """SIGKILL one of the batch's two workers while a job is unfinished, once one has finished; False if every
    job had finished first (the batch then ends as it would have).

    Both workers are stopped (SIGSTOP) while the jobs are counted, so none finishes between the count and the
    kill, and the other is let go only when the pool has found the dead worker (SIGTERM pending on the other:
    the pool stops its workers when one dies), so it cannot finish the last job before the pool fails it."""
    wait_for(
        lambda: finished_jobs(out) == 4 or (finished_jobs(out) >= 1 and len(workers_of(batch)) == 2),
        "a finished job and two workers",
    )
    stopped = []
    try:
        for worker in workers_of(batch):
            os.kill(worker, signal.SIGSTOP)
            stopped.append(worker)
        if len(stopped) < 2 or finished_jobs(out) == 4:
            return False
        killed, other = stopped
        os.kill(killed, signal.SIGKILL)
        stopped.remove(killed)
        wait_for(lambda: pending_signals(other) & 1 << (signal.SIGTERM - 1), "the pool to stop its other worker")
        return True
    except ProcessLookupError:  # a worker ended after it was listed: the batch ended its pool
        return False
    finally:
        for worker in stopped:
            try:
                os.kill(worker, signal.SIGCONT)
            except ProcessLookupError:
                pass


def test_a_killed_worker_then_resume_gives_the_uninterrupted_dataset(tmp_path, uninterrupted):
    # Before the kill, a job must have finished and another not; on a loaded machine every job can finish
    # before the test looks again, and then the batch is run again.
    for attempt in range(3):
        dataset = make_dataset(tmp_path / str(attempt), DATASET)
        out = tmp_path / str(attempt) / "out"
        process = start_batch(dataset, out)
        if kill_a_worker_before_the_jobs_end(process.pid, out):
            break
        process.communicate(timeout=TIMEOUT_S)
    else:
        raise AssertionError("the batch finished its jobs before a worker could be killed three times")
    _, stderr = process.communicate(timeout=TIMEOUT_S)
    assert process.returncode == 1, stderr.decode()  # the jobs the broken pool lost are reported as failed
    assert b"Traceback" not in stderr
    assert "failed" in statuses(out).values()
    resume_and_compare(dataset, out, uninterrupted)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the parent-death signal is Linux's prctl")
def test_workers_of_a_batch_killed_outright_stop_with_it(tmp_path):
    # SIGKILL runs no handler in the batch. Its workers' parent is the fork server, which lives on while they
    # do; each worker sees the batch end and stops as on SIGTERM, deleting the temporary files of the job it
    # was writing, instead of rendering on as an orphan; then the server ends too.
    dataset = make_dataset(tmp_path, DATASET)
    out = tmp_path / "out"
    process = start_batch(dataset, out)
    wait_for(lambda: rendering(out) and len(workers_of(process.pid)) == 2, "a job being written and two workers")
    descendants = descendants_of(process.pid)
    os.kill(process.pid, signal.SIGKILL)
    deadline = time.monotonic() + STOP_BOUND_S
    while any(is_running(pid) for pid in descendants) and time.monotonic() < deadline:
        time.sleep(0.05)
    orphans = [pid for pid in descendants if is_running(pid)]
    for pid in orphans:
        os.kill(pid, signal.SIGKILL)
    process.communicate()  # the pipes close when every descendant has exited too
    assert not orphans, "a worker went on rendering as an orphan"
    assert_unfinished_jobs_hold_no_files(out)
