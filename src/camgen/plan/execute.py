"""Run a compiled Job: render each camera's planned passes, frame by frame, and write its outputs.

Per frame: the ideal pinhole passes (radiance, depth, instance ids; `camgen.render.sequence`), the camera
model (`camgen.plan.camera_pipeline`: lens, sensor with auto-exposure, ISP, a virtual PTZ's crop), then
what the camera's stages ask for: the video in the profile's codec (``video.mp4``), frames (the 8-bit
stream as PNG/TIFF, or the linear radiance as EXR), raw DNG, depth (16-bit PNG or EXR), the
scene-referred radiance (`camgen.io.radiance`), forward optical flow and scene flow (`camgen.plan.flow`),
annotations (`camgen.plan.annotations`: MOTChallenge with its img1 images and optional public
detections, COCO, YOLO, Market-1501 re-ID crops) and the per-frame camera states (``camera.jsonl``).

Each camera's folder is written as ``CAMERA.partial`` and renamed when the camera is complete (removed
on any exception unless the render resumes: below), so a render stopped part-way leaves no per-frame files;
job.json and manifest.json
are written last, so a job directory holding them holds a finished render. `IMPLEMENTED_STAGES` are the
stages run here; `unimplemented_stages` names any other stage a job plans (a job compiled by another
camgen version), so that callers can say it is skipped.

Resuming (issue 23): every `checkpoint_interval` frames a camera writes ``CAMERA.partial/.checkpoint.json``
(`Checkpoint`): the frames done, the state one frame leaves for the next (auto-exposure's setting, the
ISP's adapting limits and white balance: `CameraPipeline.carried_state`; the radiance files' scale), the
length of every line spool (camera.jsonl, the annotations, the list of files written) and the video's
segments. The video is encoded in segments, a fresh encoder from each checkpoint on (x264's and x265's
rate control cannot be saved), kept as ``.spool/video-NNNNNNNN.mp4`` and joined without re-encoding at
the end (`camgen.io.video.join_videos`); a render that is never stopped segments at the same frames, so
its files are the same bytes. ``execute(..., resume=True)`` keeps the folders of a render that stops,
and continues each camera from its checkpoint: spools cut back to their checkpointed length, files of
later frames deleted, the pipeline's state restored. The renderer draws each frame alone, so it holds no
state to save. A camera's finished checkpoint is written before its spools go, and the finished cameras keep
theirs until the manifest (which leaves them out) is written: a stop at any point redoes no finished camera.

Pipelining (issue 23): what follows the camera model and feeds no later frame (the video's encode, the frame,
raw, depth, radiance, flow and pass files, the annotation lines, images, re-ID crops and detections,
camera.jsonl) runs in one writer thread (`camgen.plan.writer.FrameWriter`), in frame order, at most
`camgen.plan.writer.PIPELINE_FRAMES` (2) frames behind, while the main thread renders the next frame. The
main thread keeps what carries state into the next frame or needs OpenGL: the render, the camera model
(auto-exposure, the ISP's adaptation), the lens applied to the passes, the annotations' geometry and unoccluded
draws, the flow (it moves the actors). The writer gets copies of the arrays (`_detached`), so the same bytes
come out as from the serial render (``pipelined=False``; pipelined by default, on a GPU and on llvmpipe alike:
`execute`'s notes). Either way a frame's video encode runs in a thread of its own (``camgen-video-encode``)
beside that frame's other writes, and is waited for before they return (`_encoding`): the encoder and the PNG
and DNG writers each keep one core busy, outside the GIL. The writer is drained before each checkpoint and before a
camera's files are finished, so a checkpoint describes only frames fully written; a write that fails stops the render
with its own exception at the next frame (or the drain), and the render then unwinds as from any error.

Timing with the pipeline: a frame's `CameraResult.stage_frames` record adds the writer thread's stages of that
frame (timed in that thread) to the main thread's; ``io.wait`` is the main thread's time waiting for the writer
(a free slot, a drain). The stages of a frame then overlap and can sum to more than its wall time
(`frame_wall_s`): a stage's share of the wall time says how long it kept its thread busy, the main thread's
stages plus ``io.wait`` are the wall time, and a large ``io.wait`` says the writer set the pace. Serial too,
``io.video`` is the encoder thread's time, which overlaps the frame's other writes, and ``io.video.wait``
(`ENCODE_WAIT_STAGE`) the wait for it after them, in the thread that wrote them (the writer's, when pipelined:
not part of ``io.wait``).
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import dataclasses
import functools
import glob
import hashlib
import json
import math
import re
import shutil
import time
from collections.abc import Callable, Collection, Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path, PurePosixPath

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, NonNegativeInt, ValidationError

import camgen
from camgen.annotate.detection import detect_people, hog_detector
from camgen.io.annotations import IMAGE_SUFFIXES, LineSpool, SequenceAnnotations, write_reid_crops
from camgen.io.dng import SRGB_FROM_XYZ, write_dng
from camgen.io.files import atomic_path, write_text_atomic
from camgen.io.flow import write_flo, write_scene_flow
from camgen.io.frames import write_depth, write_frame
from camgen.io.manifest import MANIFEST_NAME, read_manifest, write_manifest
from camgen.io.radiance import RadianceWriter
from camgen.isp.eptz import crop_and_scale
from camgen.job import CameraJob, Job
from camgen.optics.remap import LensMapCache
from camgen.plan.annotations import Annotator
from camgen.plan.camera_pipeline import CameraPipeline, cuts_reid_crops, frame_rng
from camgen.plan.flow import FlowField
from camgen.plan.lens_stages import LensStages
from camgen.plan.timing import StageClock, stage_sums
from camgen.plan.writer import FrameWriter
from camgen.render.renderer import Passes, Renderer
from camgen.render.scene_graph import build_scene_graph, instance_table
from camgen.render.sequence import CameraRenderer

RAW_SUFFIX = {"png16": ".png", "tiff16": ".tif", "exr": ".exr"}
"""File suffix of each raw mosaic format (`outputs.raw`)."""
PARTIAL_SUFFIX = ".partial"
"""A camera's folder is written under its name with this suffix and renamed when complete."""
NOISE_THREADS = 2
"""Threads for the sensor's row bands and the tone lookup (the machines here have 2 cores)."""
CHECKPOINT_FRAMES = 250
"""A camera writes a checkpoint every this many frames (10 s of a 25 frames/s stream), rounded up to whole
GOPs of its codec (`checkpoint_interval`): a stopped render resumed redoes at most this many frames. Measured
on 2 cores: a checkpoint takes 1.3 ms (median of 11, 320×240) and 3 ms at frame 89 750 of an hour at
25 frames/s (a 9 kB file; 86 ms and 1.4 MB with 16-bit radiance files, whose per-frame clip counts it
carries). The video's segments (one per checkpoint) cost little: 100 frames of 1080p (a panned photo with
σ = 2 DN noise) as 4 segments of 25 against 1: x264 at 4096 kbit/s 2.03 against 2.07 MB, PSNR 38.36 against
38.42 dB, encode 4.0 against 4.2 s; x265 1.51 against 1.97 MB, 38.64 against 38.78 dB (its rate control
restarts below the target); joining them 10–50 ms. At the default interval the restarts vanish: 500 frames of
640×360 (a blurred noise texture panning, a moving box, σ = 2 DN) at 1024 kbit/s, GOP 50, as 2 segments of
250 against 1: x264 2.627 against 2.607 MB, PSNR 36.79 dB both; x265 2.570 against 2.569 MB, 37.45 against
37.46 dB."""
CHECKPOINT_NAME = ".checkpoint.json"
"""A camera's checkpoint, in its ``.partial`` folder (and in a finished camera's folder until the job ends)."""
CHECKPOINT_VERSION = 1
"""Version of the checkpoint's layout; a checkpoint of another version is not resumed."""

