"""`execute`'s pipelined writes (issue 23) against its serial path: the same bytes in every file for every output a
camera can write, with the writer held back so the renderer runs ahead of it; a write that fails (a full disk)
stops the render with that error within `PIPELINE_FRAMES` frames, leaving no file under a final name; and a
render resumed after such a failure is the bytes of one that never failed.

The scene: a walker before a fixed camera (no lens stage: the stream's passes are crops of the renderer's own
arrays, which the next frame overwrites), 160×120, 6 frames, checkpoints every 2 frames.
"""

from __future__ import annotations

import errno
import os
import signal
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import camgen.plan.execute
from camgen.config import load_scene
from camgen.io.files import atomic_path
from camgen.io.manifest import verify
from camgen.job import Job
from camgen.plan import PlanSettings, compile_scene
from camgen.plan.execute import (
    CHECKPOINT_NAME,
    PARTIAL_SUFFIX,
    execute,
    job_directory_name,
    read_checkpoint,
)
from camgen.plan.writer import PIPELINE_FRAMES
from camgen.render.sequence import CameraRenderer
from tests.conftest import FIXED_PROFILE, SCENE, write

pytestmark = pytest.mark.opengl

FRAMES = 6
CHECKPOINT_FRAMES = 2
FAILING_INDEX = 3
"""The frame whose PNG the full disk fails: after the checkpoint of frames 0–1, before that of 0–3."""

PROFILE = (
    FIXED_PROFILE.replace("width_px: 640", "width_px: 160")
    .replace("height_px: 480", "height_px: 120")
    .replace("pixel_pitch_um: 3.0", "pixel_pitch_um: 12.0")
    + "codec:\n  gop_frames: 2\n"
)
OUTPUTS = (
    "outputs: {video: true, frames: png, raw_dng: true, raw: png16, depth: png16, radiance: png16, flow: flo, "
    "scene_flow: true, annotations: [mot, coco, yolo, reid]}"
)
WALK_SCENE = SCENE.replace("[[-3, 5], [3, 5]]", "[[-1.5, 4], [3, 4]]").replace(
    "duration_s: 1", f"duration_s: {FRAMES / 10}\n{OUTPUTS}"
)


@pytest.fixture(scope="module")
def job(tmp_path_factory) -> Job:
    directory = tmp_path_factory.mktemp("pipelined")
    write(directory, "profiles/fixed.yaml", PROFILE)
    path = write(directory, "scenes/walk.yaml", WALK_SCENE)
    return compile_scene(load_scene(path), PlanSettings(auto_exposure_start="profile"))


def render(job: Job, out: Path, renderer, **options):
    """`execute` the test's frames; pipelined unless told (the default)."""
    options.setdefault("pipelined", True)
    return execute(job, out, renderer=renderer, frames=range(FRAMES), checkpoint_frames=CHECKPOINT_FRAMES, **options)


def files_of(job_dir: Path) -> dict[str, bytes]:
    return {path.relative_to(job_dir).as_posix(): path.read_bytes() for path in job_dir.rglob("*") if path.is_file()}


@pytest.fixture(scope="module")
def serial(job, renderer, tmp_path_factory) -> tuple[dict[str, bytes], list[str]]:
    """Every file of the serial render by path in the job directory, and the camera's files in its result's order."""
    out = tmp_path_factory.mktemp("serial")
    (result,) = render(job, out, renderer, pipelined=False, save_passes=True)
    return files_of(out / job_directory_name(job)), relative(result)


def relative(result) -> list[str]:
    return [path.relative_to(result.directory.parent).as_posix() for path in result.files]


def writer_threads() -> list[threading.Thread]:
    return [thread for thread in threading.enumerate() if thread.name == "camgen-frame-writer"]


