"""How cost grows: with resolution, with the number of actors, with the number of cameras. Each
series is fitted with a power law t = a·xᵇ (`harness.power_law_fit`); the report states b.

- Resolution: the parking lot's camera resized (same field of view) from 640×360 to 3840×2160; the
  radiance draw (1×, no supersampling) and the post-render camera model's core (the camera-model
  cases' "core" at that size), against the pixel count.
- Actors: a synthetic street at 640×360 with 1–32 walkers crossing the view, rendered end to end
  (video and MOT/COCO annotations planned); render, annotation and whole-frame ms per frame.
- Cameras: the same street with 4 walkers seen by 1–8 cameras at 640×360; compile time and the
  rendering of every camera, per frame of the sequence.
"""

from __future__ import annotations

import shutil
import tempfile
import time
import weakref
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from camgen.bench.harness import Case

RESOLUTIONS_PX = ((640, 360), (960, 540), (1280, 720), (1920, 1080), (2560, 1440), (3840, 2160))
ACTOR_COUNTS = (1, 2, 4, 8, 16, 32)
CAMERA_COUNTS = (1, 2, 4, 8)
STREET_SIZE_PX = (640, 360)
STREET_FRAMES = 4
"""Frames per end-to-end street run: one warm-up and three timed."""


def bench_profile(width_px: int, height_px: int, pixel_pitch_um: float) -> str:
    """The street's camera profile (YAML text): a 4 mm f/2 lens on an RGGB sensor of this size and pitch."""
    return (
        f"description: bench camera, {width_px}×{height_px}\n"
        f"sensor: {{width_px: {width_px}, height_px: {height_px}, pixel_pitch_um: {pixel_pitch_um}, cfa: RGGB, "
        "full_well_e: 10000,\n"
        "         conversion_gain_dn_per_e: 0.4, black_level_dn: 64, noise: {read_noise_e: 2.0}}\n"
        "lens: {focal_length_mm: 4.0, f_number: 2.0}\n"
    )


PROFILE = bench_profile(*STREET_SIZE_PX, 6.0)


def street_scene(actors: int, cameras: int, *, duration_s: float = 2, fps: float = 10) -> str:
    """A 40 m street with `actors` box walkers crossing it at staggered depths, seen by `cameras`
    cameras spread along the kerb, all looking across it (profile `street`: `bench_profile`)."""
    lines = [
        f"duration_s: {duration_s:g}",
        f"fps: {fps:g}",
        "environment:",
        "  meshes: [{type: plane, name: ground, size_m: [60, 40]}]",
        "lights: [{type: ambient, illuminance_lux: 800}, {type: sun, illuminance_lux: 20000, azimuth_deg: 200}]",
        "outputs: {video: true, annotations: [mot, coco]}",
        "actors:",
    ]
    rng = np.random.default_rng(actors)
    for i in range(actors):
        y = 6.0 + 14.0 * (i + 0.5) / actors
        x0 = float(rng.uniform(-12, -4))
        lines.append(
            f"  - {{name: walker_{i}, class: person, path: {{waypoints_m: [[{x0:.2f}, {y:.2f}], "
            f"[{x0 + 16:.2f}, {y:.2f}]], speed_m_s: 1.4}}}}"
        )
    lines.append("cameras:")
    for c in range(cameras):
        x = -6.0 + 12.0 * (c + 0.5) / cameras
        mount = f"{{position_m: [{x:.2f}, -4, 4], yaw_deg: 90, pitch_deg: -15}}"
        lines.append(f"  - {{name: cam_{c}, profile: street, mount: {mount}}}")
    return "\n".join(lines) + "\n"


