"""Track a target in camgen's video the way the seed paper's PTZ application does, scored against the
instance pass.

Seed paper §III.2 and Fig. 3: background subtraction (a) and blob detection (b) find the moving
object while the camera stands still; the hue histogram of the blob initialises OpenCV's CamShift
(Bradski 1998, the paper's [17]), which then follows the object's colour even while the camera moves.
camgen renders the instance-id pass through the same lens model as the pixels, so each frame also has
an exact ground-truth box to score the tracker against.

Usage::

    python examples/ptz_tracking.py [SCENE.yaml] [--target NAME] [--camera NAME] [--frames N] [--out DIR]

renders the scene with its passes saved, tracks the target in the camera's ``video.mp4``, prints the
score and writes ``tracking.json`` into the camera directory. The functions below work on any
rendered camera directory (``video.mp4``, ``camera.jsonl``, ``passes/<frame>.npz`` and
``passes/instances.json``, as written by ``camgen render --save-passes``).

Boxes are OpenCV rectangles ``(x_px, y_px, width_px, height_px)`` in whole pixels: a box covers
columns x … x + width − 1 and rows y … y + height − 1, with pixel centres at integer coordinates
(DESIGN.md "Conventions"). Frames are (H, W, 3) uint8 RGB.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import cv2
import numpy as np

from camgen.errors import ConfigError

Box = tuple[int, int, int, int]
"""(x_px, y_px, width_px, height_px), an OpenCV rectangle of whole pixels."""

REPO = Path(__file__).resolve().parents[1]
DEFAULT_SCENE = REPO / "scenes" / "ptz_follow.yaml"
DEFAULT_TARGET = "walker_1"
HIT_IOU = 0.5
"""IoU from which a tracked frame counts as a hit (the PASCAL VOC / OTB success threshold)."""


@dataclass(frozen=True)
class TrackerSettings:
    """Parameters of the detect-then-CamShift tracker; OpenCV's 8-bit HSV ranges (hue 0…179)."""

    warmup_frames: int = 5
    """Static frames the background model must have seen before it may detect; it restarts whenever
    the camera moves, because a moving camera makes the whole background look like foreground."""
    history_frames: int = 50
    """MOG2 history: frames over which the background model forgets."""
    variance_threshold: float = 16.0
    """MOG2 squared Mahalanobis distance above which a pixel is foreground (OpenCV's default)."""
    min_blob_area_px: int = 40
    """Foreground blobs smaller than this (noise, codec flicker) are not candidates."""
    motion_threshold_dn: int = 20
    """Grey-level difference to the previous frame from which a pixel counts as moving, 8-bit DN."""
    hue_bins: int = 32
    min_saturation: int = 60
    """Pixels below this saturation have no reliable hue and are left out of histogram and
    back-projection (the grey ground, sky and walls of a surveillance scene)."""
    min_value: int = 32
    """Pixels darker than this are left out likewise (sensor noise dominates their hue)."""
    camshift_iterations: int = 10
    camshift_epsilon_px: float = 1.0
    """CamShift stops after this many mean-shift iterations or when the window moves less than this."""
    lost_area_px: float = 16.0
    """A CamShift ellipse box smaller than this means the window has collapsed: the track is lost."""


@dataclass(frozen=True)
class TrackStep:
    """The tracker's output for one frame."""

    frame: int
    event: str
    """'detected' (initialised from a blob in this frame), 'tracked', 'lost' (the window collapsed in
    this frame) or 'searching' (no track, waiting for a detection)."""
    box_px: Box | None
    """Bounding rectangle of CamShift's rotated box, clipped to the image; None without a track."""
    centre_px: tuple[float, float] | None
    """Centre of CamShift's rotated box (x, y), px; None without a track."""


@dataclass(frozen=True)
class FrameScore:
    frame: int
    event: str
    ground_truth_px: Box | None
    track_px: Box | None
    centre_px: tuple[float, float] | None
    iou: float | None
    """IoU of track and ground truth; None when either is missing."""
    centre_inside: bool | None
    """Whether the track's centre lies inside the ground-truth box; None without ground truth."""


