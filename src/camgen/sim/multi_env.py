"""A camera network as a multi-agent environment (PettingZoo's parallel API; optional extra ``sim``).

`CameraNetworkEnv`: one agent per camera of a scene, all stepping together, for hand-off and
cooperative coverage. ``pettingzoo.test.parallel_api_test`` passes on it (tested).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from camgen.errors import ConfigError
from camgen.sim.commands import velocity_action
from camgen.sim.simulation import Observations, Simulation, stream_size_px

RESOLUTION_PX = (128, 96)
"""Default observation size (W, H), px, of every camera (the field of view is kept; see
`camgen.sim.envs.RESOLUTION_PX`)."""
MIN_HEIGHT_FRAC = 0.1
"""A target is held at a useful size when its visible box is at least this fraction of the frame high:
a 1.75 m person 108 px high in a 1080-line frame is 62 px/m, IEC 62676-4:2014's DORI "observe"
density."""
HANDOFF_BONUS = 0.5
"""Reward to a camera for each target it takes over (see `CameraNetworkEnv`)."""
SEED_MAX = 2**31 - 1


class CameraNetworkEnv(ParallelEnv):
    """Every camera of a scene is an agent; PTZ cameras steer, fixed cameras observe.

    Agents: the scene's camera names. Observation of each: its delivered frame, ``Box(0, 255, (H, W, 3),
    uint8)``. Action of a PTZ camera (mechanical or electronic): ONVIF ContinuousMove velocities
    ``(pan, tilt, zoom)`` in ``[−1, 1]³`` (as `camgen.sim.envs.ActiveTrackingEnv`); of a fixed camera:
    ``Discrete(1)``, the only thing it does being to watch.

    A camera *holds* a target at a frame when the target's visible box (ground truth) is at least
    `min_height_frac` of that camera's frame high. Each step, with S(k) the cameras holding target k
    now and S′(k) those that held it one frame before::

        coverage = |{k : S(k) ≠ ∅}| / K                    targets held by the network, in [0, 1]
        handoffs(i) = |{k : i ∈ S(k), i ∉ S′(k), S′(k) ∖ {i} ≠ ∅}|   targets camera i took over from another
        reward(i) = coverage + handoff_bonus · handoffs(i)

    so the network is paid for every target kept in view at a useful size, shared by all cameras
    (cooperation), and a camera is paid for acquiring a target another camera holds (a hand-off before
    the target is lost). Targets: `targets` (default every person, else every actor). No agent
    terminates (a target may come back); all are truncated at the scene's end.

    `infos[camera]`: ``frame``, ``time_s``, ``boxes`` (target → visible box (x0, y0, x1, y1) px or None),
    ``held`` (the targets this camera holds), ``handoffs`` (those it took over this step), ``coverage``,
    ``status`` (the head's GetStatus, None for a fixed camera) and ``events`` (clamps, range ends).
    """

    metadata = {"name": "camgen_camera_network_v0", "render_modes": []}

    def __init__(
        self,
        scene: str | Path,
        *,
        targets: list[str] | None = None,
        resolution_px: tuple[int, int] = RESOLUTION_PX,
        min_height_frac: float = MIN_HEIGHT_FRAC,
        handoff_bonus: float = HANDOFF_BONUS,
        renderer=None,
    ):
        if not 0 < min_height_frac <= 1:
            raise ConfigError(f"min_height_frac must be in (0, 1], got {min_height_frac!r}")
        if not handoff_bonus >= 0:
            raise ConfigError(f"handoff_bonus must be ≥ 0, got {handoff_bonus!r}")
        self.sim = Simulation(scene, ground_truth=True, resolution_px=resolution_px, renderer=renderer)
        source = self.sim.loaded.scene
        actors = [actor.name for actor in source.actors]
        people = [actor.name for actor in source.actors if actor.cls == "person"]
        chosen = list(targets) if targets is not None else (people or actors)
        unknown = [name for name in chosen if name not in actors]
        if unknown or not chosen:
            raise ConfigError(
                f"targets={targets!r}: {'no such actor ' + repr(unknown[0]) if unknown else 'none to follow'} in "
                f"{self.sim.loaded.path} (actors: {', '.join(actors) or 'none'})"
            )
        self.targets = chosen
        self.min_height_frac, self.handoff_bonus = min_height_frac, handoff_bonus
        self.possible_agents = list(self.sim.camera_names)
        self.agents: list[str] = []
        self.ptz_agents = [camera.name for camera in self.sim.scene.cameras if camera.head is not None]
        self._observation_spaces = {}
        self._action_spaces = {}
        for name in self.possible_agents:
            width_px, height_px = stream_size_px(self.sim.camera_job(name))
            self._observation_spaces[name] = spaces.Box(0, 255, (height_px, width_px, 3), np.uint8)
            self._action_spaces[name] = (
                spaces.Box(-1.0, 1.0, (3,), np.float32) if name in self.ptz_agents else spaces.Discrete(1)
            )
        self._held: dict[str, set[str]] = {}
        self._rng = np.random.default_rng()

    def observation_space(self, agent: str) -> spaces.Space:
        """The same object at every call (PettingZoo's test asks so)."""
        return self._observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Space:
        return self._action_spaces[agent]

    def reset(self, seed: int | None = None, options: dict[str, Any] | None = None):
        """Start the scene over; `seed` seeds the noise (without one, drawn from the env's generator)."""
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        self.agents = list(self.possible_agents)
        self._held = {}
        observations, _, infos = self._result(self.sim.reset(int(self._rng.integers(SEED_MAX))))
        return observations, infos

    def step(self, actions: dict[str, Any]):
        commands = {}
        for agent, action in actions.items():
            if agent not in self.agents:
                raise ConfigError(f"action for {agent!r}, which is not a live agent (agents: {', '.join(self.agents)})")
            if agent in self.ptz_agents:
                commands[agent] = velocity_action(action, f"{agent}: action")
        observations, rewards, infos = self._result(self.sim.step(commands))
        truncated = self.sim.frame >= self.sim.frame_count - 1
        terminations = dict.fromkeys(self.agents, False)
        truncations = dict.fromkeys(self.agents, truncated)
        if truncated:
            self.agents = []
        return observations, rewards, terminations, truncations, infos

    def _result(self, observed: Observations):
        held_now: dict[str, set[str]] = {}
        boxes: dict[str, dict[str, tuple | None]] = {}
        for agent in self.possible_agents:
            delivered = observed[agent]
            height_px = delivered.rgb8.shape[0]
            seen = {obj.name: obj.visible_box for obj in delivered.ground_truth.objects if obj.name in self.targets}
            boxes[agent] = {name: seen.get(name) for name in self.targets}
            held_now[agent] = {
                name
                for name, box in seen.items()
                if box is not None and (box[3] - box[1]) >= self.min_height_frac * height_px
            }
        holders_now = {k: {a for a in self.possible_agents if k in held_now[a]} for k in self.targets}
        holders_before = {k: {a for a in self.possible_agents if k in self._held.get(a, ())} for k in self.targets}
        coverage = sum(1 for k in self.targets if holders_now[k]) / len(self.targets)
        observations, rewards, infos = {}, {}, {}
        for agent in self.agents:
            taken = sorted(
                k
                for k in self.targets
                if agent in holders_now[k] and agent not in holders_before[k] and holders_before[k] - {agent}
            )
            delivered = observed[agent]
            observations[agent] = delivered.rgb8
            rewards[agent] = float(coverage + self.handoff_bonus * len(taken))
            infos[agent] = {
                "frame": observed.frame,
                "time_s": observed.time_s,
                "boxes": boxes[agent],
                "held": sorted(held_now[agent]),
                "handoffs": taken,
                "coverage": coverage,
                "status": delivered.status,
                "events": observed.events.get(agent, []),
            }
        self._held = held_now
        return observations, rewards, infos

    def render(self):
        return None

    def close(self) -> None:
        self.sim.close()
