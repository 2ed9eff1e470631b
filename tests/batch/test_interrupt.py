"""A batch killed mid-run and resumed ends byte for byte as an uninterrupted run, with no duplicate or
partial outputs: Ctrl-C (SIGINT to the whole process group, as a terminal sends it) and SIGKILL of one
worker process. The interrupted batch runs as its own process (`python -m camgen.cli.main batch …`)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from camgen.cli.main import main
from tests.batch.conftest import make_dataset
from tests.batch.test_run import job_files, statuses

pytestmark = pytest.mark.opengl

DATASET = """\
description: eight jobs of ten frames, long enough to be interrupted
scenes: [scenes/walk.yaml]
profiles: [small, wide]
seeds: {start: 0, count: 4}
combine: product
"""
WORKERS = ["--workers", "2"]
TIMEOUT_S = 120


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


def workers_of(pid: int) -> list[int]:
    """The pool's worker processes among `pid`'s children (not multiprocessing's resource tracker)."""
    children = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            cmdline = (entry / "cmdline").read_bytes().replace(b"\0", b" ")
        except (OSError, IndexError, ValueError):
            continue
        if ppid == pid and b"spawn_main" in cmdline:
            children.append(int(entry.name))
    return children


def resume_and_compare(dataset: Path, out: Path, uninterrupted: dict[str, bytes]) -> None:
    assert main(["batch", str(dataset), "-o", str(out), *WORKERS]) == 0
    assert job_files(out) == uninterrupted
    assert set(statuses(out).values()) <= {"done", "skipped"}
    leftovers = [p.name for p in out.rglob("*") if ".partial" in p.name]
    assert not leftovers, f"partial files left: {leftovers}"
    assert main(["verify", str(out)]) == 0


def test_ctrl_c_then_resume_gives_the_uninterrupted_dataset(tmp_path, uninterrupted):
    dataset = make_dataset(tmp_path, DATASET)
    out = tmp_path / "out"
    process = start_batch(dataset, out)
    wait_for(lambda: finished_jobs(out) >= 1, "a first finished job")
    os.killpg(process.pid, signal.SIGINT)
    _, stderr = process.communicate(timeout=TIMEOUT_S)
    assert process.returncode == 130, stderr.decode()
    assert b"Traceback" not in stderr
    assert finished_jobs(out) < 8, "the batch finished before it was interrupted; make the jobs longer"
    assert "interrupted" in statuses(out).values()
    resume_and_compare(dataset, out, uninterrupted)


def test_a_killed_worker_then_resume_gives_the_uninterrupted_dataset(tmp_path, uninterrupted):
    dataset = make_dataset(tmp_path, DATASET)
    out = tmp_path / "out"
    process = start_batch(dataset, out)
    wait_for(lambda: finished_jobs(out) >= 1 and workers_of(process.pid), "a finished job and a busy worker")
    os.kill(workers_of(process.pid)[0], signal.SIGKILL)
    _, stderr = process.communicate(timeout=TIMEOUT_S)
    assert process.returncode == 1, stderr.decode()  # the jobs the broken pool lost are reported as failed
    assert b"Traceback" not in stderr
    assert "failed" in statuses(out).values()
    resume_and_compare(dataset, out, uninterrupted)
