"""Closed-loop cases: one `Simulation.step` of the parking lot's PTZ dome (scenes/ptz_follow.yaml) read
out at 1280×720 with the full camera model (lens, sensor with auto-exposure, ISP), the head turning
under a ContinuousMove (so its frames carry motion blur, as a tracking head's do), held, and turning
with the ground truth asked for; then held and turning again without supersampling (`PlanSettings`'
supersampling 1: one radiance sample a pixel, the option a closed loop that wants speed takes; the
tradeoffs section measures what it costs in error). A case's time is one step: the head's control
steps, the state, the draw, the camera model and, where asked, the annotation of one frame."""

from __future__ import annotations

from pathlib import Path

from camgen.bench.harness import Case

STEP_SIZE_PX = (1280, 720)
CAMERA = "pole_ptz"
PAN = -0.05
"""ContinuousMove pan velocity: 5 % of the dome's 240°/s, 12°/s, a walker's angular speed at ~7 m."""
REPEATS = 10


def sim_cases(repo: Path, stage_frames: dict[str, list[dict[str, float]]], facts: dict | None = None) -> list[Case]:
    """The cases; after each runs, `stage_frames[name]` holds the per-stage wall time of its timed steps
    and `facts` the dome's render size (with its margin) and supersampling."""
    from camgen.plan import PlanSettings
    from camgen.render.renderer import Renderer
    from camgen.sim import ContinuousMove, Simulation

    scene = repo / "scenes" / "ptz_follow.yaml"
    renderer = Renderer()
    size = f"{STEP_SIZE_PX[0]}×{STEP_SIZE_PX[1]}"
    turning = {CAMERA: ContinuousMove(pan=PAN)}
    variants = {
        f"sim step {size} PTZ, head turning": (False, turning, None),
        f"sim step {size} PTZ, head held": (False, {}, None),
        f"sim step {size} PTZ, head turning, ground truth": (True, turning, None),
        f"sim step {size} PTZ, head turning, supersampling 1": (False, turning, 1),
        f"sim step {size} PTZ, head held, supersampling 1": (False, {}, 1),
    }
    cases = []
    for name, (ground_truth, commands, supersampling) in variants.items():
        state: dict = {}
        settings = None if supersampling is None else PlanSettings(supersampling=supersampling)

        def setup(name=name, ground_truth=ground_truth, commands=commands, state=state, settings=settings) -> None:
            sim = Simulation(
                scene, ground_truth=ground_truth, resolution_px=STEP_SIZE_PX, renderer=renderer, settings=settings
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
            sim.step(commands)
            # The warm-up step counts as timed here; the harness times REPEATS after it.
            stage_frames[name] = sim.stage_seconds(CAMERA)[state["first"] + 1 :]
            return None

        cases.append(Case(name, run, setup=setup, repeats=REPEATS))
    return cases
