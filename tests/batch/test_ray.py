"""camgen batch --executor ray: a bad address fails cleanly, and a missing Ray says what to install. That a local
Ray cluster writes the same bytes as the local pool is tests/batch/test_run.py's (it compares with that module's
pool output)."""

from __future__ import annotations

import sys
import time

import pytest

from camgen.cli.main import main
from tests.batch.conftest import make_dataset
from tests.batch.test_run import FRAMES, needs_ray

pytestmark = pytest.mark.opengl


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
