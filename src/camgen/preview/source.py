"""Reading what a render wrote, for the preview: which camera directories a path names, and each one's
frames, COCO annotations, per-frame camera states and the dataset card above it.

Only the files every render writes are read (coco.json, camera.jsonl, video.mp4 or frames/, the job's
manifest.json), never the MOT or YOLO layouts. Problems are `ConfigError`s naming the path and the fix.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from camgen.errors import ConfigError
from camgen.io.manifest import JOB_DIRECTORY_NAME, JOB_NAME, MANIFEST_NAME
from camgen.io.video import read_video_rgb8

COCO_NAME = "coco.json"
CAMERA_STATES_NAME = "camera.jsonl"
VIDEO_NAME = "video.mp4"
FRAMES_DIRECTORY = "frames"
FRAME_SUFFIXES = (".png", ".tif", ".tiff")
"""8-bit delivered frames; EXR frames hold linear radiance, not what the camera delivers."""
DATASET_CARD_NAME = "DATASET_CARD.md"
"""The card a batch writes at its output's root."""
DEFAULT_FPS = 25.0
"""Frame rate of the preview when neither the manifest nor camera.jsonl gives one."""

WHAT_TO_GIVE = (
    "give the directory `camgen render -o` or `camgen batch -o` wrote, a job directory (<scene>-<hash8>) "
    "or one camera's directory inside it"
)


@dataclass(frozen=True)
class CameraOutput:
    """One camera's directory of one job: ``<job>/<camera>/``."""

    directory: Path
    job_directory: Path

    @property
    def name(self) -> str:
        return self.directory.name

    @property
    def card_path(self) -> Path | None:
        """The dataset card of the batch or render this job belongs to, if there is one."""
        path = self.job_directory.parent / DATASET_CARD_NAME
        return path if path.is_file() else None


@dataclass
class RenderedSequence:
    """What the preview draws of one camera: rendered frame indices in stream order, each frame's COCO
    annotations and camera state, the categories by id, the frame size and rate."""

    output: CameraOutput
    frame_indices: list[int]
    annotations: dict[int, list[dict]]
    states: dict[int, dict]
    categories: dict[int, dict]
    width_px: int
    height_px: int
    fps: float
    tracks: dict[int, dict] = field(default_factory=dict)

    def frames_rgb8(self) -> Iterator[np.ndarray]:
        """The delivered 8-bit frames in stream order: from video.mp4, else from frames/."""
        video = self.output.directory / VIDEO_NAME
        if video.is_file():
            yield from read_video_rgb8(video)
            return
        for path in _frame_files(self.output.directory):
            image = cv2.imread(str(path), cv2.IMREAD_COLOR)
            if image is None:
                raise ConfigError(f"{path}: cannot be read as an image; render it again")
            yield cv2.cvtColor(image, cv2.COLOR_BGR2RGB)


def find_camera_outputs(path: str | Path, cameras: list[str] | None = None) -> list[CameraOutput]:
    """The camera directories `path` names, sorted: a camera directory itself, the cameras of a job
    directory, or the cameras of every job directory directly inside `path` (a render's or a batch's
    output). `cameras` keeps only those names. Raises ConfigError, naming the fix, when there is none."""
    path = Path(path)
    if not path.exists():
        raise ConfigError(f"{path}: no such directory; {WHAT_TO_GIVE}")
    if not path.is_dir():
        raise ConfigError(f"{path}: is a file, not a directory; {WHAT_TO_GIVE}")
    if _is_camera_directory(path):
        found = [CameraOutput(path, path.parent)]
    elif _is_job_directory(path):
        found = _cameras_of(path)
    else:
        found = [camera for job in sorted(path.iterdir()) if _is_job_directory(job) for camera in _cameras_of(job)]
    if not found:
        raise ConfigError(
            f"{path}: no camgen output in it (no job directory with {MANIFEST_NAME}, no camera directory with "
            f"{COCO_NAME} or {CAMERA_STATES_NAME}); {WHAT_TO_GIVE}"
        )
    if cameras:
        names = sorted({camera.name for camera in found})
        unknown = sorted(set(cameras) - set(names))
        if unknown:
            raise ConfigError(f"--camera {', '.join(unknown)}: no such camera in {path} (it has {', '.join(names)})")
        found = [camera for camera in found if camera.name in cameras]
    return found


