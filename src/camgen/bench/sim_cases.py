"""Closed-loop cases: one `Simulation.step` of the parking lot's PTZ dome (scenes/ptz_follow.yaml) read
out at 1280×720 with the full camera model (lens, sensor with auto-exposure, ISP), the head turning
under a ContinuousMove (so its frames carry motion blur, as a tracking head's do) with its frames drawn
from a turn canvas (`Simulation`'s ``turns_reprojected``, its default at this size) and with every frame drawn whole,
held, and turning with the ground truth asked for; then held and turning again without supersampling
(`PlanSettings`' supersampling 1: one radiance sample a pixel, the option a closed loop that wants speed
takes; the tradeoffs section measures what it costs in error). A case's time is one step: the head's
control steps, the state, the draw, the camera model and, where asked, the annotation of one frame. The
turning cases run more steps, so that their mean spans the canvas's redraws (about one in 18 steps)."""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from camgen.bench.harness import Case

STEP_SIZE_PX = (1280, 720)
CAMERA = "pole_ptz"
PAN = -0.05
"""ContinuousMove pan velocity: 5 % of the dome's 240°/s, 12°/s, a walker's angular speed at ~7 m."""
REPEATS = 10
TURNING_REPEATS = 36
"""Timed steps of a turning case: two canvases' worth at least, so that the mean counts their redraws."""


def sim_cases(
    repo: Path,
    stage_frames: dict[str, list[dict[str, float]]],
    facts: dict | None = None,
    steps: dict[str, dict[str, list]] | None = None,
) -> list[Case]:
    """The cases; after each runs, `stage_frames[name]` holds the per-stage wall time of its timed steps,
    `facts` the dome's render size (with its margin) and supersampling, and `steps[name]` each timed step's
    wall time, s ("seconds") and delivered frame ("frames", the turning cases')."""
    from camgen.plan import PlanSettings
    from camgen.render.renderer import Renderer
    from camgen.sim import ContinuousMove, Simulation

    scene = repo / "scenes" / "ptz_follow.yaml"
    renderer = Renderer()
    size = f"{STEP_SIZE_PX[0]}×{STEP_SIZE_PX[1]}"
    turning = {CAMERA: ContinuousMove(pan=PAN)}
    whole = f"sim step {size} PTZ, head turning, every frame drawn whole"
    whole_1 = f"sim step {size} PTZ, head turning, supersampling 1, every frame drawn whole"
    variants = {  # ground truth, commands, supersampling, turn canvas, the case compared with
        f"sim step {size} PTZ, head turning": (False, turning, None, True, whole),
        whole: (False, turning, None, False, None),
        f"sim step {size} PTZ, head held": (False, {}, None, True, None),
        f"sim step {size} PTZ, head turning, ground truth": (True, turning, None, True, None),
        f"sim step {size} PTZ, head turning, supersampling 1": (False, turning, 1, True, whole_1),
        whole_1: (False, turning, 1, False, None),
        f"sim step {size} PTZ, head held, supersampling 1": (False, {}, 1, True, None),
    }
    cases = []
    for name, (ground_truth, commands, supersampling, reprojected, baseline) in variants.items():
        state: dict = {}
        settings = None if supersampling is None else PlanSettings(supersampling=supersampling)

        def setup(
            name=name,
            ground_truth=ground_truth,
            commands=commands,
            state=state,
            settings=settings,
            reprojected=reprojected,
        ) -> None:
            sim = Simulation(
                scene,
                ground_truth=ground_truth,
                resolution_px=STEP_SIZE_PX,
                renderer=renderer,
                settings=settings,
                turns_reprojected=reprojected,
            )
            sim.reset(0)
            sim.step(commands)  # the head starts turning after the command latency
            sim.step(commands)
            sim.step(commands)
            state["sim"], state["first"] = sim, len(sim.stage_seconds(CAMERA))
            if facts is not None and settings is None:
                render = sim.camera_job(CAMERA).render
                facts.update(width_px=render.width_px, height_px=render.height_px, supersampling=render.supersampling)

        def run(name=name, commands=commands, state=state) -> None:
            sim = state["sim"]
            if sim.frame + 1 >= sim.frame_count:
                raise RuntimeError(f"{name}: the scene ended; use fewer repeats")
            start = time.perf_counter()
            observed = sim.step(commands)
            # The warm-up step counts as timed here; the harness times the repeats after it.
            stage_frames[name] = sim.stage_seconds(CAMERA)[state["first"] + 1 :]
            if steps is not None:
                record = steps.setdefault(name, {"seconds": [], "frames": []})
                record["seconds"].append(time.perf_counter() - start)
                if commands:
                    record["frames"].append(observed.cameras[CAMERA].rgb8)
            return None

        repeats = TURNING_REPEATS if commands else REPEATS
        cases.append(Case(name, run, setup=setup, repeats=repeats, baseline=baseline))
    return cases


def psnr_db(image: np.ndarray, reference: np.ndarray) -> float:
    """Peak signal-to-noise ratio of an 8-bit frame against another, dB (inf where they are equal)."""
    mse = float(np.mean((image.astype(np.float64) - reference.astype(np.float64)) ** 2))
    return math.inf if mse == 0.0 else 10.0 * math.log10(255.0**2 / mse)
