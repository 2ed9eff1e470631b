"""examples/sim_handoff.py: a fixed overview camera cues the PTZ dome, which takes the walker over."""

from __future__ import annotations

import ast
import importlib.util
import re
import sys

import pytest

from tests.conftest import REPO
from tests.sim.scenes import write_world

EXAMPLE = REPO / "examples" / "sim_handoff.py"


def _load_example():
    spec = importlib.util.spec_from_file_location("sim_handoff", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


sim_handoff = _load_example()


def test_the_example_imports_only_the_documented_api():
    imported = {node.module for node in ast.walk(ast.parse(EXAMPLE.read_text())) if isinstance(node, ast.ImportFrom)}
    assert {name for name in imported if name and name.startswith("camgen")} <= {"camgen.sim", "camgen.sim.metrics"}


@pytest.mark.opengl
def test_the_overview_cues_the_dome_onto_the_walker(tmp_path, capsys):
    # The dome starts panned 30° right of the walker's path (its view is 18° wide); the overview sees it.
    world = write_world(tmp_path, duration_s=1.5, start_x_m=-1.0, speed_m_s=1.0, dome_pan_deg=-30.0)
    args = [str(world), "--overview", "overview", "--ptz", "dome", "--target", "walker", "--resolution", "80x60"]
    assert sim_handoff.main(args) == 0
    text = capsys.readouterr().out
    match = re.search(r"([\d.]+) s after the first cue \(frame 0 → (\d+)\).*frame ([\d.]+)% of", text)
    assert match is not None, text
    latency_s, hold_frame, in_frame = float(match.group(1)), int(match.group(2)), float(match.group(3))
    # The head needs its 0.1 s latency and ~0.55 s to turn 30° (200°/s², 100°/s): at least 0.6 s.
    assert 0.6 <= latency_s <= 1.2 and hold_frame >= 6
    assert in_frame == 100.0