@dataclass(frozen=True)
class TrackingSummary:
    frames: int
    frames_visible: int
    """Frames in which the target has at least one pixel in the instance pass."""
    frames_tracked: int
    """Frames in which the tracker reports a box."""
    frames_scored: int
    """Frames with both a track and a ground-truth box."""
    mean_iou: float | None
    """Mean IoU over the scored frames; None when no frame was scored."""
    hit_rate: float | None
    """Fraction of visible frames tracked with IoU ≥ HIT_IOU (an untracked frame is a miss)."""
    centre_inside_rate: float | None
    """Fraction of visible frames whose track centre lies inside the ground-truth box."""
    false_track_frames: int
    """Frames tracked while the target is not visible."""


# --- reading a rendered camera directory -------------------------------------------------------------


def read_video_rgb(path: str | Path) -> list[np.ndarray]:
    """Decode every frame of a video as (H, W, 3) uint8 RGB (PyAV)."""
    import av

    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"{path}: no such video; render the scene first (camgen render)")
    with av.open(str(path)) as container:
        return [frame.to_ndarray(format="rgb24") for frame in container.decode(video=0)]


def read_camera_states(camera_dir: str | Path) -> list[dict]:
    """The per-frame camera states of ``camera.jsonl`` (frame, pan_deg, K_px, T_world_from_cam, …)."""
    path = Path(camera_dir) / "camera.jsonl"
    if not path.is_file():
        raise ConfigError(f"{path}: not found; is {camera_dir} a camera directory written by camgen render?")
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line]


def camera_moved(states: Sequence[dict]) -> np.ndarray:
    """(N,) bool: whether the camera's view changed since the previous frame (pose, K or distortion).

    The first frame counts as not moved. A real PTZ head reports its position likewise, which is how
    a tracker knows to restart its background model.
    """
    keys = ("T_world_from_cam", "K_px", "distortion")
    moved = np.zeros(len(states), dtype=bool)
    for i in range(1, len(states)):
        moved[i] = not all(np.allclose(states[i][key], states[i - 1][key], rtol=0, atol=1e-9) for key in keys)
    return moved


def target_instance_id(camera_dir: str | Path, target: str) -> int:
    """The instance id of the actor named `target`, from ``passes/instances.json``."""
    path = Path(camera_dir) / "passes" / "instances.json"
    if not path.is_file():
        raise ConfigError(f"{path}: not found; render with the passes saved (camgen render --save-passes)")
    table = json.loads(path.read_text(encoding="utf-8"))
    actors = [row for row in table if row["kind"] == "actor"]
    for row in actors:
        if row["name"] == target:
            return int(row["instance_id"])
    names = ", ".join(row["name"] for row in actors) or "none"
    raise ConfigError(f"--target {target}: no such actor in {path} (actors: {names})")


def tight_box(mask: np.ndarray) -> Box | None:
    """Smallest box holding every True pixel of the (H, W) `mask`; None if there is none."""
    rows = np.flatnonzero(mask.any(axis=1))
    if rows.size == 0:
        return None
    columns = np.flatnonzero(mask.any(axis=0))
    return (int(columns[0]), int(rows[0]), int(columns[-1] - columns[0] + 1), int(rows[-1] - rows[0] + 1))


def ground_truth_boxes(camera_dir: str | Path, instance_id: int, frames: Sequence[int]) -> list[Box | None]:
    """Ground-truth boxes of one instance from the saved instance pass.

    The instance pass has gone through the same lens model as the pixels and is point-sampled at pixel
    centres, so each box holds exactly the video pixels whose centre sees the instance.

    Parameters
    ----------
    camera_dir : path
        A camera directory rendered with its passes saved.
    instance_id : int
        The instance's id (`target_instance_id`).
    frames : sequence of int
        Frame numbers; each reads ``passes/<frame:06d>.npz``.

    Returns
    -------
    list of Box or None
        Per frame, the tight box of the instance's pixels; None where none is visible.
    """
    boxes = []
    for frame in frames:
        path = Path(camera_dir) / "passes" / f"{frame:06d}.npz"
        if not path.is_file():
            raise ConfigError(f"{path}: not found; render with the passes saved (camgen render --save-passes)")
        with np.load(path) as passes:
            if "instance_id" not in passes:
                raise ConfigError(
                    f"{path}: holds no instance_id pass (it has {', '.join(passes.files)}); the plan renders it only "
                    "when the scene asks for annotations (outputs.annotations)"
                )
            boxes.append(tight_box(passes["instance_id"] == instance_id))
    return boxes


