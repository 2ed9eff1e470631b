"""python -m camgen.bench [--quick] [--write BENCHMARKS.md]: run the cases, print and record the table."""

from __future__ import annotations

import argparse
import os
import platform
import re
import sys
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.progress import Progress

import camgen
from camgen.bench.cases import default_cases
from camgen.bench.harness import markdown_table, run_case
from camgen.io.files import write_text_atomic

BEGIN, END = "<!-- camgen-bench:begin -->", "<!-- camgen-bench:end -->"
REPO = Path(__file__).resolve().parents[3]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m camgen.bench", description=__doc__)
    parser.add_argument("--quick", action="store_true", help="3 repeats instead of 7")
    parser.add_argument("--write", type=Path, metavar="FILE", help="replace the generated section of FILE")
    args = parser.parse_args(argv)
    console = Console()
    cases = default_cases(REPO)
    results = []
    with Progress(console=console, transient=True) as progress:
        task = progress.add_task("benchmarks", total=len(cases))
        for case in cases:
            progress.update(task, description=case.name)
            results.append(run_case(case, repeats=3 if args.quick else 7))
            progress.advance(task)
    table = markdown_table(results)
    console.print(table, highlight=False, markup=False)
    if args.write:
        command = "make bench" + (" (--quick)" if args.quick else "")
        machine = (
            f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
            f"NumPy {np.__version__}, camgen {camgen.__version__}"
        )
        section = f"{BEGIN}\nProduced by `{command}` on {machine}.\n\n{table}\n{END}"
        text = args.write.read_text(encoding="utf-8") if args.write.exists() else ""
        if BEGIN in text and END in text:
            text = re.sub(re.escape(BEGIN) + ".*?" + re.escape(END), lambda _: section, text, flags=re.S)
        else:
            text = text.rstrip() + "\n\n" + section + "\n"
        write_text_atomic(args.write, text)
        console.print(f"wrote {args.write}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
