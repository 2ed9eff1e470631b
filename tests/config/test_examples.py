"""The shipped profiles, scenes and datasets validate, plan and say why."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from camgen.cli.main import main
from camgen.config import load_dataset, load_profile, load_scene
from tests.conftest import REPO

PROFILES = sorted((REPO / "profiles").glob("*.yaml"))
SCENES = sorted((REPO / "scenes").glob("*.yaml"))
DATASETS = sorted((REPO / "datasets").glob("*.yaml"))


def test_the_examples_exist():
    names = {p.stem for p in SCENES}
    assert {"parking_lot", "corridor", "checkerboard", "intersection_two_cameras"} <= names
    assert len(PROFILES) >= 4


@pytest.mark.parametrize("path", PROFILES, ids=lambda p: p.stem)
def test_profile_validates(path: Path):
    load_profile(path)


def uncited_lines(text: str) -> list[str]:
    """Numeric settings under `sensor:` and `lens:` with no comment giving their source.

    A line is cited by a comment on it; the entries of a list (``- {…}``) by the comment on the line
    that opens the list.
    """
    uncited, section, list_cited = [], None, False
    for line in text.splitlines():
        if re.match(r"^[a-z_]+:", line):
            section = line.split(":")[0]
        if section not in ("sensor", "lens"):
            continue
        item = re.match(r"^\s+- ", line)
        if not item:
            list_cited = "#" in line
        match = re.match(r"^\s+(?:- )?\{?([a-z_]+):\s*(.*)$", line)
        if not match or match.group(1) in ("model", "format", "description"):
            continue
        numeric = re.match(r"^[-\d.\[{]", match.group(2))
        if numeric and "#" not in line and not (item and list_cited):
            uncited.append(line.strip())
    return uncited


@pytest.mark.parametrize("path", PROFILES, ids=lambda p: p.stem)
def test_every_datasheet_number_cites_a_source_or_says_estimate(path: Path):
    assert uncited_lines(path.read_text(encoding="utf-8")) == []


def test_the_citation_check_finds_an_uncited_number():
    assert uncited_lines("sensor:\n  width_px: 1920\n  height_px: 1080  # [S1]\n") == ["width_px: 1920"]


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_scene_validates_and_plans(path: Path, capsys):
    load_scene(path)
    assert main(["plan", str(path)]) == 0
    out = capsys.readouterr().out
    assert "stages" in out and "decisions" in out
    assert "render" in out and ("run" in out or "skip" in out)


@pytest.mark.parametrize("path", DATASETS, ids=lambda p: p.stem)
def test_dataset_validates(path: Path):
    load_dataset(path)


def test_checkerboard_scene_has_at_least_twelve_poses():
    scene = load_scene(REPO / "scenes/checkerboard.yaml").scene
    assert len(scene.cameras) >= 12
    assert any(m.type == "checkerboard" for m in scene.environment.meshes)


def test_extends_merges_child_over_parent():
    base = load_profile(REPO / "profiles/ptz_2mp_30x.yaml").profile
    child = load_profile(REPO / "profiles/ptz_2mp_20x.yaml").profile
    assert child.sensor == base.sensor
    assert child.lens.focal_length_range_mm == (4.7, 94.0)
    assert child.ptz.zoom_wide_to_tele_s == 3.0
    assert child.ptz.pan_max_deg_s == base.ptz.pan_max_deg_s
    assert child.serial != base.serial


def test_validate_cli_accepts_all_examples(capsys):
    files = [str(p) for p in PROFILES + SCENES + DATASETS]
    assert main(["validate", *files]) == 0
    assert capsys.readouterr().out.count("ok ") == len(files)
