"""Batch throughput: datasets rendered by 1 and by 2 worker processes (scaling on this machine).

Two datasets, each timed on 1 and on 2 workers:

- 20 jobs of one walker through one 320×240 camera, 5 frames each (`walker_scene`): many short jobs, so the
  workers' start-up and each job's setup weigh much.
- 4 seeds of the two-camera example scene (`TWO_CAMERA_SCENE`: vehicles, walkers, riders, two cameras of
  different profiles), 3 frames each, its streams made small (`small_scene_copy`: each camera's sensor
  `TWO_CAMERA_WIDTH_PX` wide, its own aspect and field of view kept) so that a 1-worker run takes tens of
  seconds on a 2-core machine. A dataset cannot shrink a scene's streams (its `profiles:` would give every
  camera one profile), so the bench writes a copy of the scene and of its profiles with small sensors into
  its temporary workspace; the scene's content (meshes, markings, lights, actors, mounts) is the file's.

Each timed run renders the whole dataset into a fresh directory (a run into a finished one would skip
every job), the workers' start-up included: each forked from the pool's fork server, one OpenGL context each,
their first job's warm-up. The fork server's own imports (about 3 s, once per batch process, before its
first worker: `camgen.batch.executor.start_pool_server`) are not: it is made ready before the timed runs, so
that both cases start alike (the server outlives a batch, so the later runs would find it ready anyway).
The 2-worker case gives its ratio to the 1-worker case; scaling efficiency = 1 / (2 × ratio).

Each run also records CPU seconds (`BatchCpu`): the workers' (user + system, their own child processes
included), read as the growth of the fork server's reaped-children times (`reaped_children_cpu_s`: the
workers are its children, not the batch process's, so this process's `RUSAGE_CHILDREN` never sees them),
and the batch process's own (`time.process_time`). Where /proc is missing the workers' figure is left out.
"""

from __future__ import annotations

import multiprocessing.forkserver
import os
import shutil
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from camgen.bench.harness import Case

JOBS = 20
FRAMES = 5

TWO_CAMERA_SCENE = "scenes/intersection_two_cameras.yaml"
"""The two-camera example scene of issue 23's goal ("two local workers reach ≥ 1.8× one on a two-camera scene")."""
TWO_CAMERA_JOBS = 4
TWO_CAMERA_FRAMES = 3
TWO_CAMERA_WIDTH_PX = 640
"""Each camera's stream width in the bench copy (its height follows the sensor's aspect, rounded to even)."""

REAP_WAIT_S = 10.0
"""How long a run waits, after the batch returns, for the fork server to reap the workers it forked."""


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


def small_scene_copy(scene_path: Path, width_px: int, directory: Path) -> Path:
    """Write into `directory` a copy of the scene whose every camera has its own profile with a sensor
    `width_px` sites wide (`camgen.bench.variants.resized_profile`: same sensor width in mm, so the same
    horizontal field of view; the height keeps the sensor's aspect, rounded to an even count for the video
    encoders' 4:2:0), each profile written next to it; return the copy's path.

    The rest of the scene is the file's, as read. A camera with a virtual PTZ (whose stream is its
    `eptz.output_size_px`, not its sensor) is a ValueError: this copy shrinks sensors only.
    """
    from camgen.bench.variants import resized_profile
    from camgen.config.loader import load_scene
    from camgen.config.yaml_source import load_yaml

    loaded = load_scene(scene_path)
    data = load_yaml(scene_path).data
    directory.mkdir(parents=True, exist_ok=True)
    for camera in data["cameras"]:
        if camera.get("eptz") is not None:
            raise ValueError(f"{scene_path}: camera {camera['name']} has a virtual PTZ; give a scene without one")
        own = loaded.profiles[camera["name"]]
        sensor = own.profile.sensor
        height_px = 2 * round(width_px * sensor.height_px / sensor.width_px / 2)
        small = resized_profile(own.profile, width_px, height_px)
        file = f"{camera['name']}_{own.name}_{width_px}x{height_px}.yaml"
        profile_data = small.model_dump(mode="json", by_alias=True, exclude_none=True)
        (directory / file).write_text(yaml.safe_dump(profile_data, sort_keys=False, allow_unicode=True), "utf-8")
        camera["profile"] = f"./{file}"
    copy = directory / scene_path.name
    copy.write_text(yaml.safe_dump(data, sort_keys=False, allow_unicode=True), encoding="utf-8")
    return copy


def two_camera_dataset(scene_file: str) -> str:
    """The dataset (YAML) of `TWO_CAMERA_JOBS` seeds of the scene `scene_file` (relative to the dataset)."""
    return f"""\
description: {TWO_CAMERA_JOBS} seeds of the two-camera intersection, streams {TWO_CAMERA_WIDTH_PX} px wide
scenes: [{scene_file}]
seeds: {{start: 0, count: {TWO_CAMERA_JOBS}}}
"""


def write_two_camera_dataset(repo: Path, directory: Path) -> Path:
    """The two-camera bench dataset, its small scene copy and profiles written into `directory`; its path."""
    scene = small_scene_copy(repo / TWO_CAMERA_SCENE, TWO_CAMERA_WIDTH_PX, directory / "two_cameras")
    dataset = directory / "two_cameras.yaml"
    dataset.write_text(two_camera_dataset(scene.relative_to(directory).as_posix()), encoding="utf-8")
    return dataset


