"""Command logs: what a controller told the heads, saved as a file a user can read, edit and replay.

`Simulation` records every command it accepts (`Simulation.commands`: the frame and time it was
given at, the camera, the command). `command_log(sim)` takes that record with the seed, the number of
steps taken and the readout size; `save_command_log` writes it as JSON Lines (`camgen.io.command_log`):
a header line, then one line per command::

    {"format": "camgen-command-log", "version": 1, "scene": "ptz_follow", "seed": 0, "steps": 50,
     "resolution_px": [160, 120], "turns_reprojected": "auto"}
    {"frame": 0, "time_s": 0.0, "camera": "pole_ptz", "command": "ContinuousMove", "pan": -0.2,
     "tilt": 0.0, "zoom": 0.0, "timeout_s": null}

(each record on one line in the file).

A command acts from the step after the frame it was given at (`frame`; `time_s` is that frame's time,
kept for reading, and ignored on replay). `replay(log, scene)` resets a new simulation with the log's
seed and steps it `steps` times, giving each frame's commands in their order: the world is a function
of time and the noise of (seed, camera, frame), so the frames are those of the recorded run byte for
byte (tested). Replayed through other profiles (`profiles=`) or at another `resolution_px`, the same
commands drive the heads again: a normalised velocity is a fraction of *that* head's fastest, as on
real heads.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from camgen.config.loader import LoadedScene, check_cameras, find_profile, load_profile, load_scene
from camgen.errors import ConfigError
from camgen.io.command_log import read_json_lines, write_json_lines
from camgen.render.renderer import Renderer
from camgen.sim.commands import COMMAND_TYPES, Command, CommandError
from camgen.sim.simulation import LoggedCommand, Observations, Simulation

LOG_FORMAT = "camgen-command-log"
LOG_VERSION = 1
_BY_NAME = {command_type.__name__: command_type for command_type in COMMAND_TYPES}


@dataclass(frozen=True)
class CommandLog:
    """A run's commands and what is needed to run it again."""

    scene: str
    """The scene's name (its file's stem), for reading; replay takes the scene it is given."""
    seed: int
    steps: int
    """Steps taken after reset (frames delivered: steps + 1)."""
    resolution_px: tuple[int, int] | None
    commands: tuple[LoggedCommand, ...]
    turns_reprojected: bool | None = None
    """Whether the run drew a turning head's frames from its turn canvas (`Simulation`'s ``turns_reprojected``; None:
    by the readout's size, written "auto"); a log without the key was recorded before there was a canvas, when every
    turned frame was drawn whole, and is replayed so (False), as the run drew it."""


def command_log(sim: Simulation) -> CommandLog:
    """The log of `sim`'s run since its last reset."""
    if sim.frame < 0:
        raise RuntimeError("call reset() (and step) before taking the command log")
    return CommandLog(
        sim.loaded.name, sim.seed, sim.frame, sim.resolution_px, tuple(sim.commands), sim.turns_reprojected
    )


def command_record(entry: LoggedCommand) -> dict[str, Any]:
    """One log line: frame, time, camera, the command's type and its fields."""
    fields = dataclasses.asdict(entry.command)
    return {
        "frame": entry.frame,
        "time_s": entry.time_s,
        "camera": entry.camera,
        "command": type(entry.command).__name__,
        **fields,
    }


def log_records(log: CommandLog) -> list[dict[str, Any]]:
    header = {
        "format": LOG_FORMAT,
        "version": LOG_VERSION,
        "scene": log.scene,
        "seed": log.seed,
        "steps": log.steps,
        "resolution_px": None if log.resolution_px is None else list(log.resolution_px),
        "turns_reprojected": "auto" if log.turns_reprojected is None else log.turns_reprojected,
    }
    return [header, *(command_record(entry) for entry in log.commands)]


def save_command_log(log: CommandLog, path: str | Path) -> Path:
    """Write `log` as JSON Lines (atomically)."""
    return write_json_lines(path, log_records(log))


