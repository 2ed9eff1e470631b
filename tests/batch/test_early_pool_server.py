"""`camgen batch` on the local pool starts its fork server before importing what the batch itself needs, so that
the server's imports (about 3 s) overlap its own; a plan (``--plan``) or a Ray batch starts none."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from tests.batch.conftest import make_dataset

PROBE = """\
import sys
import camgen.batch.executor as executor

def early():
    print("started; camgen.batch.run imported:", "camgen.batch.run" in sys.modules, flush=True)
    raise SystemExit(7)  # enough: nothing is rendered

executor.start_pool_server = early
from camgen.cli.main import main
sys.exit(main(sys.argv[1:]))
"""


def _batch(tmp_path: Path, *options: str) -> subprocess.CompletedProcess:
    dataset = make_dataset(tmp_path / "ds")
    command = [sys.executable, "-c", PROBE, "batch", str(dataset), "-o", str(tmp_path / "out"), *options]
    return subprocess.run(command, capture_output=True, text=True, timeout=120, cwd=Path(__file__).parents[2])


def test_the_local_pool_server_starts_before_the_batch_imports(tmp_path):
    done = _batch(tmp_path, "--workers", "1")
    assert done.returncode == 7, done.stderr[-2000:]
    assert done.stdout.strip() == "started; camgen.batch.run imported: False"


def test_a_plan_starts_no_server(tmp_path):
    done = _batch(tmp_path, "--plan")
    assert done.returncode == 0, done.stderr[-2000:]
    assert "started" not in done.stdout and "walk" in done.stdout
