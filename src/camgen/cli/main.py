"""The `camgen` command: dispatches to one module per subcommand."""

from __future__ import annotations

import argparse
import sys
import warnings

from rich.console import Console
from rich.markup import escape

import camgen
from camgen.cli import batch, bench, fit, info, plan, render, schema, validate, verify
from camgen.errors import ConfigError, ConfigWarning

SUBCOMMANDS = (validate, schema, plan, info, render, verify, fit, batch, bench)


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
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _printer(err, warnings.showwarning)
            return args.run(args, out, err)
    except ConfigError as exc:
        for problem in exc.problems:
            err.print(f"[red]error[/red] {escape(str(problem))}", soft_wrap=True)
        return 2
    except KeyboardInterrupt:
        err.print("interrupted")
        return 130


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
