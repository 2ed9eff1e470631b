"""camgen.sim.envs.ActiveTrackingEnv: gymnasium's checks, and a proportional controller on the ground
truth keeps the walker nearer the image centre than a head left alone."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from camgen.errors import ConfigError
from camgen.sim.envs import ActiveTrackingEnv
from tests.sim.scenes import write_world

pytestmark = pytest.mark.opengl

RESOLUTION_PX = (80, 60)
GAIN = 0.5
"""Proportional gain: a target at the frame edge asks for half the head's fastest pan (50 deg/s here, ~5.5/s on
the 18° view: fast enough for the walker's 11°/s, slow enough for the 0.1 s latency and the frame period)."""


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    # The walker starts left of the dome's view and walks right out of it within the 2 s.
    return write_world(tmp_path_factory.mktemp("env_world"), duration_s=2.0, start_x_m=-1.0, speed_m_s=2.0)


def proportional(info: dict, size_px: tuple[int, int]) -> np.ndarray:
    """Pan and tilt towards the ground-truth box's centre (pan > 0 turns left, tilt > 0 up)."""
    box = info["target_box_px"]
    if box is None:
        return np.zeros(3, np.float32)
    width_px, height_px = size_px
    x0, y0, x1, y1 = box
    error_x = ((x0 + x1) / 2 - width_px / 2) / (width_px / 2)
    error_y = ((y0 + y1) / 2 - height_px / 2) / (height_px / 2)
    return np.clip([-GAIN * error_x, -GAIN * error_y, 0.0], -1, 1).astype(np.float32)


def _episode(env, controller) -> list[float | None]:
    _, info = env.reset(seed=3)
    errors = [info["centre_error_frac"]]
    done = False
    while not done:
        _, _, terminated, truncated, info = env.step(controller(info))
        errors.append(info["centre_error_frac"])
        done = terminated or truncated
    return errors


def test_check_env_passes(world, renderer):
    env = ActiveTrackingEnv(world, resolution_px=RESOLUTION_PX, renderer=renderer)
    try:
        check_env(env, skip_render_check=True)
        assert env.observation_space.shape == (60, 80, 3) and env.observation_space.dtype == np.uint8
        assert (env.camera_name, env.target) == ("dome", "walker")
    finally:
        env.close()


def test_registered_with_gymnasium(world, renderer):
    env = gymnasium.make("camgen/ActiveTracking-v0", scene=world, resolution_px=RESOLUTION_PX, renderer=renderer)
    try:
        observation, info = env.reset(seed=1)
        assert observation.shape == (60, 80, 3) and info["target_box_px"] is not None
    finally:
        env.close()


def test_proportional_controller_keeps_the_walker_nearer_the_centre(world, renderer):
    env = ActiveTrackingEnv(world, resolution_px=RESOLUTION_PX, renderer=renderer)
    try:
        controlled = _episode(env, lambda info: proportional(info, RESOLUTION_PX))
        idle = _episode(env, lambda info: np.zeros(3, np.float32))
    finally:
        env.close()
    # Unseen frames count as the worst error (1).
    score = [np.mean([1.0 if e is None else e for e in errors]) for errors in (controlled, idle)]
    assert None not in controlled  # the controller never loses the walker
    assert None in idle  # left alone, the head lets it walk out of the frame
    assert score[0] < 0.6 * score[1], score  # measured 0.20 against 0.51


def test_bad_arguments_name_the_fix(world, renderer):
    with pytest.raises(ConfigError, match=r"camera='gate': no such camera .* \(PTZ cameras: dome\)"):
        ActiveTrackingEnv(world, camera="gate", renderer=renderer)
    with pytest.raises(ConfigError, match=r"target='nobody': no such actor .* \(actors: walker\)"):
        ActiveTrackingEnv(world, target="nobody", renderer=renderer)
