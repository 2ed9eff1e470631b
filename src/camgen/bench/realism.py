"""Do detectors trained on real photographs find camgen's people?

The detector is OpenCV's HOG people detector (`camgen.annotate.detection`: Dalal & Triggs 2005, its
linear SVM trained on the INRIA Person data set of real photographs). Each example scene's cameras
render frames spread over the sequence with COCO ground truth; the detector runs on the 8-bit frames
as the camera delivers them.

Scoring follows the pedestrian-detection convention (Dollár et al. 2012, "Pedestrian Detection: An
Evaluation of the State of the Art"): ground truth people at least `MIN_HEIGHT_PX` tall and at least
`MIN_VISIBILITY` visible count; smaller or more occluded people are "ignore" regions (a detection on
them is neither a hit nor a false alarm). A detection matches a person at IoU ≥ 0.5 (greedy, highest
score first).
"""

from __future__ import annotations

import json
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import cv2

from camgen.annotate.detection import detect_people, hog_detector

MIN_HEIGHT_PX = 96
MIN_VISIBILITY = 0.7
IOU_MATCH = 0.5
FRAMES_PER_CAMERA = 5


@dataclass(frozen=True)
class DetectionScore:
    scene: str
    camera: str
    people: int
    """Ground-truth people that count (tall and visible enough), over all frames."""
    hits: int
    detections: int
    false_alarms: int

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


def score_frame(detections, counted, ignored) -> tuple[int, int]:
    """(hits, false alarms) of one frame's detections against counted and ignored person boxes."""
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
        elif not any(iou(det, box) >= IOU_MATCH for box in ignored):
            false_alarms += 1
    return hits, false_alarms


def score_sequence(directory: Path, hog) -> tuple[int, int, int, int]:
    """(people, hits, detections, false alarms) over a rendered camera folder (frames + coco.json)."""
    coco = json.loads((directory / "coco.json").read_text(encoding="utf-8"))
    person_id = next(c["id"] for c in coco["categories"] if c["name"] == "person")
    people = hits = detections = false_alarms = 0
    for image in coco["images"]:
        frame = cv2.imread(str(directory / image["file_name"]))
        counted, ignored = [], []
        for ann in coco["annotations"]:
            if ann["image_id"] != image["id"] or ann["category_id"] != person_id:
                continue
            if ann.get("iscrowd"):  # people too small to separate: detections there are not false alarms
                x, y, w, h = ann["bbox"]
                ignored.append((x, y, x + w, y + h))
                continue
            x, y, w, h = ann["amodal_bbox"]
            box = (x, y, x + w, y + h)
            tall = h >= MIN_HEIGHT_PX and ann["truncation"] < 0.1
            (counted if tall and ann["visibility"] >= MIN_VISIBILITY else ignored).append(box)
        found = detect_people(hog, frame)
        h_, f_ = score_frame(found, counted, ignored)
        people, hits, detections, false_alarms = (
            people + len(counted),
            hits + h_,
            detections + len(found),
            false_alarms + f_,
        )
    return people, hits, detections, false_alarms


def person_detection_scores(repo: Path, frames_per_camera: int = FRAMES_PER_CAMERA) -> list[DetectionScore]:
    """Render each example scene with people (every camera, frames spread over the sequence) and
    score the HOG detector on them."""
    from camgen.bench.e2e_cases import spread_frames
    from camgen.bench.render_cases import _renderer
    from camgen.config import load_scene
    from camgen.config.scene import Outputs
    from camgen.plan import PlanSettings, compile_scene
    from camgen.plan.execute import execute

    hog = hog_detector()
    if hog is None:
        raise RuntimeError("this OpenCV build has no HOG people detector; install opencv-contrib-python-headless")
    scores = []
    for path in sorted((repo / "scenes").glob("*.yaml")):
        loaded = load_scene(path)
        if not any(actor.cls == "person" for actor in loaded.scene.actors):
            continue
        outputs = Outputs(video=False, frames="png", annotations=["coco"], camera_metadata=False)
        scene = loaded.scene.model_copy(update={"outputs": outputs})
        job = compile_scene(type(loaded)(**{**loaded.__dict__, "scene": scene}), PlanSettings())
        out = Path(tempfile.mkdtemp(prefix="camgen-bench-realism-"))
        try:
            execute(
                job, out, renderer=_renderer(), frames=spread_frames(job.frame_count, frames_per_camera),
                resolve_path=path.parent.joinpath,
            )  # fmt: skip
            for camera in job.cameras:
                (folder,) = [p for p in out.glob(f"*/{camera.name}") if p.is_dir()]
                people, hits, detections, false_alarms = score_sequence(folder, hog)
                scores.append(DetectionScore(path.stem, camera.name, people, hits, detections, false_alarms))
        finally:
            shutil.rmtree(out, ignore_errors=True)
    return scores
