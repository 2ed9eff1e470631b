"""camgen bench: run the benchmark sections, write BENCHMARKS.md and the plots under docs/bench/."""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import tempfile
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

import camgen
from camgen.cli.common import check_output_directory, check_output_file
from camgen.errors import ConfigError

QUICK_REPEATS, FULL_REPEATS = 3, 7


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "bench",
        help="run the benchmarks: run time against error, end-to-end frames/s, skipping, cost growth",
        description=(
            "Run every benchmark section and print its text; with --write, write BENCHMARKS.md from the "
            "results (every figure in it comes from this run) and the plots beside it."
        ),
    )
    parser.add_argument("--quick", action="store_true", help=f"{QUICK_REPEATS} timed repeats instead of {FULL_REPEATS}")
    parser.add_argument("--write", type=Path, metavar="FILE", help="write the report here (e.g. BENCHMARKS.md)")
    parser.add_argument(
        "--plots", type=Path, metavar="DIR", help="where the PNG plots go (default: docs/bench beside --write)"
    )
    parser.add_argument(
        "--section",
        action="append",
        metavar="KEY",
        help="run only this section (repeatable); --write then replaces only its block in FILE",
    )
    parser.add_argument("--list", action="store_true", help="list the sections and exit")
    parser.set_defaults(run=run)


def repo_root() -> Path:
    """The checkout the example scenes are read from (the bench needs scenes/ and profiles/)."""
    return Path(__file__).resolve().parents[3]


def run(args: argparse.Namespace, out: Console, err: Console) -> int:
    from camgen.bench.report import Plots, run_sections, write_report
    from camgen.bench.sections import sections

    repo = repo_root()
    if not (repo / "scenes").is_dir():
        raise ConfigError(f"{repo}: no scenes/ directory; the benchmarks run from a checkout of camgen")
    available = sections(repo)
    if args.list:
        for section in available:
            out.print(f"{section.key:12s} {escape(section.title)}")
        return 0
    keys = [s.key for s in available]
    wanted = args.section or keys
    unknown = [k for k in wanted if k not in keys]
    if unknown:
        raise ConfigError(f"--section {', '.join(unknown)}: no such section; choose from {', '.join(keys)}")
    if args.write is not None:
        check_output_file(args.write, "--write", "give the markdown file to write (BENCHMARKS.md)")
    if args.plots is not None:
        check_output_directory(args.plots, "--plots", "give a directory for the PNG plots")
    if args.write is not None:
        plots = Plots(directory=args.plots or args.write.resolve().parent / "docs" / "bench", document=args.write)
    else:  # printing only: the committed plots are left alone
        scratch = Path(tempfile.mkdtemp(prefix="camgen-bench-plots-"))
        plots = Plots(directory=args.plots or scratch, document=scratch / "BENCHMARKS.md")
    chosen = [s for s in available if s.key in wanted]
    failures: list[tuple[str, str]] = []
    top = header(args.quick)  # before anything is written: the commit is the code's, not "dirty" by our own output

    def on_block(key: str, text: str) -> None:
        if args.write is not None:  # each section as it finishes: a later failure or Ctrl-C loses nothing
            write_report(args.write, top, {key: text}, keys)

    repeats = QUICK_REPEATS if args.quick else FULL_REPEATS
    with Progress(
        TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn(), console=err, transient=True
    ) as progress:
        task = progress.add_task("benchmarks", total=None)

        def on_case(section, case, index, count) -> None:
            progress.update(task, description=f"{section.key} {index + 1}/{count}: {escape(case.name)}")

        durations_s: dict[str, float] = {}
        blocks = run_sections(
            chosen,
            repeats=repeats,
            plots=plots,
            on_case=on_case,
            on_block=on_block,
            durations_s=durations_s,
            failures=failures,
        )
    for section in chosen:
        out.print(blocks[section.key], markup=False, highlight=False, soft_wrap=True)
    err.print("time per section: " + ", ".join(f"{key} {s:.0f} s" for key, s in durations_s.items()))
    if args.write is not None:
        write_report(args.write, top, blocks, keys)
        out.print(f"wrote {escape(str(args.write))} and plots in {escape(str(plots.directory))}")
    for key, error in failures:
        err.print(f"[red]error[/red] section {key} failed: {escape(error)}")
    return 1 if failures else 0


def header(quick: bool) -> str:
    command = "make bench" + (" (camgen bench --quick)" if quick else "")
    commit = _git_commit()
    machine = (
        f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
        f"NumPy {np.__version__}, camgen {camgen.__version__}{f' at {commit}' if commit else ''}"
    )
    return f"""# camgen benchmarks

Every figure in this file and every plot under `docs/bench/` is written by `{command}` (`camgen bench
--write BENCHMARKS.md`), here on {machine}. Times are the median of {QUICK_REPEATS if quick else FULL_REPEATS}
timed runs after one warm-up unless a table's `repeats` column says otherwise, with the inter-quartile
range; the error column is the largest error against the case's reference (a closed form or an
independent implementation) where it has one. Comparisons are ratios of medians measured in the same run
(`× baseline`), because the machines are shared and noisy; rendering is OpenGL through EGL (llvmpipe on
machines without a GPU)."""


def _git_commit() -> str | None:
    try:
        done = subprocess.run(
            ["git", "describe", "--always", "--dirty"], cwd=repo_root(), capture_output=True, text=True, timeout=10
        )
    except (OSError, subprocess.TimeoutExpired):
        return None
    return done.stdout.strip() or None if done.returncode == 0 else None
