"""Resuming a stopped render (issue 23): a render stopped after its 5th frame and resumed from its
checkpoint writes the bytes of a render never stopped, every file (video, frames, radiance, MOT, COCO,
camera.jsonl, the manifest's hashes); a checkpoint of another job, or one that cannot be read, is passed
over with a note and the camera renders from its first frame.

The scene: a walker before a fixed camera, 160×120, 8 frames, auto-exposure starting from the profile's
exposure (so the exposure a checkpoint carries changes every frame), checkpoints every 3 frames and a GOP
of 3, so the video is 3 segments joined.
"""

from __future__ import annotations

import json
import shutil
from fractions import Fraction
from pathlib import Path

import av
import cv2
import numpy as np
import pytest

import camgen.plan.execute
from camgen.cli.main import main
from camgen.config import load_scene
from camgen.io.annotations import LineSpool
from camgen.io.manifest import verify
from camgen.job import Job
from camgen.plan import PlanSettings, compile_scene
from camgen.plan.execute import (
    CHECKPOINT_NAME,
    PARTIAL_SUFFIX,
    checkpoint_interval,
    execute,
    job_directory_name,
    read_checkpoint,
)
from tests.conftest import FIXED_PROFILE, SCENE, write

pytestmark = pytest.mark.opengl

FRAMES = 8
CHECKPOINT_FRAMES = 3
STOP_AFTER_INDEX = 4
"""The render stops after frame 4 (its 5th): the checkpoint after frame 2 is its last."""
GOP_FRAMES = 3

PROFILE = (
    FIXED_PROFILE.replace("width_px: 640", "width_px: 160")
    .replace("height_px: 480", "height_px: 120")
    .replace("pixel_pitch_um: 3.0", "pixel_pitch_um: 12.0")  # the 640×480 sensor's field of view
    + f"codec:\n  gop_frames: {GOP_FRAMES}\n"
)
OUTPUTS = "outputs: {video: true, frames: png, radiance: png16, annotations: [mot, coco]}"
WALK_SCENE = SCENE.replace("[[-3, 5], [3, 5]]", "[[-1.5, 4], [3, 4]]").replace(
    "duration_s: 1", f"duration_s: {FRAMES / 10}\n{OUTPUTS}"
)


class StopError(Exception):
    """What stops a render in these tests (raised from on_frame)."""


def stop_after(index: int):
    def on_frame(camera: str, frame: int) -> None:
        if frame == index:
            raise StopError

    return on_frame


@pytest.fixture(scope="module")
def workspace(tmp_path_factory) -> Path:
    directory = tmp_path_factory.mktemp("resume")
    write(directory, "profiles/fixed.yaml", PROFILE)
    write(directory, "scenes/walk.yaml", WALK_SCENE)
    return directory


@pytest.fixture(scope="module")
def job(workspace) -> Job:
    return compile_scene(load_scene(workspace / "scenes/walk.yaml"), PlanSettings(auto_exposure_start="profile"))


def render(job: Job, out: Path, renderer, **options):
    """`execute` the test's frames; pipelined unless told (the default)."""
    options.setdefault("pipelined", True)
    return execute(job, out, renderer=renderer, frames=range(FRAMES), checkpoint_frames=CHECKPOINT_FRAMES, **options)


@pytest.fixture(scope="module")
def reference(job, renderer, tmp_path_factory) -> Path:
    """The job directory of the render never stopped."""
    out = tmp_path_factory.mktemp("reference")
    render(job, out, renderer)
    return out / job_directory_name(job)


@pytest.fixture(scope="module", params=[True, False], ids=["pipelined", "serial"])
def stopped(request, job, renderer, tmp_path_factory) -> Path:
    """An output directory holding the render stopped after frame 4 (copy it before resuming it), its writes
    pipelined or serial (`execute`'s pipelined; the resumes are pipelined)."""
    out = tmp_path_factory.mktemp("stopped")
    with pytest.raises(StopError):
        render(job, out, renderer, resume=True, pipelined=request.param, on_frame=stop_after(STOP_AFTER_INDEX))
    return out


def copy_of(stopped: Path, tmp_path: Path) -> Path:
    out = tmp_path / "out"
    shutil.copytree(stopped, out)
    return out


def files_of(job_dir: Path) -> dict[str, bytes]:
    return {path.relative_to(job_dir).as_posix(): path.read_bytes() for path in job_dir.rglob("*") if path.is_file()}


