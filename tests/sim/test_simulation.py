"""camgen.sim.Simulation: frames as camgen render makes them, deterministic under a seed and commands,
ground truth per frame, and clear errors for bad commands."""

from __future__ import annotations

import json
import math

import cv2
import numpy as np
import pytest

from camgen.config import load_scene
from camgen.plan import compile_scene
from camgen.plan.execute import execute
from camgen.sim import AbsoluteMove, CommandError, ContinuousMove, GotoPreset, Simulation, Stop
from tests.sim.scenes import write_world

pytestmark = pytest.mark.opengl

FRAMES = 4
COMMANDS = [
    {"dome": ContinuousMove(pan=-0.8, tilt=0.3, zoom=0.5)},
    {},
    {"dome": [Stop(zoom=False), AbsoluteMove(zoom_x=2.5)]},
    {"dome": GotoPreset("gate", speed=0.5)},
]


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    return write_world(tmp_path_factory.mktemp("sim_world"))


def _run(world, renderer, seed, commands, **options):
    with Simulation(world, renderer=renderer, **options) as sim:
        runs = [sim.reset(seed)]
        runs += [sim.step(step) for step in commands]
    return runs


def test_no_commands_reproduce_camgen_render_frame_for_frame(world, renderer, tmp_path):
    loaded = load_scene(world)  # its dome's program is `hold`; frames: png (lossless, no codec)
    results = execute(
        compile_scene(loaded), tmp_path, renderer=renderer, frames=range(FRAMES), resolve_path=world.parent.joinpath
    )
    runs = _run(world, renderer, None, [{}] * (FRAMES - 1))
    for result in results:
        states = [json.loads(line) for line in (result.directory / "camera.jsonl").read_text().splitlines()]
        for frame, observations in enumerate(runs):
            delivered = observations[result.name]
            png = cv2.imread(str(result.directory / "frames" / f"{frame:06d}.png"), cv2.IMREAD_UNCHANGED)[..., ::-1]
            assert np.array_equal(delivered.rgb8, png), (result.name, frame)
            state = delivered.state
            for key in ("pan_deg", "tilt_deg", "zoom_x", "focus_distance_m", "exposure_time_s", "gain_db", "time_s"):
                assert getattr(state, key) == states[frame][key], (result.name, frame, key)
            assert np.array_equal(state.K_px, states[frame]["K_px"])
            assert np.array_equal(state.T_world_from_cam, states[frame]["T_world_from_cam"])


def test_same_seed_and_commands_give_byte_identical_frames(world, renderer):
    first = _run(world, renderer, 7, COMMANDS, raw=True)
    again = _run(world, renderer, 7, COMMANDS, raw=True)
    other = _run(world, renderer, 8, COMMANDS, raw=True)
    for a, b, c in zip(first, again, other, strict=True):
        for name in ("dome", "overview"):
            assert a[name].rgb8.tobytes() == b[name].rgb8.tobytes()
            assert a[name].raw_dn.tobytes() == b[name].raw_dn.tobytes()
            assert a[name].raw_dn.dtype == np.uint16
            assert a[name].raw_dn.tobytes() != c[name].raw_dn.tobytes()  # the seed draws the noise
        assert a["dome"].state == b["dome"].state
    # The commands moved the head (after the 0.1 s latency) and the view with it.
    assert [run["dome"].status.pan_deg for run in first[:2]] == [0.0, 0.0]
    assert first[-1]["dome"].status.pan_deg < -1.0 and first[-1]["dome"].status.zoom_x > 1.5
    assert not np.array_equal(first[-1]["dome"].rgb8, first[0]["dome"].rgb8)
    assert first[-1]["overview"].state.T_world_from_cam == first[0]["overview"].state.T_world_from_cam


def test_ground_truth_follows_the_commanded_view(world, renderer):
    runs = _run(world, renderer, None, [{"dome": ContinuousMove(pan=-1.0)}, {}, {}], ground_truth=True)
    xs = []
    for observations in runs:
        delivered = observations["dome"]
        (walker,) = delivered.ground_truth.objects
        assert walker.name == "walker" and walker.cls == "person" and walker.visibility == pytest.approx(1.0)
        x0, y0, x1, y1 = walker.visible_box
        xs.append((x0 + x1) / 2)
        # The box holds the walker's projected centre through the frame's own camera state.
        centre = walker.box_3d_world_m.mean(axis=0)
        T_cam_from_world = np.linalg.inv(np.array(delivered.state.T_world_from_cam))
        p = T_cam_from_world[:3, :3] @ centre + T_cam_from_world[:3, 3]
        u, v = (np.array(delivered.state.K_px) @ (p / p[2]))[:2] + 0.5  # pixel-edge coordinates
        assert x0 <= u <= x1 and y0 <= v <= y1
    # Panning right (negative pan) moves the walker left in the image, faster than it walks right.
    assert xs[-1] < xs[0] - 10
    assert runs[-1]["dome"].status.pan_tilt == "MOVING"


def test_bad_commands_are_clear_errors_and_the_world_keeps_running(world, renderer):
    with Simulation(world, renderer=renderer) as sim:
        sim.reset()
        with pytest.raises(CommandError, match=r"no camera 'gate_cam' in .*world.yaml \(cameras: dome, overview\)"):
            sim.step({"gate_cam": Stop()})
        with pytest.raises(
            CommandError, match=r"camera 'overview' is a fixed camera .*ContinuousMove needs a PTZ camera"
        ):
            sim.step({"overview": ContinuousMove(pan=0.5)})
        with pytest.raises(CommandError, match=r"dome: command 1 \(ContinuousMove\): tilt must lie in .* got -2"):
            sim.step({"dome": [ContinuousMove(pan=0.5), ContinuousMove(tilt=-2.0)]})
        with pytest.raises(CommandError, match="pan must be a finite number, got nan"):
            sim.step({"dome": ContinuousMove(pan=math.nan)})
        assert sim.frame == 0  # nothing moved: the good command before the bad one was not given either
        observations = sim.step({"dome": AbsoluteMove(tilt_deg=45.0)})
        assert observations.frame == 1
        observations = sim.step()
        assert observations.events == {
            "dome": ["tilt: AbsoluteMove to 45° is outside the range [-90°, 10°]; clamped to 10°"]
        }
        with pytest.raises(CommandError, match="is a fixed camera"):
            sim.status("overview")
