"""The batch bench's datasets expand and compile as the timed runs need, and its CPU reading and text hold."""

from __future__ import annotations

import os
import resource
import subprocess
import sys

import pytest

from camgen.batch.expand import compile_batch_job, expand
from camgen.bench import batch_cases as bc
from camgen.bench.harness import Result
from camgen.bench.sections import _batch_scaling_text
from camgen.config import load_scene
from camgen.plan import compile_scene
from tests.conftest import REPO


@pytest.fixture(scope="module")
def two_camera_jobs(tmp_path_factory):
    dataset = bc.write_two_camera_dataset(REPO, tmp_path_factory.mktemp("bench"))
    return [(batch, compile_batch_job(batch)) for batch in expand(dataset)]


def test_the_two_camera_dataset_is_seeds_of_the_scene_with_small_streams(two_camera_jobs):
    original = compile_scene(load_scene(REPO / bc.TWO_CAMERA_SCENE))
    assert [batch.seed for batch, _ in two_camera_jobs] == list(range(bc.TWO_CAMERA_JOBS))
    assert len({job.content_hash() for _, job in two_camera_jobs}) == bc.TWO_CAMERA_JOBS
    for _, job in two_camera_jobs:
        assert job.frame_count == original.frame_count >= bc.TWO_CAMERA_FRAMES
        assert [c.name for c in job.cameras] == [c.name for c in original.cameras] and len(job.cameras) == 2
        for small, full in zip(job.cameras, original.cameras, strict=True):
            assert small.width_px == bc.TWO_CAMERA_WIDTH_PX
            assert small.height_px % 2 == 0
            assert abs(small.height_px - bc.TWO_CAMERA_WIDTH_PX * full.height_px / full.width_px) <= 1
            # the same sensor width in mm and the same lens: the same horizontal field of view
            assert small.profile.sensor.width_mm == pytest.approx(full.profile.sensor.width_mm)
            assert small.profile.lens == full.profile.lens
            assert small.states[0].T_world_from_cam == full.states[0].T_world_from_cam
        # the scene's content is the file's: actors, meshes, lights (only cameras' profiles and the seed differ)
        assert job.scene.actors == original.scene.actors
        assert job.scene.environment == original.scene.environment
        assert job.scene.lights == original.scene.lights


def test_a_scene_with_a_virtual_ptz_is_refused(tmp_path):
    with pytest.raises(ValueError, match="virtual PTZ"):
        bc.small_scene_copy(REPO / "scenes/eptz_follow.yaml", 320, tmp_path)


def test_reaped_children_cpu_matches_getrusage():
    burn = "import time\nend = time.process_time() + 0.3\nwhile time.process_time() < end: pass"
    subprocess.run([sys.executable, "-c", burn], check=True)
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    expected_s = usage.ru_utime + usage.ru_stime
    assert expected_s >= 0.3
    assert bc.reaped_children_cpu_s(os.getpid()) == pytest.approx(expected_s, abs=0.03)


def _result(name: str, median_ms: float, baseline: str | None = None) -> Result:
    return Result(name, 2, median_ms, median_ms, median_ms, median_ms, None, "", baseline)


def test_the_scaling_text_gives_each_pair_its_ratio_efficiency_and_cpu():
    one, two = "batch a, 1 worker", "batch a, 2 workers"
    results = {
        one: _result(one, 40_000.0),
        two: _result(two, 25_000.0, baseline=one),
        "batch b, 1 worker": _result("batch b, 1 worker", 10_000.0),
        "batch b, 2 workers": _result("batch b, 2 workers", 5_000.0, baseline="batch b, 1 worker"),
    }
    cpu = bc.BatchCpu(workers_s={one: [30.0, 34.0], two: [40.0, 40.0]}, batch_s={one: [0.1, 0.1], two: [0.2, 0.2]})
    first, second = _batch_scaling_text(results, cpu)
    assert "Batch, a: 2 workers take 0.62× the time of 1 (1.60× the throughput)" in first
    assert "= 80 %" in first
    assert "32.0 CPU s a run on 1 worker and 40.0 on 2" in first and "0.80 and 1.60 cores busy" in first
    assert "Batch, b: 2 workers take 0.50× the time of 1 (2.00× the throughput)" in second and "= 100 %" in second
    assert "CPU s" not in second