def load_command_log(path: str | Path) -> CommandLog:
    """Read a log written by `save_command_log` (or edited by hand); every problem names the line."""
    records = read_json_lines(path)
    if not records:
        raise ConfigError(
            f'{path}: empty; a command log starts with its header line ({{"format": "{LOG_FORMAT}", ...}})'
        )
    return parse_log(records, str(path))


def parse_log(records: Sequence[tuple[int, dict]], source: str = "<log>") -> CommandLog:
    """A `CommandLog` from (line number, record) pairs, header first."""
    number, header = records[0]
    where = f"{source}:{number}"
    if header.get("format") != LOG_FORMAT or header.get("version") != LOG_VERSION:
        raise ConfigError(
            f"{where}: the header must say format {LOG_FORMAT!r}, version {LOG_VERSION}; got "
            f"format {header.get('format')!r}, version {header.get('version')!r}"
        )
    seed, steps = header.get("seed"), header.get("steps")
    for key, value in (("seed", seed), ("steps", steps)):
        if not (isinstance(value, int) and not isinstance(value, bool) and value >= 0):
            raise ConfigError(f"{where}: {key} must be a whole number ≥ 0, got {value!r}")
    resolution = header.get("resolution_px")
    if resolution is not None and not (
        isinstance(resolution, list) and len(resolution) == 2 and all(isinstance(v, int) and v >= 2 for v in resolution)
    ):
        raise ConfigError(f"{where}: resolution_px must be null or [W, H], whole numbers ≥ 2; got {resolution!r}")
    reprojected = header.get("turns_reprojected", False)  # a log from before the key: every frame drawn whole
    if not (isinstance(reprojected, bool) or reprojected == "auto"):
        raise ConfigError(
            f'{where}: turns_reprojected must be true, false or "auto" (whether a turning head\'s frames are drawn '
            f"from its turn canvas; auto: by the readout's size), got {reprojected!r}"
        )
    reprojected = None if reprojected == "auto" else reprojected
    commands = []
    previous = 0
    for number, record in records[1:]:
        commands.append(_entry(record, f"{source}:{number}", steps))
        if commands[-1].frame < previous:
            raise ConfigError(
                f"{source}:{number}: frame {commands[-1].frame} comes after frame {previous}; "
                "keep the lines in the order the commands are given"
            )
        previous = commands[-1].frame
    return CommandLog(
        str(header.get("scene", "")),
        seed,
        steps,
        None if resolution is None else tuple(resolution),
        tuple(commands),
        reprojected,
    )


def _entry(record: dict, where: str, steps: int) -> LoggedCommand:
    record = dict(record)
    frame, camera, name = record.pop("frame", None), record.pop("camera", None), record.pop("command", None)
    time_s = record.pop("time_s", None)
    if not (isinstance(frame, int) and not isinstance(frame, bool) and 0 <= frame < steps):
        raise ConfigError(
            f"{where}: frame must be a whole number in [0, {steps - 1}] (a command acts from the step after its "
            f"frame; the header's steps is {steps}), got {frame!r}"
        )
    if not isinstance(camera, str):
        raise ConfigError(f"{where}: camera must be a camera's name, got {camera!r}")
    if name not in _BY_NAME:
        raise ConfigError(f"{where}: command {name!r} is not one of {', '.join(_BY_NAME)}")
    command_type = _BY_NAME[name]
    known = {field.name for field in dataclasses.fields(command_type)}
    unknown = sorted(set(record) - known)
    if unknown:
        raise ConfigError(f"{where}: {name} has no field {unknown[0]!r} (its fields: {', '.join(sorted(known))})")
    try:
        command = command_type(**record)
    except TypeError as exc:
        raise ConfigError(f"{where}: {name}: {exc}") from None
    for field in dataclasses.fields(command_type):
        value = getattr(command, field.name)
        if field.name == "name" and not isinstance(value, str):
            raise ConfigError(f"{where}: {name}.name must be a string, got {value!r}")
        if field.name != "name" and not (value is None or isinstance(value, (bool, int, float))):
            raise ConfigError(f"{where}: {name}.{field.name} must be a number, got {value!r}")
    frame_time = float(time_s) if isinstance(time_s, (int, float)) and math.isfinite(time_s) else math.nan
    return LoggedCommand(frame, frame_time, camera, command)


