"""The benchmark cases: configuration, planning, rendering, the lens stages, the camera model and batch throughput."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from camgen.bench.batch_cases import batch_cases
from camgen.bench.camera_cases import camera_cases
from camgen.bench.dof_cases import dof_cases
from camgen.bench.harness import Case
from camgen.bench.optics_cases import optics_cases
from camgen.bench.render_cases import render_cases
from camgen.config import load_scene
from camgen.optics.distortion import distort_normalized, undistort_normalized
from camgen.plan import compile_scene


def default_cases(repo: Path) -> list[Case]:
    scenes = sorted((repo / "scenes").glob("*.yaml"))
    cases = []
    for path in scenes:
        cases.append(Case(name=f"load + validate {path.stem}", run=lambda p=path: _load(p)))
        loaded = load_scene(path)
        cases.append(Case(name=f"compile plan {path.stem}", run=lambda s=loaded: _compile(s)))
    cases.append(_undistort_case())
    cases += render_cases(repo)
    cases += optics_cases(repo)
    cases += dof_cases()
    cases += camera_cases(repo)
    cases += batch_cases()
    return cases


def _load(path: Path) -> None:
    load_scene(path)


def _compile(loaded) -> None:
    compile_scene(loaded)


def _undistort_case() -> Case:
    """Invert a strong barrel lens over a full 1080p grid; error is the largest residual in pixels."""
    coeffs = np.array([-0.28, 0.07, 0.001, -0.0008, -0.006])
    fx = 1500.0
    u, v = np.meshgrid(np.arange(1920) - 959.5, np.arange(1080) - 539.5)
    distorted = np.stack([u / fx, v / fx], axis=-1)

    def run() -> float:
        result = undistort_normalized(distorted, coeffs)
        return float(np.max(np.abs(distort_normalized(result.points, coeffs) - distorted))) * fx

    return Case(name="undistort 1920×1080 grid (Newton, float64)", run=run, error_unit="px")
