"""Progress in a log (stderr not a terminal): a line each tenth of the work and from a timer, with done/total,
frames/s, elapsed and ETA; camgen render writes them while it renders."""

from __future__ import annotations

import io
import re
import time

import pytest
from rich.console import Console

from camgen.cli.main import main
from camgen.cli.progress import ProgressLines
from tests.conftest import FIXED_PROFILE, SCENE, write

LINE = re.compile(
    r"^(?P<label>.+): (?P<done>\d+)/(?P<total>\d+) (?P<unit>\w+) \((?P<percent>\d+) %\), (?P<fps>\d+\.\d) frames/s, "
    r"elapsed (?P<elapsed>\d+:\d\d:\d\d), ETA (?P<eta>\d+:\d\d:\d\d|–)$"
)


def progress_lines(text: str) -> list[re.Match]:
    return [match for match in map(LINE.match, text.splitlines()) if match]


def test_a_line_for_each_tenth_of_the_work_and_no_repeat_at_the_end():
    log = io.StringIO()
    with ProgressLines(Console(file=log), "render walk", 20, "frames", interval_s=3600) as progress:
        for _ in range(20):
            progress.advance()
    lines = progress_lines(log.getvalue())
    assert len(lines) == len(log.getvalue().splitlines())  # nothing but progress lines
    assert [int(line["done"]) for line in lines] == list(range(2, 21, 2))
    last = lines[-1]
    assert (last["label"], last["total"], last["unit"], last["percent"], last["eta"]) == (
        "render walk",
        "20",
        "frames",
        "100",
        "0:00:00",
    )
    assert float(last["fps"]) > 0


def test_the_timer_prints_while_no_unit_ends():
    log = io.StringIO()
    with ProgressLines(Console(file=log), "batch", 8, "jobs", interval_s=0.05):
        time.sleep(0.5)  # a job that takes long
    lines = progress_lines(log.getvalue())
    assert len(lines) >= 2
    assert {(line["done"], line["eta"]) for line in lines} == {("0", "–")}


def test_the_eta_leaves_out_units_that_took_no_work():
    log = io.StringIO()
    with ProgressLines(Console(file=log), "batch", 4, "jobs", interval_s=3600, step_frac=0.25) as progress:
        progress.advance(3, timed=False)  # skipped: already complete
        progress.advance(frames=10)
    first, last = progress_lines(log.getvalue())
    assert (first["done"], first["eta"], first["fps"]) == ("3", "–", "0.0")
    assert (last["done"], last["eta"]) == ("4", "0:00:00") and float(last["fps"]) > 0


@pytest.mark.opengl
def test_render_into_a_log_prints_progress_lines_as_it_goes(workspace, capsys):
    small = FIXED_PROFILE.replace("width_px: 640", "width_px: 160").replace("height_px: 480", "height_px: 120")
    write(workspace, "profiles/fixed.yaml", small)
    scene = write(workspace, "scenes/walk.yaml", SCENE)
    assert main(["render", str(scene), "-o", str(workspace / "out"), "--frames", "5"]) == 0
    lines = progress_lines(capsys.readouterr().err)  # capsys's stderr is not a terminal
    assert [int(line["done"]) for line in lines] == [1, 2, 3, 4, 5]
    assert {(line["label"], line["total"], line["unit"]) for line in lines} == {("render walk", "5", "frames")}
    assert lines[-1]["percent"] == "100" and float(lines[-1]["fps"]) > 0
