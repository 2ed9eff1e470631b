"""Bad input to the commands (outputs that cannot be written, inputs that are not files, profile
directories that are not there, unreadable meshes and images): one clear error naming the option or
file and the fix, exit status 2, no traceback, and nothing done before it."""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np
import pytest

from camgen.cli.main import main
from tests.conftest import FIXED_PROFILE, REPO, SCENE, write

needs_proc = pytest.mark.skipif(not Path("/proc/self").exists(), reason="needs Linux /proc")


def run(argv: list[str], capsys) -> tuple[int, str, str]:
    code = main(argv)
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err
    return code, captured.out, captured.err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["render", "{scene}", "-o", "/dev/null/x"],
            "-o /dev/null/x: cannot be created: /dev/null is a character device",
        ),
        (["render", "{scene}", "-o", "{file}/sub"], "cannot be created: {file} is a file, not a directory"),
        pytest.param(
            ["render", "{scene}", "-o", "/proc/x"], "-o /proc/x: cannot be created in /proc", marks=needs_proc
        ),
        (["plan", "{scene}", "--json", "{dir}"], "--json {dir}: is a directory; give a file name"),
        (["plan", "{scene}", "--json", "/dev/null"], "--json /dev/null: is a character device"),
        (["schema", "-o", "{file}"], "-o {file}: is a file; give a directory for the <kind>.schema.json files"),
        pytest.param(["schema", "-o", "/proc/x"], "-o /proc/x: cannot be created in /proc", marks=needs_proc),
        (["batch", "{dataset}", "-o", "/dev/null/x"], "-o /dev/null/x: cannot be created: /dev/null is a character"),
        (["bench", "--write", "{file}/BENCHMARKS.md"], "its directory {file} is a file"),
    ],
)
def test_output_locations_are_checked_before_any_work(workspace, capsys, argv, message):
    scene = write(workspace, "scenes/walk.yaml", SCENE)
    (workspace / "taken").write_text("kept")
    (workspace / "folder").mkdir()
    paths = {
        "scene": scene,
        "dir": workspace / "folder",
        "file": workspace / "taken",
        "dataset": REPO / "datasets" / "parking_lot_sweep.yaml",
    }
    code, _, err = run([arg.format(**paths) for arg in argv], capsys)
    message = message.format(**paths)
    assert code == 2 and message in err
    assert (workspace / "taken").read_text() == "kept"
    assert sorted(p.name for p in workspace.iterdir()) == ["folder", "profiles", "scenes", "taken"]
    assert not list((workspace / "folder").iterdir())


def test_an_existing_plan_json_is_replaced(workspace, capsys):
    """Like every other output: an existing file under the name is replaced, not refused."""
    scene = write(workspace, "scenes/walk.yaml", SCENE)
    target = workspace / "job.json"
    target.write_text("old")
    code, _, _ = run(["plan", str(scene), "--json", str(target)], capsys)
    assert code == 0 and target.read_text().startswith("{")


@pytest.mark.parametrize("kind", ["fifo", "device", "directory", "large"])
def test_validate_refuses_what_is_not_a_yaml_file_before_opening_it(tmp_path, capsys, kind):
    """A FIFO without a writer would block the open for ever, /dev/zero never ends: os.stat first."""
    path = tmp_path / "config.yaml"
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "device":
        path = Path("/dev/zero")
    elif kind == "directory":
        path.mkdir()
    else:
        with path.open("wb") as handle:
            handle.truncate(17 * 2**20)  # sparse: no 17 MiB written
    message = {
        "fifo": "is a FIFO (named pipe), not a regular file",
        "device": "is a character device, not a regular file",
        "directory": "is a directory, not a file",
        "large": "is 17 MiB, more than a YAML config may be (16 MiB)",
    }[kind]
    code, _, err = run(["validate", str(path)], capsys)
    assert code == 1 and f"{path}: {message}" in err


