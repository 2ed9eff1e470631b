"""The closed-loop examples scored (issue 21): each controller under ``examples/`` run through
`camgen.sim` over a whole example scene at a small readout (`SIZE_PX`), and scored by
`camgen.sim.metrics` from the ground truth.

- The scene's own follow-target program (`camgen.motion.programs.Follow`, examples/sim_follow_program.py)
  on scenes/ptz_follow.yaml: the controller camgen had before the stepping API, on ground-truth world
  positions, its goals sent as AbsoluteMove: the baseline.
- examples/sim_follow.py's controller on the same walk with the ground-truth box (a perfect detector),
  then with its CamShift colour tracker on the delivered frames: both use only the documented API, and
  the first is the issue's acceptance run (the walker in frame ≥ `IN_FRAME_GOAL` of the time).
- The first one's command log replayed (`camgen.sim.replay`) through the scene's profile (the same frames,
  checked by hash) and through `OTHER_PROFILE`, scored side by side.
- examples/sim_handoff.py on scenes/plaza.yaml: the fixed facade bullet cues the pole PTZ dome onto a
  walker; the hand-off's latency, and the network's gaps and hand-offs (`network_metrics`).

A case is one whole run (timed once, for information: nothing here depends on the time). The examples'
controllers are imported from their files (`load_example`), not copied.
"""

from __future__ import annotations

import hashlib
import importlib.util
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

from camgen.bench.harness import Case

if TYPE_CHECKING:
    from camgen.sim.metrics import ControlScores, NetworkScores

SIZE_PX = (160, 90)
"""Readout of every camera (binned: each profile's field of view and per-pixel signal kept)."""
FOLLOW_SCENE, FOLLOW_CAMERA, FOLLOW_TARGET = "ptz_follow", "pole_ptz", "walker_1"
OTHER_PROFILE = "ptz_2mp_20x"
"""The other PTZ profile the recorded log is replayed through (the scene's dome is ptz_2mp_30x)."""
HANDOFF_SCENE, HANDOFF_OVERVIEW, HANDOFF_PTZ, HANDOFF_TARGET = "plaza", "facade_bullet", "pole_ptz", "walker_03"
IN_FRAME_GOAL = 0.9
"""Issue 21's acceptance: a controller on the documented API keeps the walker in frame ≥ 90 % of the time."""


def load_example(repo: Path, name: str) -> ModuleType:
    """examples/`name`.py as a module (registered in `sys.modules`, as its dataclasses need)."""
    path = repo / "examples" / f"{name}.py"
    module_name = f"camgen_example_{name}"
    if module_name in sys.modules:
        return sys.modules[module_name]
    spec = importlib.util.spec_from_file_location(module_name, path)
    if spec is None or not path.is_file():
        raise FileNotFoundError(f"{path}: no such example (the bench runs from a checkout of camgen)")
    module = importlib.util.module_from_spec(spec)
    sys.modules[module_name] = module
    spec.loader.exec_module(module)
    return module


class Recording:
    """A `camgen.sim.Simulation` that keeps every `Observations` its `reset` and `step` return (in
    `observed`), for scoring a controller that returns less; everything else is the simulation's."""

    def __init__(self, sim):
        self._sim = sim
        self.observed: list = []

    def reset(self, seed=None):
        self.observed = [self._sim.reset(seed)]
        return self.observed[0]

    def step(self, commands=None):
        self.observed.append(self._sim.step(commands))
        return self.observed[-1]

    def __getattr__(self, name: str):
        return getattr(self._sim, name)


def frame_hashes(observed, camera: str) -> list[str]:
    """sha256 of each delivered frame of `camera` (to compare a replay with its run byte for byte)."""
    return [hashlib.sha256(o[camera].rgb8.tobytes()).hexdigest() for o in observed]


@dataclass(frozen=True)
class ControlRow:
    """One controller's run scored (`camgen.sim.metrics.ControlScores`) and what it saw."""

    controller: str
    sees: str
    scores: ControlScores
    seconds: float = math.nan
    note: str = ""


@dataclass(frozen=True)
class HandoffRow:
    overview: str
    ptz: str
    target: str
    cue_frame: int | None
    hold_frame: int | None
    latency_s: float
    dome: ControlScores | None
    """The dome's scores from the hand-off on (None: it never took the target)."""
    network: NetworkScores
    """The target over both cameras."""
    gap_frames: int
    """Frames after the first cue that neither camera held the target (the example's count)."""
    overview_held_frames: int
    """Frames the overview itself held the target (its box ≥ the hold height)."""
    fps: float
    hold_height_frac: float
    seconds: float = math.nan