# --- detection: background subtraction and blobs (Fig. 3 a, b) ---------------------------------------


def foreground_blobs(foreground: np.ndarray, min_area_px: int) -> list[np.ndarray]:
    """Connected components of the (H, W) bool `foreground`, cleaned by a morphological opening
    (drops speckle noise) and closing (fills holes); each as an (H, W) bool mask, at least
    `min_area_px` pixels."""
    mask = foreground.astype(np.uint8)
    mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3)))
    mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (7, 7)))
    count, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    return [labels == label for label in range(1, count) if stats[label, cv2.CC_STAT_AREA] >= min_area_px]


def most_moving_blob(blobs: Sequence[np.ndarray], moving: np.ndarray) -> np.ndarray | None:
    """The blob with the most pixels that changed since the previous frame (`moving`, (H, W) bool).

    A background model also flags ghosts — background uncovered where an object stood while the model
    learned — and they do not move; an object does. None if no blob moves at all.
    """
    motion_px = [int(np.count_nonzero(blob & moving)) for blob in blobs]
    if not motion_px or max(motion_px) == 0:
        return None
    return blobs[int(np.argmax(motion_px))]


# --- CamShift on the hue back-projection ---------------------------------------------------------------


def colour_mask(hsv: np.ndarray, settings: TrackerSettings) -> np.ndarray:
    """(H, W) uint8 mask (255 / 0) of the pixels saturated and bright enough to have a usable hue."""
    low = np.array([0, settings.min_saturation, settings.min_value], dtype=np.uint8)
    high = np.array([179, 255, 255], dtype=np.uint8)
    return cv2.inRange(hsv, low, high)


def hue_histogram(hsv: np.ndarray, blob: np.ndarray, settings: TrackerSettings) -> np.ndarray:
    """Hue histogram (hue_bins, 1) float32 of the blob's coloured pixels, scaled to a peak of 255."""
    mask = colour_mask(hsv, settings) & (blob.astype(np.uint8) * 255)
    histogram = cv2.calcHist([hsv], [0], mask, [settings.hue_bins], [0, 180])
    return cv2.normalize(histogram, None, 0, 255, cv2.NORM_MINMAX)


def hue_back_projection(hsv: np.ndarray, histogram: np.ndarray, settings: TrackerSettings) -> np.ndarray:
    """(H, W) uint8: each pixel's hue looked up in `histogram`, 0 where the hue is unreliable."""
    projection = cv2.calcBackProject([hsv], [0], histogram, [0, 180], 1)
    return projection & colour_mask(hsv, settings)


def camshift_step(
    projection: np.ndarray, window: Box, settings: TrackerSettings
) -> tuple[Box, Box, tuple[float, float]] | None:
    """One CamShift update from `window`: (next search window, bounding box of the rotated box clipped to
    the image, its centre (x, y) px), or None when the window has collapsed (too little mass left)."""
    criteria = (
        cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT,
        settings.camshift_iterations,
        settings.camshift_epsilon_px,
    )
    rotated, next_window = cv2.CamShift(projection, window, criteria)
    (centre_x, centre_y), (width, height), _ = rotated
    if width * height < settings.lost_area_px or next_window[2] * next_window[3] == 0:
        return None
    x, y, w, h = cv2.boundingRect(cv2.boxPoints(rotated).astype(np.float32))
    height_px, width_px = projection.shape
    x0, y0 = max(x, 0), max(y, 0)
    x1, y1 = min(x + w, width_px), min(y + h, height_px)
    box = (x0, y0, x1 - x0, y1 - y0)
    return tuple(int(v) for v in next_window), box, (float(centre_x), float(centre_y))