IMPLEMENTED_STAGES = frozenset(
    {
        "render",
        "optics.motion_blur",
        "optics.depth_of_field",
        "optics.axial_ca",
        "optics.diffraction",
        "optics.remap",
        "optics.vignetting",
        "sensor.exposure",
        "sensor.noise",
        "sensor.adc",
        "isp.demosaic",
        "isp.white_balance",
        "isp.ccm",
        "isp.false_colour",
        "isp.denoise",
        "isp.contrast_stretch",
        "isp.tone",
        "isp.sharpen",
        "isp.eptz",
        "io.video",
        "io.camera_metadata",
        "annotate",
        "io.raw_dng",
        "io.raw",
        "io.frames",
        "io.depth",
        "io.radiance",
        "io.flow",
        "io.scene_flow",
    }
)


@dataclass
class CameraResult:
    name: str
    directory: Path
    frames: int = 0
    files: list[Path] = field(default_factory=list)
    total_s: float = 0.0
    stage_frames: list[dict[str, float]] = field(default_factory=list)
    """Wall time per stage of each frame rendered, s (`camgen.plan.timing.StageClock`). The first
    frame carries the one-off costs: the scene upload, lens maps, auto-exposure's convergence. Pipelined,
    the writer thread's stages of the frame are added and the stages overlap (see the module docstring)."""
    frame_wall_s: list[float] = field(default_factory=list)
    """Wall time of each frame, s (the first from the camera's setup on)."""
    frame_cpu_s: list[float] = field(default_factory=list)
    """CPU time of the process during each frame, s, every thread's (`StageClock.frame_cpu_s`)."""
    finish_s: dict[str, float] = field(default_factory=dict)
    """Wall time per stage after the last frame: flushing the video encoder, writing annotations."""
    finish_cpu_s: float = 0.0
    """CPU time of the process after the last frame, s."""
    resumed_frames: int = 0
    """Frames taken over from a checkpoint (`execute`'s resume) instead of rendered in this run; `frames`
    counts them, the timings do not."""

    @property
    def render_s(self) -> float:
        """Time spent drawing and reading back passes (motion-blur sub-frames included), s."""
        return stage_sums(self.stage_frames).get("render", 0.0)


def job_directory_name(job: Job) -> str:
    """`<scene>-<first 8 hex digits of the job hash>`: readable, and distinct for distinct jobs."""
    return f"{job.scene_name}-{job.job_id[:8]}"


def unimplemented_stages(camera: CameraJob) -> list[str]:
    return [stage.name for stage in camera.stages if stage.name not in IMPLEMENTED_STAGES]


def rendered_record(cameras: Iterable[str], frames: Iterable[int] | None) -> dict:
    """What a manifest records as `rendered`: the cameras, and the frame indices ("all" for None)."""
    return {"cameras": list(cameras), "frames": "all" if frames is None else list(frames)}