def check_camera_output(output: CameraOutput) -> None:
    """Raise ConfigError, naming the fix, unless `output` has COCO annotations and 8-bit frames."""
    if not (output.directory / COCO_NAME).is_file():
        raise ConfigError(
            f"{output.directory}: no {COCO_NAME}; the preview draws the COCO annotations: render with coco in "
            "outputs.annotations (it is there by default)"
        )
    if not (output.directory / VIDEO_NAME).is_file() and not _frame_files(output.directory):
        raise ConfigError(
            f"{output.directory}: no {VIDEO_NAME} and no PNG or TIFF frames in {FRAMES_DIRECTORY}/; render with "
            "outputs.video: true or outputs.frames: png"
        )


def load_sequence(output: CameraOutput) -> RenderedSequence:
    """Read one camera's coco.json, camera.jsonl (when written) and its job's frame rate."""
    check_camera_output(output)
    coco = _read_json(output.directory / COCO_NAME)
    try:
        images = {image["id"]: image for image in coco["images"]}
        categories = {category["id"]: category for category in coco["categories"]}
        annotations: dict[int, list[dict]] = {image["frame_index"]: [] for image in images.values()}
        for annotation in coco["annotations"]:
            if annotation.get("iscrowd"):  # a crowd region: its members are drawn from MOT's view, not here
                continue
            annotations[images[annotation["image_id"]]["frame_index"]].append(annotation)
        tracks = {track["id"]: track for track in coco.get("tracks", [])}
        size = next(iter(images.values()), None) or next(iter(coco.get("videos", [])), None)
        width_px, height_px = (int(size["width"]), int(size["height"])) if size else (0, 0)
    except (KeyError, TypeError, StopIteration) as error:
        raise ConfigError(
            f"{output.directory / COCO_NAME}: not a COCO file as camgen writes it (missing {error}); render it again"
        ) from error
    states = _read_states(output.directory / CAMERA_STATES_NAME)
    frame_indices = sorted(states) if states else sorted(annotations)
    return RenderedSequence(
        output=output,
        frame_indices=frame_indices,
        annotations=annotations,
        states=states,
        categories=categories,
        width_px=width_px,
        height_px=height_px,
        fps=_fps(output.job_directory, states),
        tracks=tracks,
    )


def read_card(output: CameraOutput) -> str | None:
    """The dataset card's markdown, or None when the output has none."""
    path = output.card_path
    return None if path is None else path.read_text(encoding="utf-8")


def _is_camera_directory(path: Path) -> bool:
    return any((path / name).is_file() for name in (COCO_NAME, CAMERA_STATES_NAME))


def _is_job_directory(path: Path) -> bool:
    if not path.is_dir():
        return False
    return (
        (path / MANIFEST_NAME).is_file() or (path / JOB_NAME).is_file() or bool(JOB_DIRECTORY_NAME.fullmatch(path.name))
    )


def _cameras_of(job: Path) -> list[CameraOutput]:
    return [
        CameraOutput(child, job) for child in sorted(job.iterdir()) if child.is_dir() and _is_camera_directory(child)
    ]


def _frame_files(directory: Path) -> list[Path]:
    frames = directory / FRAMES_DIRECTORY
    if not frames.is_dir():
        return []
    return sorted(path for path in frames.iterdir() if path.suffix.lower() in FRAME_SUFFIXES)


def _read_json(path: Path):
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ConfigError(f"{path}: not valid JSON ({error}); render it again") from error
    except OSError as error:
        raise ConfigError(f"{path}: cannot be read ({error.strerror or error})") from error


def _read_states(path: Path) -> dict[int, dict]:
    """camera.jsonl by frame index; empty when the render wrote none (outputs.camera_metadata off)."""
    if not path.is_file():
        return {}
    states = {}
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
            states[int(record["frame"])] = record
        except (json.JSONDecodeError, KeyError, TypeError, ValueError) as error:
            raise ConfigError(
                f"{path}:{number}: not a camera state as camgen writes it ({error}); render it again"
            ) from error
    return states


def _fps(job_directory: Path, states: dict[int, dict]) -> float:
    """The job's frame rate from its manifest, else from camera.jsonl's times, else `DEFAULT_FPS`."""
    manifest = job_directory / MANIFEST_NAME
    if manifest.is_file():
        fps = _read_json(manifest).get("fps")
        if isinstance(fps, int | float) and fps > 0:
            return float(fps)
    times = [state.get("time_s") for _, state in sorted(states.items())[:2]]
    frames = sorted(states)[:2]
    if len(times) == 2 and all(isinstance(t, int | float) for t in times) and times[1] > times[0]:
        return (frames[1] - frames[0]) / (times[1] - times[0])
    return DEFAULT_FPS