def test_every_output_is_the_bytes_of_the_serial_render(job, renderer, serial, monkeypatch, tmp_path):
    """With the writer slowed down the renderer draws the next frames while it writes a frame, into the same
    arrays (as a renderer that reuses its buffers would: the passes of every frame here are one set of arrays):
    what the writer writes must still be its frame's (copies, not the renderer's arrays)."""
    stages = {stage.name for stage in job.cameras[0].stages}
    assert {"io.video", "io.frames", "io.raw_dng", "io.raw", "io.depth", "io.radiance", "io.flow"} <= stages
    assert "optics.remap" not in stages  # the stream's passes are crops of the renderer's arrays
    draw, buffers = CameraRenderer.frame, {}

    def reusing(self, index, state, **kwargs):
        frame = draw(self, index, state, **kwargs)
        for name in ("radiance", "depth_m", "instance_id"):
            array = getattr(frame.passes, name)
            if array is not None:
                buffer = buffers.setdefault(name, np.empty_like(array))
                buffer[...] = array
                setattr(frame.passes, name, buffer)
        return frame

    monkeypatch.setattr(CameraRenderer, "frame", reusing)
    write_depth, drawn, written = camgen.plan.execute.write_depth, [], []

    def slow_depth(path, depth_m, **kwargs):
        time.sleep(0.3)
        written.append(len(drawn))
        return write_depth(path, depth_m, **kwargs)

    monkeypatch.setattr(camgen.plan.execute, "write_depth", slow_depth)
    results = render(job, tmp_path, renderer, save_passes=True, on_frame=lambda camera, index: drawn.append(index))
    assert max(count - index for index, count in enumerate(written)) >= 2  # frames drawn ahead of the writes
    job_dir = tmp_path / job_directory_name(job)
    ours, theirs = files_of(job_dir), serial[0]
    assert sorted(ours) == sorted(theirs)
    assert [name for name in ours if ours[name] != theirs[name]] == []
    assert verify(job_dir) == []
    (result,) = results
    assert relative(result) == serial[1]  # the same files in the same order (the manifest's, the checkpoints')
    assert writer_threads() == []


def test_the_writers_stages_are_in_each_frames_record(job, renderer, tmp_path):
    (result,) = render(job, tmp_path, renderer)
    assert len(result.stage_frames) == len(result.frame_wall_s) == FRAMES
    for record in result.stage_frames:
        assert {"render", "io.video", "io.files", "io.radiance", "annotate", "io.wait"} <= set(record)
    assert "io.wait" in result.finish_s  # the last frames' writes, waited for
    # Each frame's CPU time is its own (not the running total) and no more than every core busy all the time
    assert len(result.frame_cpu_s) == FRAMES
    for cpu_s, wall_s in zip(result.frame_cpu_s, result.frame_wall_s, strict=True):
        assert 0 < cpu_s <= wall_s * os.cpu_count() + 0.02  # process_time ticks


class Terminated(BaseException):
    """What the test's SIGTERM handler raises (as `camgen.cli.main`'s and a batch worker's do)."""


def test_a_sigterm_while_waiting_for_the_writer_unwinds(job, renderer, monkeypatch, tmp_path):
    """SIGTERM lands while the main thread waits for the (slowed) writer: the render unwinds at once, the writer
    ends after the frame it is writing, and nothing of the render stays."""
    write_depth = camgen.plan.execute.write_depth

    def slow_depth(path, depth_m, **kwargs):
        time.sleep(0.3)
        if Path(path).stem == "000002":
            os.kill(os.getpid(), signal.SIGTERM)
        return write_depth(path, depth_m, **kwargs)

    def terminate(signum, frame):
        raise Terminated

    monkeypatch.setattr(camgen.plan.execute, "write_depth", slow_depth)
    previous = signal.signal(signal.SIGTERM, terminate)
    try:
        with pytest.raises(Terminated):
            render(job, tmp_path, renderer)
    finally:
        signal.signal(signal.SIGTERM, previous)
    assert writer_threads() == []
    assert list(tmp_path.iterdir()) == []


