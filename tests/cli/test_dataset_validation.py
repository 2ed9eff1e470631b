"""A dataset is valid only if every one of its jobs compiles: `validate` and `batch --plan` say which does not."""

from __future__ import annotations

from pathlib import Path

from camgen.cli.main import main
from tests.batch.conftest import make_dataset
from tests.conftest import SCENE, write

TWO_SCENES = """\
description: a good scene and a broken one
scenes: [scenes/walk.yaml, scenes/broken.yaml]
profiles: [small]
seeds: [1]
"""


def broken_second_scene(tmp_path: Path) -> Path:
    dataset = make_dataset(tmp_path, TWO_SCENES)
    write(tmp_path, "scenes/broken.yaml", SCENE.replace("speed_m_s: 1.4", "speed_m_s: -1.4"))
    return dataset


def test_validate_finds_the_invalid_second_scene(tmp_path: Path, capsys):
    dataset = broken_second_scene(tmp_path)
    assert main(["validate", str(dataset)]) == 1
    err = capsys.readouterr().err
    assert "job broken-small-seed1" in err
    assert "speed_m_s" in err
    assert "walk-small-seed1" not in err


def test_validate_a_good_dataset_counts_its_jobs(tmp_path: Path, capsys):
    dataset = make_dataset(tmp_path)
    assert main(["validate", str(dataset)]) == 0
    assert "4 jobs compile" in capsys.readouterr().out


def test_batch_plan_of_a_dataset_with_a_broken_job_exits_non_zero(tmp_path: Path, capsys):
    dataset = broken_second_scene(tmp_path)
    assert main(["batch", str(dataset), "-o", str(tmp_path / "out"), "--plan"]) == 1
    captured = capsys.readouterr()
    assert "does not compile" in captured.out
    assert "1 of 2 jobs do not compile" in captured.err
    assert not (tmp_path / "out").exists()


def test_batch_plan_of_a_mistyped_scene_exits_non_zero(tmp_path: Path, capsys):
    dataset = make_dataset(tmp_path, TWO_SCENES.replace("scenes/broken.yaml", "scenes/wlak.yaml"))
    assert main(["batch", str(dataset), "-o", str(tmp_path / "out"), "--plan"]) != 0
    assert "wlak.yaml" in capsys.readouterr().err


def test_batch_frames_beyond_the_jobs_is_a_warning(tmp_path: Path, capsys):
    dataset = make_dataset(tmp_path)
    assert main(["batch", str(dataset), "-o", str(tmp_path / "out"), "--plan", "--frames", "1000000"]) == 0
    err = capsys.readouterr().err
    assert "warning --frames 1000000: 4 of 4 jobs have fewer frames" in err and "walk-small-seed3 10" in err


def test_a_dataset_finds_its_profiles_where_its_scenes_do(tmp_path: Path, capsys, monkeypatch):
    """A dataset whose scenes name a profile kept elsewhere: validate and batch search --profiles and
    $CAMGEN_PROFILE_PATH as validate does for the scene alone."""
    dataset = make_dataset(tmp_path)
    elsewhere = tmp_path / "elsewhere"
    (tmp_path / "profiles").rename(elsewhere)
    assert main(["validate", str(dataset)]) == 1
    capsys.readouterr()
    assert main(["validate", "--profiles", str(elsewhere), str(tmp_path / "scenes/walk.yaml"), str(dataset)]) == 0
    assert "4 jobs compile" in capsys.readouterr().out
    monkeypatch.setenv("CAMGEN_PROFILE_PATH", str(elsewhere))
    assert main(["batch", str(dataset), "-o", str(tmp_path / "out"), "--plan"]) == 0
