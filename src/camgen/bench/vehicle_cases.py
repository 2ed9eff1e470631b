"""Vehicles: does a detector trained on real photographs find camgen's vehicles by day, at night and in weather?

YOLOv4-tiny (COCO; `camgen.bench.yolo_vehicle`) runs on the 8-bit frames each camera of each example
scene with vehicles delivers (`FRAMES_PER_CAMERA` frames spread over the sequence, `NIGHT_FRAMES_PER_CAMERA`
in a night scene; the cameras' own resolutions), at the cfg's 416 × 416 input and at an input of the frame's
aspect `WIDE_INPUT_WIDTH_PX` wide. A camera in IR night mode delivers a monochrome stream, its luma in all
three channels (`camgen.world.night.monochrome`), and the detector takes those three equal channels as a real
IR stream reaches it. Scores are reported by condition (by day in clear air, at night in IR night mode, in
fog, rain or snow: `camgen.bench.realism.scene_condition`). Scoring follows `camgen.bench.realism`
(Dollár et al. 2012's convention) with the threshold of issue 20: vehicles (bicycles, cars, motorcycles,
buses, trucks; class-agnostic) at least `MIN_HEIGHT_PX` tall (their amodal box), untruncated and at least
`MIN_VISIBILITY` visible count; smaller or more occluded ones are ignore regions; a detection matches at
IoU ≥ 0.5.
"""

from __future__ import annotations

from pathlib import Path

from camgen.bench.harness import Case
from camgen.bench.people_cases import detection_table, overall_scores
from camgen.bench.realism import (
    CONDITIONS,
    DetectionScore,
    Scorer,
    detection_scores,
    scene_condition,
    scores_by_condition,
)

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
NIGHT_FRAMES_PER_CAMERA = 8
"""Frames per camera of a night scene (`camgen.bench.realism.CONDITIONS`' night), spread over the sequence.
The night street, the one night scene, has one camera and three cars that count (two parked, one driving
towards it): 2 frames counted 6, the same 3 cars twice, where one miss moves the recall by 0.17. 8 frames
(one every 0.28 s of its 2 s) see the oncoming car at 8 distances, its beams moving over the parked cars;
the parked cars are the same in every frame but for that light and the noise, so the night figure is 8 looks
at 3 cars rather than 24 cars."""
MIN_VEHICLES_FOR_RECALL = 5
"""Fewer vehicles counted in a condition than this, and its recall is said to be too few to read: one
miss moves it by more than 0.2."""
DETECTION_CASE = "vehicle detection (YOLOv4-tiny) over the example scenes by day, at night and in weather"


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
    repo: Path,
    frames_per_camera: int = FRAMES_PER_CAMERA,
    night_frames_per_camera: int = NIGHT_FRAMES_PER_CAMERA,
    *,
    scorers=None,
    samples: dict | None = None,
) -> list[DetectionScore]:
    """Render each example scene with vehicles, every camera, frames spread over the sequence
    (`night_frames_per_camera` in a scene at night, `frames_per_camera` in the others), and score each
    scorer on the same frames. `DetectionScore.people` holds the vehicles that count. With `samples`,
    the middle frame of each camera, boxes drawn."""
    if scorers is None:
        scorers, _ = vehicle_scorers()
    if not scorers:
        return []

    def with_vehicles(scene) -> bool:
        return any(a.cls in VEHICLE_CATEGORIES for a in scene.actors)

    def at_night(scene) -> bool:
        return with_vehicles(scene) and scene_condition(scene) == CONDITIONS[1]

    def not_at_night(scene) -> bool:
        return with_vehicles(scene) and scene_condition(scene) != CONDITIONS[1]

    scores = []
    for wanted, frames in ((not_at_night, frames_per_camera), (at_night, night_frames_per_camera)):
        scores += detection_scores(repo, frames, scorers, samples, wanted=wanted, truth=ground_truth, prefix="vehicles")
    return sorted(scores, key=lambda score: (score.scene, score.camera))


def vehicle_summary(scores: list[DetectionScore], conditions: dict[str, str]) -> str:
    """Each scorer's recall and precision by condition (`scores_by_condition`: by day in clear air, at night in
    IR night mode, in fog, rain or snow; `conditions` maps a scene's stem to its condition), and for each
    condition whose vehicles are fewer than `MIN_VEHICLES_FOR_RECALL`, that its figure is too few to read."""
    text = [scores_by_condition(scores, conditions, overall_scores)]
    detector = scores[0].detector if scores else None
    for condition in CONDITIONS:
        mine = [s for s in scores if s.detector == detector and conditions.get(s.scene) == condition]
        counted = sum(s.people for s in mine)
        if mine and counted == 0:
            text.append(f"{condition[0].upper()}{condition[1:]} no vehicle counts: no recall to read.")
        elif mine and counted < MIN_VEHICLES_FOR_RECALL:
            text.append(
                f"{condition[0].upper()}{condition[1:]} only {counted} vehicle{'s' * (counted != 1)} count, fewer "
                f"than {MIN_VEHICLES_FOR_RECALL}: too few for a meaningful recall (one miss moves it by "
                f"{1 / counted:.2f})."
            )
    return " ".join(text)


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