def with_profiles(
    loaded: LoadedScene, profiles: Mapping[str, str | Path], profile_dirs: Sequence[Path] = ()
) -> LoadedScene:
    """`loaded` with cameras' profiles replaced: camera name → profile (a name looked up as on the
    command line, or a path); the key ``"*"`` replaces every camera's."""
    cameras = [camera.name for camera in loaded.scene.cameras]
    replaced = dict(loaded.profiles)
    for camera, reference in profiles.items():
        if camera != "*" and camera not in cameras:
            raise ConfigError(
                f"profile for camera {camera!r}: no such camera in {loaded.path} (cameras: {', '.join(cameras)})"
            )
        path = find_profile(str(reference), None, profile_dirs, None, ("profile", camera))
        profile = load_profile(path, profile_dirs)
        for name in cameras if camera == "*" else [camera]:
            replaced[name] = profile
    problems = check_cameras(loaded.scene, {name: p.profile for name, p in replaced.items()})
    if problems:
        given = ", ".join(f"{camera}={reference}" for camera, reference in profiles.items())
        raise ConfigError(
            [f"with the profiles {given} (the scene's are named below): {problem}" for problem in problems]
        )
    return dataclasses.replace(loaded, profiles=replaced)


def replay(
    log: CommandLog,
    scene: str | Path | LoadedScene,
    *,
    profiles: Mapping[str, str | Path] | None = None,
    resolution_px: tuple[int, int] | str | None = "logged",
    ground_truth: bool = False,
    raw: bool = False,
    renderer: Renderer | None = None,
    profile_dirs: Sequence[Path] = (),
) -> Iterator[Observations]:
    """Run `log` again on `scene`: yields frame 0's observations, then each step's.

    `profiles`: camera name (or ``"*"``) → another profile to render through; `resolution_px`: the
    readout size (default the log's; None: the profiles' own)."""
    loaded = scene if isinstance(scene, LoadedScene) else load_scene(scene, profile_dirs)
    if profiles:
        loaded = with_profiles(loaded, profiles, profile_dirs)
    size = log.resolution_px if resolution_px == "logged" else resolution_px
    by_frame: dict[int, list[LoggedCommand]] = {}
    for entry in log.commands:
        by_frame.setdefault(entry.frame, []).append(entry)
    cameras = [camera.name for camera in loaded.scene.cameras]
    unknown = sorted({entry.camera for entry in log.commands} - set(cameras))
    if unknown:
        raise ConfigError(
            f"the log commands camera {unknown[0]!r}, which {loaded.path} does not have "
            f"(cameras: {', '.join(cameras)}); replay it on the scene it was recorded on, "
            "or rename the camera in the log"
        )
    with Simulation(
        loaded,
        ground_truth=ground_truth,
        raw=raw,
        resolution_px=size,
        renderer=renderer,
        turns_reprojected=log.turns_reprojected,
    ) as sim:
        if log.steps >= sim.frame_count:
            raise ConfigError(
                f"the log takes {log.steps} steps, but {loaded.path} ends after frame {sim.frame_count - 1}; "
                "lengthen the scene's duration_s or shorten the log"
            )
        yield sim.reset(log.seed)
        for frame in range(log.steps):
            commands: dict[str, list[Command]] = {}
            for entry in by_frame.get(frame, ()):
                commands.setdefault(entry.camera, []).append(entry.command)
            try:
                observed = sim.step(commands)
            except CommandError as exc:  # an edited log's command the head refuses
                raise ConfigError(f"the log's commands at frame {frame}: {exc}") from None
            yield observed