@dataclass
class SimExampleFacts:
    """What the cases leave for the section's text."""

    follow: dict[str, ControlRow] = field(default_factory=dict)
    replays: dict[str, ControlRow] = field(default_factory=dict)
    replay_same_frames: bool | None = None
    handoff: HandoffRow | None = None
    frames: int = 0
    scene_profile: str = ""
    """The follow scene's PTZ profile."""


def held_targets(observed, cameras, target: str, min_height_frac: float) -> list[dict[str, set[str]]]:
    """Per frame, camera → {target} where the target's visible box is at least `min_height_frac` of that
    camera's frame high (as `network_metrics` takes it)."""
    held = []
    for frame in observed:
        now = {}
        for camera in cameras:
            view = frame[camera]
            obj = next((o for o in view.ground_truth.objects if o.name == target), None)
            box = None if obj is None else obj.visible_box
            tall = box is not None and box[3] - box[1] >= min_height_frac * view.rgb8.shape[0]
            now[camera] = {target} if tall else set()
        held.append(now)
    return held


def sim_example_cases(repo: Path, facts: SimExampleFacts) -> list[Case]:
    """The runs, in order (the replays take the truth run's log); each fills `facts`."""
    import time

    from camgen.render.renderer import Renderer
    from camgen.sim import Simulation, command_log, replay
    from camgen.sim.metrics import control_metrics, network_metrics, target_boxes

    follow_scene = repo / "scenes" / f"{FOLLOW_SCENE}.yaml"
    handoff_scene = repo / "scenes" / f"{HANDOFF_SCENE}.yaml"
    program_example = load_example(repo, "sim_follow_program")
    follow_example = load_example(repo, "sim_follow")
    handoff_example = load_example(repo, "sim_handoff")
    shared: dict = {}

    def renderer() -> Renderer:
        if "renderer" not in shared:
            shared["renderer"] = Renderer()
        return shared["renderer"]

    def scored(observed, camera: str, target: str, fps: float):
        boxes, heights_m = target_boxes(observed, camera, target)
        return control_metrics(boxes, SIZE_PX, fps, heights_m)

    def program_run() -> None:
        start = time.perf_counter()
        with Simulation(follow_scene, ground_truth=True, resolution_px=SIZE_PX, renderer=renderer()) as sim:
            target, observed = program_example.follow(sim, FOLLOW_CAMERA, FOLLOW_TARGET, sim.frame_count - 1)
            fps = sim.fps
            facts.scene_profile = sim.loaded.profile_names[FOLLOW_CAMERA]
        facts.frames = len(observed)
        facts.follow["program"] = ControlRow(
            "the scene's follow program (`camgen.motion.programs.Follow`), examples/sim_follow_program.py",
            "the target's world position (ground truth), 0.2 s late",
            scored(observed, FOLLOW_CAMERA, target, fps),
            time.perf_counter() - start,
        )

    def sim_follow_run(tracker: str) -> None:
        start = time.perf_counter()
        with Simulation(
            follow_scene, ground_truth=True, resolution_px=SIZE_PX, renderer=renderer(), cameras=[FOLLOW_CAMERA]
        ) as sim:
            recording = Recording(sim)
            truth, tracked = follow_example.follow(
                recording,
                FOLLOW_CAMERA,
                FOLLOW_TARGET,
                tracker,
                sim.frame_count - 1,
                follow_example.LEAD_S,
                follow_example.HEIGHT_FRAC,
                None,
            )
            fps = sim.fps
            if tracker == "truth":
                shared["log"], shared["fps"] = command_log(sim), fps
                shared["hashes"] = frame_hashes(recording.observed, FOLLOW_CAMERA)
        no_window = sum(1 for t, b in zip(truth, tracked, strict=True) if t is not None and b is None)
        sees = (
            "the target's box in each delivered frame (ground truth)"
            if tracker == "truth"
            else "CamShift on the delivered 8-bit frames (started from the first ground-truth box)"
        )
        facts.follow[tracker] = ControlRow(
            f"examples/sim_follow.py --tracker {tracker}",
            sees,
            scored(recording.observed, FOLLOW_CAMERA, FOLLOW_TARGET, fps),
            time.perf_counter() - start,
            "" if tracker == "truth" else f"no window on {no_window} frame(s) with the walker in frame",
        )

    def replay_run(profile: str | None) -> None:
        if "log" not in shared:
            raise RuntimeError("the truth run's log is missing: its case must run first")
        start = time.perf_counter()
        profiles = None if profile is None else {FOLLOW_CAMERA: profile}
        observed = list(replay(shared["log"], follow_scene, profiles=profiles, ground_truth=True, renderer=renderer()))
        fps = shared["fps"]
        if profile is None:
            facts.replay_same_frames = frame_hashes(observed, FOLLOW_CAMERA) == shared["hashes"]
        name = profile or facts.scene_profile
        facts.replays[name] = ControlRow(
            name,
            "the scene's profile" if profile is None else "another PTZ profile under profiles/",
            scored(observed, FOLLOW_CAMERA, FOLLOW_TARGET, fps),
            time.perf_counter() - start,
        )

    def handoff_run() -> None:
        start = time.perf_counter()
        try:
            with Simulation(handoff_scene, ground_truth=True, resolution_px=SIZE_PX, renderer=renderer()) as sim:
                recording = Recording(sim)
                result = handoff_example.run(recording, HANDOFF_OVERVIEW, HANDOFF_PTZ, HANDOFF_TARGET, None)
                fps = sim.fps
        finally:
            shared.pop("renderer").close()
        observed = recording.observed
        cue, hold = result["cue_frame"], result["hold_frame"]
        after = observed[hold:] if hold is not None else []
        held = held_targets(observed, (HANDOFF_OVERVIEW, HANDOFF_PTZ), HANDOFF_TARGET, handoff_example.HOLD_HEIGHT_FRAC)
        (network,) = network_metrics(held, [HANDOFF_TARGET], fps)
        facts.handoff = HandoffRow(
            HANDOFF_OVERVIEW,
            HANDOFF_PTZ,
            HANDOFF_TARGET,
            cue,
            hold,
            (hold - cue) / fps if cue is not None and hold is not None else math.nan,
            scored(after, HANDOFF_PTZ, HANDOFF_TARGET, fps) if after else None,
            network,
            result["gap_frames"],
            sum(1 for frame in held if frame[HANDOFF_OVERVIEW]),
            fps,
            handoff_example.HOLD_HEIGHT_FRAC,
            time.perf_counter() - start,
        )

    size = f"{SIZE_PX[0]}×{SIZE_PX[1]}"
    runs = {
        f"{FOLLOW_SCENE}: the follow program through camgen.sim, {size}": program_run,
        f"{FOLLOW_SCENE}: sim_follow.py, truth boxes, {size}": lambda: sim_follow_run("truth"),
        f"{FOLLOW_SCENE}: sim_follow.py, CamShift, {size}": lambda: sim_follow_run("camshift"),
        f"{FOLLOW_SCENE}: the truth run's log replayed, its profile": lambda: replay_run(None),
        f"{FOLLOW_SCENE}: the truth run's log replayed, {OTHER_PROFILE}": lambda: replay_run(OTHER_PROFILE),
        f"{HANDOFF_SCENE}: sim_handoff.py, {size}": handoff_run,
    }
    return [Case(name, run, repeats=1, warmup=0) for name, run in runs.items()]