@dataclass
class Growth:
    """The end-to-end series, filled in as their cases run: count → ms (the resolution series are
    the cases' own medians: `resolution_case_names`)."""

    actors_render_ms: dict[int, float] = field(default_factory=dict)
    actors_annotate_ms: dict[int, float] = field(default_factory=dict)
    actors_frame_ms: dict[int, float] = field(default_factory=dict)
    cameras_compile_ms: dict[int, float] = field(default_factory=dict)
    cameras_frame_ms: dict[int, float] = field(default_factory=dict)


def growth_cases(repo: Path, growth: Growth) -> list[Case]:
    cases = []
    for size in RESOLUTIONS_PX:
        cases += _resolution_cases(repo, size)
    workspace = Path(tempfile.mkdtemp(prefix="camgen-bench-growth-"))
    weakref.finalize(growth, shutil.rmtree, workspace, ignore_errors=True)
    (workspace / "street.yaml").write_text(PROFILE, encoding="utf-8")
    for n in ACTOR_COUNTS:
        cases.append(
            Case(
                name=f"growth: street 640×360 with {n} walkers, end to end",
                run=lambda n=n: _actors(workspace, n, growth),
                repeats=1,
                warmup=0,
            )
        )
    for c in CAMERA_COUNTS:
        cases.append(
            Case(
                name=f"growth: street with 4 walkers seen by {c} cameras, compile + render",
                run=lambda c=c: _cameras(workspace, c, growth),
                repeats=1,
                warmup=0,
            )
        )
    return cases


def resolution_case_names(size: tuple[int, int]) -> tuple[str, str]:
    """The names of the render and camera-model cases at `size`."""
    label = f"{size[0]}×{size[1]}"
    return f"growth: render radiance 1×, parking lot {label}", f"growth: camera model core, parking lot {label}"


def _resolution_cases(repo: Path, size: tuple[int, int]) -> list[Case]:
    from camgen.bench.camera_cases import _setup
    from camgen.bench.render_cases import _parking_lot, _renderer, _view

    draw_name, core_name = resolution_case_names(size)
    loaded = {}

    def setup() -> None:
        _, camera, graph = _parking_lot(repo, shadows=True)
        loaded["view"], loaded["graph"] = _view(camera, size), graph

    def draw() -> None:
        loaded["graph"].place_actors(2.0)
        _renderer().draw(loaded["graph"], loaded["view"], ("radiance",))

    def core() -> None:
        _, fast, _, state, passes = _setup(repo, size)
        fast.process(state, passes, rng=np.random.default_rng(0))

    return [
        Case(name=draw_name, run=draw, setup=setup, repeats=5),
        Case(
            name=core_name,
            run=core,
            setup=lambda: _discard(_setup(repo, size)),
            repeats=5,
        ),
    ]


def _actors(workspace: Path, n: int, growth: Growth) -> None:
    from camgen.bench.e2e_cases import measure

    path = workspace / f"actors_{n}.yaml"
    path.write_text(street_scene(n, 1), encoding="utf-8")
    record = measure(path, "cam_0", STREET_SIZE_PX, frames=STREET_FRAMES)
    growth.actors_render_ms[n] = record.stage_ms.get("render", 0.0)
    growth.actors_annotate_ms[n] = record.stage_ms.get("annotate", 0.0)
    growth.actors_frame_ms[n] = record.frame_ms


def _cameras(workspace: Path, c: int, growth: Growth) -> None:
    from camgen.bench.e2e_cases import execute_in_scratch, run_frames, timed_per_frame
    from camgen.config import load_scene
    from camgen.plan import compile_scene

    path = workspace / f"cameras_{c}.yaml"
    path.write_text(street_scene(4, c), encoding="utf-8")
    start = time.perf_counter()
    job = compile_scene(load_scene(path))
    growth.cameras_compile_ms[c] = 1e3 * (time.perf_counter() - start)
    results = execute_in_scratch(job, run_frames(job.frame_count, STREET_FRAMES))
    growth.cameras_frame_ms[c] = sum(timed_per_frame(result)[0] for result in results)


def _discard(_result) -> None:
    """Cases time the work, not its result."""