def execute(
    job: Job,
    out_dir: str | Path,
    *,
    renderer: Renderer,
    frames: Iterable[int] | None = None,
    cameras: Iterable[str] | None = None,
    resolve_path: Callable[[str], Path] | None = None,
    save_passes: bool = False,
    on_frame: Callable[[str, int], None] | None = None,
    resume: bool = False,
    checkpoint_frames: int | None = None,
    on_resume: Callable[[str, int, int], None] | None = None,
    on_note: Callable[[str], None] | None = None,
    pipelined: bool = True,
) -> list[CameraResult]:
    """Render `job` into ``out_dir/<scene>-<hash>/<camera>/`` and return what was written.

    frames: frame indices to render (default: all). Auto-exposure runs from the first frame rendered,
    so a subset starts from the profile's exposure, not where a full render would be. save_passes:
    also write each frame's passes, through the lens into the output frame, as
    ``passes/<frame>.npz`` (radiance_cd_m2, depth_m, instance_id) and its raw DN.
    on_frame(camera, index) is called after each frame (for progress).

    resume: continue a render of the same job, frames and options that stopped, from each camera's last
    checkpoint (see the module docstring), and keep the unfinished folders if this render stops too
    (without it, a render starts clean and a stopped one deletes what it wrote). A checkpoint of another
    render (job, frames, save_passes, camgen version) or one that cannot be read is discarded with a note
    and the camera starts from its first frame; a job directory with a manifest (a finished render) is a
    ValueError. checkpoint_frames: frames between checkpoints (default `CHECKPOINT_FRAMES`) before
    `checkpoint_interval` rounds them to whole GOPs (it sets where the video is segmented, so renders
    compared byte for byte use the same).
    on_resume(camera, frames_done, frames) is called for each camera taken up from a checkpoint (a
    finished camera: frames_done = frames); on_note(message) gets the one-line notes.

    pipelined: each frame's writes (the video's encode, the files, the annotation lines and images,
    camera.jsonl) run in a background thread while the next frame renders (`camgen.plan.writer`; see
    "Pipelining" in the module docstring); False writes each frame before rendering the next. The files are
    the same bytes either way. Pipelined by default, on a GPU and on llvmpipe alike: a GPU draws while the CPU
    waits for it, so the writes of the frame before overlap the draw; llvmpipe draws on every core, but a frame
    spends most of its time in one thread (the Python around the draws, the camera model, the annotations), and
    the writer thread fills the other core then. Measured on 2 cores, quiet (one camera at 1920×1080 with every
    output the scene plans, the first frame left out; serial and pipelined in turn, each its own process): the
    parking lot's PTZ, 10 frames, 3 rounds: 1132 / 832 / 860 ms a frame serial against 792 / 751 / 772
    pipelined (0.90×); the misty street, 2 rounds: 236 / 218 against 152 / 158 (0.69×); the intersection's 4K
    box camera, 4 frames, 2 rounds, its frame 95 % drawing: 6780 / 6439 against 6509 / 6547 (1.0×); the
    corridor, whose depth of field already keeps both cores busy, 10 frames, 3 rounds: 467 / 479 / 486 against
    526 / 543 / 468 (1.0–1.13×). Earlier, when the parking lot's frame was 1.3–1.9 s and mostly its draws, the
    writer beside llvmpipe slowed them more than it hid, and a software rasterizer wrote in turn.
    """
    checkpoint_frames = CHECKPOINT_FRAMES if checkpoint_frames is None else checkpoint_frames
    if isinstance(checkpoint_frames, bool) or not isinstance(checkpoint_frames, int) or checkpoint_frames < 1:
        raise ValueError(f"checkpoint_frames must be an integer ≥ 1, got {checkpoint_frames!r}")
    job_dir = Path(out_dir) / job_directory_name(job)
    indices = list(range(job.frame_count) if frames is None else frames)
    wanted = None if cameras is None else set(cameras)
    chosen = [(i, camera) for i, camera in enumerate(job.cameras) if wanted is None or camera.name in wanted]
    note = on_note or (lambda message: None)
    if resume and finished_render(job, out_dir, cameras, None if frames is None else indices) is not None:
        raise ValueError(f"{job_dir}: {NOTHING_TO_RESUME}")
    # A render starts clean: no job.json or manifest.json until it completes, and no files left in a
    # camera's directory by an earlier render of it (fewer frames, other outputs, a killed run), unless it
    # resumes a checkpoint of this very render.
    for stale in ("manifest.json", "job.json"):
        (job_dir / stale).unlink(missing_ok=True)
    identities = {
        camera.name: _identity(job, camera, indices, save_passes, checkpoint_interval(camera, checkpoint_frames))
        for _, camera in chosen
    }
    taken_up = {
        camera.name: _checkpoint_to_resume(job_dir, camera.name, identities[camera.name], note) if resume else None
        for _, camera in chosen
    }
    for _, camera in chosen:
        for directory in (job_dir / camera.name, job_dir / f"{camera.name}{PARTIAL_SUFFIX}"):
            checkpoint = taken_up[camera.name]
            kept = checkpoint is not None and directory.name == checkpoint.directory_name(camera.name)
            if not kept and directory.is_dir():
                shutil.rmtree(directory)
    results = []
    maps = LensMapCache()  # cameras with the same lens and zoom share their maps
    try:
        with ThreadPoolExecutor(NOISE_THREADS) as executor:
            for camera_index, camera in chosen:
                checkpoint = taken_up[camera.name]
                final = job_dir / camera.name
                if checkpoint is not None and checkpoint.complete:
                    results.append(_finished_camera(final, checkpoint))
                    if on_resume is not None:
                        on_resume(camera.name, checkpoint.frames_done, len(indices))
                    continue
                # A camera's files (per-frame images included) are written under a temporary name and the
                # folder is renamed when the camera is complete; a render stopped part-way leaves none.
                partial = job_dir / f"{camera.name}{PARTIAL_SUFFIX}"
                context = _Context(
                    job, camera_index, partial, renderer, maps, executor, identities[camera.name], pipelined
                )
                try:
                    result = _execute_camera(
                        context, indices, resolve_path, save_passes, on_frame, checkpoint, on_resume
                    )
                except CheckpointError as error:
                    note(f"{camera.name}: cannot resume: {error}; rendering {camera.name} from its first frame")
                    shutil.rmtree(partial)
                    result = _execute_camera(context, indices, resolve_path, save_passes, on_frame, None, None)
                partial.replace(final)
                result.directory = final
                result.files = [final / path.relative_to(partial) for path in result.files]
                results.append(result)
        # Written last: a job directory with job.json in it holds a finished render, of the cameras and
        # frames the manifest's `rendered` names (all of them unless --camera/--frames chose fewer).
        write_text_atomic(job_dir / "job.json", job.to_json())
        rendered = rendered_record([r.name for r in results], indices if frames is not None else None)
        # The finished cameras keep their checkpoints until the manifest is written (a stop before it, while
        # it hashes every file, resumes without redoing them); the manifest does not list them.
        checkpoints = [result.directory / CHECKPOINT_NAME for result in results]
        excluded = {path.relative_to(job_dir).as_posix() for path in checkpoints}
        write_manifest(job, job_dir, rendered=rendered, exclude=excluded)  # after everything, job.json included
        for path in checkpoints:
            path.unlink(missing_ok=True)
    except BaseException:
        # Stopped anywhere before the manifest (an error, Ctrl-C, a batch worker's SIGTERM, even between
        # job.json and the manifest): nothing this render wrote stays, finished cameras included, so a job
        # directory without a manifest holds no file of it; unless it is to be resumed.
        if not resume:
            discard_unfinished(job, job_dir, wanted)
        raise
    return results


NOTHING_TO_RESUME = (
    "holds a finished render of this job (manifest.json): nothing to resume; render without --resume to render it again"
)


def finished_render(
    job: Job, out_dir: str | Path, cameras: Iterable[str] | None = None, frames: Iterable[int] | None = None
) -> Path | None:
    """The manifest of a finished render of `job` in `out_dir` (its job directory) that rendered what `execute`
    with these `cameras` and `frames` would (its `rendered` record: None means every camera, every frame), or
    None: a finished render of fewer frames or other cameras is not the one asked for."""
    job_dir = Path(out_dir) / job_directory_name(job)
    manifest, _ = read_manifest(job_dir)
    if manifest is None:
        return None
    wanted = None if cameras is None else set(cameras)
    names = [camera.name for camera in job.cameras if wanted is None or camera.name in wanted]
    asked = rendered_record(names, None if frames is None else list(frames))
    return job_dir / MANIFEST_NAME if manifest.get("rendered") == asked else None


def other_unfinished_renders(job: Job, out_dir: str | Path) -> list[Path]:
    """Job directories in `out_dir` of the same scene name but another job (the scene, its profiles or the
    settings changed) that hold a stopped render (a camera's ``.partial`` folder): `execute` resumes only
    its own job's, so a caller can say these were left as they are."""
    ours = job_directory_name(job)
    found = []
    for directory in sorted(Path(out_dir).glob(f"{glob.escape(job.scene_name)}-*")):
        name = directory.name
        if name == ours or not directory.is_dir() or not _HASH8.fullmatch(name[len(job.scene_name) + 1 :]):
            continue
        if any(child.name.endswith(PARTIAL_SUFFIX) and child.is_dir() for child in directory.iterdir()):
            found.append(directory)
    return found


def discard_unfinished(job: Job, job_dir: Path, cameras: Collection[str] | None = None) -> bool:
    """Delete what an unfinished render of `job` left in `job_dir` (its cameras' folders, finished or
    ``.partial``, and job.json), unless the job's manifest is there (a finished render). cameras: only these
    cameras' folders (None: every camera of the job). The job directory goes too once it is empty. Returns
    whether anything was deleted. Used when a render stops part-way, by `execute` itself, and by a batch whose
    worker was killed before it could (`camgen.batch.run`)."""
    job_dir = Path(job_dir)
    if not job_dir.is_dir() or (job_dir / "manifest.json").exists():
        return False
    deleted = False
    for camera in job.cameras:
        if cameras is not None and camera.name not in cameras:
            continue
        for directory in (job_dir / camera.name, job_dir / f"{camera.name}{PARTIAL_SUFFIX}"):
            if directory.is_dir():
                shutil.rmtree(directory, ignore_errors=True)
                deleted = True
    job_json = job_dir / "job.json"
    if job_json.exists():
        job_json.unlink(missing_ok=True)
        deleted = True
    with contextlib.suppress(OSError):
        job_dir.rmdir()  # only if empty
    return deleted


class CheckpointError(ValueError):
    """A checkpoint that cannot be resumed: unreadable, or not matching the files beside it."""


