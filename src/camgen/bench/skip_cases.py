"""What skipping saves: each example scene's planned pipeline against the same job with every stage
forced on (`PlanSettings(force_all_stages=True)`), and the difference that makes to the output.

One camera per scene (its first), its stream at 1280×720, renders the same spread frames both ways
through render + camera model (`CameraRenderer` + `CameraPipeline`, as `execute` runs them, outputs
left out). Both start from the exposure auto-exposure settles at for the planned job, and draw the
same noise (same frame seeds). The output difference is the RMS over the 8-bit frame of planned −
forced, in codes, set against the frame's own temporal noise: the RMS difference between two noise
draws of the planned frame (the same passes processed again with another seed), divided by √2. A
skip is invisible when its difference is well under the noise; the bench states the ratio.
"""

from __future__ import annotations

import copy
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from camgen.bench.e2e_cases import spread_frames
from camgen.bench.harness import Case
from camgen.bench.variants import at_output_size, one_camera
from camgen.config import load_scene
from camgen.plan import PlanSettings, compile_scene
from camgen.plan.camera_pipeline import CameraPipeline, frame_rng
from camgen.plan.timing import StageClock, stage_sums
from camgen.sensor.auto_exposure import ExposureSetting

FRAMES = 3
"""One warm-up and two timed frames."""
STREAM_SIZE_PX = (1280, 720)
"""The stream size every scene is measured at (`variants.at_output_size`), which bounds the cost of
the 4K cameras; the plan's decisions are those of this size."""


@dataclass(frozen=True)
class SkipResult:
    scene: str
    camera: str
    skipped: tuple[str, ...]
    """Stages the plan leaves out (those the forced job adds)."""
    planned_ms: float
    forced_ms: float
    planned_stage_ms: dict[str, float]
    forced_stage_ms: dict[str, float]
    difference_codes: float
    """RMS of planned − forced over the 8-bit frames, codes."""
    noise_codes: float
    """RMS temporal noise of the planned frames, codes."""

    @property
    def speedup(self) -> float:
        return self.forced_ms / self.planned_ms


class _Camera:
    """Render + camera model of a job's only camera, frame by frame, timed."""

    def __init__(self, job, renderer, resolve_path, executor):
        from camgen.render.scene_graph import build_scene_graph
        from camgen.render.sequence import CameraRenderer

        self.job, self.camera = job, job.cameras[0]
        self.clock = StageClock()
        self.pipeline = CameraPipeline(job, self.camera, executor=executor, clock=self.clock)
        self.drawer = CameraRenderer(renderer, build_scene_graph(job.scene, resolve_path), self.camera)
        self.walls_s: list[float] = []

    def frame(self, index: int, setting=None):
        """The frame's 8-bit output and its passes; `setting` starts auto-exposure there, else (on a
        first frame) it converges on the view."""
        start = time.perf_counter()
        clock, pipeline = self.clock, self.pipeline
        if setting is not None:
            pipeline.setting = setting
        state = pipeline.state_for(index)
        with clock("render"):
            passes = self.drawer.frame(index, state).passes
        if setting is None and not self.walls_s and self.camera.exposure_mode == "auto":
            pipeline.converge_exposure(state, passes)
            state = pipeline.state_for(index)
            with clock("render"):
                passes = self.drawer.frame(index, state).passes
        rgb8 = pipeline.process(state, passes, rng=frame_rng(self.job.seed, 0, index)).rgb8
        clock.end_frame()
        self.walls_s.append(time.perf_counter() - start)
        return rgb8, state, passes

    def timed_ms(self) -> tuple[float, dict[str, float]]:
        """Mean wall ms per frame and stage ms per frame, the first (warm-up) frame left out."""
        timed = max(len(self.walls_s) - 1, 1)
        stage_ms = {k: 1e3 * v / timed for k, v in stage_sums(self.clock.frames[1:]).items()}
        return 1e3 * sum(self.walls_s[1:]) / timed, stage_ms


def _isp_state(isp) -> dict | None:
    """A copy of the ISP's adapting state (white balance, stretch limits), to restore it."""
    if isp is None:
        return None
    return {key: copy.deepcopy(value) for key, value in vars(isp).items() if key != "executor"}


def measure(path: Path, frames: int = FRAMES, size: tuple[int, int] = STREAM_SIZE_PX) -> SkipResult:
    """Planned and forced frames interleaved, so that both see the same load on the machine."""
    from camgen.bench.render_cases import _renderer

    loaded = load_scene(path)
    variant = at_output_size(one_camera(loaded, loaded.scene.cameras[0].name), *size)
    planned_job = compile_scene(variant, PlanSettings())
    forced_job = compile_scene(variant, PlanSettings(force_all_stages=True))
    indices = spread_frames(planned_job.frame_count, frames)
    indices += indices[-1:] * (frames - len(indices))  # a short sequence repeats its last frame
    resolve = path.parent.joinpath
    with ThreadPoolExecutor(2) as executor:
        planned = _Camera(planned_job, _renderer(), resolve, executor)
        forced = _Camera(forced_job, _renderer(), resolve, executor)
        try:
            for n, index in enumerate(indices):
                last = n == len(indices) - 1
                if last:  # the noise draw below must see the ISP as it was before this frame
                    isp_before = _isp_state(planned.pipeline.isp)
                a, state, passes = planned.frame(index)
                settled = ExposureSetting(state.exposure_time_s, state.gain_db)
                b, _, _ = forced.frame(index, settled if n == 0 else None)
                forced.pipeline.setting = planned.pipeline.setting  # the same next exposure
            if isp_before is not None:
                vars(planned.pipeline.isp).update(isp_before)
            c = planned.pipeline.process(state, passes, rng=frame_rng(planned_job.seed + 1, 0, indices[-1])).rgb8
        finally:
            planned.drawer.close()
            forced.drawer.close()
    planned_ms, planned_stages = planned.timed_ms()
    forced_ms, forced_stages = forced.timed_ms()
    a, b, c = (x.astype(np.float64) for x in (a, b, c))
    planned_names = {s.name for s in planned_job.cameras[0].stages}
    return SkipResult(
        scene=path.stem,
        camera=planned_job.cameras[0].name,
        skipped=tuple(s.name for s in forced_job.cameras[0].stages if s.name not in planned_names),
        planned_ms=planned_ms,
        forced_ms=forced_ms,
        planned_stage_ms=planned_stages,
        forced_stage_ms=forced_stages,
        difference_codes=float(np.sqrt(np.mean((a - b) ** 2))),
        noise_codes=float(np.sqrt(np.mean((a - c) ** 2) / 2)),
    )


def skip_cases(repo: Path, records: dict[str, SkipResult]) -> list[Case]:
    cases = []
    for path in sorted((repo / "scenes").glob("*.yaml")):
        name = f"skipping {path.stem}: planned vs every stage forced on"

        def run(path=path, name=name) -> None:
            records[name] = measure(path)

        cases.append(Case(name=name, run=run, repeats=1, warmup=0))
    return cases
