"""Long sequences (issue 23): how long planning takes as the sequence grows, up to the hour at 25
frames/s with 50 actors that issue 23 sets its goal for (≤ 10 s on this machine).

The scene is the parking-lot example (its PTZ dome at its home view, its cars, cyclist and three walkers)
with 42 more walkers on looping routes through the lot (50 actors in all), at 1, 10 and 60 minutes.
Planning is `compile_scene`: every camera state of every frame, the skip decisions (which walk every
frame's actor motion and blur circle) and the job's content hash, after the scene file is loaded.

Rendering's memory: the bench street (`growth_cases.street_scene`, 8 walkers, 320×180) rendered for
`MEMORY_FRAMES` frames with video, MOT, COCO and camera.jsonl, the process's resident memory read after
every frame (/proc/self/statm); its slope over the frames after the first `MEMORY_WARMUP` is what a long
sequence adds per frame.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import weakref
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from camgen.bench.harness import Case

ACTORS = 50
MINUTES = (1, 10, 60)
MEMORY_FRAMES = 300
MEMORY_WARMUP = MEMORY_FRAMES // 2
"""The slope is fitted over the second half: in the first, memory rises in steps as walkers come into
view and the encoder fills its look-ahead (measured: the steps stop by frame 105 of 300)."""
MEMORY_SIZE_PX = (320, 180)


def long_scene(repo: Path, minutes: float) -> str:
    """The parking lot as a `minutes`-long sequence with `ACTORS` actors (YAML text); its profiles are
    the repository's (the scene is written into a copy of `scenes/`)."""
    scene = yaml.safe_load((repo / "scenes/parking_lot.yaml").read_text(encoding="utf-8"))
    scene["duration_s"] = 60.0 * minutes
    rng = np.random.default_rng(23)
    extra = ACTORS - len(scene["actors"])
    for i in range(extra):
        a, b = rng.uniform([-25, -5], [25, 15], size=(2, 2)).round(1).tolist()
        scene["actors"].append(
            {
                "name": f"extra_walker_{i}",
                "class": "person",
                "path": {"waypoints_m": [a, b], "speed_m_s": round(float(rng.uniform(1.0, 1.6)), 2), "loop": True},
            }
        )
    return yaml.safe_dump(scene, sort_keys=False)


@dataclass
class LongFacts:
    """Filled in as the cases run: minutes → (frames, camera states, job JSON MB)."""

    sizes: dict[float, tuple[int, int, float]] = field(default_factory=dict)
    resident_mb: list[float] = field(default_factory=list)
    """Resident memory after each frame of the memory case, MB."""


def long_cases(repo: Path, facts: LongFacts) -> list[Case]:
    from camgen.config import load_scene
    from camgen.plan import compile_scene

    workspace = Path(tempfile.mkdtemp(prefix="camgen-bench-long-"))
    weakref.finalize(facts, shutil.rmtree, workspace, ignore_errors=True)
    shutil.copytree(repo / "scenes", workspace / "scenes")
    shutil.copytree(repo / "profiles", workspace / "profiles")
    loaded = {}

    def setup(minutes: float) -> None:
        """Load the scene and plan it once, untimed, for its sizes (the job file's JSON alone took 0.7 s
        of the hour)."""
        path = workspace / "scenes" / f"long_{minutes:g}min.yaml"
        path.write_text(long_scene(repo, minutes), encoding="utf-8")
        loaded[minutes] = load_scene(path)
        job = compile_scene(loaded[minutes])
        states = sum(len(camera.states) for camera in job.cameras)
        facts.sizes[minutes] = (job.frame_count, states, len(job.to_json()) / 1e6)

    def plan(minutes: float) -> None:
        compile_scene(loaded[minutes])

    def render_memory() -> None:
        render_resident_mb(workspace, facts)

    return [
        *(
            Case(
                name=f"plan: parking lot, {ACTORS} actors, {minutes} min at 25 frames/s",
                run=lambda m=minutes: plan(m),
                setup=lambda m=minutes: setup(m),
                repeats=1 if minutes >= 60 else 3,
                warmup=0,
            )
            for minutes in MINUTES
        ),
        Case(
            name=f"render: street {MEMORY_SIZE_PX[0]}×{MEMORY_SIZE_PX[1]}, {MEMORY_FRAMES} frames, memory per frame",
            run=render_memory,
            repeats=1,
            warmup=0,
        ),
    ]


def resident_mb() -> float:
    """This process's resident memory now, MB (Linux)."""
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 1e6


def render_resident_mb(workspace: Path, facts: LongFacts) -> None:
    """Render the memory case and record the resident memory after each frame in `facts`."""
    from camgen.bench.growth_cases import bench_profile, street_scene
    from camgen.bench.render_cases import _renderer
    from camgen.config import load_scene
    from camgen.plan import compile_scene
    from camgen.plan.execute import execute

    # The street's camera at half its size, the same field of view (twice the pixel pitch).
    (workspace / "street.yaml").write_text(bench_profile(*MEMORY_SIZE_PX, 12.0), encoding="utf-8")
    path = workspace / "memory_street.yaml"  # its outputs: video, MOT and COCO; camera.jsonl by default
    path.write_text(street_scene(8, 1, duration_s=MEMORY_FRAMES / 25, fps=25), encoding="utf-8")
    job = compile_scene(load_scene(path))
    facts.resident_mb.clear()
    out = workspace / "memory_out"
    try:
        execute(job, out, renderer=_renderer(), on_frame=lambda camera, index: facts.resident_mb.append(resident_mb()))
    finally:
        shutil.rmtree(out, ignore_errors=True)
