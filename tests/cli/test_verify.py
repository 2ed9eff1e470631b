"""camgen verify: 0 when every job matches its manifest, 1 naming each bad file, 2 for a bad path."""

from __future__ import annotations

import pytest

from camgen.cli.main import main
from camgen.io.manifest import MANIFEST_NAME
from tests.io.test_manifest import compile_walk, fake_job_dir


@pytest.fixture
def out(workspace):
    """An output directory holding two rendered jobs of the same scene (different content)."""
    job = compile_walk(workspace)
    out = workspace / "out"
    fake_job_dir(job, out)
    other = job.model_copy(update={"seed": 2})
    fake_job_dir(other.model_copy(update={"job_id": other.content_hash()}), out, seed=1)
    return out


def test_verify_passes_untouched_jobs(out, capsys):
    assert main(["verify", str(out)]) == 0
    stdout = capsys.readouterr().out
    assert stdout.count("ok") == 2 and "(4 files, 2.5 MB)" in stdout


def test_verify_takes_a_job_directory(out, capsys):
    job_dir = sorted(out.iterdir())[0]
    assert main(["verify", str(job_dir)]) == 0
    assert f"ok  {job_dir} (4 files" in capsys.readouterr().out


def test_verify_names_each_bad_file(out, capsys):
    first, second = sorted(out.iterdir())
    (first / "cam" / "camera.jsonl").write_text("changed\n")
    (second / "cam" / "video.mp4").unlink()
    (second / "cam" / ".video.x.partial.mp4").write_bytes(b"\0")
    assert main(["verify", str(out)]) == 1
    captured = capsys.readouterr()
    assert f"modified {first}/cam/camera.jsonl: size 8 B, the manifest says 24 B" in captured.err
    assert f"missing {second}/cam/video.mp4" in captured.err
    assert f"extra {second}/cam/.video.x.partial.mp4" in captured.err
    assert "2 of 2 job(s) failed verification" in captured.err
    assert captured.out == ""


def test_verify_fails_on_a_corrupt_manifest(out, capsys):
    job_dir = sorted(out.iterdir())[0]
    (job_dir / MANIFEST_NAME).write_text("{")
    assert main(["verify", str(job_dir)]) == 1
    err = capsys.readouterr().err
    assert f"manifest {job_dir}/manifest.json: not valid JSON" in err
    assert "Traceback" not in err


@pytest.mark.parametrize(("name", "message"), [("absent", "no such file"), ("file.txt", "is a file")])
def test_verify_rejects_a_bad_path(workspace, capsys, name, message):
    (workspace / "file.txt").write_text("")
    assert main(["verify", str(workspace / name)]) == 2
    assert message in capsys.readouterr().err
