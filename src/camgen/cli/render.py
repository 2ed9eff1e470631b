"""camgen render SCENE -o OUT: compile a scene and render it through the camera model (lens, sensor, ISP,
codec), with per-frame camera states."""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

from camgen.cli.common import add_profile_dirs_option, check_output_directory, profile_dirs
from camgen.cli.progress import ProgressLines
from camgen.config import load_scene
from camgen.errors import ConfigError
from camgen.plan import PlanSettings, compile_scene
from camgen.plan.timing import shares_text, stage_sums


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("render", help="render a scene's cameras into video and passes")
    parser.add_argument("scene", type=Path, metavar="SCENE")
    parser.add_argument("-o", "--out", type=Path, required=True, metavar="DIR", help="output directory")
    parser.add_argument("--frames", type=int, metavar="N", help="render only the first N frames")
    parser.add_argument("--camera", action="append", metavar="NAME", help="render only this camera (repeatable)")
    parser.add_argument(
        "--supersampling",
        type=int,
        metavar="S",
        help=f"radiance anti-aliasing: S×S samples per pixel (default {PlanSettings().supersampling})",
    )
    parser.add_argument(
        "--save-passes", action="store_true", help="also write each frame's passes as passes/<frame>.npz"
    )
    add_profile_dirs_option(parser)
    parser.set_defaults(run=run)


def run(args: argparse.Namespace, out: Console, err: Console) -> int:
    from camgen.plan.execute import execute, job_directory_name, unimplemented_stages
    from camgen.render.renderer import Renderer

    if args.frames is not None and args.frames < 1:
        raise ConfigError(f"--frames must be ≥ 1, got {args.frames}")
    settings = PlanSettings()
    if args.supersampling is not None:
        if not 1 <= args.supersampling <= 8:
            raise ConfigError(f"--supersampling must be 1…8, got {args.supersampling}")
        settings = PlanSettings(supersampling=args.supersampling)
    check_output_directory(args.out, "-o", "give a directory to write the job into")
    loaded = load_scene(args.scene, profile_dirs(args))
    job = compile_scene(loaded, settings)
    names = {camera.name for camera in job.cameras}
    unknown = sorted(set(args.camera or ()) - names)
    if unknown:
        raise ConfigError(
            f"--camera {', '.join(unknown)}: no such camera in {args.scene} (it has {', '.join(sorted(names))})"
        )
    count = job.frame_count if args.frames is None else min(args.frames, job.frame_count)
    if args.frames is not None and args.frames > job.frame_count:
        err.print(
            f"[yellow]warning[/yellow] --frames {args.frames}: {escape(str(args.scene))} has only {job.frame_count} "
            f"frames (duration_s {job.scene.duration_s:g} × fps {job.fps:g}); rendering those {job.frame_count}",
            soft_wrap=True,
        )
    chosen = [c for c in job.cameras if args.camera is None or c.name in args.camera]
    for camera in chosen:
        skipped = unimplemented_stages(camera)
        if skipped:
            err.print(
                f"[yellow]note[/yellow] {escape(camera.name)}: planned stages not implemented in this version are "
                f"skipped: {', '.join(skipped)}",
                soft_wrap=True,
            )
    resolve = loaded.path.parent.joinpath
    with (
        Renderer() as renderer,
        _frame_progress(err, f"render {job.scene_name}", [c.name for c in chosen], count) as on_frame,
    ):
        results = execute(
            job,
            args.out,
            renderer=renderer,
            frames=range(count),
            cameras=args.camera,
            resolve_path=resolve,
            save_passes=args.save_passes,
            on_frame=on_frame,
        )
    out.print(f"{escape(job.scene_name)}: job {job.job_id[:16]} on {escape(renderer.gl_renderer)}", highlight=False)
    for result in results:
        per_frame_ms = 1e3 * result.render_s / max(result.frames, 1)
        out.print(
            f"  {escape(result.name)}: {result.frames} frames, render {per_frame_ms:.0f} ms/frame, "
            f"total {result.total_s:.1f} s → {escape(str(result.directory))}",
            highlight=False,
        )
        shares = shares_text(stage_sums([*result.stage_frames, result.finish_s]), result.total_s)
        if shares:
            out.print(f"    time: {shares}", highlight=False)
        for path in result.files[:3]:
            out.print(f"    {escape(str(path))}", highlight=False)
        if len(result.files) > 3:
            out.print(f"    … and {len(result.files) - 3} more files", highlight=False)
    out.print(f"job directory: {escape(str(Path(args.out) / job_directory_name(job)))}", highlight=False)
    return 0


@contextmanager
def _frame_progress(err: Console, label: str, cameras: list[str], count: int) -> Iterator[Callable[[str, int], None]]:
    """`execute`'s on_frame for `count` frames of each of `cameras`: a bar per camera on a terminal, periodic
    lines (`ProgressLines`) in a log."""
    if not err.is_terminal:
        with ProgressLines(err, label, count * len(cameras), "frames") as lines:
            yield lambda name, index: lines.advance()
        return
    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn())
    with Progress(*columns, console=err) as progress:
        tasks = {name: progress.add_task(escape(name), total=count) for name in cameras}
        yield lambda name, index: progress.advance(tasks[name])