def track_target(
    frames_rgb: Sequence[np.ndarray], moved: Sequence[bool], settings: TrackerSettings = TrackerSettings()
) -> list[TrackStep]:
    """Detect the moving object while the camera is static, then follow its hue with CamShift.

    Per frame: the MOG2 background model learns (it restarts when `moved` says the camera's view
    changed); without a track, once the model has seen `warmup_frames` static frames, the foreground
    blob that moves most becomes the target, and the hue histogram of its pixels initialises CamShift;
    with a track, CamShift follows the hue back-projection — through camera motion too — until its
    window collapses, and the tracker searches again. Ground truth is never used.

    Parameters
    ----------
    frames_rgb : sequence of (H, W, 3) uint8
        The video, RGB.
    moved : sequence of bool, one per frame
        Whether the camera's view changed since the previous frame (`camera_moved`).
    settings : TrackerSettings

    Returns
    -------
    list of TrackStep, one per frame.
    """
    if len(moved) != len(frames_rgb):
        raise ValueError(f"moved has {len(moved)} entries for {len(frames_rgb)} frames")
    steps = []
    subtractor = None
    static_frames = 0
    previous_grey = None
    histogram = None
    window = None
    for index, rgb in enumerate(frames_rgb):
        hsv = cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV)
        grey = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
        if subtractor is None or moved[index]:
            subtractor = cv2.createBackgroundSubtractorMOG2(
                history=settings.history_frames, varThreshold=settings.variance_threshold, detectShadows=True
            )
            static_frames = 0
            previous_grey = None  # a difference across a camera move is not object motion
        # detectShadows marks shadows 127 and objects 255: a cast shadow is not part of the object.
        foreground = subtractor.apply(rgb) == 255
        static_frames += 1
        event, update = "searching", None
        if window is not None:
            update = camshift_step(hue_back_projection(hsv, histogram, settings), window, settings)
            event = "tracked" if update is not None else "lost"
        if update is None and static_frames > settings.warmup_frames and previous_grey is not None:
            moving = cv2.absdiff(grey, previous_grey) > settings.motion_threshold_dn
            blob = most_moving_blob(foreground_blobs(foreground, settings.min_blob_area_px), moving)
            if blob is not None:
                histogram = hue_histogram(hsv, blob, settings)
                update = camshift_step(hue_back_projection(hsv, histogram, settings), tight_box(blob), settings)
                event = "detected" if update is not None else event
        if update is None:
            window = None
            steps.append(TrackStep(index, event, None, None))
        else:
            window, box, centre = update
            steps.append(TrackStep(index, event, box, centre))
        previous_grey = grey
    return steps


# --- scoring -------------------------------------------------------------------------------------------


def box_iou(a: Box, b: Box) -> float:
    """Intersection over union of two pixel boxes, IoU = |a ∩ b| / |a ∪ b|, counted in whole pixels.

    Parameters
    ----------
    a, b : Box
        (x_px, y_px, width_px, height_px).

    Returns
    -------
    float
        In [0, 1]; 0 for disjoint boxes (or two empty ones).
    """
    overlap_w = max(0, min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0]))
    overlap_h = max(0, min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1]))
    intersection = overlap_w * overlap_h
    union = a[2] * a[3] + b[2] * b[3] - intersection
    return intersection / union if union > 0 else 0.0


def centre_inside(centre_px: tuple[float, float], box: Box) -> bool:
    """Whether the point lies on the pixels of `box`, which span x − ½ … x + width − ½ (pixel centres
    at integers)."""
    x, y = centre_px
    return box[0] - 0.5 <= x <= box[0] + box[2] - 0.5 and box[1] - 0.5 <= y <= box[1] + box[3] - 0.5


