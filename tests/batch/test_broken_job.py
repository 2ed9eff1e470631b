"""A job that cannot be built (its scene names a mesh file that does not exist) is reported with its
error in dataset.json and DATASET.md, and every other job of the dataset completes."""

from __future__ import annotations

import json

import pytest

from camgen.cli.main import main
from tests.batch.conftest import make_dataset
from tests.conftest import SCENE, write

pytestmark = pytest.mark.opengl

DATASET = """\
description: one good scene and one with a broken mesh path
scenes: [scenes/walk.yaml, scenes/broken.yaml]
profiles: [small]
seeds: [3]
combine: product
"""
BROKEN = SCENE.replace(
    "      size_m: [20, 20]\n",
    "      size_m: [20, 20]\n    - {type: file, name: bench, path: meshes/missing_bench.glb}\n",
)


def test_a_broken_mesh_path_fails_its_job_only(tmp_path, capsys):
    assert BROKEN != SCENE
    dataset = make_dataset(tmp_path, DATASET)
    write(tmp_path, "scenes/broken.yaml", BROKEN)
    out = tmp_path / "out"
    assert main(["batch", str(dataset), "-o", str(out), "--frames", "2", "--workers", "1"]) == 1
    err = capsys.readouterr().err
    assert "Traceback" not in err
    jobs = {job["name"]: job for job in json.loads((out / "dataset.json").read_text())["jobs"]}
    assert jobs["walk-small-seed3"]["status"] == "done" and jobs["walk-small-seed3"]["frames"] == 2
    broken = jobs["broken-small-seed3"]
    assert broken["status"] == "failed" and "missing_bench.glb" in broken["error"]
    assert broken["directory"] is None
    assert "missing_bench.glb" in (out / "DATASET.md").read_text()
    assert main(["verify", str(out)]) == 0
