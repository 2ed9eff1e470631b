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
    parser.add_argument(
        "--resume",
        action="store_true",
        help=(
            "continue a stopped render of the same scene, frames and options from each camera's last "
            "checkpoint (written every few hundred frames), and keep what this render wrote if it "
            "is stopped too; the files are the bytes of an unstopped render. With nothing to resume it renders "
            "from the start"
        ),
    )
    add_profile_dirs_option(parser)
    parser.set_defaults(run=run)


def run(args: argparse.Namespace, out: Console, err: Console) -> int:
    from camgen.plan.execute import (
        NOTHING_TO_RESUME,
        execute,
        finished_render,
        job_directory_name,
        other_unfinished_renders,
        unimplemented_stages,
    )
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

    def note(message: str) -> None:
        err.print(f"[yellow]note[/yellow] {escape(message)}", soft_wrap=True)

    if args.resume:
        if finished_render(job, args.out, args.camera, range(count)) is not None:
            note(f"{Path(args.out) / job_directory_name(job)}: {NOTHING_TO_RESUME}")
            return 0
        for other in other_unfinished_renders(job, args.out):
            note(
                f"{other} holds a stopped render of another version of scene {job.scene_name} (the scene, a "
                "profile or the settings changed since): not resumed, and left as it is"
            )
    resolve = loaded.path.parent.joinpath
    with (
        Renderer() as renderer,
        _frame_progress(err, f"render {job.scene_name}", [c.name for c in chosen], count) as (on_frame, on_resume),
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
            resume=args.resume,
            on_resume=on_resume,
            on_note=note,
        )
    out.print(f"{escape(job.scene_name)}: job {job.job_id[:16]} on {escape(renderer.gl_renderer)}", highlight=False)
    for result in results:
        rendered = result.frames - result.resumed_frames
        per_frame_ms = 1e3 * result.render_s / max(rendered, 1)
        resumed = f" ({result.resumed_frames} of them before the stop)" if result.resumed_frames else ""
        out.print(
            f"  {escape(result.name)}: {result.frames} frames{resumed}, render {per_frame_ms:.0f} ms/frame, "
            f"total {result.total_s:.1f} s → {escape(str(result.directory))}",
            highlight=False,
        )
        stages = stage_sums([*result.stage_frames, result.finish_s])
        shares = shares_text(stages, result.total_s)
        if shares:
            cpu_s = sum(result.frame_cpu_s) + result.finish_cpu_s
            busy = f"; CPU {cpu_s:.1f} s, {cpu_s / result.total_s:.1f} cores busy" if result.total_s > 0 else ""
            # One line however many stages pass the cut (a console wraps at its width: 160 when piped).
            out.print(f"    time: {shares}{busy}", highlight=False, soft_wrap=True)
            if sum(stages.values()) > result.total_s:
                out.print(
                    "    (the writes run in threads beside the drawing: each stage's share is the time it kept its "
                    "thread busy, and the shares add up to more than 100 %)",
                    highlight=False,
                )
        for path in result.files[:3]:
            out.print(f"    {escape(str(path))}", highlight=False)
        if len(result.files) > 3:
            out.print(f"    … and {len(result.files) - 3} more files", highlight=False)
    out.print(f"job directory: {escape(str(Path(args.out) / job_directory_name(job)))}", highlight=False)
    return 0


@contextmanager
def _frame_progress(
    err: Console, label: str, cameras: list[str], count: int
) -> Iterator[tuple[Callable[[str, int], None], Callable[[str, int, int], None]]]:
    """`execute`'s on_frame and on_resume for `count` frames of each of `cameras`: a bar per camera on a
    terminal, periodic lines (`ProgressLines`) in a log. A camera resumed from a checkpoint says so in a
    line and counts its frames done as done, out of the rate and the ETA."""

    def resuming(name: str, done: int, total: int) -> None:
        if done < total:
            err.print(f"resuming {escape(name)} at frame {done} of {total}", highlight=False)
        else:
            err.print(f"{escape(name)}: all {total} frames were done before the stop", highlight=False)

    if not err.is_terminal:
        with ProgressLines(err, label, count * len(cameras), "frames") as lines:

            def resumed(name: str, done: int, total: int) -> None:
                resuming(name, done, total)
                lines.advance(done, frames=0, timed=False)

            yield (lambda name, index: lines.advance()), resumed
        return
    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn())
    with Progress(*columns, console=err) as progress:
        tasks = {name: progress.add_task(escape(name), total=count) for name in cameras}

        def resumed_bar(name: str, done: int, total: int) -> None:
            resuming(name, done, total)
            progress.reset(tasks[name], total=count, completed=done)  # the rate from the frames rendered now

        yield (lambda name, index: progress.advance(tasks[name])), resumed_bar
