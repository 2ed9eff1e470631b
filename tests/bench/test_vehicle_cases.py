"""The realism sections' split of the example scenes by condition (day, night, weather;
`camgen.bench.realism`, `camgen.bench.vehicle_cases`) and their sentences."""

from __future__ import annotations

from pathlib import Path

from camgen.bench.vehicle_cases import weather_scenes

REPO = Path(__file__).resolve().parents[2]


def test_weather_scenes_are_those_with_fog_or_rain(tmp_path):
    assert weather_scenes(REPO) == {"misty_street", "rainy_street", "snowy_street"}
    (tmp_path / "scenes").mkdir()
    for name in ("misty_street", "parking_lot"):
        (tmp_path / "scenes" / f"{name}.yaml").write_text((REPO / "scenes" / f"{name}.yaml").read_text())
    for profile in (REPO / "profiles").glob("*.yaml"):
        (tmp_path / "profiles").mkdir(exist_ok=True)
        (tmp_path / "profiles" / profile.name).write_text(profile.read_text())
    assert weather_scenes(tmp_path) == {"misty_street"}


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
