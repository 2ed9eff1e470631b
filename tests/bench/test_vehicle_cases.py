"""The realism sections' split of the example scenes by condition (day, night, weather;
`camgen.bench.realism`, `camgen.bench.vehicle_cases`) and their sentences."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from camgen.bench import vehicle_cases
from camgen.bench.realism import CONDITIONS, DetectionScore, Scorer, score_sequence
from camgen.bench.vehicle_cases import (
    FRAMES_PER_CAMERA,
    NIGHT_FRAMES_PER_CAMERA,
    vehicle_detection_scores,
    vehicle_summary,
)

REPO = Path(__file__).resolve().parents[2]


def test_night_scenes_with_vehicles_are_scored_on_their_own_frame_count(monkeypatch):
    """The night street (IR night mode, parked and oncoming cars) is scored on `NIGHT_FRAMES_PER_CAMERA` frames,
    every other scene with vehicles (by day, in weather) on `FRAMES_PER_CAMERA`, and no scene twice."""
    from camgen.config import load_scene

    calls = []

    def fake_detection_scores(repo, frames, scorers, samples, *, wanted, truth, prefix):
        calls.append((frames, wanted))
        return []

    monkeypatch.setattr(vehicle_cases, "detection_scores", fake_detection_scores)
    vehicle_detection_scores(REPO, scorers=[Scorer("fake", lambda frame: [])])
    assert sorted(frames for frames, _ in calls) == sorted([FRAMES_PER_CAMERA, NIGHT_FRAMES_PER_CAMERA])
    scenes = {path.stem: load_scene(path).scene for path in sorted((REPO / "scenes").glob("*.yaml"))}
    chosen = {frames: {stem for stem, scene in scenes.items() if wanted(scene)} for frames, wanted in calls}
    assert chosen[NIGHT_FRAMES_PER_CAMERA] == {"night_street"}
    day_and_weather = chosen[FRAMES_PER_CAMERA]
    assert {"parking_lot", "rainy_street", "misty_street"} <= day_and_weather
    assert "night_street" not in day_and_weather and "checkerboard" not in day_and_weather  # no vehicles there


def test_the_summary_has_a_sentence_for_each_condition_and_flags_too_few_night_vehicles():
    conditions = {"parking_lot": CONDITIONS[0], "night_street": CONDITIONS[1], "rainy_street": CONDITIONS[2]}
    scores = []
    for detector, night_hits in (("square", 1), ("wide", 3)):
        scores += [
            DetectionScore("parking_lot", "a", 10, hits=9, detections=9, false_alarms=0, detector=detector),
            DetectionScore("night_street", "b", 3, night_hits, 3, false_alarms=3 - night_hits, detector=detector),
            DetectionScore("rainy_street", "c", 6, hits=6, detections=6, false_alarms=0, detector=detector),
        ]
    text = vehicle_summary(scores, conditions)
    assert "By day in clear air (parking_lot): square: recall **0.90** (9 of 10)" in text
    assert "At night (IR night mode) (night_street): square: recall **0.33** (1 of 3), precision 0.33; " in text
    assert "wide: recall **1.00** (3 of 3)" in text
    assert "In fog, rain or snow (rainy_street): square: recall **1.00** (6 of 6)" in text
    assert text.endswith(
        f"At night (IR night mode) only 3 vehicles count, fewer than {vehicle_cases.MIN_VEHICLES_FOR_RECALL}: "
        "too few for a meaningful recall (one miss moves it by 0.33)."
    )
    enough = [
        s if s.scene != "night_street" else DetectionScore(s.scene, s.camera, 8, 4, 4, 0, s.detector) for s in scores
    ]
    assert "too few" not in vehicle_summary(enough, conditions)
    none = [
        s if s.scene != "night_street" else DetectionScore(s.scene, s.camera, 0, 0, 2, 2, s.detector) for s in scores
    ]
    assert "At night (IR night mode) no vehicle counts: no recall to read." in vehicle_summary(none, conditions)


@pytest.mark.parametrize("stored_channels", [1, 3])
def test_a_monochrome_frame_reaches_the_detector_as_three_equal_channels(tmp_path, stored_channels):
    """A camera in IR night mode sends its luma in three equal channels (`camgen.world.night.monochrome`);
    whether the PNG holds one grey channel or three, the detector gets (H, W, 3) with equal channels, as a
    real IR stream reaches a detector, and the grey values unchanged."""
    grey = np.random.default_rng(3).integers(0, 256, (24, 40), dtype=np.uint8)
    stored = grey if stored_channels == 1 else np.repeat(grey[..., None], 3, axis=-1)
    (tmp_path / "frames").mkdir()
    cv2.imwrite(str(tmp_path / "frames/000000.png"), stored)
    coco = {
        "images": [{"id": 1, "file_name": "frames/000000.png", "width": 40, "height": 24}],
        "annotations": [],
        "categories": [{"id": 3, "name": "car"}],
    }
    (tmp_path / "coco.json").write_text(json.dumps(coco), encoding="utf-8")
    seen = []
    score_sequence(
        tmp_path, [Scorer("probe", lambda frame: seen.append(frame) or [])], truth=vehicle_cases.ground_truth
    )
    (frame,) = seen
    assert frame.shape == (24, 40, 3)
    for channel in range(3):
        np.testing.assert_array_equal(frame[..., channel], grey)


def test_each_example_scene_has_the_condition_its_environment_says():
    """Issue 20 asks person recall by day, at night (IR) and in rain: the night street counts as night, the
    misty and rainy streets as weather, the rest as day (`camgen.bench.realism.scene_conditions`)."""
    from camgen.bench.realism import CONDITIONS, scene_conditions

    conditions = scene_conditions(REPO)
    assert conditions["night_street"] == CONDITIONS[1]
    assert conditions["misty_street"] == conditions["rainy_street"] == conditions["snowy_street"] == CONDITIONS[2]
    assert conditions["parking_lot"] == conditions["plaza"] == CONDITIONS[0]


def test_scores_by_condition_sums_each_condition_over_its_scenes():
    from camgen.bench.people_cases import overall_scores
    from camgen.bench.realism import DetectionScore, scores_by_condition

    scores = [
        DetectionScore("plaza", "a", people=10, hits=8, detections=9, false_alarms=1),
        DetectionScore("parking_lot", "b", people=10, hits=2, detections=2, false_alarms=0),
        DetectionScore("night_street", "c", people=4, hits=1, detections=3, false_alarms=2),
    ]
    conditions = {"plaza": "by day in clear air", "parking_lot": "by day in clear air"}
    conditions["night_street"] = "at night (IR night mode)"
    text = scores_by_condition(scores, conditions, overall_scores)
    assert text == (
        "By day in clear air (parking_lot, plaza): HOG: recall **0.50** (10 of 20), precision 0.91. "
        "At night (IR night mode) (night_street): HOG: recall **0.25** (1 of 4), precision 0.33."
    )


def test_a_detector_without_detections_has_no_precision_rather_than_nan():
    from camgen.bench.people_cases import overall_scores
    from camgen.bench.realism import DetectionScore

    text = overall_scores([DetectionScore("night_street", "c", people=4, hits=0, detections=0, false_alarms=0)])
    assert text == "HOG: recall **0.00** (0 of 4), precision — (no detection)"
    assert "nan" not in overall_scores([DetectionScore("s", "c", people=0, hits=0, detections=0, false_alarms=0)])
