"""camgen batch DATASET -o OUT: expand a dataset into jobs and render them on a local process pool or Ray."""

from __future__ import annotations

import argparse
import os
import shlex
import signal
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from camgen.cli.common import add_profile_dirs_option, check_output_directory, profile_dirs
from camgen.cli.progress import ProgressLines
from camgen.errors import ConfigError

if TYPE_CHECKING:
    from camgen.batch.run import BatchSummary, JobOutcome
    from camgen.config.dataset import Dataset


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("batch", help="render every job of a dataset (scenes × profiles × seeds)")
    parser.add_argument("dataset", type=Path, metavar="DATASET")
    parser.add_argument("-o", "--out", type=Path, required=True, metavar="DIR", help="output directory")
    parser.add_argument("--plan", action="store_true", help="print the jobs without rendering")
    parser.add_argument(
        "--workers",
        type=int,
        default=os.cpu_count() or 1,
        metavar="N",
        help="worker processes, or CPUs of a local Ray (default: CPU count); unused with --address",
    )
    parser.add_argument("--retries", type=int, default=1, metavar="N", help="tries after a job fails (default 1)")
    parser.add_argument("--frames", type=int, metavar="N", help="render only the first N frames of each job")
    parser.add_argument(
        "--executor",
        choices=("local", "ray"),
        default="local",
        help="local: a process pool on this machine (default); ray: one Ray task per job (needs camgen[ray]). "
        "With Ray, -o and the dataset's files must be on a filesystem shared by every node, at the same path",
    )
    parser.add_argument(
        "--address",
        metavar="ADDR",
        help="the Ray cluster to run on (e.g. auto, HOST:6379, ray://HOST:10001); default: start a local Ray",
    )
    parser.add_argument(
        "--resume",
        action="store_true",
        help=(
            "continue the jobs a stopped batch (or a failed try) left unfinished from each camera's last checkpoint "
            "(written every few hundred frames), as render --resume does, and keep what the running jobs wrote if "
            "this batch is stopped or a job fails too; finished jobs are skipped either way, and the files are the "
            "bytes of a batch never stopped. Without it, unfinished jobs are deleted and rendered from the start"
        ),
    )
    add_profile_dirs_option(parser)
    parser.set_defaults(run=run)


def run(args: argparse.Namespace, out: Console, err: Console) -> int:
    if args.executor == "local" and not args.plan:
        # The local pool's fork server imports what a job needs (about 3 s) while this process does the same
        # and compiles the jobs, instead of after: a 20-job batch on 1 worker 9.6 → 7.4 s.
        from camgen.batch.executor import start_pool_server

        start_pool_server()
    from camgen.batch.expand import compile_dataset
    from camgen.batch.run import check_options, frames_of, run_batch
    from camgen.config.loader import load_dataset
    from camgen.plan.execute import job_directory_name

    if args.frames is not None and args.frames < 1:
        raise ConfigError(f"--frames must be ≥ 1, got {args.frames}")
    check_options(workers=args.workers, retries=args.retries, executor=args.executor, address=args.address)
    check_output_directory(args.out, "-o", "give a directory to write the dataset into")
    dirs = profile_dirs(args)
    # a job that does not compile fails (reported, no render); the others go on
    jobs = [
        (batch, "; ".join(str(problem) for problem in job.problems) if isinstance(job, ConfigError) else job)
        for batch, job in compile_dataset(args.dataset, dirs)
    ]
    shorter = [
        (batch.name, job.frame_count)
        for batch, job in jobs
        if not isinstance(job, str) and args.frames is not None and job.frame_count < args.frames
    ]
    if shorter:
        counts = ", ".join(f"{name} {count}" for name, count in shorter[:4]) + (" …" if len(shorter) > 4 else "")
        err.print(
            f"[yellow]warning[/yellow] --frames {args.frames}: {len(shorter)} of {len(jobs)} jobs have fewer frames "
            f"(duration_s × fps: {escape(counts)}); those render all of theirs",
            soft_wrap=True,
        )
    if args.plan:
        table = Table(title=f"{escape(str(args.dataset))}: {len(jobs)} jobs")
        randomized = any(batch.randomized for batch, _ in jobs)
        for column in ("job", "scene", "profile", "seed", "frames", "directory", *(["light ×"] if randomized else [])):
            table.add_column(column)
        for batch, job in jobs:
            light = batch.randomized.get("light_scale")
            table.add_row(
                escape(batch.name),
                escape(batch.scene_path.name),
                escape(batch.profile or "(scene's own)"),
                str(batch.seed),
                "–" if isinstance(job, str) else str(frames_of(job, args.frames)),
                escape(f"does not compile: {job}" if isinstance(job, str) else job_directory_name(job)),
                *([f"{light:.3g}" if light is not None else "–"] if randomized else []),
            )
        out.print(table)
        broken = sum(isinstance(job, str) for _, job in jobs)
        if broken:
            err.print(f"{broken} of {len(jobs)} jobs do not compile; fix them before rendering", markup=False)
            return 1
        return 0
    with _job_progress(err, len(jobs)) as count:

        def on_event(outcome: JobOutcome) -> None:
            count(outcome)
            if outcome.status == "failed":
                err.print(
                    f"[red]failed[/red] {escape(outcome.batch.name)} after {outcome.attempts} tries: "
                    f"{escape(outcome.error or '')}",
                    soft_wrap=True,
                )

        dataset = load_dataset(args.dataset, dirs)
        summary = run_batch(
            jobs,
            args.out,
            workers=args.workers,
            retries=args.retries,
            frames=args.frames,
            description=dataset.description,
            on_event=on_event,
            executor=args.executor,
            address=args.address,
            resume=args.resume,
        )
    _write_dataset_files(args, dataset, summary, out, err)
    table = Table(title=f"{escape(str(args.dataset))} → {escape(str(args.out))}")
    for column in ("done", "skipped", "failed", "frames", "wall time", "frames/s"):
        table.add_column(column, justify="right")
    fps = summary.rendered_frames / summary.wall_s if summary.wall_s > 0 else 0.0
    table.add_row(
        str(summary.count("done")),
        str(summary.count("skipped")),
        str(summary.count("failed")),
        str(summary.frames),
        f"{summary.wall_s:.1f} s",
        f"{fps:.2f}",
    )
    out.print(table)
    if summary.stop_signal is not None:
        again = (
            "finished; run again with --resume to continue them from their checkpoints"
            if args.resume
            else "rendered; run again to render them (complete jobs are skipped)"
        )
        err.print(
            f"interrupted ({signal.Signals(summary.stop_signal).name}): {summary.count('interrupted')} jobs not {again}"
        )
        return 128 + summary.stop_signal  # the shell's code for a command a signal ended: 130, 143
    return 0 if summary.ok else 1


