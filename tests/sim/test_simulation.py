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


def test_a_turning_head_is_drawn_from_its_canvas_reproducibly(world, renderer):
    """A pan alone (no zoom) draws the turned frames from the turn canvas (`turns_reprojected`): the
    same commands give the same bytes again, and frames within resampling of every turned frame drawn whole (the
    frames after the head stops are drawn whole again: test_turned_frames; delivered, they can still differ by a
    code value where auto-exposure, which remembers the turned frames, settled a hair apart)."""
    commands = [{"dome": ContinuousMove(pan=-0.6)}, {}, {}, {}, {"dome": Stop()}, {}, {}]
    canvas = _run(world, renderer, 3, commands, turns_reprojected=True)
    again = _run(world, renderer, 3, commands, turns_reprojected=True)
    whole = _run(world, renderer, 3, commands, turns_reprojected=False)
    for a, b in zip(canvas, again, strict=True):
        assert a["dome"].rgb8.tobytes() == b["dome"].rgb8.tobytes()
    turned = [k for k, run in enumerate(canvas) if run["dome"].status.pan_deg != canvas[k - 1]["dome"].status.pan_deg]
    assert len(turned) >= 3, turned
    differ = 0
    for k in turned:
        a, b = canvas[k]["dome"].rgb8.astype(float), whole[k]["dome"].rgb8.astype(float)
        psnr_db = 10 * np.log10(255**2 / max(np.mean((a - b) ** 2), 1e-12))
        assert psnr_db > 30, (k, psnr_db)
        differ += not np.array_equal(a, b)
    assert differ >= 2  # the canvas drew them


def test_by_default_a_small_readout_draws_turned_frames_whole(world, renderer, monkeypatch):
    """`turns_reprojected` None decides by each camera's readout: from TURN_CANVAS_MIN_PX pixels the canvas, below
    it every turned frame drawn whole (a small step's cost is its fixed costs; the canvas would only resample)."""
    from camgen.sim import simulation

    def reprojected(size) -> list[bool]:
        with Simulation(world, renderer=renderer, resolution_px=size) as sim:
            return [drawer.turns_reprojected for drawer in sim._drawers.values()]

    assert simulation.TURN_CANVAS_MIN_PX == 320 * 240
    assert reprojected((80, 60)) == [False, False]  # the dome and the overview
    monkeypatch.setattr(simulation, "TURN_CANVAS_MIN_PX", 160 * 120)  # the test world's sensors are 160×120
    assert reprojected((160, 120)) == [True, True]
    assert reprojected((80, 60)) == [False, False]


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
        with pytest.raises(
            CommandError, match=r"dome: command 1 \(GotoPreset\): no preset 'nowhere' \(presets: gate\)"
        ):
            sim.step({"dome": [ContinuousMove(pan=0.5), GotoPreset("nowhere")]})
        with pytest.raises(CommandError, match=r"dome: expected a PTZ command or a list of them, got 'left'"):
            sim.step({"dome": "left"})
        assert sim.commands == []  # none of the refused steps' commands was given
        assert sim.frame == 0  # nothing moved: the good command before the bad one was not given either
        observations = sim.step({"dome": AbsoluteMove(tilt_deg=45.0)})
        assert observations.frame == 1
        observations = sim.step()
        assert observations.events == {
            "dome": ["tilt: AbsoluteMove to 45° is outside the range [-90°, 10°]; clamped to 10°"]
        }
        # GetStatus says it too (ONVIF's PTZStatus Error), in the observation and when asked
        status = sim.status("dome")
        assert status.error == "tilt: AbsoluteMove to 45° is outside the range [-90°, 10°]; clamped to 10°"
        assert (status.clamp.requested_tilt_deg, status.clamp.clamped_tilt_deg) == (45.0, 10.0)
        assert observations.cameras["dome"].status.clamp == status.clamp
        with pytest.raises(CommandError, match="is a fixed camera"):
            sim.status("overview")


