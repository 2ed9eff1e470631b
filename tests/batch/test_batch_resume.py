"""`camgen batch --resume` (issue 23): a job a stopped batch or a failed try left unfinished is continued from
its checkpoints instead of deleted and rendered again, and every job ends as the bytes of a batch never stopped.

The dataset: one 160×120 camera with a GOP of 3 frames, two seeds, 20 frames a job, checkpoints every 3 frames
(`run_batch`'s checkpoint_frames; the CLI keeps `execute`'s default, which these short jobs never reach). The
reference is a batch never stopped, rendered by the process pool. A job is stopped by SIGTERM to a batch that runs
as its own process, or made to raise once, a frame after its first checkpoint, in a batch whose jobs run in this
process (`InlineExecutor`, so that the monkeypatch reaches them).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
from concurrent.futures import Future
from pathlib import Path

import pytest

import camgen.batch.executor
import camgen.batch.run
import camgen.plan.execute
from camgen.batch.executor import render_job
from camgen.batch.expand import compile_dataset
from camgen.batch.run import run_batch
from camgen.cli.main import main
from camgen.plan.execute import CHECKPOINT_NAME, PARTIAL_SUFFIX, read_checkpoint
from tests.batch.conftest import SMALL_PROFILE, make_dataset
from tests.batch.test_interrupt import TIMEOUT_S, is_running, wait_for
from tests.batch.test_run import job_files, needs_ray
from tests.batch.test_stop_cleanup import CrashedWorkers, KilledWorkers
from tests.conftest import SCENE, write

pytestmark = pytest.mark.opengl

FRAMES = 20
CHECKPOINT_FRAMES = 3
DATASET = """\
description: one small camera with a short GOP, two seeds
scenes: [scenes/walk.yaml]
profiles: [small]
seeds: [3, 4]
combine: product
"""
BATCH_SCRIPT = """\
import sys

from camgen.batch.expand import compile_dataset
from camgen.batch.run import run_batch

if __name__ == "__main__":
    dataset, out, checkpoint_frames = sys.argv[1], sys.argv[2], int(sys.argv[3])
    jobs = [(batch, job if not isinstance(job, Exception) else str(job)) for batch, job in compile_dataset(dataset)]
    summary = run_batch(jobs, out, workers=1, retries=0, resume=True, checkpoint_frames=checkpoint_frames)
    sys.exit(0 if summary.stop_signal is None else 128 + summary.stop_signal)
