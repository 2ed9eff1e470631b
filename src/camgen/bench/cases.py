"""Planning cases: loading and compiling each example scene, and the lens model's inverse."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from camgen.bench.harness import Case
from camgen.config import load_scene
from camgen.optics.distortion import distort_normalized, undistort_normalized
from camgen.plan import compile_scene


def planning_cases(repo: Path) -> list[Case]:
    cases = []
    for path in sorted((repo / "scenes").glob("*.yaml")):
        cases.append(Case(name=f"load + validate {path.stem}", run=lambda p=path: _load(p), repeats=5))
        loaded = load_scene(path)
        cases.append(Case(name=f"compile plan {path.stem}", run=lambda s=loaded: _compile(s), repeats=3))
    cases.append(_undistort_case())
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

    return Case(name="undistort 1920×1080 grid (Newton, float64)", run=run, error_unit="px", repeats=3)
