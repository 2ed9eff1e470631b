"""camgen batch: worker count does not change the bytes, runs resume, failures are contained."""

from __future__ import annotations

import importlib.util
import json
import re
import shutil
from pathlib import Path

import pytest

from camgen.batch.dataset_files import CARD_PLOTS_DIR
from camgen.batch.expand import compile_batch_job, expand
from camgen.batch.run import is_complete
from camgen.cli.main import main
from camgen.plan.execute import job_directory_name
from tests.batch.conftest import make_dataset

pytestmark = pytest.mark.opengl

FRAMES = ["--frames", "2"]
needs_ray = pytest.mark.skipif(importlib.util.find_spec("ray") is None, reason="needs camgen[ray]")
TIMING_KEYS = {"seconds"}


def job_files(out: Path) -> dict[str, bytes]:
    """Every file of every job directory in `out`, by path relative to `out`."""
    return {
        path.relative_to(out).as_posix(): path.read_bytes()
        for job_dir in out.iterdir()
        if job_dir.is_dir() and job_dir.name != CARD_PLOTS_DIR
        for path in sorted(job_dir.rglob("*"))
        if path.is_file()
    }


def jobs_without_timing(out: Path) -> list[dict]:
    """dataset.json's job list, less the per-job wall times."""
    jobs = json.loads((out / "dataset.json").read_text())["jobs"]
    return [{key: value for key, value in job.items() if key not in TIMING_KEYS} for job in jobs]


def statuses(out: Path) -> dict[str, str]:
    return {job["name"]: job["status"] for job in json.loads((out / "dataset.json").read_text())["jobs"]}


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    """A workspace with the tiny dataset rendered by one worker into out/."""
    workspace = tmp_path_factory.mktemp("reference")
    dataset = make_dataset(workspace)
    assert main(["batch", str(dataset), "-o", str(workspace / "out"), "--workers", "1", *FRAMES]) == 0
    return workspace


def copy_of(reference: Path, tmp_path: Path) -> Path:
    workspace = tmp_path / "copy"
    shutil.copytree(reference, workspace)
    return workspace


def test_a_run_writes_four_verified_jobs_and_a_dataset_record(reference, capsys):
    out = reference / "out"
    assert set(statuses(out).values()) == {"done"} and len(statuses(out)) == 4
    assert len([p for p in out.iterdir() if p.is_dir() and p.name != CARD_PLOTS_DIR]) == 4
    readme = (out / "DATASET.md").read_text()
    assert "a walker seen through two small cameras" in readme and f"camgen verify {out}" in readme
    assert "| walk-wide-seed4 |" in readme
    assert len(json.loads((out / "coco.json").read_text())["videos"]) == 4
    assert "| walk-wide-seed4 | cam | wide | 160×120 | 10 | 2 |" in (out / "DATASET_CARD.md").read_text()
    assert main(["verify", str(out)]) == 0


def test_two_workers_write_the_same_bytes_as_one(reference, tmp_path):
    dataset = make_dataset(tmp_path)
    assert main(["batch", str(dataset), "-o", str(tmp_path / "out"), "--workers", "2", *FRAMES]) == 0
    assert job_files(tmp_path / "out") == job_files(reference / "out")


def test_a_complete_run_is_skipped_and_a_broken_job_redone(reference, tmp_path, capsys):
    workspace = copy_of(reference, tmp_path)
    out, dataset = workspace / "out", workspace / "tiny.yaml"
    assert main(["batch", str(dataset), "-o", str(out), "--workers", "2", *FRAMES]) == 0
    assert set(statuses(out).values()) == {"skipped"}
    killed, truncated = (out / job_directory_name(compile_batch_job(job)) for job in expand(dataset)[1:3])
    (killed / "manifest.json").unlink()  # as a job killed before its end leaves it
    video = truncated / "cam" / "video.mp4"
    video.write_bytes(video.read_bytes()[:100])
    assert main(["batch", str(dataset), "-o", str(out), "--workers", "2", *FRAMES]) == 0
    assert statuses(out) == {
        "walk-small-seed3": "skipped",
        "walk-small-seed4": "done",
        "walk-wide-seed3": "done",
        "walk-wide-seed4": "skipped",
    }
    assert job_files(out) == job_files(reference / "out")
    merged, expected = (json.loads((directory / "coco.json").read_text()) for directory in (out, reference / "out"))
    assert {**merged, "info": None} == {**expected, "info": None}  # rebuilt from disk (info names the git commit)
    # Into a log (capsys's stderr is not a terminal), progress comes as lines; a frame rate once jobs are done.
    last = capsys.readouterr().err.splitlines()[-1]
    assert re.fullmatch(r"batch: 4/4 jobs \(100 %\), \d+\.\d frames/s, elapsed \d:\d\d:\d\d, ETA 0:00:00", last), last
    assert not last.startswith("batch: 4/4 jobs (100 %), 0.0 frames/s")