def assert_same_files(job_dir: Path, reference: Path) -> None:
    ours, theirs = files_of(job_dir), files_of(reference)
    assert sorted(ours) == sorted(theirs)
    assert [name for name in ours if ours[name] != theirs[name]] == []
    assert verify(job_dir) == []


def test_a_stopped_render_keeps_its_checkpoint(request, job, reference, stopped):
    partial = stopped / job_directory_name(job) / f"cam{PARTIAL_SUFFIX}"
    checkpoint = read_checkpoint(partial / CHECKPOINT_NAME)
    assert (checkpoint.frames_done, checkpoint.next_frame, checkpoint.complete) == (3, 3, False)
    assert checkpoint.video_segments == ["video-00000000.mp4"]
    # The exposure it carries is the one the render never stopped used for frame 3 (exactly: floats as repr),
    # and not the profile's, where a pipeline without it would start.
    states = [json.loads(line) for line in (reference / "cam" / "camera.jsonl").read_text().splitlines()]
    assert checkpoint.pipeline["exposure_time_s"] == states[3]["exposure_time_s"] != states[0]["exposure_time_s"]
    assert checkpoint.pipeline["isp"]["limits"] is not None and checkpoint.pipeline["isp"]["white_balance_log"]
    # Frames 3 and 4 were written after it (serial), or those of them the writer had started when the stop came
    # (pipelined: it drops the frames it has not started): their lines and files are what a resume cuts away.
    lines, _ = checkpoint.spools["camera"]
    written = len((partial / ".spool" / "camera.lines").read_text().splitlines())
    pngs = len(list((partial / "frames").glob("*.png")))
    if request.node.callspec.params["stopped"]:
        assert lines == 3 and 3 <= written <= 5 and pngs == written
    else:
        assert lines == 3 and written == 5 and pngs == 5
    assert not (partial / "video.mp4").exists() and not list(partial.rglob("*.partial*"))


def test_a_resumed_render_is_the_bytes_of_one_never_stopped(job, renderer, reference, stopped, tmp_path):
    out = copy_of(stopped, tmp_path)
    # What a kill in the middle of writing frame 5 leaves: a temporary file no later frame overwrites.
    stray = out / job_directory_name(job) / f"cam{PARTIAL_SUFFIX}" / "frames" / ".000005.1f2e3d4c.partial.png"
    stray.write_bytes(b"\x89PNG")
    resumed, notes = [], []
    (result,) = render(job, out, renderer, resume=True, on_resume=lambda *a: resumed.append(a), on_note=notes.append)
    assert resumed == [("cam", 3, FRAMES)] and notes == []
    assert (result.frames, result.resumed_frames, len(result.stage_frames)) == (FRAMES, 3, FRAMES - 3)
    assert_same_files(out / job_directory_name(job), reference)
    assert not list(out.rglob(CHECKPOINT_NAME))


def test_the_joined_video_has_every_frame_and_key_frames_a_gop_apart(reference):
    """3 segments (frames 0–2, 3–5, 6–7) joined: PyAV reads 8 frames at pts i/fps, key frames at 0, 3, 6
    only, each frame the PNG written beside it up to the codec's loss."""
    with av.open(str(reference / "cam" / "video.mp4")) as container:
        stream = container.streams.video[0]
        assert stream.frames == FRAMES
        packets = [packet for packet in container.demux(stream) if packet.size]
        ticks = Fraction(1, 10) / stream.time_base
        assert [packet.pts for packet in packets] == [i * ticks for i in range(FRAMES)]
        assert [i for i, packet in enumerate(packets) if packet.is_keyframe] == [0, 3, 6]
        container.seek(0)
        decoded = [frame.to_ndarray(format="rgb24") for frame in container.decode(stream)]
    assert len(decoded) == FRAMES
    for index, frame in enumerate(decoded):
        png = cv2.cvtColor(cv2.imread(str(reference / "cam" / "frames" / f"{index:06d}.png")), cv2.COLOR_BGR2RGB)
        assert np.abs(frame.astype(int) - png).mean() < 3.0


