"""The vehicles section's split of the example scenes into clear air and weather (`camgen.bench.vehicle_cases`)."""

from __future__ import annotations

from pathlib import Path

from camgen.bench.vehicle_cases import weather_scenes

REPO = Path(__file__).resolve().parents[2]


def test_weather_scenes_are_those_with_fog_or_rain(tmp_path):
    assert weather_scenes(REPO) == {"misty_street", "rainy_street"}
    (tmp_path / "scenes").mkdir()
    for name in ("misty_street", "parking_lot"):
        (tmp_path / "scenes" / f"{name}.yaml").write_text((REPO / "scenes" / f"{name}.yaml").read_text())
    for profile in (REPO / "profiles").glob("*.yaml"):
        (tmp_path / "profiles").mkdir(exist_ok=True)
        (tmp_path / "profiles" / profile.name).write_text(profile.read_text())
    assert weather_scenes(tmp_path) == {"misty_street"}
