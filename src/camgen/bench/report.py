"""Run benchmark sections and write BENCHMARKS.md: generated prose, tables and plots, every figure
from the run that writes it.

A section is a set of cases and a function that turns their results into markdown (and plots).
Writing every section replaces the whole file; writing some (`--section`) replaces only their blocks,
which are delimited by ``<!-- camgen-bench:KEY:begin -->`` / ``…:end -->`` markers.
"""

from __future__ import annotations

import os
import re
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

from camgen.bench.harness import Case, Result, run_case
from camgen.io.files import write_text_atomic


@dataclass(frozen=True)
class Plots:
    """Where a section writes its figures, and how BENCHMARKS.md links to them."""

    directory: Path
    document: Path
    """The markdown file the links are relative to."""

    def path(self, name: str) -> Path:
        return self.directory / name

    def link(self, name: str, alt: str) -> str:
        relative = os.path.relpath(self.directory / name, self.document.resolve().parent)
        return f"![{alt}]({Path(relative).as_posix()})"


@dataclass(frozen=True)
class Section:
    key: str
    title: str
    cases: Callable[[], list[Case]]
    """Built when the section runs (building may load scenes or render inputs)."""
    body: Callable[[Mapping[str, Result], Plots], str]
    """Markdown after the cases ran, from their results; may write plots."""


def run_sections(
    sections, *, repeats: int, plots: Plots, on_case=None, on_block=None, durations_s=None, failures=None
) -> dict[str, str]:
    """Run each section's cases and return its markdown block by key.

    `on_case(section, case, index, count)` is called before each case (progress), `on_block(key,
    block)` after each section (to write it at once: a later failure loses nothing). A section whose
    cases or text raise gets a block saying so, and its key and error go into `failures` (a list);
    the other sections still run. `durations_s`, a dict, receives each section's wall time.
    """
    blocks = {}
    for section in sections:
        start = time.perf_counter()
        try:
            cases = section.cases()
            results: dict[str, Result] = {}
            for i, case in enumerate(cases):
                if on_case is not None:
                    on_case(section, case, i, len(cases))
                results[case.name] = run_case(case, repeats=repeats)
            body = section.body(results, plots).strip()
        except Exception as error:  # one broken section must not lose the others' results
            if failures is None:
                raise
            failures.append((section.key, f"{type(error).__name__}: {error}"))
            body = f"**This section failed in this run:** `{type(error).__name__}: {error}`."
        blocks[section.key] = block(section, body)
        if on_block is not None:
            on_block(section.key, blocks[section.key])
        if durations_s is not None:
            durations_s[section.key] = time.perf_counter() - start
    return blocks


def markers(key: str) -> tuple[str, str]:
    return f"<!-- camgen-bench:{key}:begin -->", f"<!-- camgen-bench:{key}:end -->"


def block(section: Section, body: str) -> str:
    begin, end = markers(section.key)
    return f"{begin}\n## {section.title}\n\n{body}\n{end}"


def write_report(path: Path, header: str, blocks: Mapping[str, str], order: list[str]) -> None:
    """All of `order` run: the file is the header and the blocks. Some: their blocks replace the
    ones in the file (appended where missing), the rest is kept."""
    if set(order) <= set(blocks):
        text = header.strip() + "\n\n" + "\n\n".join(blocks[key] for key in order) + "\n"
    else:
        text = path.read_text(encoding="utf-8") if path.exists() else header.strip() + "\n"
        for key, new in blocks.items():
            begin, end = markers(key)
            pattern = re.escape(begin) + ".*?" + re.escape(end)
            if re.search(pattern, text, flags=re.S):
                text = re.sub(pattern, lambda _, new=new: new, text, flags=re.S)
            else:
                text = text.rstrip() + "\n\n" + new + "\n"
    write_text_atomic(path, text)
