"""A batch stopped while a worker is stuck (killed after the grace period, so it never unwound its job) deletes
that job's temporary files itself. No rendering: the executor is a stand-in that writes what a killed worker
leaves behind."""

from __future__ import annotations

from concurrent.futures import Future
from pathlib import Path

import camgen.batch.run as batch_run
from camgen.batch.expand import compile_dataset
from camgen.cli.main import main
from camgen.plan.execute import PARTIAL_SUFFIX, discard_unfinished, job_directory_name
from tests.batch.conftest import make_dataset


class KilledWorkers:
    """Each submitted job gets the folder a worker killed mid-frame leaves (``<camera>.partial/img1/*.jpg``);
    the first wait is interrupted, as by Ctrl-C; cancelled jobs have no result (their worker was killed)."""

    name = "local"

    def __init__(self, workers: int) -> None:
        self.submitted: list[Future] = []

    def submit(self, job_json, out_dir, frames, scene_path, resume, checkpoint_frames):
        from camgen.job import Job

        job = Job.from_json(job_json)
        for camera in job.cameras:
            frames_dir = Path(out_dir) / job_directory_name(job) / f"{camera.name}{PARTIAL_SUFFIX}" / "img1"
            frames_dir.mkdir(parents=True)
            (frames_dir / "000001.jpg").write_bytes(b"\xff\xd8")
        self.submitted.append(Future())
        return self.submitted[-1]

    def wait(self, handles):
        raise KeyboardInterrupt

    def result(self, handle):
        return None

    def cancel(self, handles):
        for handle in handles:
            handle.cancel()

    def close(self):
        pass


def test_a_stopped_batch_deletes_what_its_killed_workers_left(tmp_path, monkeypatch):
    dataset = make_dataset(tmp_path)
    out = tmp_path / "out"
    monkeypatch.setattr(batch_run, "PoolExecutor", KilledWorkers)
    assert main(["batch", str(dataset), "-o", str(out), "--workers", "2"]) == 130
    left = [path.relative_to(out).as_posix() for path in out.rglob("*") if path.is_file()]
    assert left and all(".partial" not in name and not name.startswith("walk-") for name in left), left


def test_discard_unfinished_keeps_a_finished_job(tmp_path):
    dataset = make_dataset(tmp_path)
    (_, job), *_ = compile_dataset(dataset)
    job_dir = tmp_path / job_directory_name(job)
    camera = job.cameras[0].name
    (job_dir / camera).mkdir(parents=True)
    (job_dir / camera / "gt.txt").write_text("1\n")
    (job_dir / "manifest.json").write_text("{}")
    assert not discard_unfinished(job, job_dir) and (job_dir / camera / "gt.txt").exists()
    (job_dir / "manifest.json").unlink()
    (job_dir / "job.json").write_text("{}")
    (job_dir / f"{camera}{PARTIAL_SUFFIX}").mkdir()
    (job_dir / "notes.txt").write_text("a user's file")
    assert discard_unfinished(job, job_dir)
    assert [path.name for path in job_dir.iterdir()] == ["notes.txt"]


class CrashedWorkers(KilledWorkers):
    """Each job's worker dies hard mid-frame (the kernel's OOM killer, a crash in the driver): its ``.partial``
    folder stays, and the pool reports the job failed, as `camgen.batch.run._result` does for a broken pool."""

    def submit(self, job_json, out_dir, frames, scene_path, resume, checkpoint_frames):
        from camgen.job import Job

        job = Job.from_json(job_json)
        for camera in job.cameras:  # a retry starts over where the last try left its files, as `execute` does
            frames_dir = Path(out_dir) / job_directory_name(job) / f"{camera.name}{PARTIAL_SUFFIX}" / "img1"
            frames_dir.mkdir(parents=True, exist_ok=True)
            (frames_dir / "000001.jpg").write_bytes(b"\xff\xd8")
        handle = Future()
        handle.set_result((0, 0.0, "BrokenProcessPool: A process in the process pool was terminated abruptly", 0))
        return handle

    def wait(self, handles):
        return [handle for handle in handles if handle.done()]

    def result(self, handle):
        return handle.result()


def test_a_job_whose_worker_died_leaves_no_files(tmp_path, monkeypatch):
    """No stop: the batch runs to its end with every job failed, retried once. A worker that died never unwound
    its job, so the batch deletes what it left (as `execute` deletes what a job that raised left)."""
    dataset = make_dataset(tmp_path)
    out = tmp_path / "out"
    monkeypatch.setattr(batch_run, "PoolExecutor", CrashedWorkers)
    assert main(["batch", str(dataset), "-o", str(out), "--workers", "2", "--retries", "1"]) != 0
    left = [path.relative_to(out).as_posix() for path in out.rglob("*") if path.is_file()]
    assert left and all(".partial" not in name and not name.startswith("walk-") for name in left), left