def test_other_frames_are_not_taken_for_a_complete_job(reference):
    batch = expand(reference / "tiny.yaml")[0]
    job = compile_batch_job(batch)
    job_dir = reference / "out" / job_directory_name(job)
    assert is_complete(job, job_dir, 2)
    assert not is_complete(job, job_dir, 3)
    assert not is_complete(compile_batch_job(expand(reference / "tiny.yaml")[1]), job_dir, 2)


def test_a_failing_job_is_retried_reported_and_the_others_complete(tmp_path, capsys):
    dataset = make_dataset(tmp_path)
    out = tmp_path / "out"
    blocked = out / job_directory_name(compile_batch_job(expand(dataset)[2]))
    blocked.mkdir(parents=True)
    (blocked / "cam").write_text("a file where the camera's directory goes")
    assert main(["batch", str(dataset), "-o", str(out), "--workers", "2", "--retries", "1", *FRAMES]) == 1
    jobs = {job["name"]: job for job in json.loads((out / "dataset.json").read_text())["jobs"]}
    failed = jobs.pop("walk-wide-seed3")
    assert failed["status"] == "failed" and failed["attempts"] == 2
    assert failed["error"].startswith(("FileExistsError", "NotADirectoryError")), failed["error"]
    assert {job["status"] for job in jobs.values()} == {"done"}
    assert "failed walk-wide-seed3 after 2 tries" in capsys.readouterr().err
    assert "| walk-wide-seed3 |" in (out / "DATASET.md").read_text()


# Here rather than in tests/batch/test_ray.py (the rest of Ray's tests): the local pool's output it is compared
# with is this module's `reference`, rendered once for the module (--dist loadfile keeps a module on one process).
# In its own file the test rendered the pool's output again, a third of its time.
@needs_ray
def test_a_local_ray_cluster_writes_the_same_bytes_as_the_local_pool(reference, tmp_path, monkeypatch):
    # Without --address camgen starts a Ray of its own, even where RAY_ADDRESS names a cluster (Ray would
    # connect there and refuse the CPU count): here one nobody listens at.
    monkeypatch.setenv("RAY_ADDRESS", "127.0.0.1:9")
    ray_dir = tmp_path / "ray"
    ray_dataset = make_dataset(ray_dir)
    args = ["batch", str(ray_dataset), "-o", str(ray_dir / "out"), "--executor", "ray", "--workers", "2", *FRAMES]
    assert main(args) == 0
    assert job_files(ray_dir / "out") == job_files(reference / "out")
    assert len(job_files(ray_dir / "out")) > 4
    ray_record = json.loads((ray_dir / "out" / "dataset.json").read_text())
    assert ray_record["executor"] == "ray"
    assert {job["status"] for job in ray_record["jobs"]} == {"done"}
    pool_jobs, ray_jobs = jobs_without_timing(reference / "out"), jobs_without_timing(ray_dir / "out")
    for job in pool_jobs + ray_jobs:  # the scene's path differs with the workspace
        job["scene"] = Path(job["scene"]).name
    assert ray_jobs == pool_jobs
    assert main(args) == 0  # a second run skips every job, without starting Ray's workers on anything
    assert {job["status"] for job in json.loads((ray_dir / "out" / "dataset.json").read_text())["jobs"]} == {"skipped"}
