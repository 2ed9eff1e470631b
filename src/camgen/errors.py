"""Errors camgen raises for user input.

A `ConfigError` carries one or more `Problem`s, each pointing at a file, line and column, a key path
and the reason, so the CLI can print them like a compiler does and exit without a traceback::

    scenes/lot.yaml:23:7: cameras[1].ptz.pan_max_deg_s must be > 0, got -30
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class Location:
    """A place in a source file; `line` and `column` are 1-based as editors show them."""

    file: str
    line: int
    column: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"


def format_key_path(path: Sequence[str | int]) -> str:
    """Render a key path the way a user reads it: ``cameras[1].ptz.pan_max_deg_s``."""
    text = ""
    for part in path:
        if isinstance(part, int):
            text += f"[{part}]"
        else:
            text += f".{part}" if text else str(part)
    return text


@dataclass(frozen=True)
class Problem:
    """One thing wrong with user input.

    `message` is the predicate that failed, written to follow the key path:
    ``must be > 0, got -30``.
    """

    path: tuple[str | int, ...]
    message: str
    location: Location | None = None

    def __str__(self) -> str:
        where = f"{self.location}: " if self.location else ""
        key = format_key_path(self.path)
        return f"{where}{key} {self.message}" if key else f"{where}{self.message}"


class ConfigError(ValueError):
    """User input that camgen cannot accept; `problems` lists every reason found."""

    def __init__(self, problems: Sequence[Problem] | str):
        if isinstance(problems, str):
            problems = [Problem(path=(), message=problems)]
        self.problems: tuple[Problem, ...] = tuple(problems)
        super().__init__("\n".join(str(p) for p in self.problems))


class ConfigWarning(UserWarning):
    """User input camgen accepts but that is probably not what was meant; `problem` says where and why."""

    def __init__(self, problem: Problem):
        self.problem = problem
        super().__init__(str(problem))
