"""manifest.json: the resolved job and every file's hash; verify finds modified, missing and extra files."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.errors import ConfigError
from camgen.io import manifest as manifest_module
from camgen.io.manifest import (
    MANIFEST_NAME,
    build_manifest,
    file_sha256,
    find_job_directories,
    manifest_text,
    read_manifest,
    verify,
    write_manifest,
)
from camgen.plan import Job, compile_scene
from tests.conftest import SCENE, write

VIDEO_BYTES = 2_500_000
"""More than two hashing chunks, so chunk boundaries are exercised."""


def compile_walk(workspace: Path) -> Job:
    return compile_scene(load_scene(write(workspace, "scenes/walk.yaml", SCENE)))


def fake_job_dir(job: Job, out: Path, *, seed: int = 0) -> Path:
    """A job directory as a render leaves it (video, camera states, job.json), with its manifest."""
    job_dir = out / f"{job.scene_name}-{job.job_id[:8]}"
    camera_dir = job_dir / job.cameras[0].name
    camera_dir.mkdir(parents=True)
    video = np.random.default_rng(seed).integers(0, 256, VIDEO_BYTES, dtype=np.uint8)
    (camera_dir / "video.mp4").write_bytes(video.tobytes())
    (camera_dir / "camera.jsonl").write_text('{"frame":0}\n{"frame":1}\n')
    (camera_dir / "passes").mkdir()
    (camera_dir / "passes" / "instances.json").write_text("[]")
    (job_dir / "job.json").write_text(job.to_json())
    write_manifest(job, job_dir)
    return job_dir


@pytest.fixture
def job(workspace: Path) -> Job:
    return compile_walk(workspace)


@pytest.fixture
def job_dir(job: Job, workspace: Path) -> Path:
    return fake_job_dir(job, workspace / "out")


def test_manifest_records_the_resolved_job(job, job_dir):
    manifest = json.loads((job_dir / MANIFEST_NAME).read_text())
    dumped = job.model_dump(mode="json", by_alias=True)
    assert manifest["manifest_version"] == 1
    assert manifest["camgen_version"] == job.camgen_version
    assert manifest["job_id"] == job.job_id == job.content_hash()
    assert (manifest["scene_name"], manifest["seed"]) == ("walk", 1)
    assert (manifest["frame_count"], manifest["fps"]) == (job.frame_count, job.fps)
    assert manifest["scene"] == dumped["scene"]
    assert manifest["settings"] == dumped["settings"]
    (camera,) = manifest["cameras"]
    assert camera == {
        "name": "cam",
        "profile_name": "fixed",
        "serial": job.cameras[0].serial,
        "profile": dumped["cameras"][0]["profile"],
    }
    assert "states" not in camera  # per-frame states stay in job.json and camera.jsonl


def test_manifest_lists_every_file_but_itself_with_hash_and_size(job_dir):
    files = json.loads((job_dir / MANIFEST_NAME).read_text())["files"]
    assert list(files) == ["cam/camera.jsonl", "cam/passes/instances.json", "cam/video.mp4", "job.json"]
    for name, entry in files.items():
        data = (job_dir / name).read_bytes()
        assert entry == {"sha256": hashlib.sha256(data).hexdigest(), "size_bytes": len(data)}


def test_manifest_is_byte_identical_across_builds_and_places(job, job_dir, tmp_path):
    first = (job_dir / MANIFEST_NAME).read_bytes()
    write_manifest(job, job_dir)
    assert (job_dir / MANIFEST_NAME).read_bytes() == first
    elsewhere = tmp_path / "elsewhere" / job_dir.name
    shutil.copytree(job_dir, elsewhere)
    assert manifest_text(build_manifest(job, elsewhere)).encode() == first
    assert str(job_dir) not in first.decode()  # no absolute paths, so no dependence on where it ran


def test_manifest_is_written_atomically_and_ends_with_newline(job_dir):
    assert not [p for p in job_dir.rglob("*") if ".partial" in p.name]
    assert (job_dir / MANIFEST_NAME).read_text().endswith("}\n")


def test_verify_passes_an_untouched_job(job_dir):
    assert verify(job_dir) == []


def test_verify_reports_one_changed_byte(job_dir):
    video = job_dir / "cam" / "video.mp4"
    data = bytearray(video.read_bytes())
    data[VIDEO_BYTES // 2] ^= 0x01
    video.write_bytes(bytes(data))
    (problem,) = verify(job_dir)
    assert (problem.path, problem.kind) == ("cam/video.mp4", "modified")
    assert "content differs" in problem.message


def test_verify_reports_a_changed_size(job_dir):
    with open(job_dir / "cam" / "camera.jsonl", "a") as handle:
        handle.write("\n")
    (problem,) = verify(job_dir)
    assert (problem.path, problem.kind) == ("cam/camera.jsonl", "modified")
    assert "size 25 B, the manifest says 24 B" in problem.message


def test_verify_reports_a_missing_file(job_dir):
    (job_dir / "cam" / "passes" / "instances.json").unlink()
    (problem,) = verify(job_dir)
    assert (problem.path, problem.kind) == ("cam/passes/instances.json", "missing")


def test_verify_reports_a_stray_partial_file(job_dir):
    (job_dir / "cam" / ".video.abc123.partial.mp4").write_bytes(b"\0" * 10)
    (problem,) = verify(job_dir)
    assert (problem.path, problem.kind) == ("cam/.video.abc123.partial.mp4", "extra")


def test_verify_reports_every_problem_in_path_order(job_dir):
    (job_dir / "job.json").unlink()
    (job_dir / "cam" / "camera.jsonl").write_text("changed")
    (job_dir / "notes.txt").write_text("added")
    assert [(p.path, p.kind) for p in verify(job_dir)] == [
        ("cam/camera.jsonl", "modified"),
        ("job.json", "missing"),
        ("notes.txt", "extra"),
    ]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('{"files": {"cam/video.mp4": {"sha256": ', "not valid JSON (line 1, column 40: Expecting value)"),
        ("[1, 2]", "no 'files' table"),
        ('{"files": {"../job.json": {"sha256": "' + "0" * 64 + '", "size_bytes": 1}}}', "not a relative path"),
        ('{"files": {"job.json": {"sha256": "xyz", "size_bytes": 1}}}', "sha256 must be 64 lowercase hex"),
        ('{"files": {"job.json": {"sha256": "' + "0" * 64 + '", "size_bytes": -1}}}', "size_bytes must be an integer"),
    ],
)
def test_verify_reports_a_corrupt_manifest(job_dir, text, message):
    (job_dir / MANIFEST_NAME).write_text(text)
    (problem,) = verify(job_dir)
    assert (problem.path, problem.kind) == (MANIFEST_NAME, "manifest")
    assert message in problem.message


def test_verify_reports_a_missing_manifest(job_dir):
    (job_dir / MANIFEST_NAME).unlink()
    (problem,) = verify(job_dir)
    assert (problem.path, problem.kind) == (MANIFEST_NAME, "manifest")
    assert problem.message.startswith("missing")
    assert read_manifest(job_dir)[0] is None


def test_verify_reports_progress_up_to_the_total(job_dir):
    calls = []
    assert verify(job_dir, on_progress=lambda done, total: calls.append((done, total))) == []
    total = sum(entry["size_bytes"] for entry in read_manifest(job_dir)[0]["files"].values())
    assert calls[0] == (0, total) and calls[-1] == (total, total)
    assert len(calls) > 4  # the video is read in several chunks
    assert [done for done, _ in calls] == sorted(done for done, _ in calls)


def test_file_sha256_reads_in_chunks(tmp_path, monkeypatch):
    monkeypatch.setattr(manifest_module, "CHUNK_BYTES", 1000)
    data = np.random.default_rng(3).integers(0, 256, 10_500, dtype=np.uint8).tobytes()
    path = tmp_path / "blob"
    path.write_bytes(data)
    chunks = []
    assert file_sha256(path, chunks.append) == hashlib.sha256(data).hexdigest()
    assert chunks == [1000] * 10 + [500]
    path.write_bytes(b"")
    assert file_sha256(path) == hashlib.sha256(b"").hexdigest()


def test_find_job_directories(job, job_dir, workspace):
    out = job_dir.parent
    assert find_job_directories(job_dir) == [job_dir]
    assert find_job_directories(job_dir / MANIFEST_NAME) == [job_dir]
    assert find_job_directories(out) == [job_dir]
    stopped = out / "walk-0123abcd"  # a render that stopped before job.json and the manifest
    (stopped / "cam").mkdir(parents=True)
    (out / "logs").mkdir()
    assert find_job_directories(out) == [stopped, job_dir]
    assert find_job_directories(stopped) == [stopped]
    assert verify(stopped)[0].kind == "manifest"


@pytest.mark.parametrize(
    ("name", "message"),
    [("absent", "no such file or directory"), ("file.txt", "is a file"), ("empty", "nothing to verify")],
)
def test_find_job_directories_rejects_what_holds_no_job(tmp_path, name, message):
    (tmp_path / "file.txt").write_text("")
    (tmp_path / "empty" / "cam").mkdir(parents=True)
    with pytest.raises(ConfigError, match=message):
        find_job_directories(tmp_path / name)
