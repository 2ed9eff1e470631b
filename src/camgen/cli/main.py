"""The `camgen` command: dispatches to one module per subcommand."""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import warnings

from rich.console import Console
from rich.markup import escape

import camgen
from camgen.cli import (
    batch,
    bench,
    coverage,
    evaluate,
    fit,
    info,
    layout,
    plan,
    preview,
    render,
    schema,
    sim,
    validate,
    verify,
)
from camgen.errors import ConfigError, ConfigWarning

SUBCOMMANDS = (
    validate,
    schema,
    plan,
    info,
    render,
    verify,
    preview,
    fit,
    batch,
    bench,
    coverage,
    layout,
    sim,
    evaluate,
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="camgen",
        description="Synthetic surveillance video that matches real camera hardware.",
    )
    parser.add_argument("--version", action="version", version=f"camgen {camgen.__version__}")
    subparsers = parser.add_subparsers(title="commands", metavar="COMMAND", required=True)
    for module in SUBCOMMANDS:
        module.add_parser(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    # Piped output (CI logs, files) gets a wide console so tables stay readable.
    width = None if sys.stdout.isatty() else 160
    out = Console(highlight=False, width=width)
    err = Console(stderr=True, highlight=False, width=width)
    # SIGTERM (a service manager's stop, `kill`) unwinds like Ctrl-C: partial outputs keep their temporary
    # names and are removed, no manifest is written. (`batch` installs its own handlers while it runs.)
    in_main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _terminate) if in_main_thread else None
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _printer(err, warnings.showwarning)
            return args.run(args, out, err)
    except ConfigError as exc:
        for problem in exc.problems:
            err.print(f"[red]error[/red] {escape(str(problem))}", soft_wrap=True)
        return 2
    except Terminated:
        err.print("terminated")
        return 128 + signal.SIGTERM
    except KeyboardInterrupt:
        err.print("interrupted")
        return 130
    finally:
        if in_main_thread:
            signal.signal(signal.SIGTERM, signal.SIG_DFL if previous is None else previous)


class Terminated(KeyboardInterrupt):
    """Raised by SIGTERM in the main thread, so that a command stopped by it unwinds as after Ctrl-C."""


def _terminate(signum: int, frame) -> None:
    raise Terminated


def _printer(err: Console, fallback):
    """`warnings.showwarning` that prints a `ConfigWarning` like an error, marked as a warning."""

    def show(message, category, filename, lineno, file=None, line=None) -> None:
        if issubclass(category, ConfigWarning):
            err.print(f"[yellow]warning[/yellow] {escape(str(message))}", soft_wrap=True)
        else:
            fallback(message, category, filename, lineno, file, line)

    return show


if __name__ == "__main__":
    sys.exit(main())