def _crate_edge_width_px(rgb8: np.ndarray) -> int:
    """Columns over which the blue crate's right edge rises from 10 % to 90 % of its step (blue minus
    red, averaged over the crate's rows; the crate fills columns ~0–40 of the dome's view at pan 5°)."""
    rows = rgb8[20:55, :80].astype(np.float32)
    profile = (rows[..., 2] - rows[..., 0]).mean(axis=0)
    crate, ground = profile[10:38].mean(), profile[50:80].mean()
    step = (profile[20:70] - ground) / (crate - ground)
    return int(np.sum((step > 0.1) & (step < 0.9)))


def test_a_turning_head_blurs_its_frames_along_the_turn(renderer, tmp_path):
    # Dusk (20 lux): auto-exposure opens to ~7.6 ms, over which the full-speed pan sweeps ~6.6 px.
    dusk = write_world(tmp_path, illuminance_lux=20.0, duration_s=2.5, dome_pan_deg=-30.0)
    with Simulation(dusk, renderer=renderer, cameras=["dome"]) as sim:
        sim.reset()
        for _ in range(7):  # 0.1 s latency, then 0.5 s (25°) to the full 100°/s: the crate is in view
            turning = sim.step({"dome": ContinuousMove(pan=1.0)})["dome"]
        assert turning.state.pan_deg_s == pytest.approx(100.0)
        sim.step({"dome": AbsoluteMove(pan_deg=turning.state.pan_deg)})
        still = sim.step()["dome"]
        while still.status.pan_tilt == "MOVING" and still.frame < 24:  # brakes from 100°/s, comes back
            still = sim.step()["dome"]
        assert still.status.pan_tilt == "IDLE" and still.state.pan_deg == pytest.approx(turning.state.pan_deg, abs=0.01)
    # The same view: a box blur of length L = f·ω·t_exposure along the pan rises 10–90 % over 0.8·L.
    sweep_px = turning.state.K_px[0][0] * np.radians(100.0) * turning.state.exposure_time_s
    assert _crate_edge_width_px(turning.rgb8) == pytest.approx(0.8 * sweep_px, abs=1.5)
    assert _crate_edge_width_px(still.rgb8) <= 2


def test_a_resolution_finer_than_a_sensor_is_a_clear_error(world):
    """Binning keeps each pixel's electrons (quantum efficiency over the area ratio): a finer grid would need a
    quantum efficiency over 1, which the profile's validation refused with a traceback."""
    from camgen.errors import ConfigError

    finer = r"resolution_px 320×120 is finer than the sensor of camera '\w+' \(160×120 px, "
    with pytest.raises(ConfigError, match=finer):
        Simulation(world, resolution_px=(320, 120))
    Simulation(world, resolution_px=(160, 120)).close()  # the sensors' own size still opens


def test_a_held_head_tests_no_mover_for_blur_the_plan_left_out(renderer, monkeypatch, tmp_path):
    """The plan finds a slow walker too slow to blur, so it has no motion-blur stage; the simulation adds
    one for the dome's turns only (``actors_blur`` False): a held step places the actors at the frame time
    alone, as `camgen render`'s frames of the plan do (the blur test places them at the exposure's ends too)."""
    from camgen.render.scene_graph import SceneGraph

    times: list[float] = []
    placing = SceneGraph.place_actors

    def place(self, time_s):
        times.append(time_s)
        return placing(self, time_s)

    slow = write_world(tmp_path, speed_m_s=0.05, illuminance_lux=20000.0)
    with Simulation(slow, renderer=renderer, cameras=["dome"]) as sim:
        stage = next(s for s in sim.camera_job("dome").stages if s.name == "optics.motion_blur")
        assert stage.params["actors_blur"] is False and stage.params["displacement_max_px"] == 0.0
        sim.reset(0)
        monkeypatch.setattr(SceneGraph, "place_actors", place)
        observed = [sim.step({}) for _ in range(2)]
    frame_times = {observation.time_s for observation in observed}
    assert times and set(times) <= frame_times, (sorted(set(times)), frame_times)