def _write_dataset_files(
    args: argparse.Namespace, dataset: Dataset, summary: BatchSummary, out: Console, err: Console
) -> None:
    """The merged COCO file, its splits and the dataset card (`camgen.batch.dataset_files`), from what is on
    disk after the jobs, whichever way they ended."""
    from camgen.batch.dataset_files import CARD_NAME, MERGED_NAME, JobRecord, write_dataset_files

    records = [
        JobRecord(
            name=o.batch.name,
            directory=None if o.directory is None else o.directory.name,
            status=o.status,
            scene=o.batch.scene_path.name,
            profile=o.batch.profile,
            seed=o.batch.seed,
            error=o.error,
        )
        for o in summary.outcomes
    ]
    split_seed = dataset.seed if dataset.splits.seed is None else dataset.splits.seed
    try:
        write_dataset_files(
            args.out,
            records,
            dataset=args.dataset.stem,
            description=dataset.description,
            ratios=dataset.splits.ratios,
            split_seed=split_seed,
            command=command_line(args),
            licence=dataset.license,
            frames_limit=args.frames,
        )
    except OSError as exc:
        err.print(f"[red]error[/red] the dataset files were not written: {escape(str(exc))}", soft_wrap=True)
        return
    out.print(
        f"dataset files: {escape(str(args.out / MERGED_NAME))} (+ coco_train/val/test.json, splits.json), "
        f"{escape(str(args.out / CARD_NAME))}",
        soft_wrap=True,
    )


def command_line(args: argparse.Namespace) -> str:
    """The `camgen batch` command as parsed: every option with the value it ran with, for the dataset card."""
    words = ["camgen", "batch", str(args.dataset), "-o", str(args.out), "--workers", str(args.workers)]
    words += ["--retries", str(args.retries)]
    if args.frames is not None:
        words += ["--frames", str(args.frames)]
    if args.executor != "local":
        words += ["--executor", args.executor]
    if args.address is not None:
        words += ["--address", args.address]
    if args.resume:
        words.append("--resume")
    for directory in args.profiles:
        words += ["--profiles", str(directory)]
    return shlex.join(words)


@contextmanager
def _job_progress(err: Console, total: int) -> Iterator[Callable[[JobOutcome], None]]:
    """Counts each job's outcome: rich's bar on a terminal, periodic lines (`ProgressLines`) in a log. Skipped
    jobs and jobs that did not compile took no time, so they are left out of the ETA's rate, and so are the
    frames a resumed job took over from its checkpoints."""

    def rendered(outcome: JobOutcome) -> int:
        return outcome.frames - outcome.resumed_frames if outcome.status == "done" else 0

    if not err.is_terminal:
        with ProgressLines(err, "batch", total, "jobs") as lines:
            yield lambda outcome: lines.advance(frames=rendered(outcome), timed=outcome.attempts > 0)
        return
    columns = (
        TextColumn("jobs"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[fps]:.1f} frames/s"),
        TimeRemainingColumn(),
    )
    with Progress(*columns, console=err) as progress:
        task = progress.add_task("jobs", total=total, fps=0.0)
        frames_done = 0

        def count(outcome: JobOutcome) -> None:
            nonlocal frames_done
            frames_done += rendered(outcome)
            elapsed_s = progress.tasks[task].elapsed or 0.0
            progress.update(task, advance=1, fps=frames_done / elapsed_s if elapsed_s > 0 else 0.0)

        yield count