"""


def make_workspace(directory: Path) -> Path:
    """The dataset's files in `directory`; returns the dataset's path."""
    for name in ("fixed", "small"):  # the scene's camera names fixed; the dataset puts small in its place
        write(directory, f"profiles/{name}.yaml", SMALL_PROFILE + "codec:\n  gop_frames: 3\n")
    write(directory, "scenes/walk.yaml", SCENE.replace("duration_s: 1", f"duration_s: {FRAMES / 10}"))
    return write(directory, "tiny.yaml", DATASET)


def compiled(dataset: Path) -> list:
    jobs = compile_dataset(dataset)
    problems = [str(job) for _, job in jobs if isinstance(job, Exception)]
    assert not problems, problems
    return jobs


def run(dataset: Path, out: Path, **options) -> camgen.batch.run.BatchSummary:
    return run_batch(compiled(dataset), out, workers=1, checkpoint_frames=CHECKPOINT_FRAMES, **options)


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> dict[str, bytes]:
    """Every job file of the batch never stopped (the process pool, no resume)."""
    workspace = tmp_path_factory.mktemp("never-stopped")
    summary = run(make_workspace(workspace), workspace / "out", retries=0)
    assert [o.status for o in summary.outcomes] == ["done", "done"]
    assert [o.frames for o in summary.outcomes] == [FRAMES, FRAMES]
    return job_files(workspace / "out")


class InlineExecutor:
    """A `JobExecutor` that runs each job in this process as it is submitted (the pool's `render_job`)."""

    name = "local"

    def __init__(self, workers: int) -> None:
        self.submitted: list[bool] = []
        """Each submit's resume."""

    def submit(self, job_json, out_dir, frames, scene_path, resume, checkpoint_frames) -> Future:
        self.submitted.append(resume)
        handle: Future = Future()
        handle.set_result(render_job(job_json, out_dir, frames, scene_path, resume, checkpoint_frames))
        return handle

    def wait(self, handles):
        return list(handles)

    def result(self, handle):
        return handle.result()

    def cancel(self, handles) -> None:
        pass

    def close(self) -> None:
        pass


class JobError(RuntimeError):
    pass


@pytest.fixture
def inline(monkeypatch, renderer):
    """Jobs run in this process, on the test session's renderer."""
    monkeypatch.setattr(camgen.batch.run, "PoolExecutor", InlineExecutor)
    monkeypatch.setattr(camgen.batch.executor, "_worker_renderer", renderer)


@pytest.fixture
def fail_once(monkeypatch):
    """The first job rendered raises JobError once, while it writes the frame after its first checkpoint (the
    video segment after it started, the spools a line longer than the checkpoint says)."""
    write_files = camgen.plan.execute._write_files
    raised = []

    def failing(context, stages, state, frame, captured, rgb8, stream, result):
        if not raised and result.frames == CHECKPOINT_FRAMES + 1:
            raised.append(frame.index)
            raise JobError("a job error after its first checkpoint")
        return write_files(context, stages, state, frame, captured, rgb8, stream, result)

    monkeypatch.setattr(camgen.plan.execute, "_write_files", failing)
    return raised


def kept_checkpoints(out: Path) -> list:
    return [read_checkpoint(path) for path in sorted(out.glob(f"*/*{PARTIAL_SUFFIX}/{CHECKPOINT_NAME}"))]


def assert_as_never_stopped(out: Path, reference: dict[str, bytes]) -> None:
    assert job_files(out) == reference
    assert not [path.name for path in out.rglob("*") if PARTIAL_SUFFIX in path.name or path.name == CHECKPOINT_NAME]
    assert main(["verify", str(out)]) == 0


def test_a_retry_after_a_job_error_resumes_from_the_checkpoint(tmp_path, inline, fail_once, reference):
    out = tmp_path / "out"
    summary = run(make_workspace(tmp_path), out, retries=1, resume=True)
    assert fail_once, "no job raised"
    first, second = summary.outcomes
    assert (first.status, first.attempts, first.frames, first.resumed_frames) == ("done", 2, FRAMES, CHECKPOINT_FRAMES)
    assert (second.status, second.attempts, second.resumed_frames) == ("done", 1, 0)
    assert_as_never_stopped(out, reference)
    record = json.loads((out / "dataset.json").read_text())["jobs"]
    assert [job["resumed_frames"] for job in record] == [CHECKPOINT_FRAMES, 0]


def test_without_resume_a_retry_after_a_job_error_renders_from_the_start(tmp_path, inline, fail_once, reference):
    out = tmp_path / "out"
    summary = run(make_workspace(tmp_path), out, retries=1)
    assert fail_once, "no job raised"
    first, _ = summary.outcomes
    assert (first.status, first.attempts, first.resumed_frames) == ("done", 2, 0)
    assert_as_never_stopped(out, reference)


def test_a_failed_job_keeps_its_checkpoint_for_a_later_batch_with_resume(tmp_path, inline, fail_once, reference):
    dataset, out = make_workspace(tmp_path), tmp_path / "out"
    failed, done = run(dataset, out, retries=0, resume=True).outcomes
    assert (failed.status, done.status) == ("failed", "done")
    assert "JobError: a job error after its first checkpoint" in failed.error
    (checkpoint,) = kept_checkpoints(out)
    assert (checkpoint.frames_done, checkpoint.complete) == (CHECKPOINT_FRAMES, False)
    resumed, skipped = run(dataset, out, retries=0, resume=True).outcomes
    assert (resumed.status, resumed.resumed_frames, skipped.status) == ("done", CHECKPOINT_FRAMES, "skipped")
    assert_as_never_stopped(out, reference)


def test_without_resume_a_failed_job_leaves_no_files(tmp_path, inline, fail_once):
    out = tmp_path / "out"
    failed, done = run(make_workspace(tmp_path), out, retries=0).outcomes
    assert (failed.status, done.status) == ("failed", "done")
    assert not failed.directory.exists()


def test_a_finished_job_whose_files_changed_is_rendered_again_with_resume(tmp_path, inline, reference):
    # Not skipped (it fails verify) and not resumable (execute refuses to resume over a finished manifest).
    dataset, out = make_workspace(tmp_path), tmp_path / "out"
    first, _ = run(dataset, out, retries=0, resume=True).outcomes
    video = first.directory / "cam" / "video.mp4"  # the first job's (a glob's order is the file system's)
    video.write_bytes(b"not a video")
    again = run(dataset, out, retries=0, resume=True).outcomes
    assert [(o.status, o.resumed_frames) for o in again] == [("done", 0), ("skipped", 0)]
    assert_as_never_stopped(out, reference)


def test_sigterm_keeps_the_running_job_and_resume_continues_it(tmp_path, reference):
    dataset, out = make_workspace(tmp_path), tmp_path / "out"
    script = write(tmp_path, "batch.py", textwrap.dedent(BATCH_SCRIPT))
    process = subprocess.Popen(
        [sys.executable, str(script), str(dataset), str(out), str(CHECKPOINT_FRAMES)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )
    try:
        # The first job's first checkpoint: 17 frames of it are still to render when the signal comes.
        wait_for(lambda: bool(kept_checkpoints(out)), "the first checkpoint")
        os.kill(process.pid, signal.SIGTERM)
        _, stderr = process.communicate(timeout=TIMEOUT_S)
    finally:
        if is_running(process.pid):
            os.killpg(process.pid, signal.SIGKILL)
            process.communicate()
    assert process.returncode == 128 + signal.SIGTERM, stderr.decode()
    assert b"Traceback" not in stderr, stderr.decode()
    statuses = [job["status"] for job in json.loads((out / "dataset.json").read_text())["jobs"]]
    assert statuses == ["interrupted", "interrupted"]
    (checkpoint,) = kept_checkpoints(out)  # the stopped worker kept the running job's folder
    assert 0 < checkpoint.frames_done < FRAMES and not checkpoint.complete
    assert main(["verify", str(out)]) == 1  # a stopped dataset is not a finished one
    first, second = run(dataset, out, retries=0, resume=True).outcomes
    assert (first.status, first.resumed_frames) == ("done", checkpoint.frames_done)
    assert (second.status, second.resumed_frames) == ("done", 0)
    assert_as_never_stopped(out, reference)


@needs_ray
@pytest.mark.slow  # 31 s (a local Ray's start): `make test` keeps the pool's resume tests and Ray's same bytes
def test_ray_resumes_a_job_a_failed_try_left(tmp_path, monkeypatch, renderer, fail_once, reference):
    # The checkpoint is made in this process (`InlineExecutor`); Ray's workers, in processes of their own, take
    # the job up from it with the pool's `render_job`.
    dataset, out = make_workspace(tmp_path), tmp_path / "out"
    with monkeypatch.context() as patch:
        patch.setattr(camgen.batch.run, "PoolExecutor", InlineExecutor)
        patch.setattr(camgen.batch.executor, "_worker_renderer", renderer)
        assert [o.status for o in run(dataset, out, retries=0, resume=True).outcomes] == ["failed", "done"]
    resumed, skipped = run(dataset, out, retries=0, resume=True, executor="ray").outcomes
    assert (resumed.status, resumed.resumed_frames, skipped.status) == ("done", CHECKPOINT_FRAMES, "skipped")
    assert_as_never_stopped(out, reference)


def partial_files(out: Path) -> list[str]:
    return sorted(
        path.relative_to(out).as_posix() for path in out.rglob("*") if path.is_file() and PARTIAL_SUFFIX in str(path)
    )


def test_with_resume_a_stopped_batch_keeps_what_its_killed_workers_left(tmp_path, monkeypatch):
    # tests/batch/test_stop_cleanup.py's stand-in, without rendering: without --resume all of it is deleted.
    dataset, out = make_dataset(tmp_path), tmp_path / "out"
    monkeypatch.setattr(camgen.batch.run, "PoolExecutor", KilledWorkers)
    assert main(["batch", str(dataset), "-o", str(out), "--workers", "2", "--resume"]) == 130
    assert len(partial_files(out)) == 4  # the stand-in starts every job it is given: one frame each


def test_with_resume_a_job_whose_worker_died_keeps_its_files(tmp_path, monkeypatch):
    dataset, out = make_dataset(tmp_path), tmp_path / "out"
    monkeypatch.setattr(camgen.batch.run, "PoolExecutor", CrashedWorkers)
    assert main(["batch", str(dataset), "-o", str(out), "--workers", "2", "--retries", "1", "--resume"]) == 1
    assert len(partial_files(out)) == 4  # every job failed twice; the retry wrote over the first try's frame


@pytest.mark.parametrize("bad", [0, -3, 2.5, True, "250"])
def test_a_bad_checkpoint_interval_is_refused_before_any_worker_starts(tmp_path, bad):
    """`run_batch` refuses a checkpoint interval that is not an integer ≥ 1 with its message, before it starts a
    worker or writes anything (each job's `execute` would otherwise fail with it in its worker)."""
    from camgen.errors import ConfigError

    with pytest.raises(ConfigError, match=r"checkpoint_frames must be an integer ≥ 1"):
        run_batch([], tmp_path / "out", workers=1, retries=0, resume=True, checkpoint_frames=bad)
    assert not (tmp_path / "out").exists()
