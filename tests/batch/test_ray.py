"""camgen batch --executor ray: a local Ray cluster writes the same bytes as the local pool; a bad address fails
cleanly."""

from __future__ import annotations

import importlib.util
import json
import sys
import time
from pathlib import Path

import pytest

from camgen.cli.main import main
from tests.batch.conftest import make_dataset
from tests.batch.test_run import FRAMES, job_files

pytestmark = pytest.mark.opengl
needs_ray = pytest.mark.skipif(importlib.util.find_spec("ray") is None, reason="needs camgen[ray]")

TIMING_KEYS = {"seconds"}


def jobs_without_timing(out: Path) -> list[dict]:
    """dataset.json's job list, less the per-job wall times."""
    jobs = json.loads((out / "dataset.json").read_text())["jobs"]
    return [{key: value for key, value in job.items() if key not in TIMING_KEYS} for job in jobs]


@needs_ray
def test_a_local_ray_cluster_writes_the_same_bytes_as_the_local_pool(tmp_path):
    pool_dir, ray_dir = tmp_path / "pool", tmp_path / "ray"
    pool_dataset, ray_dataset = make_dataset(pool_dir), make_dataset(ray_dir)
    assert main(["batch", str(pool_dataset), "-o", str(pool_dir / "out"), "--workers", "2", *FRAMES]) == 0
    args = ["batch", str(ray_dataset), "-o", str(ray_dir / "out"), "--executor", "ray", "--workers", "2", *FRAMES]
    assert main(args) == 0
    assert job_files(ray_dir / "out") == job_files(pool_dir / "out")
    assert len(job_files(ray_dir / "out")) > 4
    ray_record = json.loads((ray_dir / "out" / "dataset.json").read_text())
    assert ray_record["executor"] == "ray"
    assert {job["status"] for job in ray_record["jobs"]} == {"done"}
    pool_jobs, ray_jobs = jobs_without_timing(pool_dir / "out"), jobs_without_timing(ray_dir / "out")
    for job in pool_jobs + ray_jobs:  # the scene's path differs with the workspace
        job["scene"] = Path(job["scene"]).name
    assert ray_jobs == pool_jobs
    assert main(args) == 0  # a second run skips every job, without starting Ray's workers on anything
    assert {job["status"] for job in json.loads((ray_dir / "out" / "dataset.json").read_text())["jobs"]} == {"skipped"}


@needs_ray
def test_an_unreachable_ray_address_fails_with_a_message(tmp_path, capsys):
    dataset = make_dataset(tmp_path)
    started = time.perf_counter()
    code = main(["batch", str(dataset), "-o", str(tmp_path / "out"), "--executor", "ray", "--address", "127.0.0.1:9"])
    assert code == 2
    assert time.perf_counter() - started < 20
    err = capsys.readouterr().err
    assert "--address 127.0.0.1:9" in err and "Traceback" not in err


def test_without_ray_installed_the_error_says_what_to_install(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # what `import ray` meets where it is not installed
    monkeypatch.delitem(sys.modules, "camgen.batch.ray_executor", raising=False)
    dataset = make_dataset(tmp_path)
    assert main(["batch", str(dataset), "-o", str(tmp_path / "out"), "--executor", "ray", *FRAMES]) == 2
    assert "install camgen[ray]" in capsys.readouterr().err