def reaped_children_cpu_s(pid: int) -> float:
    """CPU seconds (user + system) of the children process `pid` has waited for, and of theirs
    (`cutime` + `cstime`, fields 16 and 17 of /proc/<pid>/stat, proc(5)), at clock-tick resolution."""
    stat = Path(f"/proc/{pid}/stat").read_text(encoding="ascii")
    fields = stat.rsplit(")", 1)[1].split()  # fields[0] is field 3 (state): the command name may hold spaces
    return (int(fields[13]) + int(fields[14])) / os.sysconf("SC_CLK_TCK")


def _children(pid: int) -> list[int]:
    """Processes whose parent is `pid`, zombies (ended, not yet waited for) included."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text(encoding="ascii", errors="replace").rsplit(")", 1)[1].split()
        except OSError:  # ended while listed
            continue
        if int(fields[1]) == pid:
            found.append(int(stat.parent.name))
    return found


def _pool_server_pid() -> int | None:
    """The local pool's fork server's process id (multiprocessing keeps it privately), or None."""
    return getattr(multiprocessing.forkserver._forkserver, "_forkserver_pid", None)


@dataclass
class BatchCpu:
    """CPU seconds of each timed batch run, by case name, in run order."""

    workers_s: dict[str, list[float]] = field(default_factory=dict)
    """The workers' (user + system, their child processes included); no entry where it could not be read."""
    batch_s: dict[str, list[float]] = field(default_factory=dict)
    """The batch process's own (it plans, waits and writes the dataset record)."""


def _timed_run(name: str, run, cpu: BatchCpu | None) -> None:
    """Call `run()`; record its CPU seconds in `cpu` under `name`."""
    server = _pool_server_pid()
    readable = server is not None and Path(f"/proc/{server}/stat").exists()
    workers_before = reaped_children_cpu_s(server) if readable else 0.0
    batch_before = time.process_time()
    run()
    batch_s = time.process_time() - batch_before
    if cpu is None:
        return
    cpu.batch_s.setdefault(name, []).append(batch_s)
    if not readable:
        return
    deadline = time.monotonic() + REAP_WAIT_S
    while _children(server) and time.monotonic() < deadline:
        time.sleep(0.05)
    if not _children(server):  # every worker ended and waited for: its time is in the server's
        cpu.workers_s.setdefault(name, []).append(reaped_children_cpu_s(server) - workers_before)


def ready_pool_server() -> None:
    """Start the fork server and wait until it has imported: it forks its first process after that."""
    from camgen.batch.executor import pool_context, start_pool_server

    start_pool_server()
    with ProcessPoolExecutor(1, mp_context=pool_context()) as pool:
        pool.submit(os.getpid).result()


def _pair(name: str, dataset: Path, workspace: Path, frames: int, cpu: BatchCpu | None) -> list[Case]:
    """1-worker and 2-worker cases rendering the `frames` first frames of each job of `dataset`."""
    from camgen.batch.expand import compile_batch_job, expand
    from camgen.batch.run import run_batch

    jobs = [(batch, compile_batch_job(batch)) for batch in expand(dataset)]

    def run(workers: int) -> None:
        out = workspace / f"{dataset.stem}-out{workers}"
        shutil.rmtree(out, ignore_errors=True)
        summary = run_batch(jobs, out, workers=workers, retries=0, frames=frames)
        if not summary.ok:
            raise RuntimeError(f"bench batch failed: {[o.error for o in summary.outcomes if o.error]}")

    one, two = f"{name}, 1 worker", f"{name}, 2 workers"
    return [
        Case(name=one, run=lambda: _timed_run(one, lambda: run(1), cpu), setup=ready_pool_server, repeats=2, warmup=0),
        Case(
            name=two,
            run=lambda: _timed_run(two, lambda: run(2), cpu),
            setup=ready_pool_server,
            repeats=2,
            warmup=0,
            baseline=one,
        ),
    ]


def batch_cases(repo: Path, cpu: BatchCpu | None = None) -> list[Case]:
    """The walker dataset's pair of cases, then the two-camera dataset's; each run's CPU seconds go into `cpu`."""
    workspace = Path(tempfile.mkdtemp(prefix="camgen-bench-batch-"))
    (workspace / "bench.yaml").write_text(PROFILE, encoding="utf-8")
    (workspace / "scene.yaml").write_text(SCENE, encoding="utf-8")
    (workspace / "dataset.yaml").write_text(DATASET, encoding="utf-8")
    two_cameras = write_two_camera_dataset(repo, workspace)
    return [
        *_pair(f"batch {JOBS} jobs × {FRAMES} frames 320×240", workspace / "dataset.yaml", workspace, FRAMES, cpu),
        *_pair(
            f"batch two cameras, {TWO_CAMERA_JOBS} jobs × {TWO_CAMERA_FRAMES} frames, {TWO_CAMERA_WIDTH_PX} px wide",
            two_cameras,
            workspace,
            TWO_CAMERA_FRAMES,
            cpu,
        ),
    ]
