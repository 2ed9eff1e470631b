"""camgen sim replay LOG SCENE -o OUT: run a recorded command log again, through the scene's profiles or
others, writing every camera's delivered frames (and with --ground-truth its MOT ground truth and, for
a --target, the PTZ control metrics)."""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from camgen.cli.common import add_profile_dirs_option, check_output_directory, profile_dirs
from camgen.errors import ConfigError


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("sim", help="closed-loop simulation: replay a recorded command log")
    commands = parser.add_subparsers(title="sim commands", metavar="SIM_COMMAND", required=True)
    replay = commands.add_parser(
        "replay", help="re-render a command log (same frames byte for byte, or other profiles)"
    )
    replay.add_argument("log", type=Path, metavar="LOG", help="a command log (JSON Lines; camgen.sim.save_command_log)")
    replay.add_argument("scene", type=Path, metavar="SCENE")
    replay.add_argument("-o", "--out", type=Path, required=True, metavar="OUT", help="directory for the frames")
    replay.add_argument(
        "--profile",
        action="append",
        default=[],
        metavar="[CAMERA=]PROFILE",
        help="render CAMERA (every camera without CAMERA=) through another profile (a name or a path; repeatable)",
    )
    size = replay.add_mutually_exclusive_group()
    size.add_argument("--resolution", metavar="WxH", help="read the cameras out at W×H (default: the log's)")
    size.add_argument("--native", action="store_true", help="read the cameras out at their profiles' resolutions")
    replay.add_argument("--ground-truth", action="store_true", help="also write gt/gt.txt (MOTChallenge) per camera")
    replay.add_argument(
        "--target", metavar="ACTOR", help="report how each PTZ camera kept this actor (needs --ground-truth)"
    )
    add_profile_dirs_option(replay)
    replay.set_defaults(run=run_replay)


def _resolution(text: str | None, native: bool):
    if native:
        return None
    if text is None:
        return "logged"
    parts = text.lower().split("x")
    if len(parts) != 2 or not all(p.isdigit() and int(p) >= 2 for p in parts):
        raise ConfigError(f"--resolution {text!r}: expected WxH, two whole numbers ≥ 2 (e.g. 320x180)")
    return int(parts[0]), int(parts[1])


def _profiles(values: list[str]) -> dict[str, str]:
    profiles = {}
    for value in values:
        camera, _, profile = value.rpartition("=")
        if not profile:
            raise ConfigError(f"--profile {value!r}: give a profile name or path, optionally after CAMERA=")
        profiles[camera or "*"] = profile
    return profiles


def run_replay(args: argparse.Namespace, out: Console, err: Console) -> int:
    from camgen.config import load_scene
    from camgen.io.annotations import SequenceAnnotations
    from camgen.io.files import write_text_atomic
    from camgen.io.frames import write_frame
    from camgen.sim.log import load_command_log, replay
    from camgen.sim.metrics import control_metrics, target_boxes

    if args.target and not args.ground_truth:
        raise ConfigError(f"--target {args.target}: the control metrics come from the ground truth; add --ground-truth")
    check_output_directory(args.out, "-o")
    resolution = _resolution(args.resolution, args.native)
    log = load_command_log(args.log)
    loaded = load_scene(args.scene, profile_dirs(args))
    actors = [actor.name for actor in loaded.scene.actors]
    if args.target and args.target not in actors:
        raise ConfigError(
            f"--target {args.target}: no such actor in {args.scene} (actors: {', '.join(actors) or 'none'})"
        )
    fps = loaded.scene.fps
    runs = replay(
        log,
        loaded,
        profiles=_profiles(args.profile),
        resolution_px=resolution,
        ground_truth=args.ground_truth,
        profile_dirs=profile_dirs(args),
    )
    sequences: dict[str, SequenceAnnotations] = {}
    tracks: dict[str, tuple[list, list]] = {}
    sizes: dict[str, tuple[int, int]] = {}
    for observed in runs:
        for name, camera in observed.cameras.items():
            write_frame(args.out / name / "frames" / f"{observed.frame:06d}.png", camera.rgb8, format="png")
            height_px, width_px = camera.rgb8.shape[:2]
            sizes[name] = (width_px, height_px)
            if args.ground_truth:
                if name not in sequences:
                    sequences[name] = SequenceAnnotations(
                        name=name,
                        fps=fps,
                        width_px=width_px,
                        height_px=height_px,
                        frame_count=log.steps + 1,
                        frame_suffix=".png",
                    )
                sequences[name].add(camera.ground_truth)
            if args.target:
                boxes, heights_m = target_boxes([observed], name, args.target)
                kept = tracks.setdefault(name, ([], []))
                kept[0].extend(boxes)
                kept[1].extend(heights_m)
    for name, sequence in sequences.items():
        sequence.write_mot(args.out / name)
    out.print(
        f"replayed {log.steps} steps of {escape(str(args.log))} on {escape(str(args.scene))} "
        f"into {escape(str(args.out))}"
    )
    if args.target:
        table = Table(title=f"how each camera kept {escape(args.target)}", title_justify="left")
        for column in ("camera", "in frame", "centring error px", "centring error frac", "height frac", "px/m"):
            table.add_column(column, justify="right")
        report = {}
        for name, (boxes, heights_m) in tracks.items():
            scores = control_metrics(boxes, sizes[name], fps, heights_m)
            report[name] = {k: None if v != v else v for k, v in dataclasses.asdict(scores).items()}  # NaN: null
            table.add_row(
                escape(name),
                f"{scores.in_frame_frac:.1%}",
                f"{scores.centring_error_px:.1f}",
                f"{scores.centring_error_frac:.3f}",
                f"{scores.height_frac:.3f}",
                f"{scores.resolution_px_per_m:.1f}",
            )
        out.print(table)
        write_text_atomic(args.out / "control_metrics.json", json.dumps(report, indent=1) + "\n")
    return 0
