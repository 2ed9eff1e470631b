"""The closed-loop examples' bench section (`camgen.bench.sim_example_cases`): the examples load from their
files, a recording keeps what the simulation returned, holds and hand-offs are counted from the boxes, and
the text flags the issue's in-frame acceptance."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from camgen.bench.sim_example_cases import (
    ControlRow,
    HandoffRow,
    Recording,
    SimExampleFacts,
    acceptance_text,
    held_targets,
    load_example,
    section_text,
)
from camgen.sim.metrics import control_metrics, network_metrics
from tests.conftest import REPO


def test_the_examples_load_from_their_files_once():
    module = load_example(REPO, "sim_follow")
    assert callable(module.follow) and module.LEAD_S > 0
    assert load_example(REPO, "sim_follow") is module
    with pytest.raises(FileNotFoundError, match=r"no_such_example\.py: no such example"):
        load_example(REPO, "no_such_example")


def test_the_section_is_listed_after_the_step_timings():
    from camgen.bench.sections import sections

    keys = [section.key for section in sections(REPO)]
    assert keys.index("sim_examples") == keys.index("sim") + 1


class _FakeSim:
    frame_count = 3

    def __init__(self):
        self.frame = -1

    def reset(self, seed=None):
        self.frame = 0
        return ("reset", seed)

    def step(self, commands=None):
        self.frame += 1
        return ("step", self.frame, commands)


def test_a_recording_keeps_every_observation_and_passes_the_rest_through():
    recording = Recording(_FakeSim())
    assert recording.reset(7) == ("reset", 7)
    recording.step({"dome": "a"})
    recording.step()
    assert recording.observed == [("reset", 7), ("step", 1, {"dome": "a"}), ("step", 2, None)]
    assert recording.frame_count == 3 and recording.frame == 2
    recording.reset(0)
    assert recording.observed == [("reset", 0)]


def _frame(boxes_by_camera, height_px=90):
    """An Observations-like frame: camera → a view whose ground truth has `walker` at the given box."""
    cameras = {}
    for camera, box in boxes_by_camera.items():
        objects = [] if box is None else [SimpleNamespace(name="walker", visible_box=box)]
        cameras[camera] = SimpleNamespace(
            ground_truth=SimpleNamespace(objects=objects), rgb8=SimpleNamespace(shape=(height_px, 160, 3))
        )
    return cameras


def test_a_camera_holds_the_target_from_the_hold_height_and_the_dome_takes_it_over():
    small, tall = (10, 40, 14, 48), (70, 20, 90, 60)  # 8 and 40 px high in a 90 px frame
    frames = [
        _frame({"wide": small, "dome": None}),  # seen, too small to hold: cue only
        _frame({"wide": (10, 30, 20, 39.5), "dome": None}),  # 9.5 px ≥ 9: held
        _frame({"wide": (10, 30, 20, 39.5), "dome": tall}),  # both: the dome takes it over, gap 0
        _frame({"wide": small, "dome": None}),  # neither
        _frame({"wide": None, "dome": tall}),  # the dome again: a reacquisition, not a hand-off
    ]
    held = held_targets(frames, ("wide", "dome"), "walker", 0.1)
    assert held == [
        {"wide": set(), "dome": set()},
        {"wide": {"walker"}, "dome": set()},
        {"wide": {"walker"}, "dome": {"walker"}},
        {"wide": set(), "dome": set()},
        {"wide": set(), "dome": {"walker"}},
    ]
    (scores,) = network_metrics(held, ["walker"], fps=25.0)
    assert [(h.frame, h.from_cameras, h.to_camera, h.gap_s) for h in scores.handoffs] == [(2, ("wide",), "dome", 0.0)]
    assert scores.gaps == 1 and scores.held_frac == pytest.approx(3 / 4)


def _row(in_frame: int, frames: int = 10, name: str = "examples/sim_follow.py --tracker truth") -> ControlRow:
    boxes = [(70.0, 35.0, 90.0, 55.0)] * in_frame + [None] * (frames - in_frame)
    return ControlRow(name, "boxes", control_metrics(boxes, (160, 90), 25.0))


def test_the_acceptance_passes_from_ninety_percent_in_frame_and_fails_below():
    assert acceptance_text(_row(9)).endswith("kept it in frame 90.0 % of 10 frames: **PASS**.")
    assert acceptance_text(_row(89, 100)).endswith("kept it in frame 89.0 % of 100 frames: **FAIL**.")
    assert "**FAIL**" in acceptance_text(None)


def test_the_text_has_each_table_and_no_nan():
    facts = SimExampleFacts(frames=10, scene_profile="ptz_2mp_30x", replay_same_frames=True)
    facts.follow = {"truth": _row(10), "camshift": _row(4)}
    facts.replays = {name: _row(n, name=name) for name, n in (("ptz_2mp_30x", 10), ("ptz_2mp_20x", 9))}
    network = network_metrics(
        [{"wide": {"walker"}, "dome": set()}, {"wide": set(), "dome": {"walker"}}], ["walker"], 25
    )
    facts.handoff = HandoffRow(
        "wide",
        "dome",
        "walker",
        0,
        1,
        0.04,
        None,
        network[0],
        gap_frames=0,
        overview_held_frames=1,
        fps=25.0,
        hold_height_frac=0.1,
    )
    text = section_text(facts, {"run": 61.2}, 1.5)
    assert "nan" not in text.lower()
    assert "kept it in frame 100.0 % of 10 frames: **PASS**" in text
    assert "the frames are the run's: yes" in text
    assert "| wide → dome | 0 | 1 | 0.04 | 0 | 1 | wide → dome (0.00) | 100.0 % (no gap) | — | — | — |" in text
    assert "| ptz_2mp_20x | 90.0 % | 0.0 (0.000) | 0.222 | — | 1 | — | boxes |" in text
    assert math.isnan(facts.follow["truth"].scores.reacquire_s) and "| 0 | — |" in text
    assert "run: 61 s" in text
    assert "|---|---:|---:|---:|---:|---:|---:|---|" in text  # the last column is text