class RadianceState(BaseModel):
    """What a camera's `RadianceWriter` carries from frame to frame."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    scale_cd_m2_per_dn: float | None
    clipped: dict[str, int]


class Checkpoint(BaseModel):
    """``CAMERA.partial/.checkpoint.json``: where a camera's render stands after `frames_done` frames, and
    which render it is of (the first seven fields, `_identity`). Floats are written as Python's repr, so
    they read back exactly."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    checkpoint_version: int
    camgen_version: str
    job_id: str
    camera: str
    frames: str
    """The frame indices rendered (`_frames_text`)."""
    save_passes: bool
    interval_frames: int = Field(ge=1)
    """Frames between checkpoints (`checkpoint_interval`), which sets the video's segments."""
    frames_done: int = Field(ge=0)
    next_frame: int | None
    """The frame index the render continues with; None when `complete`."""
    complete: bool
    """The camera is finished and its folder renamed; the checkpoint stays there until the job's manifest."""
    pipeline: dict | None = None
    """`CameraPipeline.carried_state`, or None for a camera without one."""
    radiance: RadianceState | None = None
    spools: dict[str, tuple[NonNegativeInt, NonNegativeInt]] = Field(default_factory=dict)
    """Line spool name → (lines, bytes) of its file (`LineSpool.mark`)."""
    video_segments: list[str] = Field(default_factory=list)
    """Video segments written so far, in order, under ``.spool/``."""
    files: list[str] | None = None
    """A complete camera's files, relative POSIX paths (an unfinished one lists them in its files spool)."""

    def directory_name(self, camera: str) -> str:
        """The folder this checkpoint belongs in: the camera's, or its ``.partial`` one."""
        return camera if self.complete else f"{camera}{PARTIAL_SUFFIX}"


def checkpoint_interval(camera: CameraJob, checkpoint_frames: int = CHECKPOINT_FRAMES) -> int:
    """Frames between a camera's checkpoints: `checkpoint_frames`, rounded up to a whole number of its
    codec's GOPs when it writes H.264/H.265 video, so each video segment (which starts with a key frame)
    starts where the stream has one anyway and the key frames stay exactly `Codec.gop_frames` apart."""
    codec = camera.profile.codec
    if any(stage.name == "io.video" for stage in camera.stages) and codec.name != "mjpeg":
        return math.ceil(checkpoint_frames / codec.gop_frames) * codec.gop_frames
    return checkpoint_frames


def _frames_text(indices: Sequence[int]) -> str:
    """The frame indices of a render, short: ``0–249`` for a run of them, else their count and hash."""
    if not indices:
        return "none"
    if list(indices) == list(range(indices[0], indices[-1] + 1)):
        return f"{indices[0]}–{indices[-1]}"
    digest = hashlib.sha256(json.dumps(list(indices)).encode()).hexdigest()
    return f"{len(indices)} frames, sha256 {digest[:16]}"


def _identity(job: Job, camera: CameraJob, indices: Sequence[int], save_passes: bool, interval: int) -> dict:
    """The fields of a `Checkpoint` that say which render it is of; a checkpoint resumes only its own."""
    return {
        "checkpoint_version": CHECKPOINT_VERSION,
        "camgen_version": camgen.__version__,
        "job_id": job.job_id,
        "camera": camera.name,
        "frames": _frames_text(indices),
        "save_passes": save_passes,
        "interval_frames": interval,
    }


def _mismatch(checkpoint: Checkpoint, identity: dict) -> str | None:
    """Why `checkpoint` is not of the render `identity` describes, or None when it is."""
    if checkpoint.checkpoint_version != identity["checkpoint_version"]:
        return f"its layout is version {checkpoint.checkpoint_version}, this camgen's {CHECKPOINT_VERSION}"
    if checkpoint.camgen_version != identity["camgen_version"]:
        return f"it was written by camgen {checkpoint.camgen_version}, this is {identity['camgen_version']}"
    if checkpoint.job_id != identity["job_id"]:
        return (
            f"it is of another job ({checkpoint.job_id[:16]}…, this one is {identity['job_id'][:16]}…): "
            "the scene, a profile or the plan settings changed"
        )
    if checkpoint.camera != identity["camera"]:
        return f"it is of camera {checkpoint.camera}"
    if checkpoint.frames != identity["frames"]:
        return f"it is of a render of frames {checkpoint.frames}, this one renders frames {identity['frames']}"
    if checkpoint.save_passes != identity["save_passes"]:
        saved = "saved" if checkpoint.save_passes else "did not save"
        return f"its render {saved} the passes, this one does{'' if identity['save_passes'] else ' not'}"
    if checkpoint.interval_frames != identity["interval_frames"]:
        return (
            f"it checkpointed every {checkpoint.interval_frames} frames, this render every "
            f"{identity['interval_frames']} (the video's segments would differ)"
        )
    return None


_SEGMENT_NAME = "video-{:08d}.mp4"
_HASH8 = re.compile(r"[0-9a-f]{8}")


def read_checkpoint(path: str | Path) -> Checkpoint:
    """The checkpoint at `path`; CheckpointError saying what is wrong with it when it cannot be used."""
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError as error:
        raise CheckpointError(f"{path.name} is not UTF-8 text ({error.reason} at byte {error.start})") from None
    except json.JSONDecodeError as error:
        raise CheckpointError(
            f"{path.name} is not valid JSON (line {error.lineno}, column {error.colno}: {error.msg})"
        ) from None
    except OSError as error:
        raise CheckpointError(f"{path.name} cannot be read ({error.strerror or error})") from None
    try:
        checkpoint = Checkpoint.model_validate(data)
    except ValidationError as error:
        first = error.errors()[0]
        where = ".".join(str(part) for part in first["loc"]) or "its top level"
        raise CheckpointError(f"{path.name}: {where}: {first['msg']}") from None
    # The spools' names are checked against the render's own when it is resumed (`_restore`).
    names = [*checkpoint.video_segments, *(checkpoint.files or ())]
    unsafe = [name for name in names if not _inside(name)]
    if unsafe:
        raise CheckpointError(f"{path.name}: names {unsafe[0]!r}, which no render writes")
    return checkpoint


def _inside(name: str) -> bool:
    """Whether `name` is a relative POSIX path that stays inside the folder it is relative to."""
    posix = PurePosixPath(name)
    return bool(name) and not posix.is_absolute() and ".." not in posix.parts and "\\" not in name


def _checkpoint_to_resume(job_dir: Path, camera: str, identity: dict, note: Callable[[str], None]) -> Checkpoint | None:
    """The checkpoint of `camera` in `job_dir` that this render (`identity`) resumes: its finished folder's
    or its ``.partial`` folder's. Any other is passed over with a note (the caller deletes the folders)."""
    fresh = f"rendering {camera} from its first frame"
    for directory, complete in ((job_dir / camera, True), (job_dir / f"{camera}{PARTIAL_SUFFIX}", False)):
        if not directory.is_dir():
            continue
        path = directory / CHECKPOINT_NAME
        shown = f"{directory.name}/{CHECKPOINT_NAME}"
        if not path.is_file():
            if not complete:
                note(f"{camera}: {directory.name} holds no checkpoint (it stopped before its first); {fresh}")
            continue
        try:
            checkpoint = read_checkpoint(path)
        except CheckpointError as error:
            note(f"{camera}: cannot resume from {shown}: {error}; {fresh}")
            continue
        reason = _mismatch(checkpoint, identity)
        if reason is None and complete and not checkpoint.complete:
            reason = "it is not the checkpoint of a finished camera"
        if reason is None and checkpoint.complete:
            missing = next((name for name in checkpoint.files or () if not (directory / name).is_file()), None)
            reason = None if missing is None else f"it lists {missing}, which is missing"
        if reason is not None:
            note(f"{camera}: discarding {shown}: {reason}; {fresh}")
            continue
        if checkpoint.complete and not complete:
            # Stopped after the camera's last checkpoint, before its folder was renamed: rename it now.
            final = job_dir / camera
            if final.is_dir():
                shutil.rmtree(final)
            directory.replace(final)
        return checkpoint
    return None