def score_track(
    steps: Sequence[TrackStep], ground_truth: Sequence[Box | None]
) -> tuple[list[FrameScore], TrackingSummary]:
    """Score a track against the ground truth, frame by frame.

    Parameters
    ----------
    steps : sequence of TrackStep
        The tracker's output (`track_target`).
    ground_truth : sequence of Box or None, one per step
        The target's boxes (`ground_truth_boxes`); None where it is not visible.

    Returns
    -------
    rows : list of FrameScore
        Per frame: both boxes, IoU where both exist, and whether the track's centre lies in the truth.
    summary : TrackingSummary
        Mean IoU over the frames scored; hit rate (IoU ≥ HIT_IOU) and centre-inside rate over the frames
        in which the target is visible, so that frames without a track count as misses.
    """
    if len(steps) != len(ground_truth):
        raise ValueError(f"{len(steps)} track steps for {len(ground_truth)} ground-truth frames")
    rows = []
    for step, truth in zip(steps, ground_truth, strict=True):
        tracked = step.box_px is not None
        rows.append(
            FrameScore(
                frame=step.frame,
                event=step.event,
                ground_truth_px=truth,
                track_px=step.box_px,
                centre_px=step.centre_px,
                iou=box_iou(step.box_px, truth) if tracked and truth is not None else None,
                centre_inside=None if truth is None else tracked and centre_inside(step.centre_px, truth),
            )
        )
    visible = [row for row in rows if row.ground_truth_px is not None]
    scored = [row.iou for row in rows if row.iou is not None]
    summary = TrackingSummary(
        frames=len(rows),
        frames_visible=len(visible),
        frames_tracked=sum(row.track_px is not None for row in rows),
        frames_scored=len(scored),
        mean_iou=float(np.mean(scored)) if scored else None,
        hit_rate=sum(row.iou is not None and row.iou >= HIT_IOU for row in visible) / len(visible) if visible else None,
        centre_inside_rate=sum(bool(row.centre_inside) for row in visible) / len(visible) if visible else None,
        false_track_frames=sum(row.track_px is not None and row.ground_truth_px is None for row in rows),
    )
    return rows, summary


@dataclass(frozen=True)
class TrackingResult:
    target: str
    instance_id: int
    settings: TrackerSettings
    frames: list[FrameScore]
    summary: TrackingSummary

    def to_json(self) -> str:
        return json.dumps(asdict(self), indent=1)


def track_camera_directory(
    camera_dir: str | Path, target: str, settings: TrackerSettings = TrackerSettings()
) -> TrackingResult:
    """Track `target` in a rendered camera directory and score it against its instance pass.

    Parameters
    ----------
    camera_dir : path
        ``<out>/<job>/<camera>/`` with ``video.mp4``, ``camera.jsonl`` and ``passes/``.
    target : str
        The actor's name, as in the scene and ``passes/instances.json``.
    settings : TrackerSettings

    Returns
    -------
    TrackingResult
        Per-frame scores and their summary; ``to_json()`` gives what ``tracking.json`` holds.
    """
    camera_dir = Path(camera_dir)
    instance_id = target_instance_id(camera_dir, target)
    states = read_camera_states(camera_dir)
    frames_rgb = read_video_rgb(camera_dir / "video.mp4")
    if len(frames_rgb) != len(states):
        raise ConfigError(f"{camera_dir}: video.mp4 has {len(frames_rgb)} frames but camera.jsonl {len(states)}")
    ground_truth = ground_truth_boxes(camera_dir, instance_id, [state["frame"] for state in states])
    steps = track_target(frames_rgb, camera_moved(states), settings)
    # The steps count from 0; name them by the rendered frame numbers.
    steps = [TrackStep(state["frame"], s.event, s.box_px, s.centre_px) for state, s in zip(states, steps, strict=True)]
    rows, summary = score_track(steps, ground_truth)
    return TrackingResult(target, instance_id, settings, rows, summary)


# --- command line --------------------------------------------------------------------------------------


def render_with_passes(
    scene_path: Path, out_dir: Path, target: str, camera: str | None, frame_count: int | None
) -> Path:
    """Render one camera of the scene (its first `frame_count` frames) with its passes saved, after
    checking that `target` is one of its actors and that the plan renders the instance pass; returns
    the camera directory."""
    from rich.progress import MofNCompleteColumn, Progress

    from camgen.config import load_scene
    from camgen.plan import PlanSettings, compile_scene
    from camgen.plan.execute import execute
    from camgen.render.renderer import Renderer

    loaded = load_scene(scene_path)
    actors = [actor.name for actor in loaded.scene.actors]
    if target not in actors:
        raise ConfigError(f"--target {target}: no such actor in {scene_path} (actors: {', '.join(actors) or 'none'})")
    job = compile_scene(loaded, PlanSettings())
    names = [c.name for c in job.cameras]
    name = names[0] if camera is None else camera
    if name not in names:
        raise ConfigError(f"--camera {name}: no such camera in {scene_path} (it has {', '.join(names)})")
    if "instance_id" not in job.cameras[names.index(name)].render.passes:
        raise ConfigError(
            f"{scene_path}: the plan renders no instance_id pass for camera {name}, so there is no ground truth; "
            "ask for annotations (outputs.annotations: [mot])"
        )
    count = job.frame_count if frame_count is None else min(frame_count, job.frame_count)
    with Renderer() as renderer, Progress(*Progress.get_default_columns(), MofNCompleteColumn()) as progress:
        task = progress.add_task(f"render {name}", total=count)
        (result,) = execute(
            job,
            out_dir,
            renderer=renderer,
            frames=range(count),
            cameras=[name],
            resolve_path=loaded.path.parent.joinpath,
            save_passes=True,
            on_frame=lambda *_: progress.advance(task),
        )
    return result.directory


