"""examples/sim_tracking.py: a proportional controller through the gymnasium environment, as a script."""

from __future__ import annotations

import importlib.util
import sys

import pytest

from tests.conftest import REPO
from tests.sim.scenes import write_world


def _load_example():
    spec = importlib.util.spec_from_file_location("sim_tracking", REPO / "examples" / "sim_tracking.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


sim_tracking = _load_example()


@pytest.mark.opengl
def test_the_script_compares_the_controller_with_a_head_left_alone(tmp_path, capsys):
    world = write_world(tmp_path, duration_s=1.0)
    assert sim_tracking.main([str(world), "--steps", "6", "--out", str(tmp_path / "out")]) == 0
    text = capsys.readouterr().out
    assert "proportional" in text and "none" in text
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["0000.png"]


def test_the_script_reports_a_missing_scene(tmp_path, capsys):
    assert sim_tracking.main([str(tmp_path / "none.yaml")]) == 2
    assert "none.yaml: no such scene file" in capsys.readouterr().err