@pytest.mark.parametrize(
    ("argv", "env", "message"),
    [
        (["--profiles", "/nonexistent"], None, "--profiles /nonexistent: no such directory"),
        (["--profiles", "{file}"], None, "--profiles {file}: is not a directory"),
        ([], "{file}", "$CAMGEN_PROFILE_PATH entry {file}: is not a directory"),
        ([], "/nonexistent", "$CAMGEN_PROFILE_PATH entry /nonexistent: no such directory"),
    ],
)
def test_profile_directories_must_be_directories(workspace, capsys, monkeypatch, argv, env, message):
    scene = write(workspace, "scenes/walk.yaml", SCENE)
    file = str(workspace / "profiles" / "fixed.yaml")
    if env is not None:
        monkeypatch.setenv("CAMGEN_PROFILE_PATH", env.replace("{file}", file))
    argv = [arg.replace("{file}", file) for arg in argv]
    code, _, err = run(["validate", str(scene), *argv], capsys)
    assert code == 2 and message.replace("{file}", file) in err
    assert "give a directory that holds profile YAML files" in err


def test_info_looks_up_a_profile_name(workspace, capsys, monkeypatch):
    monkeypatch.chdir(workspace)
    monkeypatch.delenv("CAMGEN_PROFILE_PATH", raising=False)
    code, out, _ = run(["info", "fixed"], capsys)
    assert code == 0 and "test fixed camera" in out
    monkeypatch.chdir(workspace / "scenes")
    code, out, _ = run(["info", "ptz", "--profiles", str(workspace / "profiles")], capsys)
    assert code == 0 and "test ptz camera" in out
    code, _, err = run(["info", "fixd", "--profiles", str(workspace / "profiles")], capsys)
    assert code == 2 and "names profile 'fixd'" in err and "did you mean 'fixed'?" in err


def _scene_with_mesh(workspace: Path, mesh_path: str) -> Path:
    mesh = "      size_m: [20, 20]\n    - {type: file, name: statue, path: MESH}\n"
    return write(
        workspace, "scenes/mesh.yaml", SCENE.replace("      size_m: [20, 20]\n", mesh.replace("MESH", mesh_path))
    )


def test_a_mesh_path_that_is_a_directory(workspace, capsys):
    (workspace / "scenes" / "statue").mkdir()
    scene = _scene_with_mesh(workspace, "statue")
    code, _, err = run(["validate", str(scene)], capsys)
    assert code == 1
    assert "mesh.yaml:9:" in err and "environment.meshes[1].path refers to 'statue'" in err
    assert "is a directory, not a file" in err and "does not exist" not in err


def test_a_corrupt_obj_is_named_as_such(workspace, capsys):
    (workspace / "scenes" / "statue.obj").write_text("v 0 0 0\nv 1 0 0\nf 1 2 3\n")  # face names a 3rd vertex
    scene = _scene_with_mesh(workspace, "statue.obj")
    code, _, err = run(["validate", str(scene)], capsys)
    assert code == 1
    assert "mesh.yaml:9:" in err and "environment.meshes[1].path cannot be read as a mesh" in err
    assert "statue.obj): the file is truncated or corrupt" in err