def _finished_camera(directory: Path, checkpoint: Checkpoint) -> CameraResult:
    """The result of a camera a stopped render had finished (its complete checkpoint); what is left of its spools
    and video segments (a stop just after that checkpoint) is deleted."""
    shutil.rmtree(directory / ".spool", ignore_errors=True)
    files = [directory / name for name in checkpoint.files or ()]
    return CameraResult(
        checkpoint.camera, directory, checkpoint.frames_done, files, resumed_frames=checkpoint.frames_done
    )


def _restore(
    checkpoint: Checkpoint,
    directory: Path,
    indices: Sequence[int],
    spools: dict[str, LineSpool],
    pipeline: CameraPipeline | None,
    radiance_files: RadianceWriter | None,
    result: CameraResult,
) -> list[str]:
    """Take a camera's render up from `checkpoint`: spools cut back to their checkpointed lines, every file
    written after it deleted, the pipeline's and the radiance files' state restored, `result` holding the
    files and frames done. Returns the video segments so far. CheckpointError when the folder does not
    hold what the checkpoint says."""
    done = checkpoint.frames_done
    if not (0 < done < len(indices)) or checkpoint.next_frame != indices[done] or done % checkpoint.interval_frames:
        raise CheckpointError(
            f"{CHECKPOINT_NAME} says {done} frames are done and frame {checkpoint.next_frame} is next, which is no "
            f"checkpoint of these {len(indices)} frames every {checkpoint.interval_frames}"
        )
    if set(checkpoint.spools) != set(spools):
        raise CheckpointError(
            f"{CHECKPOINT_NAME} marks the spools {', '.join(sorted(checkpoint.spools)) or 'none'}, this render "
            f"writes {', '.join(sorted(spools))}"
        )
    if (checkpoint.pipeline is None) != (pipeline is None) or (checkpoint.radiance is None) != (
        radiance_files is None or radiance_files.format == "exr"
    ):
        raise CheckpointError(f"{CHECKPOINT_NAME} is of a camera with other stages")
    spool_dir = directory / ".spool"
    segments = list(checkpoint.video_segments)
    missing = next((name for name in segments if not (spool_dir / name).is_file()), None)
    if missing is not None:
        raise CheckpointError(f".spool/{missing} is missing")
    try:
        for name, (lines, size_bytes) in checkpoint.spools.items():
            spools[name].resume(lines, size_bytes)
        if pipeline is not None:
            pipeline.restore_state(checkpoint.pipeline)
    except (OSError, KeyError, TypeError, ValueError) as error:
        raise CheckpointError(str(error)) from None
    result.files = [directory / line for line in spools["files"]]
    if any(not _inside(path.relative_to(directory).as_posix()) for path in result.files):
        raise CheckpointError(".spool/files.lines names a file outside the camera's folder")
    absent = next((path for path in result.files if not path.is_file()), None)
    if absent is not None:
        raise CheckpointError(f"{absent.relative_to(directory)}, written before the checkpoint, is missing")
    if checkpoint.radiance is not None:
        radiance_files.scale_cd_m2_per_dn = checkpoint.radiance.scale_cd_m2_per_dn
        radiance_files.clipped = dict(checkpoint.radiance.clipped)
    keep = {
        *result.files,
        directory / CHECKPOINT_NAME,
        *(spool.path for spool in spools.values()),
        *(spool_dir / name for name in segments),
    }
    _delete_all_but(directory, keep)
    result.frames = result.resumed_frames = done
    return segments


def _delete_all_but(directory: Path, keep: set[Path]) -> None:
    """Delete every file under `directory` not in `keep` (what frames after a checkpoint wrote, a temporary
    file a stop left), and the folders that leaves empty."""
    emptied = set()
    for path in sorted(directory.rglob("*")):
        if path not in keep and (path.is_file() or path.is_symlink()):
            path.unlink()
            emptied.add(path.parent)
    for folder in sorted(emptied, key=lambda folder: len(folder.parts), reverse=True):
        while folder != directory and folder.name != ".spool" and not any(folder.iterdir()):
            folder.rmdir()
            folder = folder.parent


def _write_checkpoint(
    directory: Path,
    identity: dict,
    indices: Sequence[int],
    result: CameraResult,
    *,
    spools: dict[str, LineSpool] | None = None,
    pipeline: CameraPipeline | None = None,
    radiance_files: RadianceWriter | None = None,
    segments: Sequence[str] = (),
) -> None:
    """Write the camera's checkpoint after `result.frames` frames (atomically): with `spools`, an unfinished
    camera's (the new files appended to the files spool first, every spool flushed and marked); without,
    a finished camera's, listing its files."""
    complete = spools is None
    if not complete:
        files = spools["files"]
        for path in result.files[len(files) :]:
            files.append(path.relative_to(directory).as_posix())
    radiance = (
        None
        if radiance_files is None or radiance_files.format == "exr"
        else RadianceState(scale_cd_m2_per_dn=radiance_files.scale_cd_m2_per_dn, clipped=radiance_files.clipped)
    )
    checkpoint = Checkpoint(
        **identity,
        frames_done=result.frames,
        next_frame=None if complete else indices[result.frames],
        complete=complete,
        pipeline=None if pipeline is None else pipeline.carried_state(),
        radiance=None if complete else radiance,
        spools={} if complete else {name: spool.mark() for name, spool in spools.items()},
        video_segments=list(segments),
        files=[path.relative_to(directory).as_posix() for path in result.files] if complete else None,
    )
    write_text_atomic(directory / CHECKPOINT_NAME, json.dumps(checkpoint.model_dump(mode="json"), indent=1) + "\n")


@dataclass
class _Context:
    job: Job
    camera_index: int
    directory: Path
    renderer: Renderer
    maps: LensMapCache
    executor: ThreadPoolExecutor
    identity: dict
    """The render's `_identity` for this camera's checkpoints."""
    pipelined: bool = False
    """Whether the frames' writes run in the writer thread (`FrameWriter`)."""


@dataclass(frozen=True)
class _WrittenFrame:
    """The frame the writes are of: its index (not the renderer's passes, which a renderer may draw the next
    frame into)."""

    index: int


@dataclass
class _FrameResult:
    """What a frame's writes see of the camera's `CameraResult`: the frames done before this frame (the main
    thread counts on meanwhile), and the list of files, which the writes extend in frame order."""

    frames: int
    files: list[Path]


