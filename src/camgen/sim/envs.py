"""Gymnasium environments on the stepping API (optional extra ``sim``: ``pip install camgen[sim]``).

``camgen/ActiveTracking-v0`` (`ActiveTrackingEnv`): one PTZ camera follows one walking actor.
Importing this module registers it, so ``gymnasium.make("camgen/ActiveTracking-v0", scene=...)`` works
after ``import camgen.sim.envs``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from camgen.errors import ConfigError
from camgen.plan.annotations import ObjectAnnotation
from camgen.sim.commands import velocity_action
from camgen.sim.simulation import Observations, Simulation, stream_size_px

DEFAULT_SCENE = Path(__file__).resolve().parents[3] / "scenes" / "ptz_follow.yaml"
"""The parking lot's pole-mounted dome following walker_1 (in a source checkout)."""
RESOLUTION_PX = (128, 96)
"""Default observation size (W, H), px: the camera read out over its whole sensor at this size (the
field of view is kept), so a step of the parking lot costs tens of milliseconds, not a 1080p frame's
second."""
SEED_MAX = 2**31 - 1


class ActiveTrackingEnv(gymnasium.Env):
    """Keep a walking actor centred and at a chosen size in a PTZ camera's frame.

    Observation: the camera's delivered frame, ``Box(0, 255, (H, W, 3), uint8)`` (full lens, sensor,
    ISP; (W, H) = `resolution_px`, default 128 × 96). Action: ONVIF ContinuousMove velocities
    ``(pan, tilt, zoom)`` in ``[−1, 1]³``, each a fraction of the head's fastest (pan > 0 turns left,
    tilt > 0 up, zoom > 0 towards tele); the head answers with the profile's acceleration and command
    latency. One step is one frame period of the scene.

    Reward, from the ground truth (the target's visible box, pixel-edge coordinates, W × H frame)::

        e = ((x_c − W/2) / (W/2), (y_c − H/2) / (H/2))          centre offset, each in [−1, 1]
        reward = (1 − min(|e| / √2, 1)) − |h / H − target_height_frac|   while the target is seen
        reward = −1                                                     while it is not

    so 1 is the target centred at the wanted height and the centring term falls to 0 at a corner.
    Termination: the target unseen for `lost_frames` consecutive frames (terminated); the scene's end
    (truncated). `info` holds the target's visible box (x0, y0, x1, y1) px or None, the centre offset
    ``centre_error_frac`` (|e| / √2), the head's status and what it reported (clamps, range ends).

    Parameters
    ----------
    scene : path or None
        A scene YAML; default ``scenes/ptz_follow.yaml`` of a source checkout.
    camera : str or None
        The PTZ camera (default the scene's first PTZ camera).
    target : str or None
        The actor to follow (default the camera's follow-program target, else the first actor).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(
        self,
        scene: str | Path | None = None,
        *,
        camera: str | None = None,
        target: str | None = None,
        resolution_px: tuple[int, int] = RESOLUTION_PX,
        target_height_frac: float = 0.3,
        lost_frames: int = 10,
        render_mode: str | None = None,
        renderer=None,
    ):
        path = Path(DEFAULT_SCENE if scene is None else scene)
        if not path.is_file():
            raise ConfigError(f"{path}: no such scene file; pass scene= a scene YAML with a PTZ camera")
        if not 0 < target_height_frac <= 1:
            raise ConfigError(f"target_height_frac must be in (0, 1], got {target_height_frac!r}")
        if not (isinstance(lost_frames, int) and lost_frames >= 1):
            raise ConfigError(f"lost_frames must be a whole number ≥ 1, got {lost_frames!r}")
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        from camgen.config import load_scene

        loaded = load_scene(path)
        ptz = [c for c in loaded.scene.cameras if c.head is not None]
        if not ptz:
            raise ConfigError(f"{path}: has no PTZ camera (a camera with a ptz or eptz block) to steer")
        chosen = ptz[0] if camera is None else next((c for c in loaded.scene.cameras if c.name == camera), None)
        if chosen is None:
            names = ", ".join(c.name for c in ptz)
            raise ConfigError(f"camera={camera!r}: no such camera in {path} (PTZ cameras: {names})")
        actors = [actor.name for actor in loaded.scene.actors]
        program = chosen.head.program if chosen.head is not None else None
        if target is None:
            target = getattr(program, "target", None) or (actors[0] if actors else None)
        if target not in actors:
            raise ConfigError(f"target={target!r}: no such actor in {path} (actors: {', '.join(actors) or 'none'})")
        self.sim = Simulation(
            loaded, ground_truth=True, resolution_px=resolution_px, renderer=renderer, cameras=[chosen.name]
        )
        self.camera_name, self.target = chosen.name, target
        self.target_height_frac, self.lost_frames = target_height_frac, lost_frames
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": self.sim.fps}
        width_px, height_px = stream_size_px(self.sim.camera_job(chosen.name))
        self.observation_space = spaces.Box(0, 255, (height_px, width_px, 3), np.uint8)
        self.action_space = spaces.Box(-1.0, 1.0, (3,), np.float32)
        self._frame: np.ndarray | None = None
        self._unseen = 0

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Start the scene over. `seed` seeds the noise (and this env's generator); without one, each
        episode's noise seed is drawn from the env's generator."""
        super().reset(seed=seed)
        noise_seed = int(self.np_random.integers(SEED_MAX))
        self._unseen = 0
        observation, _, _, _, info = self._result(self.sim.reset(noise_seed))
        return observation, info

    def step(self, action):
        move = velocity_action(action, f"{self.camera_name}: action")
        observations = self.sim.step({self.camera_name: move})
        return self._result(observations)

    def _result(self, observations: Observations):
        seen = self.sim.camera_job(self.camera_name)
        width_px, height_px = stream_size_px(seen)
        delivered = observations[self.camera_name]
        target = _find(delivered.ground_truth.objects, self.target)
        box = None if target is None else target.visible_box
        info: dict[str, Any] = {
            "frame": observations.frame,
            "time_s": observations.time_s,
            "target_box_px": box,
            "status": delivered.status,
            "events": observations.events.get(self.camera_name, []),
        }
        if box is None:
            self._unseen += 1
            reward, info["centre_error_frac"] = -1.0, None
        else:
            self._unseen = 0
            x0, y0, x1, y1 = box
            offset = math.hypot(
                ((x0 + x1) / 2 - width_px / 2) / (width_px / 2), ((y0 + y1) / 2 - height_px / 2) / (height_px / 2)
            )
            centre_error = min(offset / math.sqrt(2.0), 1.0)
            size_error = abs((y1 - y0) / height_px - self.target_height_frac)
            reward = (1.0 - centre_error) - size_error
            info["centre_error_frac"] = centre_error
        terminated = self._unseen >= self.lost_frames
        truncated = observations.frame >= self.sim.frame_count - 1
        self._frame = delivered.rgb8
        return delivered.rgb8, float(reward), terminated, truncated, info

    def render(self):
        return None if self.render_mode is None else self._frame

    def close(self) -> None:
        self.sim.close()


def _find(objects: list[ObjectAnnotation], name: str) -> ObjectAnnotation | None:
    return next((obj for obj in objects if obj.name == name), None)


gymnasium.register(id="camgen/ActiveTracking-v0", entry_point="camgen.sim.envs:ActiveTrackingEnv")
