"""Command logs as files: JSON Lines, one JSON object a line, so a user can read and edit one.

The first line is the header (``{"format": "camgen-command-log", "version": 1, ...}``), each further
line one command record. The records are plain dicts; `camgen.sim.log` gives them their meaning.
"""

from __future__ import annotations

import json
from pathlib import Path

from camgen.errors import ConfigError
from camgen.io.files import input_file_problem, write_text_atomic

MAX_LOG_BYTES = 256 * 2**20
"""The largest log read (256 MiB: a million commands of ~200 bytes)."""


def write_json_lines(path: str | Path, records: list[dict]) -> Path:
    """Write `records` one a line (atomically: a partial file never takes the name)."""
    path = Path(path)
    write_text_atomic(path, "".join(json.dumps(record, separators=(", ", ": ")) + "\n" for record in records))
    return path


def read_json_lines(path: str | Path) -> list[tuple[int, dict]]:
    """(line number from 1, record) for every non-blank line; a line that is no JSON object is a
    `ConfigError` naming the file and line."""
    path = Path(path)
    problem = input_file_problem(path, max_bytes=MAX_LOG_BYTES, what="command log")
    if problem:
        raise ConfigError(f"{path}: {problem}; give a command log written by camgen (Simulation commands saved)")
    records = []
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except json.JSONDecodeError as exc:
            raise ConfigError(
                f"{path}:{number}: not JSON ({exc.msg} at column {exc.colno}); one JSON object a line"
            ) from None
        if not isinstance(record, dict):
            raise ConfigError(f"{path}:{number}: expected a JSON object ({{...}}), got {line.strip()[:60]!r}")
        records.append((number, record))
    return records