def percent(value: float | None) -> str:
    return "—" if value is None or math.isnan(value) else f"{100 * value:.1f} %"


def _num(value: float, digits: int, unit: str = "") -> str:
    return "—" if value is None or math.isnan(value) else f"{value:.{digits}f}{unit}"


def control_table(rows, first_header: str, last_header: str | None = None, last=None) -> str:
    """A markdown table of `ControlRow`s: in frame, centring error, height, px/m, losses, reacquire."""
    head = (
        f"| {first_header} | in frame | centring error px (of the half-diagonal) | height / frame | px/m "
        "| losses | reacquire s |" + (f" {last_header} |" if last_header else "")
    )
    lines = [head, "|---|" + "---:|" * 6 + ("---|" if last_header else "")]
    for row in rows:
        s = row.scores
        cells = [
            row.controller,
            percent(s.in_frame_frac),
            f"{_num(s.centring_error_px, 1)} ({_num(s.centring_error_frac, 3)})",
            _num(s.height_frac, 3),
            _num(s.resolution_px_per_m, 1),
            str(s.losses),
            _num(s.reacquire_s, 2),
        ]
        if last_header:
            cells.append(last(row))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def acceptance_text(row: ControlRow | None, goal: float = IN_FRAME_GOAL) -> str:
    """The issue's in-frame acceptance for `row`, with PASS or FAIL."""
    if row is None:
        return "**FAIL**: the acceptance run did not run."
    frac = row.scores.in_frame_frac
    verdict = "PASS" if frac >= goal else "FAIL"
    return (
        f"Acceptance (issue 21: a controller written only against the documented API keeps the walker in frame "
        f"≥ {100 * goal:.0f} % of the time): {row.controller} kept it in frame {percent(frac)} of {row.scores.frames} "
        f"frames: **{verdict}**."
    )