@pytest.mark.parametrize(
    ("spoil", "message"),
    [
        (lambda data: {**data, "job_id": "0" * 64}, "discarding cam.partial/.checkpoint.json: it is of another job"),
        (None, "cannot resume from cam.partial/.checkpoint.json: .checkpoint.json is not valid JSON (line 1"),
    ],
    ids=["another_job", "corrupt"],
)
def test_a_checkpoint_it_cannot_use_is_discarded(job, renderer, reference, stopped, tmp_path, spoil, message):
    out = copy_of(stopped, tmp_path)
    path = out / job_directory_name(job) / f"cam{PARTIAL_SUFFIX}" / CHECKPOINT_NAME
    path.write_text("{not json" if spoil is None else json.dumps(spoil(json.loads(path.read_text()))))
    resumed, notes = [], []
    render(job, out, renderer, resume=True, on_resume=lambda *a: resumed.append(a), on_note=notes.append)
    assert resumed == [] and len(notes) == 1
    assert message in notes[0] and notes[0].endswith("rendering cam from its first frame")
    assert_same_files(out / job_directory_name(job), reference)


def test_a_camera_finished_before_the_stop_is_kept(workspace, renderer, tmp_path):
    """Two cameras, stopped in the second: the first, finished and renamed, keeps its checkpoint until the
    job's manifest, and the resume takes it over without rendering it again."""
    second = "\n  - name: side\n    profile: fixed\n    mount: {position_m: [2, -4, 3], yaw_deg: 100, pitch_deg: -25}\n"
    scene = write(workspace, "scenes/two.yaml", WALK_SCENE.rstrip("\n") + second)
    job = compile_scene(load_scene(scene), PlanSettings(auto_exposure_start="profile"))
    render(job, tmp_path / "reference", renderer)
    out = tmp_path / "out"
    stopped = {"cam": None, "side": STOP_AFTER_INDEX}
    with pytest.raises(StopError):
        render(
            job, out, renderer, resume=True, on_frame=lambda camera, index: stop_after(stopped[camera])(camera, index)
        )
    job_dir = out / job_directory_name(job)
    assert read_checkpoint(job_dir / "cam" / CHECKPOINT_NAME).complete
    resumed = []
    results = render(job, out, renderer, resume=True, on_resume=lambda *a: resumed.append(a))
    assert resumed == [("cam", FRAMES, FRAMES), ("side", 3, FRAMES)]
    assert [(r.name, r.resumed_frames, len(r.stage_frames)) for r in results] == [("cam", 8, 0), ("side", 3, 5)]
    assert_same_files(job_dir, tmp_path / "reference" / job_directory_name(job))


def _stop_after_execute_camera(patch) -> None:
    """After the camera's last checkpoint (a finished camera's), before ``cam.partial`` became ``cam``."""
    execute_camera = camgen.plan.execute._execute_camera

    def stopped_after(*args):
        execute_camera(*args)
        raise StopError

    patch.setattr(camgen.plan.execute, "_execute_camera", stopped_after)


def _stop_in_manifest(patch) -> None:
    """While the manifest hashes every file (a long render's last step)."""

    def stopped(*args, **kwargs):
        raise StopError

    patch.setattr(camgen.plan.execute, "write_manifest", stopped)


def _stop_clearing_spools(patch) -> None:
    """Just after the camera's finished checkpoint, while its spools and video segments are deleted."""
    close = camgen.plan.execute.LineSpool.close

    def stopped(self, *args, **kwargs):
        if not kwargs.get("keep") and not args:
            raise StopError
        return close(self, *args, **kwargs)

    patch.setattr(camgen.plan.execute.LineSpool, "close", stopped)


@pytest.mark.parametrize("stop", [_stop_after_execute_camera, _stop_in_manifest, _stop_clearing_spools])
def test_a_camera_stopped_after_it_finished_is_taken_over(job, renderer, reference, monkeypatch, tmp_path, stop):
    """Stopped anywhere after the camera's finished checkpoint: the resume takes the finished camera over (its
    folder renamed, what is left of its spools deleted) and renders nothing."""
    with monkeypatch.context() as patch, pytest.raises(StopError):
        stop(patch)
        render(job, tmp_path, renderer, resume=True)
    resumed = []
    (result,) = render(job, tmp_path, renderer, resume=True, on_resume=lambda *a: resumed.append(a))
    assert resumed == [("cam", FRAMES, FRAMES)] and result.stage_frames == []
    assert_same_files(tmp_path / job_directory_name(job), reference)