def disk_full_at(index: int, monkeypatch) -> list[OSError]:
    """The frame `index`'s PNG fails half-way as on a full disk: its temporary file half written, then ENOSPC.
    Returns the list the raised error goes into."""
    write_frame, raised = camgen.plan.execute.write_frame, []

    def failing(path, image, **kwargs):
        if Path(path).name == f"{index:06d}.png" and Path(path).parent.name == "frames":
            with atomic_path(path) as tmp:
                tmp.write_bytes(b"\x89PNG\r\n")
                raised.append(OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path)))
                raise raised[-1]
        return write_frame(path, image, **kwargs)

    monkeypatch.setattr(camgen.plan.execute, "write_frame", failing)
    return raised


@pytest.mark.parametrize("resume", [False, True], ids=["clean", "resume"])
def test_a_failed_write_stops_the_render_with_its_error(job, renderer, monkeypatch, tmp_path, resume):
    raised = disk_full_at(FAILING_INDEX, monkeypatch)
    drawn = []
    with pytest.raises(OSError) as stopped:
        render(job, tmp_path, renderer, resume=resume, on_frame=lambda camera, index: drawn.append(index))
    assert stopped.value is raised[0]
    assert "No space left on device" in str(stopped.value) and stopped.value.filename.endswith("frames/000003.png")
    assert max(drawn) <= FAILING_INDEX + PIPELINE_FRAMES  # stopped at the next frame, not at the end
    assert writer_threads() == []
    job_dir = tmp_path / job_directory_name(job)
    if not resume:
        assert not job_dir.exists()  # nothing of the render stays
        return
    # Kept to resume: under its temporary folder name, with no file of the failed frame and no temporary file.
    assert sorted(path.name for path in job_dir.iterdir()) == [f"cam{PARTIAL_SUFFIX}"]
    partial = job_dir / f"cam{PARTIAL_SUFFIX}"
    assert not (partial / "frames" / "000003.png").exists()
    assert not [path for path in partial.rglob("*") if ".partial" in path.name and path.is_file()]
    checkpoint = read_checkpoint(partial / CHECKPOINT_NAME)
    assert (checkpoint.frames_done, checkpoint.next_frame) == (2, 2)


def test_a_render_resumed_after_a_failed_write_is_the_bytes_of_one_that_never_failed(
    job, renderer, serial, monkeypatch, tmp_path
):
    with monkeypatch.context() as patch, pytest.raises(OSError):
        disk_full_at(FAILING_INDEX, patch)
        render(job, tmp_path, renderer, resume=True, save_passes=True)
    (result,) = render(job, tmp_path, renderer, resume=True, save_passes=True)
    assert result.resumed_frames == 2
    ours, theirs = files_of(tmp_path / job_directory_name(job)), serial[0]
    assert sorted(ours) == sorted(theirs)
    assert [name for name in ours if ours[name] != theirs[name]] == []


def test_a_render_pipelines_unless_told(job, renderer, monkeypatch, tmp_path):
    """On llvmpipe too (measured faster on 2 cores: `execute`'s notes): the writes run in the writer thread."""
    import camgen.plan.writer

    made = []

    class Recorded(camgen.plan.writer.FrameWriter):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            made.append(self.threaded)

    monkeypatch.setattr(camgen.plan.execute, "FrameWriter", Recorded)
    execute(job, tmp_path / "default", renderer=renderer, frames=range(2))
    execute(job, tmp_path / "serial", renderer=renderer, frames=range(2), pipelined=False)
    assert made == [True, False]


def encoder_threads() -> list[threading.Thread]:
    return [thread for thread in threading.enumerate() if thread.name.startswith("camgen-video-encode")]


