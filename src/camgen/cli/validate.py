"""camgen validate FILE…: check profiles, scenes and datasets; print every problem with its place."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from contextlib import nullcontext
from pathlib import Path

from rich.console import Console
from rich.markup import escape

from camgen.cli.common import add_profile_dirs_option, detect_kind, profile_dirs
from camgen.config import load_profile, load_scene
from camgen.errors import ConfigError


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("validate", help="check profile, scene and dataset YAML files")
    parser.add_argument("files", nargs="+", type=Path, metavar="FILE")
    parser.add_argument("--kind", choices=["profile", "scene", "dataset"], help="skip detection by keys")
    add_profile_dirs_option(parser)
    parser.set_defaults(run=run)


def run(args: argparse.Namespace, out: Console, err: Console) -> int:
    dirs = profile_dirs(args)
    failed = 0
    for path in args.files:
        try:
            kind = args.kind or detect_kind(path)
            if kind is None:
                raise ConfigError(
                    f"{path}: cannot tell what this is: a profile has 'sensor' and 'lens', a scene "
                    "'cameras', a dataset 'scenes'; or pass --kind"
                )
            if kind == "profile":
                load_profile(path, dirs)
            elif kind == "scene":
                load_scene(path, dirs)
            else:
                with err.status(f"compiling every job of {escape(str(path))}") if err.is_terminal else nullcontext():
                    kind = f"dataset, {_check_dataset(path, dirs)} jobs compile"
            out.print(f"[green]ok[/green]  {escape(str(path))} ({kind})")
        except ConfigError as exc:
            failed += 1
            for problem in exc.problems:
                err.print(f"[red]error[/red] {escape(str(problem))}", soft_wrap=True)
    if failed:
        err.print(f"{failed} of {len(args.files)} file(s) invalid", markup=False)
    return 1 if failed else 0


def _check_dataset(path: Path, profile_dirs: Sequence[Path]) -> int:
    """The number of jobs of a dataset; raises ConfigError with every job that does not compile.

    A dataset is valid only if every job compiles: a scene that is invalid alone, a profile that does not fit
    a scene's PTZ program, or randomized values that break a scene all show here, not hours into a batch.
    """
    from camgen.batch.expand import compile_dataset

    jobs = compile_dataset(path, profile_dirs)
    problems = [problem for _, job in jobs if isinstance(job, ConfigError) for problem in job.problems]
    if problems:
        raise ConfigError(problems)
    return len(jobs)