def test_a_finished_render_of_fewer_frames_is_not_what_resume_was_asked(job, renderer, reference, tmp_path):
    """A finished render of the first frames only: resuming the whole sequence renders it (it is not "nothing to
    resume"), and resuming the same frames again is."""
    execute(job, tmp_path, renderer=renderer, frames=range(FRAMES // 2), checkpoint_frames=CHECKPOINT_FRAMES)
    (result,) = render(job, tmp_path, renderer, resume=True)
    assert (result.frames, result.resumed_frames) == (FRAMES, 0)
    assert_same_files(tmp_path / job_directory_name(job), reference)
    with pytest.raises(ValueError, match="nothing to resume"):
        render(job, tmp_path, renderer, resume=True)


def test_without_resume_a_stopped_render_leaves_nothing(job, renderer, tmp_path):
    with pytest.raises(StopError):
        render(job, tmp_path, renderer, on_frame=stop_after(STOP_AFTER_INDEX))
    assert list(tmp_path.iterdir()) == []


def test_the_cli_resumes_and_then_has_nothing_to_resume(workspace, monkeypatch, capsys, tmp_path):
    """`camgen render --resume`: with nothing to resume it renders (here it is stopped, Ctrl-C after frame
    4, and keeps its folder); again, it resumes and says where; once more, there is nothing to resume."""
    scene, out = workspace / "scenes/walk.yaml", tmp_path / "out"
    arguments = ["render", str(scene), "-o", str(out), "--frames", str(FRAMES), "--resume"]
    (out / "walk-0123abcd" / f"cam{PARTIAL_SUFFIX}").mkdir(parents=True)  # another job's stopped render
    monkeypatch.setattr(camgen.plan.execute, "CHECKPOINT_FRAMES", CHECKPOINT_FRAMES)
    write_files = camgen.plan.execute._write_files

    def interrupted(context, stages, state, frame, *args):
        write_files(context, stages, state, frame, *args)
        if frame.index == STOP_AFTER_INDEX:
            raise KeyboardInterrupt

    with monkeypatch.context() as patch:
        patch.setattr(camgen.plan.execute, "_write_files", interrupted)
        assert main(arguments) == 130
    err = capsys.readouterr().err
    assert "walk-0123abcd holds a stopped render of another version of scene walk" in " ".join(err.split())
    (job_dir,) = (path for path in out.iterdir() if path.name != "walk-0123abcd")
    assert (job_dir / f"cam{PARTIAL_SUFFIX}" / CHECKPOINT_NAME).is_file()

    assert main(arguments) == 0
    assert "resuming cam at frame 3 of 8" in capsys.readouterr().err
    assert verify(job_dir) == []
    finished = files_of(job_dir)

    assert main(arguments) == 0
    assert "nothing to resume" in capsys.readouterr().err
    assert files_of(job_dir) == finished


@pytest.mark.parametrize("value", [0, -3, 2.5, True, "250"])
def test_a_bad_checkpoint_interval_is_refused_before_anything_is_written(job, renderer, tmp_path, value):
    with pytest.raises(ValueError, match=r"checkpoint_frames must be an integer ≥ 1, got"):
        execute(job, tmp_path, renderer=renderer, frames=range(FRAMES), checkpoint_frames=value)
    assert list(tmp_path.iterdir()) == []


def test_the_checkpoint_interval_is_whole_gops(job):
    """Rounded up to a multiple of the codec's GOP (3 here) where an H.264/H.265 video is written, so a
    segment starts where the stream has a key frame anyway; as asked where none is (MJPEG: every frame is one)."""
    (camera,) = job.cameras
    assert [checkpoint_interval(camera, frames) for frames in (1, 3, 4, 250)] == [3, 3, 6, 252]
    mjpeg = camera.profile.model_copy(update={"codec": camera.profile.codec.model_copy(update={"name": "mjpeg"})})
    assert checkpoint_interval(camera.model_copy(update={"profile": mjpeg}), 4) == 4


def test_a_line_spool_resumes_from_its_mark(tmp_path):
    spool = LineSpool(tmp_path / "lines")
    spool.append("a")
    spool.append("b")
    mark = spool.mark()
    spool.append("c")  # written after the checkpoint
    spool.close(keep=True)
    resumed = LineSpool(tmp_path / "lines")
    resumed.resume(*mark)
    resumed.append("d")
    assert (len(resumed), list(resumed)) == (3, ["a", "b", "d"])
    resumed.close()
    assert not (tmp_path / "lines").exists()
    (tmp_path / "short").write_text("a\n")
    with pytest.raises(ValueError, match="shorter than the 4 bytes of its checkpoint"):
        LineSpool(tmp_path / "short").resume(2, 4)
    with pytest.raises(ValueError, match="a mark of -1 lines"):
        LineSpool(tmp_path / "short").resume(-1, 2)
    (tmp_path / "other").write_text("a b\n")
    with pytest.raises(ValueError, match="hold 1 lines, its checkpoint says 2"):
        LineSpool(tmp_path / "other").resume(2, 4)
