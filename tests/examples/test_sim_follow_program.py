"""examples/sim_follow_program.py: camgen's follow-target program (`camgen.motion.programs.Follow`) steering a
head through camgen.sim's commands."""

from __future__ import annotations

import importlib.util
import math
import re
import sys
from types import SimpleNamespace

import pytest

from camgen.config import load_scene
from camgen.errors import ConfigError
from camgen.sim import PtzStatus
from tests.conftest import REPO
from tests.sim.scenes import write_world

EXAMPLE = REPO / "examples" / "sim_follow_program.py"


def _load_example():
    spec = importlib.util.spec_from_file_location("sim_follow_program", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


sim_follow_program = _load_example()


class _Observed:
    def __init__(self, time_s: float):
        self.time_s = time_s
        self.status = PtzStatus(0.0, -12.0, 1.5, "IDLE", "IDLE", time_s)

    def __getitem__(self, camera: str):
        assert camera == "dome"
        return SimpleNamespace(status=self.status)


def test_the_first_goal_is_the_dead_zone_edge_short_of_the_walker(tmp_path):
    """The walker's box centre at t = 0 is (−1, 8, 0.875) m, the dome at (0, −2, 3) m looking along +y, so
    its bearing is pan atan(1/10) = 5.71° (left: positive), tilt −atan(2.125/√101) = −11.94°. Follow moves
    its goal just inside a window half the dead zone (0.3 of 160 px: ±24 px at fx 333.3 px · zoom 1.5,
    ±2.75°; half: 1.37°, over cos(tilt) in pan): pan 5.71 − 1.40; the tilt is inside. It zooms to put the 1.75 m
    walker at 0.3 of the 120 px frame at 10.27 m: 0.63×, the wide end 1× (past the 1.25 dead band from 1.5×). At the
    program's 50°/s of the head's 100°/s: speed 0.5."""
    world = write_world(tmp_path, program="{type: follow, target: walker, speed_deg_s: 50}")
    follower = sim_follow_program.ProgramFollower(SimpleNamespace(loaded=load_scene(world)), "dome")
    move = follower.command(_Observed(0.0))
    bearing_deg = math.degrees(math.atan2(1.0, 10.0))
    tilt_rad = math.atan2(3.0 - 0.875, math.hypot(1.0, 10.0))
    window_deg = 0.5 * math.degrees(math.atan(0.3 * 160 / 2 / (4.0 / 0.012 * 1.5))) / math.cos(tilt_rad)
    assert move.pan_deg == pytest.approx(bearing_deg - window_deg, abs=1e-6)
    assert move.tilt_deg == pytest.approx(-12.0, abs=1e-9)
    assert move.zoom_x == pytest.approx(1.0)
    assert move.speed == pytest.approx(0.5)


def test_a_camera_that_is_not_a_ptz_or_has_nothing_to_follow_is_refused(tmp_path):
    loaded = load_scene(write_world(tmp_path))
    sim = SimpleNamespace(loaded=loaded)
    with pytest.raises(ConfigError, match=r"'overview' is not a mechanical PTZ camera.*PTZ cameras: dome"):
        sim_follow_program.ProgramFollower(sim, "overview")
    with pytest.raises(ConfigError, match="has no follow program; name the actor"):
        sim_follow_program.ProgramFollower(sim, "dome")
    with pytest.raises(ConfigError, match="no actor 'ghost' to follow"):
        sim_follow_program.ProgramFollower(sim, "dome", "ghost")


@pytest.mark.opengl
def test_the_program_keeps_the_walker_in_frame_through_the_sim(tmp_path, capsys):
    # At 3 m/s the walker leaves a still head's view after 0.9 s (tests/examples/test_sim_follow.py).
    world = write_world(tmp_path, duration_s=1.6, start_x_m=-1.0, speed_m_s=3.0)
    args = [str(world), "--camera", "dome", "--target", "walker", "--resolution", "80x60", "--steps", "15"]
    assert sim_follow_program.main([*args, "--log", str(tmp_path / "run.jsonl")]) == 0
    text = capsys.readouterr().out
    assert float(re.search(r"in frame ([\d.]+)% of 16 frames", text).group(1)) == 100.0
    assert (tmp_path / "run.jsonl").read_text().count("AbsoluteMove") == 15