@pytest.mark.parametrize("pipelined", [False, True], ids=["serial", "pipelined"])
def test_the_video_encodes_beside_the_frames_other_writes(job, renderer, monkeypatch, tmp_path, pipelined):
    """Each frame's encode runs in the encoder's thread while that frame's files are written: the encode of frame 0
    holds until frame 0's depth file exists (it never would with the encode before the files, in one thread). The
    video is the bytes of the same frames encoded one after another in this thread (one segment: no checkpoint)."""
    from camgen.io.video import VideoWriter, join_videos

    write, seen = VideoWriter.write, []

    def waiting(self, frame_rgb8):
        if not seen:
            depth = next(tmp_path.glob("*/cam*/depth/000000.png"), None)
            deadline = time.monotonic() + 10
            while depth is None and time.monotonic() < deadline:
                time.sleep(0.01)
                depth = next(tmp_path.glob("*/cam*/depth/000000.png"), None)
            seen.append(depth is not None)
        seen.append(threading.current_thread().name)
        return write(self, frame_rgb8)

    monkeypatch.setattr(VideoWriter, "write", waiting)
    (result,) = execute(job, tmp_path, renderer=renderer, frames=range(FRAMES), pipelined=pipelined)
    assert seen[0] is True  # frame 0's depth was written while its encode waited
    assert len(seen) == FRAMES + 1 and all(name.startswith("camgen-video-encode") for name in seen[1:])
    assert encoder_threads() == []
    for record in result.stage_frames:
        assert record["io.video"] > 0 and "io.files" in record

    monkeypatch.setattr(VideoWriter, "write", write)
    camera, frames_dir = job.cameras[0], result.directory / "frames"
    settings = {"width_px": camera.width_px, "height_px": camera.height_px, "fps": job.fps}
    settings |= {"codec": camera.profile.codec, "preset": camera.profile.codec.preset}
    segment = tmp_path / "reference-segment.mp4"
    reference = VideoWriter(segment, **settings)
    for path in sorted(frames_dir.glob("*.png")):
        reference.write(np.asarray(cv2_rgb(path)))
    reference.close()
    join_videos([segment], tmp_path / "reference.mp4", **settings)
    assert (result.directory / "video.mp4").read_bytes() == (tmp_path / "reference.mp4").read_bytes()


def cv2_rgb(path: Path) -> np.ndarray:
    import cv2

    return cv2.imread(str(path), cv2.IMREAD_COLOR)[..., ::-1]


@pytest.mark.parametrize("pipelined", [False, True], ids=["serial", "pipelined"])
def test_an_encode_that_fails_stops_the_render_with_its_error(job, renderer, monkeypatch, tmp_path, pipelined):
    """The encode of frame 3 fails (after frame 3's files began): the render stops with that error object, no
    encoder thread is left, and nothing of the render stays."""
    from camgen.io.video import VideoWriter

    write, calls, raised = VideoWriter.write, [], []

    def failing(self, frame_rgb8):
        calls.append(1)
        if len(calls) == FAILING_INDEX + 1:
            raised.append(OSError(errno.EIO, os.strerror(errno.EIO), "encoder"))
            raise raised[-1]
        return write(self, frame_rgb8)

    monkeypatch.setattr(VideoWriter, "write", failing)
    drawn = []
    with pytest.raises(OSError) as stopped:
        render(job, tmp_path, renderer, pipelined=pipelined, on_frame=lambda camera, index: drawn.append(index))
    assert stopped.value is raised[0]
    assert max(drawn) <= FAILING_INDEX + PIPELINE_FRAMES
    assert encoder_threads() == [] and writer_threads() == []
    assert list(tmp_path.iterdir()) == []


def test_io_wait_is_the_main_threads_wait_alone(job, renderer, monkeypatch, tmp_path):
    """``io.wait`` is the main thread's time waiting for the writer (`execute`'s module docstring), so a frame's
    never exceeds that frame's wall time. With each encode slowed to 0.6 s the writer waits some 0.5 s a frame for
    the encoder; that wait is its own (``io.video.wait``), not added to the main thread's ``io.wait`` (it was: the
    second frame, handed over without a wait, then counted ~0.5 s of io.wait in a ~0.1 s frame)."""
    from camgen.io.video import VideoWriter

    write = VideoWriter.write

    def slow(self, frame_rgb8):
        time.sleep(0.6)
        return write(self, frame_rgb8)

    monkeypatch.setattr(VideoWriter, "write", slow)
    (result,) = execute(job, tmp_path, renderer=renderer, frames=range(4), pipelined=True)
    for record, wall_s in zip(result.stage_frames, result.frame_wall_s, strict=True):
        assert record["io.wait"] <= wall_s + 1e-3
        assert record["io.video.wait"] > 0.3  # the writer's wait for the slowed encode