def test_a_truncated_jpeg_is_named_without_libjpeg_chatter(tmp_path, capfd):
    images = tmp_path / "images"
    images.mkdir()
    image = np.random.default_rng(0).integers(0, 255, (120, 160), dtype=np.uint8)
    data = cv2.imencode(".jpg", image)[1].tobytes()
    (images / "cut.jpg").write_bytes(data[: len(data) // 2])
    argv = ["fit", "lens", "--images", str(images), "--board", "checkerboard:9x6:25mm", "-o", str(tmp_path / "l.yaml")]
    assert main(argv) == 2
    err = capfd.readouterr().err
    assert "cut.jpg is truncated: its JPEG data ends after" in err and "before the end-of-image marker" in err
    assert "Premature end" not in err and "board not found" not in err


def test_a_flat_reference_has_no_noise_to_fit(tmp_path, capsys):
    (tmp_path / "base.yaml").write_text(FIXED_PROFILE)
    cv2.imwrite(str(tmp_path / "flat.png"), np.full((48, 64, 3), 128, np.uint8))
    argv = ["fit", "match", "--reference", str(tmp_path / "flat.png"), "--profile", str(tmp_path / "base.yaml")]
    code, _, err = run([*argv, "-o", str(tmp_path / "m.yaml")], capsys)
    assert code == 2
    assert f"--reference {tmp_path / 'flat.png'}: the reference shows no noise" in err
    assert "its first frame is one flat level (128 in every pixel)" in err
    assert "give the camera's own output with its noise" in err
    assert not (tmp_path / "m.yaml").exists()


def test_plan_summarises_per_frame_lists(workspace, capsys):
    scene = write(workspace, "scenes/long.yaml", SCENE.replace("duration_s: 1", "duration_s: 20"))
    code, out, _ = run(["plan", str(scene), "--force-all"], capsys)
    assert code == 0
    assert "camera_motion_px=[200 values, all 0]" in out and "0.0, 0.0, 0.0" not in out
    assert "terms=[shot, prnu" in out  # short lists of names stay as they are


def test_render_says_when_frames_exceed_the_scene(workspace, capsys, monkeypatch):
    """The warning comes before rendering; the renderer and executor are stand-ins (no OpenGL needed)."""
    import camgen.plan.execute
    import camgen.render.renderer

    class NoRenderer:
        gl_renderer = "none"

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

    rendered = []
    monkeypatch.setattr(camgen.render.renderer, "Renderer", NoRenderer)
    monkeypatch.setattr(camgen.plan.execute, "execute", lambda job, out, *, frames, **_: rendered.append(frames) or [])
    scene = write(workspace, "scenes/walk.yaml", SCENE)
    code, _, err = run(["render", str(scene), "-o", str(workspace / "out"), "--frames", "1000000"], capsys)
    assert code == 0 and rendered == [range(10)]
    assert "--frames 1000000: " in err and "has only 10 frames (duration_s 1 × fps 10); rendering those 10" in err


def _camera_output(root: Path, files: dict[str, str]) -> Path:
    """A job directory walk-0123abcd/ with one camera directory cam/ holding `files` (name → text)."""
    camera = root / "walk-0123abcd" / "cam"
    camera.mkdir(parents=True)
    (camera.parent / "manifest.json").write_text('{"fps": 10, "files": {}}')
    for name, text in files.items():
        (camera / name).write_text(text)
    return camera.parent


COCO = '{"images": [{"id": 1, "frame_index": 0, "width": 8, "height": 8}], "annotations": [], "categories": []}'


@pytest.mark.parametrize(
    ("argv", "files", "message"),
    [
        (["{root}/nothing"], None, "{root}/nothing: no such directory; give the directory `camgen render -o`"),
        (["{root}/taken"], None, "{root}/taken: is a file, not a directory; give the directory"),
        (["{root}"], None, "{root}: no camgen output in it (no job directory with manifest.json"),
        (["{root}"], {"camera.jsonl": ""}, "{job}/cam: no coco.json; the preview draws the COCO annotations"),
        (["{job}/cam"], {"coco.json": COCO}, "{job}/cam: no video.mp4 and no PNG or TIFF frames in frames/"),
        (["{job}", "--camera", "door"], {"coco.json": COCO}, "--camera door: no such camera in {job} (it has cam)"),
        (["{job}", "-o", "{root}/taken"], {"coco.json": COCO, "video.mp4": ""}, "-o {root}/taken: is a file"),
        (["{job}"], {"coco.json": "{", "video.mp4": ""}, "{job}/cam/coco.json: not valid JSON"),
        (["{job}"], {"coco.json": COCO, "video.mp4": "not a video"}, "{job}/cam/video.mp4: cannot be decoded as video"),
        (["{job}", "--max-width", "0"], {"coco.json": COCO}, "--max-width must be ≥ 16 px, got 0"),
    ],
)
def test_preview_names_what_is_not_a_render(tmp_path, capsys, argv, files, message):
    (tmp_path / "taken").write_text("kept")
    job = _camera_output(tmp_path, files) if files is not None else tmp_path / "walk-0123abcd"
    paths = {"root": tmp_path, "job": job}
    code, _, err = run(["preview", *(arg.format(**paths) for arg in argv)], capsys)
    assert code == 2 and message.format(**paths) in " ".join(err.split())
    assert not list(tmp_path.glob("**/*.webm")) and (tmp_path / "taken").read_text() == "kept"
