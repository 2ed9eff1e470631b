"""camgen verify OUT…: check rendered job directories against their manifest.json.

Exit status 0 when every file of every job is as its manifest records, 1 when anything differs
(each bad file is named), 2 when a path is missing or holds no job.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, DownloadColumn, Progress, TextColumn, TimeRemainingColumn

from camgen.io.manifest import FileProblem, find_job_directories, read_manifest, verify

KIND_STYLE = {"manifest": "red", "missing": "red", "modified": "red", "extra": "yellow", "unreadable": "red"}


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("verify", help="check rendered files against their job's manifest.json")
    parser.add_argument(
        "paths",
        nargs="+",
        type=Path,
        metavar="OUT",
        help="a job directory (with manifest.json) or a directory holding job directories",
    )
    parser.set_defaults(run=run)


def run(args: argparse.Namespace, out: Console, err: Console) -> int:
    jobs = [job_dir for path in args.paths for job_dir in find_job_directories(path)]
    failed = 0
    columns = (TextColumn("{task.description}"), BarColumn(), DownloadColumn(), TimeRemainingColumn())
    with Progress(*columns, console=err, transient=True, disable=not err.is_terminal) as progress:
        for job_dir in jobs:
            problems = _verify_with_progress(job_dir, progress)
            if not problems:
                manifest, _ = read_manifest(job_dir)
                files = manifest["files"].values()
                size_mb = sum(entry["size_bytes"] for entry in files) / 1e6
                out.print(f"[green]ok[/green]  {escape(str(job_dir))} ({len(files)} files, {size_mb:.1f} MB)")
                continue
            failed += 1
            err.print(f"[red]FAILED[/red] {escape(str(job_dir))}: {len(problems)} problem(s)")
            for problem in problems:
                style = KIND_STYLE[problem.kind]
                err.print(
                    f"  [{style}]{problem.kind}[/{style}] {escape(str(job_dir / problem.path))}: "
                    f"{escape(problem.message)}",
                    soft_wrap=True,
                )
    if failed:
        err.print(f"{failed} of {len(jobs)} job(s) failed verification", markup=False)
    return 1 if failed else 0


def _verify_with_progress(job_dir: Path, progress: Progress) -> list[FileProblem]:
    task = progress.add_task(escape(job_dir.name), total=None)
    try:
        return verify(job_dir, on_progress=lambda done, total: progress.update(task, completed=done, total=total))
    finally:
        progress.remove_task(task)
