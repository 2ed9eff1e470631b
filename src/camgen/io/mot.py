"""Reading MOTChallenge text files: a sequence's ``gt/gt.txt`` and a tracker's output.

One line per box: ``frame, id, bb_left, bb_top, bb_width, bb_height, conf[, class, visibility | x, y,
z]`` (Milan et al. 2016, arXiv:1603.00831; the MOTChallenge devkit). Frames count from 1, boxes are
in pixels. A ground-truth file has class and visibility; a tracker's has ``conf`` (any score) and
three more fields that MOTChallenge ignores. Blank lines are skipped.
"""

from __future__ import annotations

import configparser
import math
from pathlib import Path

import numpy as np

from camgen.errors import ConfigError
from camgen.io.files import input_file_problem

MAX_MOT_BYTES = 512 * 2**20
"""The largest MOT file read (512 MiB: millions of boxes)."""
MOT_COLUMNS = ("frame", "id", "bb_left", "bb_top", "bb_width", "bb_height", "conf", "class", "visibility")


def read_mot(path: str | Path, *, ground_truth: bool = False) -> np.ndarray:
    """(N, 9) float64: the columns of `MOT_COLUMNS`; class and visibility are read from a ground-truth
    file (`ground_truth`) and −1 for a tracker's output (whose last fields are MOT's unused x, y, z).
    A malformed line is a `ConfigError` naming the file and line."""
    path = Path(path)
    what = "ground-truth file" if ground_truth else "tracker output"
    problem = input_file_problem(path, max_bytes=MAX_MOT_BYTES, what=what)
    if problem:
        raise ConfigError(
            f"{path}: {problem}; give a MOTChallenge text file (frame, id, left, top, width, height, ...)"
        )
    rows = []
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        text = line.strip()
        if not text:
            continue
        fields = [field.strip() for field in text.replace(" ", ",").split(",") if field.strip()]
        try:
            values = [float(field) for field in fields]
        except ValueError:
            raise ConfigError(
                f"{path}:{number}: not numbers: {text[:80]!r}; a MOT line is comma-separated numbers"
            ) from None
        if len(values) < 6:
            raise ConfigError(
                f"{path}:{number}: {len(values)} fields, a MOT line needs at least 6 "
                "(frame, id, left, top, width, height)"
            )
        if not all(math.isfinite(v) for v in values[:6]):
            raise ConfigError(f"{path}:{number}: frame, id and box must be finite numbers, got {text[:80]!r}")
        if values[0] < 1 or values[0] != int(values[0]):
            raise ConfigError(
                f"{path}:{number}: frame {values[0]:g} is not a whole number ≥ 1 (MOT counts frames from 1)"
            )
        if values[4] < 0 or values[5] < 0:
            raise ConfigError(
                f"{path}:{number}: a box's width and height must be ≥ 0, got {values[4]:g} × {values[5]:g}"
            )
        conf = values[6] if len(values) > 6 else 1.0
        tail = values[7:9] if ground_truth and len(values) >= 9 else [-1.0, -1.0]
        rows.append([*values[:6], conf, *tail])
    return np.array(rows, dtype=np.float64).reshape(-1, len(MOT_COLUMNS))


def read_seqinfo(directory: str | Path) -> dict[str, str]:
    """The ``[Sequence]`` section of ``seqinfo.ini`` in `directory` (empty when there is none)."""
    path = Path(directory) / "seqinfo.ini"
    if not path.is_file():
        return {}
    parser = configparser.ConfigParser()
    parser.optionxform = str  # keep imWidth's case
    parser.read_string(path.read_text(encoding="utf-8"))
    return dict(parser["Sequence"]) if parser.has_section("Sequence") else {}
