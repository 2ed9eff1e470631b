"""Vehicles: does a detector trained on real photographs find camgen's vehicles by day?

YOLOv4-tiny (COCO; `camgen.bench.yolo_vehicle`) runs on the 8-bit frames each camera of each example
scene with vehicles and a daytime sky delivers (`FRAMES_PER_CAMERA` frames spread over the sequence,
the cameras' own resolutions), at the cfg's 416 × 416 input and at an input of the frame's aspect
`WIDE_INPUT_WIDTH_PX` wide. Scoring follows `camgen.bench.realism` (Dollár et al. 2012's convention)
with the threshold of issue 20: vehicles (bicycles, cars, motorcycles, buses, trucks; class-agnostic)
at least `MIN_HEIGHT_PX` tall (their amodal box), untruncated and at least `MIN_VISIBILITY` visible
count; smaller or more occluded ones are ignore regions; a detection matches at IoU ≥ 0.5.
"""

from __future__ import annotations

from pathlib import Path

from camgen.bench.harness import Case
from camgen.bench.people_cases import detection_table
from camgen.bench.realism import DetectionScore, Scorer, detection_scores

MIN_HEIGHT_PX = 48
"""Issue 20's threshold for a vehicle that counts."""
MIN_VISIBILITY = 0.7
FRAMES_PER_CAMERA = 2
"""Frames per camera, spread over the sequence: fewer than the people section's 5 (the first and the last), to keep
the section near 30 minutes on 2 shared cores: rendering every camera at its own resolution dominates
(a 4K frame took about 4 minutes there)."""
WIDE_INPUT_WIDTH_PX = 832
"""Width of the second input, its height the frame's aspect rounded to a multiple of 32 (darknet's
stride): twice the cfg's 416, so that a vehicle 48 px tall in a 1080p frame meets the network at about
21 px rather than 18 px (416 / 1080 · 48) and at its own aspect."""
VEHICLE_CATEGORIES = ("bicycle", "car", "motorcycle", "bus", "truck")
"""camgen's COCO categories (`camgen.io.annotations.COCO_CATEGORY_IDS`) that are vehicles."""
DETECTION_CASE = "vehicle detection (YOLOv4-tiny) over the example scenes by day"


def ground_truth(coco: dict, image_id: int) -> tuple[list, list]:
    """(counted, ignored) vehicle boxes (x0, y0, x1, y1) of one image: counted vehicles are at least
    `MIN_HEIGHT_PX` tall, untruncated (< 10 %) and at least `MIN_VISIBILITY` visible (amodal box)."""
    ids = {c["id"] for c in coco["categories"] if c["name"] in VEHICLE_CATEGORIES}
    counted, ignored = [], []
    for ann in coco["annotations"]:
        if ann["image_id"] != image_id or ann["category_id"] not in ids:
            continue
        x, y, w, h = ann.get("amodal_bbox", ann["bbox"])
        box = (x, y, x + w, y + h)
        whole = h >= MIN_HEIGHT_PX and ann.get("truncation", 0.0) < 0.1 and not ann.get("iscrowd")
        (counted if whole and ann.get("visibility", 1.0) >= MIN_VISIBILITY else ignored).append(box)
    return counted, ignored


def vehicle_scorers() -> tuple[list[Scorer], str | None]:
    """YOLOv4-tiny at 416 × 416 and at the frame's aspect `WIDE_INPUT_WIDTH_PX` wide, when its weights
    are installed; and why not (None when they are)."""
    from camgen.bench import yolo_vehicle

    missing = yolo_vehicle.available()
    if missing is not None:
        return [], missing
    square = yolo_vehicle.VehicleDetector()
    wide = yolo_vehicle.VehicleDetector(aspect_width_px=WIDE_INPUT_WIDTH_PX)  # `yolo_vehicle.aspect_input_px`
    return [
        Scorer(f"{square.name} 416×416", square),
        Scorer(f"{wide.name} {WIDE_INPUT_WIDTH_PX} wide", wide),
    ], None


def vehicle_detection_scores(
    repo: Path, frames_per_camera: int = FRAMES_PER_CAMERA, *, scorers=None, samples: dict | None = None
) -> list[DetectionScore]:
    """Render each example scene with vehicles by day (no `environment.night_sky`), every camera,
    frames spread over the sequence, and score each scorer on the same frames. `DetectionScore.people`
    holds the vehicles that count. With `samples`, the middle frame of each camera, boxes drawn."""

    if scorers is None:
        scorers, _ = vehicle_scorers()
    if not scorers:
        return []

    def by_day_with_vehicles(scene) -> bool:
        return scene.environment.night_sky is None and any(a.cls in VEHICLE_CATEGORIES for a in scene.actors)

    return detection_scores(
        repo, frames_per_camera, scorers, samples, wanted=by_day_with_vehicles, truth=ground_truth, prefix="vehicles"
    )


def weather_scenes(repo: Path) -> set[str]:
    """Stems of the example scenes (`vehicle_detection_scores`' scenes) with fog, rain or snow in their
    environment (`camgen.bench.realism.scene_condition`): their vehicles are scored too, but issue 20's goal
    is read as clear air by day."""
    from camgen.bench.realism import CONDITIONS, scene_conditions

    return {stem for stem, condition in scene_conditions(repo).items() if condition == CONDITIONS[2]}


def vehicle_cases(repo: Path, scores: list[DetectionScore], samples: dict | None = None) -> list[Case]:
    def detect() -> None:
        scores.clear()
        if samples is not None:
            samples.clear()
        scores.extend(vehicle_detection_scores(repo, samples=samples))

    return [Case(DETECTION_CASE, detect, repeats=1, warmup=0)]


def vehicle_table(scores: list[DetectionScore]) -> str:
    """One row per scene and camera; recall and precision (with their counts) for each scorer."""
    return detection_table(scores, f"vehicles ≥ {MIN_HEIGHT_PX} px, ≥ {100 * MIN_VISIBILITY:.0f} % visible")
