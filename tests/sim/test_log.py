"""Command logs: a controlled episode saved and replayed gives the same frames byte for byte (API and
`camgen sim replay`), a replay through another profile renders other frames with its metrics, and
`camgen evaluate` scores the replay's ground truth against itself as perfect."""

from __future__ import annotations

import dataclasses
import json
import re

import cv2
import numpy as np
import pytest

from camgen.cli.main import main
from camgen.errors import ConfigError
from camgen.sim import AbsoluteMove, ContinuousMove, GotoPreset, SetPreset, Simulation
from camgen.sim.log import command_log, load_command_log, replay, save_command_log
from tests.conftest import write
from tests.sim.scenes import FIXED_PROFILE, PTZ_PROFILE, write_world

pytestmark = pytest.mark.opengl

RESOLUTION_PX = (80, 60)
STEPS = 6


@pytest.fixture(scope="module")
def episode(tmp_path_factory, renderer):
    """A controlled episode: pan towards the walker's ground-truth box, store and recall a preset."""
    directory = tmp_path_factory.mktemp("log_world")
    world = write_world(directory, duration_s=0.8, start_x_m=-1.0, speed_m_s=2.0)
    frames = []
    with Simulation(world, ground_truth=True, resolution_px=RESOLUTION_PX, renderer=renderer) as sim:
        observed = sim.reset(seed=9)
        frames.append({name: camera.rgb8 for name, camera in observed.cameras.items()})
        for k in range(STEPS):
            box = next(o.visible_box for o in observed["dome"].ground_truth.objects if o.name == "walker")
            error_x = ((box[0] + box[2]) / 2 - RESOLUTION_PX[0] / 2) / (RESOLUTION_PX[0] / 2)
            commands = [ContinuousMove(pan=float(np.clip(-0.5 * error_x, -1, 1)), zoom=0.3)]
            if k == 2:
                commands = [SetPreset("here"), AbsoluteMove(tilt_deg=-10.0, speed=0.5)]
            if k == 4:
                commands = [GotoPreset("here")]
            observed = sim.step({"dome": commands})
            frames.append({name: camera.rgb8 for name, camera in observed.cameras.items()})
        log = command_log(sim)
    path = save_command_log(log, directory / "episode.jsonl")
    return world, path, log, frames


def test_the_log_records_every_command_with_its_frame_and_time(episode):
    _, path, log, _ = episode
    assert (log.seed, log.steps, log.resolution_px) == (9, STEPS, RESOLUTION_PX)
    assert [entry.frame for entry in log.commands] == [0, 1, 2, 2, 3, 4, 5]
    assert [entry.time_s for entry in log.commands] == pytest.approx([0, 0.1, 0.2, 0.2, 0.3, 0.4, 0.5])
    lines = path.read_text().splitlines()
    assert json.loads(lines[0])["format"] == "camgen-command-log" and len(lines) == 1 + len(log.commands)
    assert load_command_log(path) == log  # floats survive the text exactly


def test_the_log_says_how_turned_frames_were_drawn(episode, tmp_path):
    """A run that drew every turned frame whole says so, and its replay does the same; a log written before the key
    was drawn so too (every turned frame whole) and is replayed so."""
    _, path, log, _ = episode
    assert log.turns_reprojected is None  # by the readout's size (80×60 draws whole), written "auto"
    assert json.loads(path.read_text().splitlines()[0])["turns_reprojected"] == "auto"
    assert load_command_log(path).turns_reprojected is None
    whole = save_command_log(dataclasses.replace(log, turns_reprojected=False), tmp_path / "whole.jsonl")
    assert load_command_log(whole).turns_reprojected is False
    records = path.read_text().splitlines()
    header = json.loads(records[0])
    del header["turns_reprojected"]
    old = write(tmp_path, "old.jsonl", "\n".join([json.dumps(header), *records[1:]]) + "\n")
    assert load_command_log(old).turns_reprojected is False


def test_replay_reproduces_the_frames_byte_for_byte(episode, renderer):
    world, path, _, frames = episode
    replayed = [
        {name: camera.rgb8 for name, camera in observed.cameras.items()}
        for observed in replay(load_command_log(path), world, renderer=renderer)
    ]
    assert len(replayed) == STEPS + 1
    for original, again in zip(frames, replayed, strict=True):
        for name in original:
            assert original[name].tobytes() == again[name].tobytes()
    assert not np.array_equal(frames[0]["dome"], frames[-1]["dome"])  # the head did move