def iou_bands(rows: Sequence[FrameScore]) -> list[tuple[str, int]]:
    """Frame counts per outcome: IoU bands of the scored frames, then the frames not scored."""
    bands = [
        ("IoU ≥ 0.75", lambda r: r.iou is not None and r.iou >= 0.75),
        ("0.5 ≤ IoU < 0.75", lambda r: r.iou is not None and 0.5 <= r.iou < 0.75),
        ("0.25 ≤ IoU < 0.5", lambda r: r.iou is not None and 0.25 <= r.iou < 0.5),
        ("IoU < 0.25", lambda r: r.iou is not None and r.iou < 0.25),
        ("visible, not tracked", lambda r: r.ground_truth_px is not None and r.track_px is None),
        ("tracked, not visible", lambda r: r.ground_truth_px is None and r.track_px is not None),
        ("neither", lambda r: r.ground_truth_px is None and r.track_px is None),
    ]
    return [(label, sum(map(test, rows))) for label, test in bands]


def format_report(result: TrackingResult) -> str:
    """A small text table of the per-frame outcomes and the score."""
    lines = [f"target {result.target} (instance {result.instance_id})", f"{'frames':>8}  outcome"]
    lines += [f"{count:>8}  {label}" for label, count in iou_bands(result.frames)]
    summary = result.summary

    def fraction(value: float | None) -> str:
        return "n/a" if value is None else f"{value:.3f}"

    lines += [
        f"mean IoU over {summary.frames_scored} scored frames: {fraction(summary.mean_iou)}",
        f"hit rate (IoU ≥ {HIT_IOU}) over {summary.frames_visible} visible frames: {fraction(summary.hit_rate)}",
        f"centre inside ground truth: {fraction(summary.centre_inside_rate)}",
        f"frames tracked: {summary.frames_tracked} of {summary.frames}",
    ]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    from camgen.io.files import write_text_atomic

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", type=Path, nargs="?", default=DEFAULT_SCENE, metavar="SCENE")
    parser.add_argument("--target", default=DEFAULT_TARGET, metavar="NAME", help="actor to track")
    parser.add_argument("--camera", metavar="NAME", help="camera to render (default: the scene's first)")
    parser.add_argument("--frames", type=int, metavar="N", help="render only the first N frames")
    parser.add_argument("--out", type=Path, default=Path("out"), metavar="DIR", help="output directory")
    args = parser.parse_args(argv)
    try:
        if not args.scene.is_file():
            if args.scene == DEFAULT_SCENE:
                raise ConfigError(
                    f"{DEFAULT_SCENE}, the default scene, does not exist (yet); pass a scene, e.g. "
                    "python examples/ptz_tracking.py tests/data/ptz_tracking/red_walker.yaml --target red_walker"
                )
            raise ConfigError(f"{args.scene}: no such scene file")
        if args.frames is not None and args.frames < 1:
            raise ConfigError(f"--frames must be ≥ 1, got {args.frames}")
        camera_dir = render_with_passes(args.scene, args.out, args.target, args.camera, args.frames)
        result = track_camera_directory(camera_dir, args.target)
    except ConfigError as exc:
        for problem in exc.problems:
            print(f"error: {problem}", file=sys.stderr)
        return 2
    write_text_atomic(camera_dir / "tracking.json", result.to_json())
    print(format_report(result))
    print(f"wrote {camera_dir / 'tracking.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