def _detached(value):
    """`value` sharing no array with anything: arrays copied, dataclasses, lists, tuples and dicts rebuilt around
    detached members; anything else (numbers, strings, frozen states) as it is. What the writer thread gets:
    the renderer draws the next frame into the arrays the passes are views of, and a rig poses its next frame."""
    if isinstance(value, np.ndarray):
        return value.copy()
    if isinstance(value, list | tuple):
        return type(value)(_detached(item) for item in value)
    if isinstance(value, dict):
        return {key: _detached(item) for key, item in value.items()}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = dataclasses.fields(value)
        return replace(value, **{f.name: _detached(getattr(value, f.name)) for f in fields if f.init})
    return value


def _add_stage_records(frames: list[dict[str, float]], written: list[dict[str, float]]) -> None:
    """Add the writer thread's seconds per stage of each frame (`FrameWriter.frames`) to the main thread's
    record of the same frame (`frames`, in order, from the first frame of this run)."""
    for record, writes in zip(frames, written, strict=True):
        for stage, seconds in writes.items():
            record[stage] = record.get(stage, 0.0) + seconds


def _execute_camera(
    context: _Context, indices, resolve_path, save_passes, on_frame, checkpoint: Checkpoint | None, on_resume
) -> CameraResult:
    job, directory = context.job, context.directory
    camera = job.cameras[context.camera_index]
    result = CameraResult(camera.name, directory)
    started = time.perf_counter()
    clock = StageClock()
    stages = {stage.name: stage for stage in camera.stages}
    pipeline = (
        CameraPipeline(job, camera, maps=context.maps, executor=context.executor, clock=clock)
        if "radiance" in camera.render.passes
        else None
    )
    lens = pipeline.lens if pipeline is not None else LensStages(camera, context.maps)
    video = None
    segment = ""
    width_px, height_px = camera.output_size_px or (camera.width_px, camera.height_px)
    video_settings = {
        "width_px": width_px,
        "height_px": height_px,
        "fps": job.fps,
        "codec": camera.profile.codec,
        "preset": camera.profile.codec.preset,
    }
    segments: list[str] = []
    interval = context.identity["interval_frames"]
    # Per-frame lines (camera.jsonl, the annotations) go to files under the camera's folder as they come,
    # not into memory: a long sequence renders in flat memory (issue 23). Deleted when the camera ends.
    spool_dir = directory / ".spool"
    metadata = LineSpool(spool_dir / "camera.lines")
    spools = {"camera": metadata, "files": LineSpool(spool_dir / "files.lines")}
    """Every line spool of the camera by name: what a checkpoint marks (`_write_checkpoint`)."""
    camera_renderer = CameraRenderer(context.renderer, build_scene_graph(job.scene, resolve_path), camera)
    annotator = sequence = detector = None
    formats = ()
    if "annotate" in stages:
        annotator = Annotator(camera_renderer, lens)
        frames_format = stages["io.frames"].params["format"] if "io.frames" in stages else None
        params = stages["annotate"].params
        formats = params["formats"]
        if "detections" in params:
            detector = hog_detector()
            if detector is None:
                raise RuntimeError(
                    "outputs.mot_detections needs OpenCV's HOG people detector, which this OpenCV build "
                    "lacks; install opencv-contrib-python-headless"
                )
        sequence = SequenceAnnotations(
            name=camera.name,
            fps=job.fps,
            width_px=width_px,
            height_px=height_px,
            frame_count=max(indices) + 1 if indices else 0,
            frame_suffix=None if frames_format is None else FRAME_SUFFIX[frames_format],
            image_suffix=IMAGE_SUFFIXES[params.get("images", "jpg")],
            detections=detector is not None,
            spool_dir=spool_dir,
        )
        spools.update(sequence.spools())
        graph = camera_renderer.graph
        actor_nodes = zip(graph.actors, graph.actor_nodes, strict=True)
        track_ids = {actor.name: graph.instance_ids[node] for actor, node in actor_nodes}
        for index, (actor, node) in enumerate(zip(graph.actors, graph.actor_nodes, strict=True)):
            rig = graph.rig(index)
            attributes = None if rig is None or rig.model is None else rig.model.appearance.attributes()
            sequence.describe(
                graph.instance_ids[node],
                name=actor.name,
                cls=actor.cls,
                attributes=attributes,
                rides=None if actor.rides is None else track_ids[actor.rides],
            )
    radiance_files = (
        RadianceWriter(directory / "radiance", stages["io.radiance"].params["format"])
        if "io.radiance" in stages
        else None
    )
    flow_field = FlowField(camera_renderer, lens) if {"io.flow", "io.scene_flow"} & stages.keys() else None
    converge = (
        pipeline is not None and camera.exposure_mode == "auto" and job.settings.auto_exposure_start == "converged"
    )
    frame_writer = FrameWriter(clock, threaded=context.pipelined)
    # The video's encode runs in a thread of its own beside the frame's other writes (`_encoding`).
    encoder = ThreadPoolExecutor(1, thread_name_prefix="camgen-video-encode") if "io.video" in stages else None

    def write_frame_outputs(clock: StageClock, **writes) -> None:
        """One frame's writes (`FrameWriter`: in the writer thread when pipelined), the video's encode beside the
        others (`_encoding`), done when this returns."""
        nonlocal video, segment
        encoding = None
        if writes["rgb8"] is not None and "io.video" in stages:
            if video is None:  # a segment from each checkpoint on (see the module docstring)
                from camgen.io.video import VideoWriter  # PyAV only where a video is written

                with clock("io.video"):
                    segment = _SEGMENT_NAME.format(writes["done"].frames)
                    video = VideoWriter(spool_dir / segment, **video_settings)
            encoding = encoder.submit(_timed, video.write, writes["rgb8"])
        with _encoding(encoding, clock):
            frame_other_writes(clock, **writes)

    def frame_other_writes(
        clock: StageClock, *, frame, done, state, captured, rgb8, stream, scene_radiance, annotated, flow
    ) -> None:
        """A frame's writes but the video's, in this order. `done`: the frames done before this one and the
        camera's list of files, which these writes extend."""
        with clock("io.files"):
            _write_files(context, stages, state, frame, captured, rgb8, stream, done)
        if scene_radiance is not None:
            with clock("io.radiance"):
                done.files.append(radiance_files.write(f"{frame.index:06d}", scene_radiance))
        if annotated is not None:
            with clock("annotate"):
                sequence.add(annotated)
                if cuts_reid_crops(stages) and rgb8 is not None:
                    done.files += write_reid_crops(directory, annotated, rgb8, camera_number=context.camera_index + 1)
            if rgb8 is not None:
                with clock("io.annotation_images"):
                    if "mot" in formats:
                        done.files.append(sequence.write_mot_image(directory, frame.index, rgb8))
                    if "yolo" in formats:
                        done.files += sequence.write_yolo_frame(directory, annotated, rgb8)
                if detector is not None:
                    with clock("annotate.detect"):
                        sequence.add_detections(frame.index, detect_people(detector, rgb8[..., ::-1]))
        if flow is not None:
            flow_px, displacement_m = flow
            with clock("io.flow"):
                if "io.flow" in stages:
                    done.files.append(directory / "flow" / f"{frame.index:06d}.flo")
                    write_flo(done.files[-1], flow_px)
                if "io.scene_flow" in stages:
                    done.files.append(directory / "scene_flow" / f"{frame.index:06d}.exr")
                    write_scene_flow(done.files[-1], displacement_m)
        if "io.camera_metadata" in stages:
            record = state.model_dump(mode="json")
            output_K = record.pop("output_K_px")
            if state.window_px is not None:  # K_px describes the stream; the sensor's is kept beside it
                record["sensor_K_px"] = record["K_px"]
                record["K_px"] = output_K
            if captured is not None:
                record["metered_level_frac"] = captured.metered_level_frac
                if captured.white_balance_rgb is not None:
                    record["white_balance_rgb"] = captured.white_balance_rgb
            metadata.append(json.dumps(record, separators=(",", ":")))
        if save_passes:
            if done.frames == 0:
                table = [vars(instance) for instance in instance_table(job.scene)]
                done.files.append(directory / "passes" / "instances.json")
                write_text_atomic(done.files[-1], json.dumps(table, indent=1))
            raw = None if captured is None else captured.raw_dn
            with clock("io.passes"):
                _save_passes(directory / "passes" / f"{frame.index:06d}.npz", stream, raw, done)

    try:
        if checkpoint is not None:
            segments = _restore(checkpoint, directory, indices, spools, pipeline, radiance_files, result)
            converge = False  # the restored exposure is where the frames before left it
            if on_resume is not None:
                on_resume(camera.name, result.frames, len(indices))
        for index in indices[result.frames :]:
            frame_writer.check()  # a write that failed stops the render here
            state = camera.states[index] if pipeline is None else pipeline.state_for(index)
            with clock("render"):
                # A frame drawn to meter the view is drawn sharp: its exposure is the profile's guess.
                frame = camera_renderer.frame(index, state, sharp=converge)
            if converge:
                # Start as a camera that has watched this view for a while, not from the profile's guess.
                converge = False
                pipeline.converge_exposure(state, frame.passes)
                settled = pipeline.state_for(index)
                if camera_renderer.redraws_settled(state, settled):
                    with clock("render"):
                        frame = camera_renderer.frame(index, settled)  # the blur spans the settled exposure
                state = settled
            captured = None
            if pipeline is not None:
                rng = frame_rng(job.seed, context.camera_index, frame.index)
                captured = pipeline.process(state, frame.passes, rng=rng)
            rgb8 = None if captured is None else captured.rgb8
            if rgb8 is not None and state.window_px is not None:
                with clock("isp.eptz"):
                    rgb8 = crop_and_scale(rgb8, state.window_px, camera.output_size_px)
            with clock("optics.passes"):
                stream = _stream_passes(camera, stages, state, frame.passes, lens, save_passes)
            # What the writer gets must not change under it: the renderer draws the next frame into the passes
            # these are views of (without a lens stage the stream is a crop of them).
            detach = _detached if context.pipelined else (lambda value: value)
            stream = detach(stream)
            scene_radiance = None
            if radiance_files is not None:
                with clock("io.radiance"):
                    scene_radiance = lens.scene_radiance(state, frame.passes.radiance)
                    if state.window_px is not None:
                        scene_radiance = crop_and_scale(scene_radiance, state.window_px, camera.output_size_px)
            annotated = None
            if annotator is not None:
                window = state.window_px

                def to_stream(image, window=window):
                    return (
                        image if window is None else crop_and_scale(image, window, camera.output_size_px, nearest=True)
                    )

                with clock("annotate"):  # draws each actor alone: OpenGL, so in this thread
                    annotated = annotator.annotate(state, stream, post=None if window is None else to_stream)
            flow = None
            if flow_field is not None and frame.index + 1 < job.frame_count:
                with clock("io.flow"):  # after the annotations: it moves the actors to the next frame
                    flow = flow_field.flow(state, camera.states[frame.index + 1], stream)
            writes = functools.partial(
                write_frame_outputs,
                frame=_WrittenFrame(frame.index),
                done=_FrameResult(result.frames, result.files),
                state=state,
                captured=None if captured is None else detach(replace(captured, rgb8=None)),
                rgb8=detach(rgb8),
                stream=stream,
                scene_radiance=detach(scene_radiance),
                annotated=detach(annotated),
                flow=detach(flow),
            )
            frame_writer.submit(writes)
            result.frames += 1
            if result.frames % interval == 0 and result.frames < len(indices):
                frame_writer.drain()  # a checkpoint describes frames written, every one of them
                if video is not None:  # the segment ends here: the next starts with a fresh encoder
                    _close_segment(video, segment, segments, clock)
                    video = None
                with clock("io.checkpoint"):
                    _write_checkpoint(
                        directory,
                        context.identity,
                        indices,
                        result,
                        spools=spools,
                        pipeline=pipeline,
                        radiance_files=radiance_files,
                        segments=segments,
                    )
            clock.end_frame()
            if on_frame is not None:
                on_frame(camera.name, frame.index)
        frame_writer.close()
        if frame_writer.threaded:
            _add_stage_records(clock.frames, frame_writer.frames)
        if video is not None:
            _close_segment(video, segment, segments, clock)
            video = None
        if segments:
            from camgen.io.video import join_videos

            with clock("io.video"):
                join_videos([spool_dir / name for name in segments], directory / "video.mp4", **video_settings)
            result.files.append(directory / "video.mp4")
        if radiance_files is not None and result.frames:
            result.files.append(radiance_files.close())
        if len(metadata):
            result.files.append(metadata.write(directory / "camera.jsonl"))
        if sequence is not None:
            with clock("annotate"):
                if "mot" in formats:
                    result.files += sequence.write_mot(directory)
                if "coco" in formats:
                    result.files.append(sequence.write_coco(directory / "coco.json"))
                if "yolo" in formats:
                    result.files.append(sequence.write_yolo_data(directory))
        # Kept in the finished folder until the job's manifest: a stop before it resumes without this camera.
        # Written before the spools and segments go, so that a stop between the two leaves a checkpoint that
        # holds (`_finished_camera` clears what is left of the spools).
        _write_checkpoint(directory, context.identity, indices, result, pipeline=pipeline)
        for spool in spools.values():
            spool.close()
        for name in segments:
            (spool_dir / name).unlink()
        if spool_dir.is_dir():
            spool_dir.rmdir()
        clock.end_frame()
        result.stage_frames, result.finish_s = clock.frames[:-1], clock.frames[-1]
        result.frame_wall_s = clock.frame_wall_s[:-1]
        result.frame_cpu_s, result.finish_cpu_s = clock.frame_cpu_s[:-1], clock.frame_cpu_s[-1]
    except BaseException:
        # The folder is deleted (`discard_unfinished`) or, for a render that resumes, kept with its spools
        # and the segments up to its last checkpoint; the segment being written is never finished. The writer
        # and the encoder end first: nothing writes into the folder after this.
        frame_writer.stop()
        if encoder is not None:
            encoder.shutdown(wait=True, cancel_futures=True)
        if video is not None:
            video.abort()
        for spool in spools.values():
            spool.close(keep=True)
        raise
    finally:
        if encoder is not None:
            encoder.shutdown(wait=True)
        camera_renderer.close()
    result.total_s = time.perf_counter() - started
    return result


