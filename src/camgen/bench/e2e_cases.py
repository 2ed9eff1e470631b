"""End to end: frames/s of `camgen render` per example scene and profile at 720p and 1080p, with the
share of each stage.

Each case renders one camera of an example scene (each distinct profile once) through `execute`, as
`camgen render` does, with every output the scene plans (video, frames, depth, raw, annotations),
into a temporary directory. The stream is resized to the size named (`variants.at_output_size`:
the sensor keeps its width in mm, a virtual PTZ keeps its sensor and changes its stream). The frames are
consecutive, from the middle of the sequence (`run_frames`), as `camgen render` draws them: a frame
after its predecessor draws only what changed since (`camgen.render.sequence`, "Still frames"), so
frames spread over the sequence would time a cost that no render pays. The first is a warm-up (scene
upload, lens maps, auto-exposure's convergence, the whole first draw) and is not counted. A frame's
time is its wall time; the encoder's flush and the annotation files written at the end are shared out
over the timed frames.
"""

from __future__ import annotations

import dataclasses
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from camgen.bench.harness import Case
from camgen.bench.variants import at_output_size, one_camera
from camgen.config import load_scene
from camgen.plan import PlanSettings, compile_scene
from camgen.plan.timing import stage_sums

STREAM_SIZES_PX = {"720p": (1280, 720), "1080p": (1920, 1080)}
FRAMES = 3
"""Frames rendered per case: one warm-up and two timed."""


@dataclass(frozen=True)
class EndToEnd:
    """What one end-to-end case measured."""

    scene: str
    camera: str
    profile: str
    size: str
    stages: tuple[str, ...]
    """The camera's planned stages."""
    stage_ms: dict[str, float]
    """Mean ms per timed frame in each instrumented stage (the finish shared out)."""
    frame_ms: float
    """Mean wall ms per timed frame."""
    warm: bool = True
    """False for a one-frame sequence: its only frame, warm-up included, is what is timed."""
    cpu_ms: float = 0.0
    """Mean CPU ms of the process per timed frame, every thread's (the finish shared out as the wall time's)."""

    @property
    def frames_per_s(self) -> float:
        return 1e3 / self.frame_ms

    @property
    def cores_busy(self) -> float:
        """CPU time over wall time: how many cores the frames kept busy on average."""
        return self.cpu_ms / self.frame_ms

    @property
    def other_ms(self) -> float:
        return max(self.frame_ms - sum(self.stage_ms.values()), 0.0)


def scene_cameras(repo: Path) -> list[tuple[Path, str, str]]:
    """(scene file, camera, profile name): each scene's first camera of each distinct profile."""
    chosen = []
    for path in sorted((repo / "scenes").glob("*.yaml")):
        loaded, seen = load_scene(path), set()
        for camera in loaded.scene.cameras:
            profile = loaded.profiles[camera.name].name
            if profile not in seen:
                seen.add(profile)
                chosen.append((path, camera.name, profile))
    return chosen


def run_frames(frame_count: int, count: int) -> list[int]:
    """`count` consecutive frame indices from the middle of the sequence (fewer if it is shorter)."""
    count = min(count, frame_count)
    start = min(frame_count // 2, frame_count - count)
    return list(range(start, start + count))


def spread_frames(frame_count: int, count: int) -> list[int]:
    """`count` frame indices spread evenly over the sequence, the first one first (fewer if short)."""
    return sorted({int(i) for i in np.linspace(0, frame_count - 1, count).round()})


def measure(
    path: Path, camera: str, size: tuple[int, int], frames: int = FRAMES, settings=None, *, video: bool = True
) -> EndToEnd:
    """Render `frames` spread frames of `camera` in the scene at `path` at `size` and time them; `video`
    False leaves the scene's video output out (a machine without PyAV)."""
    loaded = load_scene(path)
    variant = at_output_size(one_camera(loaded, camera), *size)
    if not video:
        outputs = variant.scene.outputs.model_copy(update={"video": False})
        variant = dataclasses.replace(variant, scene=variant.scene.model_copy(update={"outputs": outputs}))
    job = compile_scene(variant, settings or PlanSettings())
    (result,) = execute_in_scratch(job, run_frames(job.frame_count, frames), path.parent.joinpath)
    frame_ms, stage_ms = timed_per_frame(result)
    return EndToEnd(
        scene=path.stem,
        camera=camera,
        profile=loaded.profiles[camera].name,
        size=f"{size[0]}×{size[1]}",
        stages=tuple(stage.name for stage in job.cameras[0].stages),
        stage_ms=stage_ms,
        frame_ms=frame_ms,
        warm=len(result.frame_wall_s) > 1,
        cpu_ms=cpu_per_frame_ms(result),
    )


def execute_in_scratch(job, frames: list[int], resolve_path=None) -> list:
    """`execute` the job's `frames` into a temporary directory, removed afterwards; the results."""
    from camgen.bench.render_cases import _renderer
    from camgen.plan.execute import execute

    out = Path(tempfile.mkdtemp(prefix="camgen-bench-execute-"))
    try:
        return execute(job, out, renderer=_renderer(), frames=frames, resolve_path=resolve_path)
    finally:
        shutil.rmtree(out, ignore_errors=True)


def timed_per_frame(result) -> tuple[float, dict[str, float]]:
    """Mean wall ms and ms per stage of a camera's timed frames (all but the first, the warm-up;
    a one-frame render times its only frame). The encoder's flush holds frames buffered from every
    frame, the warm-up's too, so the timed frames take their share of the finish."""
    timed = max(len(result.frame_wall_s) - 1, 1)
    frame_records = result.stage_frames[1:] if len(result.stage_frames) > 1 else result.stage_frames
    share = timed / len(result.frame_wall_s)
    finish = {stage: s * share for stage, s in result.finish_s.items()}
    totals = stage_sums([*frame_records, finish])
    frame_ms = _timed_mean_ms(result.frame_wall_s, sum(result.finish_s.values()))
    return frame_ms, {stage: 1e3 * s / timed for stage, s in totals.items()}


def cpu_per_frame_ms(result) -> float:
    """Mean CPU ms of the process per timed frame (as `timed_per_frame`: the warm-up left out, the finish
    shared out)."""
    return _timed_mean_ms(result.frame_cpu_s, result.finish_cpu_s)


def _timed_mean_ms(per_frame_s: list[float], finish_s: float) -> float:
    """Mean ms per timed frame of a per-frame time (`timed_per_frame`'s frames), the timed frames' share of
    `finish_s`, the time after the last frame, included."""
    timed = max(len(per_frame_s) - 1, 1)
    share = timed / max(len(per_frame_s), 1)
    return 1e3 * (sum(per_frame_s[1:] or per_frame_s) + finish_s * share) / timed


def e2e_cases(repo: Path, records: dict[str, EndToEnd]) -> list[Case]:
    """One case per (scene, profile, size); each stores its `EndToEnd` in `records` by case name."""
    cases = []
    for path, camera, profile in scene_cameras(repo):
        for size_name, size in STREAM_SIZES_PX.items():
            name = f"end to end {path.stem} / {profile} {size_name}"

            def run(path=path, camera=camera, size=size, name=name) -> None:
                records[name] = measure(path, camera, size)

            cases.append(Case(name=name, run=run, repeats=1, warmup=0))
    return cases