def test_cli_replay_writes_the_same_frames_and_renders_another_profile(episode, tmp_path):
    world, path, _, frames = episode
    assert main(["sim", "replay", str(path), str(world), "-o", str(tmp_path / "same")]) == 0
    for k, original in enumerate(frames):
        png = cv2.imread(str(tmp_path / "same" / "dome" / "frames" / f"{k:06d}.png"), cv2.IMREAD_UNCHANGED)
        assert png[..., ::-1].tobytes() == original["dome"].tobytes()
    # A longer lens on the dome: the same commands, other frames, and each camera's metrics.
    tele = write(tmp_path, "tele.yaml", PTZ_PROFILE.replace("[4.0, 40.0]", "[8.0, 80.0]"))
    other = tmp_path / "tele_run"
    args = ["sim", "replay", str(path), str(world), "-o", str(other), "--profile", f"dome={tele}"]
    assert main([*args, "--ground-truth", "--target", "walker"]) == 0
    last = cv2.imread(str(other / "dome" / "frames" / f"{STEPS:06d}.png"))[..., ::-1]
    assert not np.array_equal(last, frames[-1]["dome"])
    overview = cv2.imread(str(other / "overview" / "frames" / f"{STEPS:06d}.png"))[..., ::-1]
    assert overview.tobytes() == frames[-1]["overview"].tobytes()  # its profile is unchanged
    metrics = json.loads((other / "control_metrics.json").read_text())
    assert set(metrics) == {"dome", "overview"} and metrics["overview"]["in_frame_frac"] == 1.0
    # The replay's ground truth scored against itself.
    gt = other / "dome" / "gt" / "gt.txt"
    assert main(["evaluate", str(other / "dome"), str(gt), "--target-id", "1", "--json", str(tmp_path / "s.json")]) == 0
    scores = json.loads((tmp_path / "s.json").read_text())
    assert scores["tracking"]["mota"] == 1.0 and scores["tracking"]["idf1"] == 1.0 and scores["tracking"]["hota"] == 1.0
    assert scores["control"]["frames"] == STEPS + 1


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ('{"frame": 9, "camera": "dome", "command": "Stop"}', r"log.jsonl:2: frame must be a whole number in \[0, 5\]"),
        ('{"frame": 0, "camera": "dome", "command": "Jump"}', r"log.jsonl:2: command 'Jump' is not one of"),
        ('{"frame": 0, "camera": "dome", "command": "Stop", "fast": 1}', r"Stop has no field 'fast'"),
        ("[1, 2]", r"log.jsonl:2: expected a JSON object"),
        ("HEADER", r"log.jsonl:1: turns_reprojected must be true, false or \"auto\" .* got 'yes'"),
        ("{frame: 0}", r"log.jsonl:2: not JSON"),
    ],
)
def test_a_bad_log_line_is_named(tmp_path, line, message):
    header = (
        '{"format": "camgen-command-log", "version": 1, "scene": "w", "seed": 0, "steps": 6, "resolution_px": null}'
    )
    if line == "HEADER":  # a bad header key
        header, line = (
            header[:-1] + ', "turns_reprojected": "yes"}',
            '{"frame": 0, "camera": "dome", "command": "Stop"}',
        )
    path = write(tmp_path, "log.jsonl", header + "\n" + line + "\n")
    with pytest.raises(ConfigError, match=message):
        load_command_log(path)


def test_replay_names_what_does_not_fit_the_scene(episode, renderer, tmp_path):
    world, path, log, _ = episode
    records = path.read_text().splitlines()
    renamed = write(tmp_path, "renamed.jsonl", "\n".join([records[0], records[1].replace('"dome"', '"gate_cam"')]))
    with pytest.raises(ConfigError, match=r"the log commands camera 'gate_cam', which .*world.yaml does not have"):
        next(replay(load_command_log(renamed), world, renderer=renderer))
    edited = write(
        tmp_path, "edited.jsonl", "\n".join([records[0], re.sub(r'"pan": [-\d.e]+', '"pan": 3.0', records[1])])
    )
    replayed = replay(load_command_log(edited), world, renderer=renderer)
    next(replayed)  # frame 0 renders; the edited command is refused at the first step
    with pytest.raises(
        ConfigError, match=r"the log's commands at frame 0: dome: command 0 \(ContinuousMove\): pan must"
    ):
        next(replayed)
    fixed = write(tmp_path, "fixed.yaml", FIXED_PROFILE)
    with pytest.raises(ConfigError, match=r"with the profiles dome=.*fixed.yaml .*cameras\[0\]\.ptz is set"):
        next(replay(log, world, profiles={"dome": fixed}, renderer=renderer))
