"""The memory a compile needs, estimated before anything is allocated (`camgen.plan.budget`)."""

from __future__ import annotations

import tracemalloc
from pathlib import Path

import pytest

from camgen.config import load_scene
from camgen.errors import ConfigError
from camgen.plan import compile_scene
from camgen.plan.budget import BYTES_PER_CAMERA_FRAME, check_job_size, compile_memory_bytes, memory_bytes
from tests.conftest import SCENE, write

GIB = 2**30


def scene_of(workspace: Path, duration_s: float, fps: float = 10, cameras: int = 1):
    text = SCENE.replace("duration_s: 1", f"duration_s: {duration_s}").replace("fps: 10", f"fps: {fps}")
    text += "".join(
        f"  - name: cam{i}\n    profile: fixed\n    mount: {{position_m: [{i}, -5, 3]}}\n" for i in range(1, cameras)
    )
    return load_scene(write(workspace, f"scenes/s{duration_s}_{cameras}.yaml", text))


def test_a_day_at_30_fps_is_refused_on_a_16_gib_machine(workspace: Path):
    scene = scene_of(workspace, 86400, fps=30).scene
    with pytest.raises(ConfigError) as caught:
        check_job_size(scene, (16 * GIB, "physical"))
    (problem,) = caught.value.problems
    assert problem.path == ("duration_s",)
    assert problem.message.startswith("× fps = 86400 s × 30 Hz = 2592000 frames for each of 1 camera(s)")
    assert "need about 39.6 GiB, more than 50% of this machine's 16 GiB of physical memory" in problem.message
    assert "At most 524288 frames per camera fit (duration_s ≤ 17476 s at this fps)" in problem.message


def test_the_estimate_grows_with_frames_and_cameras(workspace: Path):
    one = scene_of(workspace, 10).scene
    three = scene_of(workspace, 10, cameras=3).scene
    assert compile_memory_bytes(one) == 100 * BYTES_PER_CAMERA_FRAME
    assert compile_memory_bytes(three) == 3 * compile_memory_bytes(one)
    check_job_size(three, (GIB, "available"))
    with pytest.raises(ConfigError, match=r"for each of 3 camera\(s\)"):
        check_job_size(three, (4 * 2**20, "available"))


def test_the_machine_memory_is_read_and_an_unknown_size_refuses_nothing(workspace: Path, monkeypatch):
    have, what = memory_bytes()
    assert have > 2**20 and what in ("available", "physical")
    monkeypatch.setattr("camgen.plan.budget.memory_bytes", lambda: None)
    check_job_size(scene_of(workspace, 86400, fps=30).scene)


def test_the_estimate_bounds_what_compile_allocates(workspace: Path):
    loaded = scene_of(workspace, 30)
    tracemalloc.start()
    try:
        compile_scene(loaded)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak <= compile_memory_bytes(loaded.scene)