ENCODE_WAIT_STAGE = "io.video.wait"
"""The stage of a frame's wait for its video encode after its other writes (`_encoding`): in the writer's thread
when pipelined, so kept apart from ``io.wait``, the main thread's wait for the writer
(`camgen.plan.writer.WAIT_STAGE`)."""


def _timed(function: Callable, *args) -> float:
    """Call `function(*args)`; the seconds it took."""
    start = time.perf_counter()
    function(*args)
    return time.perf_counter() - start


@contextlib.contextmanager
def _encoding(encoding, clock: StageClock):
    """Around a frame's other writes while its video frame is encoded in the encoder's thread (`encoding`, a
    future of `_timed`, or None): afterwards, wait for the encode, add its seconds to the frame's ``io.video``
    and the wait to ``io.video.wait`` (`ENCODE_WAIT_STAGE`), and raise the encode's exception. Where the other
    writes raise, theirs is raised once the encode has ended (the caller then aborts the video), and the encode's
    is dropped.

    The encode (x265 or x264, one thread for reproducible bytes: `camgen.io.video`) and the frame, depth and raw
    files (OpenImageIO's PNG and DNG writers) each keep one core busy and release the GIL, so on two cores the
    frame's writes take about the longer of the two instead of their sum (BENCHMARKS.md, end to end).
    """
    if encoding is None:
        yield
        return
    try:
        yield
    except BaseException:
        concurrent.futures.wait([encoding])
        raise
    with clock(ENCODE_WAIT_STAGE):
        seconds = encoding.result()
    clock.add("io.video", seconds)


