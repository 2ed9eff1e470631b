"""Batch throughput: a 20-job dataset rendered by 1 and by 2 worker processes (scaling on this machine).

Each timed run renders the whole dataset into a fresh directory (a run into a finished one would skip
every job), the workers' start-up included: each forked from the pool's fork server, one OpenGL context each,
their first job's warm-up. The fork server's own imports (about 3 s, once per batch process, before its
first worker: `camgen.batch.executor.start_pool_server`) are not: it is made ready before the timed runs, so
that both cases start alike (the server outlives a batch, so the later runs would find it ready anyway).
The 2-worker case gives its ratio to the 1-worker case; scaling efficiency = 1 / (2 × ratio).
"""

from __future__ import annotations

import os
import shutil
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from camgen.bench.harness import Case

JOBS = 20
FRAMES = 5


def bench_profile(width_px: int, height_px: int, focal_length_mm: float, what: str) -> str:
    """A small camera profile (YAML) for batch benches: `width_px` × `height_px`, a lens of `focal_length_mm`."""
    return f"""\
description: {what}, {width_px}×{height_px}
sensor: {{width_px: {width_px}, height_px: {height_px}, pixel_pitch_um: 3.0, cfa: RGGB, full_well_e: 10000,
         conversion_gain_dn_per_e: 0.4, black_level_dn: 64, noise: {{read_noise_e: 2.0}}}}
lens: {{focal_length_mm: {float(focal_length_mm)!r}, f_number: 2.0}}
"""


def walker_scene(profile: str) -> str:
    """A one-second scene (YAML) of one walker crossing a plane, seen by one camera of profile `profile`."""
    return f"""\
duration_s: 1
fps: 10
environment:
  meshes: [{{type: plane, name: ground, size_m: [20, 20]}}]
lights: [{{type: ambient, illuminance_lux: 1000}}]
actors:
  - {{name: walker, class: person, path: {{waypoints_m: [[-3, 5], [3, 5]], speed_m_s: 1.4}}}}
cameras:
  - {{name: cam, profile: {profile}, mount: {{position_m: [0, -5, 3], yaw_deg: 90, pitch_deg: -20}}}}
"""


PROFILE = bench_profile(320, 240, 2.0, "bench camera")
SCENE = walker_scene("bench")
DATASET = f"""\
description: {JOBS} seeds of one walker through a 320×240 camera
scenes: [scene.yaml]
seeds: {{start: 0, count: {JOBS}}}
"""


def batch_cases() -> list[Case]:
    from camgen.batch.executor import pool_context, start_pool_server
    from camgen.batch.expand import compile_batch_job, expand
    from camgen.batch.run import run_batch

    workspace = Path(tempfile.mkdtemp(prefix="camgen-bench-batch-"))
    (workspace / "bench.yaml").write_text(PROFILE, encoding="utf-8")
    (workspace / "scene.yaml").write_text(SCENE, encoding="utf-8")
    (workspace / "dataset.yaml").write_text(DATASET, encoding="utf-8")
    jobs = [(batch, compile_batch_job(batch)) for batch in expand(workspace / "dataset.yaml")]

    def run(workers: int) -> None:
        out = workspace / f"out{workers}"
        shutil.rmtree(out, ignore_errors=True)
        summary = run_batch(jobs, out, workers=workers, retries=0, frames=FRAMES)
        if not summary.ok:
            raise RuntimeError(f"bench batch failed: {[o.error for o in summary.outcomes if o.error]}")

    def ready_pool_server() -> None:
        """Start the fork server and wait until it has imported: it forks its first process after that."""
        start_pool_server()
        with ProcessPoolExecutor(1, mp_context=pool_context()) as pool:
            pool.submit(os.getpid).result()

    name = f"batch {JOBS} jobs × {FRAMES} frames 320×240"
    return [
        Case(name=f"{name}, 1 worker", run=lambda: run(1), setup=ready_pool_server, repeats=2, warmup=0),
        Case(
            name=f"{name}, 2 workers",
            run=lambda: run(2),
            setup=ready_pool_server,
            repeats=2,
            warmup=0,
            baseline=f"{name}, 1 worker",
        ),
    ]
