"""Dataset expansion: deterministic, product and zip, distinct hashes, and bad entries named."""

from __future__ import annotations

import pytest

from camgen.batch.expand import compile_batch_job, expand
from camgen.cli.main import main
from camgen.errors import ConfigError
from tests.batch.conftest import DATASET, make_dataset


def test_product_gives_every_scene_profile_seed_in_order(dataset):
    jobs = expand(dataset)
    assert [(j.scene_path.name, j.profile, j.seed) for j in jobs] == [
        ("walk.yaml", "small", 3),
        ("walk.yaml", "small", 4),
        ("walk.yaml", "wide", 3),
        ("walk.yaml", "wide", 4),
    ]
    assert [j.name for j in jobs] == ["walk-small-seed3", "walk-small-seed4", "walk-wide-seed3", "walk-wide-seed4"]
    assert expand(dataset) == jobs


def test_zip_pairs_the_lists(tmp_path):
    text = DATASET.replace("product", "zip").replace("[scenes/walk.yaml]", "[scenes/walk.yaml, scenes/walk.yaml]")
    path = make_dataset(tmp_path, text)
    assert [(j.profile, j.seed) for j in expand(path)] == [("small", 3), ("wide", 4)]


def test_no_profiles_keeps_the_scenes_own(tmp_path):
    path = make_dataset(tmp_path, "scenes: [scenes/walk.yaml]\nseeds: {start: 7, count: 2}\n")
    jobs = expand(path)
    assert [(j.name, j.profile, j.seed) for j in jobs] == [("walk-own-seed7", None, 7), ("walk-own-seed8", None, 8)]
    assert compile_batch_job(jobs[0]).cameras[0].profile_name == "fixed"


def test_compiled_jobs_take_the_profile_and_seed_and_hash_distinctly(dataset):
    compiled = [compile_batch_job(job) for job in expand(dataset)]
    assert [(job.cameras[0].profile_name, job.seed) for job in compiled] == [
        ("small", 3),
        ("small", 4),
        ("wide", 3),
        ("wide", 4),
    ]
    assert compiled[2].cameras[0].profile.lens.focal_length_min_mm == 3.0
    assert len({job.job_id for job in compiled}) == 4
    assert compile_batch_job(expand(dataset)[1]).job_id == compiled[1].job_id


def test_a_repeated_seed_is_rejected(tmp_path):
    path = make_dataset(tmp_path, DATASET.replace("[3, 4]", "[3, 3]"))
    with pytest.raises(ConfigError, match=r"walk-small-seed3.*more than once"):
        expand(path)


def test_a_scene_that_fails_to_compile_names_the_dataset_and_job(dataset):
    (dataset.parent / "scenes" / "walk.yaml").write_text("fps: 10\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"tiny\.yaml: job walk-small-seed3 \(entry 0\)"):
        compile_batch_job(expand(dataset)[0])


@pytest.mark.parametrize(
    ("text", "names"),
    [
        (DATASET.replace("scenes/walk.yaml", "scenes/gone.yaml"), ["tiny.yaml", "scenes[0]", "gone.yaml"]),
        (DATASET.replace("[small, wide]", "[small, nope]"), ["tiny.yaml", "profiles[1]", "nope"]),
    ],
)
def test_cli_rejects_a_dataset_with_a_bad_entry(tmp_path, capsys, text, names):
    path = make_dataset(tmp_path, text)
    assert main(["batch", str(path), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert all(name in err for name in names), err
    assert not (tmp_path / "out").exists()


def test_cli_rejects_a_missing_dataset_file(tmp_path, capsys):
    assert main(["batch", str(tmp_path / "absent.yaml"), "-o", str(tmp_path / "out")]) == 2
    assert "absent.yaml: no such dataset file" in capsys.readouterr().err


def test_cli_plan_lists_the_jobs_without_rendering(dataset, capsys):
    assert main(["batch", str(dataset), "-o", str(dataset.parent / "out"), "--plan", "--frames", "2"]) == 0
    text = capsys.readouterr().out
    assert all(f"walk-{p}-seed{s}" in text for p in ("small", "wide") for s in (3, 4))
    assert not (dataset.parent / "out").exists()


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--workers", "0"], "--workers must be ≥ 1, got 0"),
        (["--retries", "-1"], "--retries must be ≥ 0, got -1"),
        (["--frames", "0"], "--frames must be ≥ 1, got 0"),
        (["--address", "127.0.0.1:6379"], "--address 127.0.0.1:6379 is for --executor ray"),
    ],
)
def test_bad_run_options_are_refused_before_anything_is_rendered(dataset, tmp_path, capsys, extra, message):
    assert main(["batch", str(dataset), "-o", str(tmp_path / "out"), *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()