def _close_segment(video, name: str, segments: list[str], clock: StageClock) -> None:
    """Finish the video segment `name` being written (its file complete under ``.spool/``) and list it."""
    with clock("io.video"):
        video.close()
    segments.append(name)


FRAME_SUFFIX = {"png": ".png", "tiff": ".tiff", "exr": ".exr"}
DEPTH_SUFFIX = {"png16": ".png", "exr": ".exr"}


def _stream_passes(camera: CameraJob, stages, state, rendered: Passes, lens: LensStages, save_passes: bool) -> Passes:
    """The frame's passes through the lens and onto the stream (a virtual PTZ's crop), once, holding
    only those that the saved passes, the EXR frames, the depth files, the annotations or the flow use."""
    radiance = save_passes or ("io.frames" in stages and stages["io.frames"].params["format"] == "exr")
    flow = "io.flow" in stages or "io.scene_flow" in stages
    depth = save_passes or "io.depth" in stages or radiance or flow  # the blur stages read depth too
    ids = save_passes or "annotate" in stages or flow
    if not (radiance or depth or ids):
        return Passes()
    through = lens.apply(
        state,
        Passes(
            radiance=rendered.radiance if radiance else None,
            depth_m=rendered.depth_m if depth else None,
            instance_id=rendered.instance_id if ids else None,
        ),
    )
    return through if state.window_px is None else _eptz_passes(through, state.window_px, camera.output_size_px)


def _write_files(context: _Context, stages, state, frame, captured, rgb8, stream: Passes, result: CameraResult) -> None:
    """The optional per-frame files: raw DNG, frames (8-bit stream or linear EXR radiance), depth.
    `stream`: the frame's passes through the lens, on the stream (`_stream_passes`)."""
    camera = context.job.cameras[context.camera_index]
    directory, name = context.directory, f"{frame.index:06d}"
    if "io.raw_dng" in stages and captured is not None:
        sensor = camera.profile.sensor
        qe = sensor.quantum_efficiency
        mono = sensor.cfa == "mono"
        gains = captured.white_balance_rgb
        path = directory / "raw" / f"{name}.dng"
        write_dng(
            path,
            captured.raw_dn,
            cfa=sensor.cfa,
            black_level_dn=sensor.black_level_dn,
            white_level_dn=sensor.white_level_dn,
            bit_depth=sensor.bit_depth,
            color_matrix_xyz_to_camera=None if mono else np.diag([qe.r, qe.g, qe.b]) @ SRGB_FROM_XYZ,
            as_shot_neutral_rgb=None if mono or gains is None else tuple(min(gains) / g for g in gains),
            camera_name=camera.profile_name,
            exposure_time_s=state.exposure_time_s,
            f_number=state.f_number,
            temperature_c=sensor.temperature_c,
        )
        result.files.append(path)
    if "io.raw" in stages and captured is not None:
        kind = stages["io.raw"].params["format"]
        sensor = camera.profile.sensor
        if result.frames == 0:  # what a reader needs to interpret the samples, once per camera
            meta = directory / "raw" / "raw.json"
            write_text_atomic(
                meta,
                json.dumps(
                    {
                        "cfa": sensor.cfa,
                        "black_level_dn": sensor.black_level_dn,
                        "white_level_dn": sensor.white_level_dn,
                        "bit_depth": sensor.bit_depth,
                        "unit": "DN as the ADC delivered them, black level included",
                    },
                    indent=1,
                ),
            )
            result.files.append(meta)
        path = directory / "raw" / f"{name}{RAW_SUFFIX[kind]}"
        raw = np.ascontiguousarray(captured.raw_dn)
        if kind == "exr":
            write_frame(path, raw.astype(np.float32), format="exr")
        else:
            write_frame(path, raw.astype(np.uint16), format="png" if kind == "png16" else "tiff")
        result.files.append(path)
    if "io.frames" in stages:
        kind = stages["io.frames"].params["format"]
        path = directory / "frames" / f"{name}{FRAME_SUFFIX[kind]}"
        if kind == "exr":  # linear: the scene radiance through the lens, cd/m², before the sensor
            write_frame(path, np.ascontiguousarray(stream.radiance, dtype=np.float32), format="exr")
        elif rgb8 is not None:
            write_frame(path, rgb8, format=kind)
        result.files.append(path)
    if "io.depth" in stages:
        kind = stages["io.depth"].params["format"]
        path = directory / "depth" / f"{name}{DEPTH_SUFFIX[kind]}"
        write_depth(path, stream.depth_m, format=kind)
        result.files.append(path)


def _eptz_passes(passes, window, output_size_px):
    """The stream's crop of output-size passes: radiance averaged, depth and ids by nearest pixel."""
    return type(passes)(
        radiance=None if passes.radiance is None else crop_and_scale(passes.radiance, window, output_size_px),
        depth_m=None
        if passes.depth_m is None
        else crop_and_scale(passes.depth_m, window, output_size_px, nearest=True),
        instance_id=None
        if passes.instance_id is None
        else crop_and_scale(passes.instance_id, window, output_size_px, nearest=True),
    )


def _save_passes(path: Path, passes, raw_dn, result: CameraResult) -> None:
    arrays = {
        key: value
        for key, value in (
            ("radiance_cd_m2", passes.radiance),
            ("depth_m", passes.depth_m),
            ("instance_id", passes.instance_id),
            ("raw_dn", raw_dn),
        )
        if value is not None
    }
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        np.savez_compressed(handle, **arrays)
    result.files.append(path)
