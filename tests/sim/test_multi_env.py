"""camgen.sim.multi_env.CameraNetworkEnv: PettingZoo's parallel API test, and the reward's coverage
and hand-off terms checked against the ground truth they are defined on."""

from __future__ import annotations

import numpy as np
import pytest

pettingzoo_test = pytest.importorskip("pettingzoo.test")

from camgen.errors import ConfigError  # noqa: E402
from camgen.sim.multi_env import CameraNetworkEnv  # noqa: E402
from tests.sim.scenes import write_world  # noqa: E402

pytestmark = pytest.mark.opengl

RESOLUTION_PX = (80, 60)


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    # 0.8 s at 10 fps: 8 steps per episode. The walker starts 2.6 m left, in the overview's view (its 27°
    # field from 12 m) but not the dome's (18° from 10 m), and walks into the dome's at ~0.35 s.
    return write_world(tmp_path_factory.mktemp("multi_world"), duration_s=0.8, start_x_m=-2.6, speed_m_s=3.0)


def test_parallel_api_test_passes(world, renderer):
    env = CameraNetworkEnv(world, resolution_px=RESOLUTION_PX, renderer=renderer)
    try:
        pettingzoo_test.parallel_api_test(env, num_cycles=20)
        assert env.possible_agents == ["dome", "overview"]
        assert env.action_space("dome").shape == (3,) and env.action_space("overview").n == 1
    finally:
        env.close()


def test_reward_is_coverage_plus_the_handoff_bonus(world, renderer):
    env = CameraNetworkEnv(world, resolution_px=RESOLUTION_PX, renderer=renderer, min_height_frac=0.05)
    try:
        observations, infos = env.reset(seed=5)
        for agent in env.agents:
            assert env.observation_space(agent).contains(observations[agent])
        held_before = {agent: set(infos[agent]["held"]) for agent in env.agents}
        assert held_before == {"dome": set(), "overview": {"walker"}}
        # The walker enters the still dome's view while the overview holds it: a hand-off to the dome.
        handoffs = 0
        for _ in range(8):
            actions = {"dome": np.zeros(3, np.float32), "overview": 0}
            observations, rewards, terminations, truncations, infos = env.step(actions)
            for agent in rewards:
                boxes = infos[agent]["boxes"]
                held = {
                    name
                    for name, box in boxes.items()
                    if box is not None and box[3] - box[1] >= 0.05 * RESOLUTION_PX[1]
                }
                assert set(infos[agent]["held"]) == held
            covered = set().union(*(set(infos[a]["held"]) for a in infos))
            for agent in rewards:
                taken = {
                    name
                    for name in infos[agent]["held"]
                    if name not in held_before[agent] and any(name in held_before[o] for o in held_before if o != agent)
                }
                assert set(infos[agent]["handoffs"]) == taken
                assert rewards[agent] == pytest.approx(len(covered) / 1 + 0.5 * len(taken))
                handoffs += len(taken)
            held_before = {agent: set(infos[agent]["held"]) for agent in infos}
            if all(truncations.values()):
                break
        assert handoffs == 1 and held_before == {"dome": {"walker"}, "overview": {"walker"}}
        assert not any(terminations.values())
    finally:
        env.close()


def test_bad_arguments_name_the_fix(world, renderer):
    with pytest.raises(ConfigError, match=r"targets=\['ghost'\]: no such actor 'ghost' in .* \(actors: walker\)"):
        CameraNetworkEnv(world, targets=["ghost"], renderer=renderer)
    with pytest.raises(ConfigError, match="min_height_frac must be in"):
        CameraNetworkEnv(world, min_height_frac=0.0, renderer=renderer)


def test_bad_actions_are_clear_errors_and_the_world_keeps_running(world, renderer):
    from camgen.sim import CommandError

    env = CameraNetworkEnv(world, resolution_px=RESOLUTION_PX, renderer=renderer)
    try:
        env.reset(seed=1)
        with pytest.raises(CommandError, match="dome: action: pan must be a finite number, got nan"):
            env.step({"dome": np.array([np.nan, 0, 0]), "overview": 0})
        with pytest.raises(CommandError, match=r"dome: action: the action must be three numbers .* got 2"):
            env.step({"dome": [0.5, 0.1], "overview": 0})
        with pytest.raises(CommandError, match=r"dome: action: tilt must lie in ONVIF's normalised space"):
            env.step({"dome": [0.0, -1.5, 0.0], "overview": 0})
        _, _, _, _, infos = env.step({"dome": np.zeros(3, np.float32), "overview": 0})
        assert infos["dome"]["frame"] == 1
    finally:
        env.close()
