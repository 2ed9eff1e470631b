"""Steer a PTZ dome with a proportional controller through camgen's gymnasium environment.

The controller sees only what the documented API gives: each step's ground-truth box of the target
(``info["target_box_px"]``, pixel-edge coordinates) and answers with ONVIF ContinuousMove velocities
in [−1, 1] (pan > 0 turns left, tilt > 0 up). It is compared with a head left where it starts.

Usage::

    python examples/sim_tracking.py [SCENE.yaml] [--steps N] [--out DIR]

prints the mean centring error (the target's centre offset as a fraction of the half-diagonal, 1
while the target is unseen) and the frames on target for both, and writes every tenth controlled
frame as PNG into DIR (default ``out/sim_tracking``).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np

REPO = Path(__file__).resolve().parents[1]
DEFAULT_SCENE = REPO / "scenes" / "ptz_follow.yaml"
GAIN = 0.5
"""Pan/tilt velocity (fraction of the fastest) per unit of centre offset (a half-frame)."""
ZOOM_GAIN = 2.0
"""Zoom velocity per unit of height error (target height fraction − wanted)."""


def proportional(info: dict, size_px: tuple[int, int], target_height_frac: float) -> np.ndarray:
    """ContinuousMove (pan, tilt, zoom) towards the target's box: centre it and zoom to its wanted height."""
    box = info["target_box_px"]
    if box is None:
        return np.zeros(3, np.float32)
    width_px, height_px = size_px
    x0, y0, x1, y1 = box
    error_x = ((x0 + x1) / 2 - width_px / 2) / (width_px / 2)
    error_y = ((y0 + y1) / 2 - height_px / 2) / (height_px / 2)
    error_h = target_height_frac - (y1 - y0) / height_px
    return np.clip([-GAIN * error_x, -GAIN * error_y, ZOOM_GAIN * error_h], -1, 1).astype(np.float32)


def episode(env, controller, steps: int, out: Path | None) -> tuple[float, float]:
    """(mean centring error, fraction of frames with the target seen) over one episode."""
    frame, info = env.reset(seed=0)
    errors = []
    for k in range(steps):
        errors.append(1.0 if info["centre_error_frac"] is None else info["centre_error_frac"])
        if out is not None and k % 10 == 0:
            cv2.imwrite(str(out / f"{k:04d}.png"), cv2.resize(frame, None, fx=3, fy=3)[..., ::-1])
        frame, _, terminated, truncated, info = env.step(controller(info))
        if terminated or truncated:
            break
    seen = [e < 1.0 for e in errors]
    return float(np.mean(errors)), float(np.mean(seen))


def main(argv: Sequence[str] | None = None) -> int:
    from camgen.errors import ConfigError
    from camgen.sim.envs import ActiveTrackingEnv

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", type=Path, nargs="?", default=DEFAULT_SCENE, metavar="SCENE")
    parser.add_argument("--steps", type=int, default=150, metavar="N", help="steps per episode (default 150)")
    parser.add_argument("--out", type=Path, default=Path("out/sim_tracking"), metavar="DIR")
    args = parser.parse_args(argv)
    try:
        env = ActiveTrackingEnv(args.scene)
    except ConfigError as exc:
        for problem in exc.problems:
            print(f"error: {problem}", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    height_px, width_px, _ = env.observation_space.shape
    try:
        controlled = episode(
            env, lambda info: proportional(info, (width_px, height_px), env.target_height_frac), args.steps, args.out
        )
        idle = episode(env, lambda info: np.zeros(3, np.float32), args.steps, None)
    finally:
        env.close()
    print(f"{'controller':>12}  mean centring error  frames on target")
    for name, (error, seen) in (("proportional", controlled), ("none", idle)):
        print(f"{name:>12}  {error:19.3f}  {seen:16.1%}")
    print(f"wrote every tenth controlled frame to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