def section_text(facts: SimExampleFacts, run_s: dict[str, float], load_average: float) -> str:
    """BENCHMARKS.md's text of the section from the runs' `facts` (`run_s`: each run's wall time, s, for
    information; `load_average`: the machine's when it ended)."""
    size = f"{SIZE_PX[0]}×{SIZE_PX[1]}"
    text = [
        "**Closed-loop examples** (`camgen.bench.sim_example_cases`, issue 21): each controller under "
        f"`examples/` drives `camgen.sim` over a whole example scene read out at {size} (binned: each "
        "profile's field of view and per-pixel signal kept), seed 0, and is scored from the ground truth by "
        "`camgen.sim.metrics` (`control_metrics`: frames with the target in frame, the mean centring error of "
        "its visible box, its height in the frame and in px/m, losses and time to reacquire; "
        "`network_metrics`: hand-offs and gaps). The controllers are imported from the examples' files.",
        f"**Following {FOLLOW_TARGET} in scenes/{FOLLOW_SCENE}.yaml** ({FOLLOW_CAMERA}, {facts.scene_profile}, "
        f"{facts.frames} frames at 25 fps). The baseline is the follow-target program camgen had before the "
        "stepping API (`camgen.motion.programs.Follow`, the scene's own `program: {type: follow}`) asked each "
        "frame with the head's status, its goal sent as ONVIF AbsoluteMove: it sees the target's ground-truth "
        "world position, as in a programmed render, but loses its goal's feed-forward rate (AbsoluteMove has "
        "none) and waits the head's command latency. `examples/sim_follow.py` uses only the documented API.",
        control_table(
            list(facts.follow.values()),
            "controller",
            "sees",
            lambda row: "; ".join(filter(None, (row.sees, row.note))),
        ),
        acceptance_text(facts.follow.get("truth")),
    ]
    camshift = facts.follow.get("camshift")
    if camshift is not None:
        s = camshift.scores
        text.append(
            f"The CamShift tracker's mean centring error: {s.centring_error_px:.1f} px, "
            f"{s.centring_error_frac:.3f} of the half-diagonal ({camshift.note})."
        )
    if facts.replays:
        same = {True: "yes (sha256 of every frame)", False: "**no**", None: "not checked"}[facts.replay_same_frames]
        text += [
            "**The truth run's command log replayed** (`camgen.sim.replay`, open loop: the same AbsoluteMove "
            f"goals) through the scene's profile and through {OTHER_PROFILE}, side by side. Through the scene's "
            f"profile the frames are the run's: {same}.",
            control_table(list(facts.replays.values()), "profile", "replayed through", lambda row: row.sees),
        ]
    handoff = facts.handoff
    if handoff is not None:
        network = handoff.network
        handoffs = network.handoffs
        dome = handoff.dome
        gaps = "no gap" if network.gaps == 0 else f"{network.gaps} gaps, mean {network.mean_gap_s:.2f} s"
        rows = [
            "| overview → dome | first cue (frame) | dome holds (frame) | hand-off latency s | frames neither "
            "held it after the cue | frames the overview held it | hand-offs (gap s) | held by some camera "
            "after the first hold | dome after the hand-off: in frame | centring error px (of the "
            "half-diagonal) | px/m |",
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
            f"| {handoff.overview} → {handoff.ptz} | {handoff.cue_frame} | {handoff.hold_frame} "
            f"| {handoff.latency_s:.2f} | {handoff.gap_frames} | {handoff.overview_held_frames} "
            f"| {', '.join(f'{h.from_cameras[0]} → {h.to_camera} ({h.gap_s:.2f})' for h in handoffs) or 'none'} "
            f"| {percent(network.held_frac)} ({gaps}) "
            + (
                "| — | — | — |"
                if dome is None
                else f"| {percent(dome.in_frame_frac)} of {dome.frames} | {dome.centring_error_px:.1f} "
                f"({dome.centring_error_frac:.3f}) | {dome.resolution_px_per_m:.1f} |"
            ),
        ]
        text += [
            f"**Hand-off** (`examples/sim_handoff.py`, scenes/{HANDOFF_SCENE}.yaml, {handoff.target}): the fixed "
            f"{handoff.overview} sees the walker (ground-truth box: a perfect detector) and cues "
            f"{handoff.ptz} through the ground point under its feet; a camera holds the walker once its box "
            f"is ≥ {100 * handoff.hold_height_frac:.0f} % of the frame high (DORI observe at 1080 lines). "
            "Hand-off latency: from the first cue to "
            "the dome holding it. `network_metrics` counts a hand-off where a camera takes over a target "
            "another held (the gap: the time between; 0 where both held it at once), and the share of frames "
            "some camera held it from the first hold on.",
            "\n".join(rows),
        ]
    runs = "; ".join(f"{name}: {seconds:.0f} s" for name, seconds in run_s.items())
    text.append(
        f"Each run once, for information (load average {load_average:.1f} on the 2 cores when it ended): {runs}."
    )
    return "\n\n".join(text)
