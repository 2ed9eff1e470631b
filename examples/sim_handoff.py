"""A fixed overview camera cues a PTZ dome onto a person it sees, and the dome takes the person over.

Written only against the documented API (`camgen.sim`). On `scenes/plaza.yaml` the facade bullet sees
`walker_03` from the first frame while the pole PTZ dome, at home, does not. Each frame:

1. **Cue.** The overview's box of the target (ground truth: a perfect detector) gives its feet, the
   bottom centre of the box; undistorted through the overview's own `K_px` and `distortion`
   (`cv2.undistortPoints`), its viewing ray from `T_world_from_cam` meets the ground (z = 0), and the
   aim point is 0.9 m above that (a person's middle).
2. **Aim.** The aim point in the dome's current camera frame (its `T_world_from_cam`) gives the pan and
   tilt offsets, atan2(x, z) / cos(tilt) and atan2(y, z); the dome gets ONVIF AbsoluteMove there.
3. **Hand-off.** Once the dome's own frame shows the target at a useful size (its box ≥ 10 % of the
   frame high: DORI "observe" for a person at 1080 lines), the dome follows it on its own box, leading
   by its command latency, and zooms it to 30 % of the frame height.

Reports the hand-off latency (from the first cue to the dome holding the target), the frames after it
with the target in the dome's frame, the dome's centring error, and the frames neither camera held the
target at a useful size.

Usage::

    python examples/sim_handoff.py [SCENE] [--overview NAME] [--ptz NAME] [--target NAME]
                                   [--resolution WxH] [--out DIR]
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np

from camgen.sim import AbsoluteMove, Simulation
from camgen.sim.metrics import control_metrics

REPO = Path(__file__).resolve().parents[1]
DEFAULT_SCENE = REPO / "scenes" / "plaza.yaml"
AIM_HEIGHT_M = 0.9
"""The aim point above the feet: about the middle of an adult (half of a 1.75 m stature)."""
HOLD_HEIGHT_FRAC = 0.1
"""A camera holds the target when its box is at least this fraction of the frame high."""
HEIGHT_FRAC = 0.3
LEAD_S = 0.14


def box_of(view, target: str):
    return next((o.visible_box for o in view.ground_truth.objects if o.name == target), None)


def ground_point(view, box) -> np.ndarray | None:
    """The world point (z = 0) under the box's bottom centre, seen by `view`'s camera."""
    state = view.state
    K = np.array(state.K_px)
    feet = np.array([[[(box[0] + box[2]) / 2 - 0.5, box[3] - 0.5]]])  # pixel edges → OpenCV centres
    normalised = cv2.undistortPoints(feet, K, np.array(state.distortion)).reshape(2)
    T = np.array(state.T_world_from_cam)
    ray = T[:3, :3] @ np.array([normalised[0], normalised[1], 1.0])
    origin = T[:3, 3]
    if ray[2] >= 0:
        return None  # at or above the horizon
    return origin + ray * (-origin[2] / ray[2])


def aim(view, point: np.ndarray) -> tuple[float, float]:
    """Pan and tilt (degrees, the head's own) that put `point` on the dome's optical axis."""
    state = view.state
    T = np.array(state.T_world_from_cam)
    x, y, z = T[:3, :3].T @ (point - T[:3, 3])
    pan = state.pan_deg - math.degrees(math.atan2(x, z)) / math.cos(math.radians(state.tilt_deg))
    tilt = state.tilt_deg - math.degrees(math.atan2(y, math.hypot(x, z)))
    return pan, tilt


def run(sim: Simulation, overview: str, ptz: str, target: str, out: Path | None) -> dict:
    observed = sim.reset(seed=0)
    cue_frame = hold_frame = None
    handed_off = False
    history: list[tuple[float, float, float]] = []
    dome_boxes, gaps = [], 0
    for k in range(sim.frame_count):
        wide, dome = observed[overview], observed[ptz]
        wide_box, dome_box = box_of(wide, target), box_of(dome, target)
        height_px = dome.rgb8.shape[0]
        dome_holds = dome_box is not None and dome_box[3] - dome_box[1] >= HOLD_HEIGHT_FRAC * height_px
        wide_holds = wide_box is not None and wide_box[3] - wide_box[1] >= HOLD_HEIGHT_FRAC * wide.rgb8.shape[0]
        if wide_box is not None and cue_frame is None:
            cue_frame = k
        if dome_holds and not handed_off:
            handed_off, hold_frame = True, k
        if handed_off:
            dome_boxes.append(dome_box)
        gaps += cue_frame is not None and not (dome_holds or wide_holds)
        if out is not None and k % 10 == 0:
            cv2.imwrite(str(out / f"{k:04d}.png"), np.hstack([wide.rgb8, dome.rgb8])[..., ::-1])
        if observed.frame + 1 >= sim.frame_count:
            break
        command = None
        if handed_off and dome_box is not None:  # follow on the dome's own box
            state = dome.state
            K = np.array(state.K_px)
            u, v = (dome_box[0] + dome_box[2]) / 2 - 0.5, (dome_box[1] + dome_box[3]) / 2 - 0.5
            pan = state.pan_deg - math.degrees(math.atan((u - K[0, 2]) / K[0, 0])) / math.cos(
                math.radians(state.tilt_deg)
            )
            tilt = state.tilt_deg - math.degrees(math.atan((v - K[1, 2]) / K[1, 1]))
            history.append((dome.time_s, pan, tilt))
            if len(history) >= 2:
                dt = history[-1][0] - history[-2][0]
                pan += LEAD_S * (history[-1][1] - history[-2][1]) / dt
                tilt += LEAD_S * (history[-1][2] - history[-2][2]) / dt
            box_height = dome_box[3] - dome_box[1]
            zoom_x = state.zoom_x * min(max(HEIGHT_FRAC * height_px / box_height, 0.8), 1.2)
            command = AbsoluteMove(pan_deg=pan, tilt_deg=tilt, zoom_x=zoom_x)
        elif wide_box is not None:  # cue from the overview
            point = ground_point(wide, wide_box)
            if point is not None:
                pan, tilt = aim(dome, point + np.array([0.0, 0.0, AIM_HEIGHT_M]))
                command = AbsoluteMove(pan_deg=pan, tilt_deg=tilt)
        observed = sim.step({ptz: command} if command is not None else {})
    return {
        "cue_frame": cue_frame,
        "hold_frame": hold_frame,
        "dome_boxes": dome_boxes,
        "gap_frames": gaps,
        "frames": k + 1,
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", type=Path, nargs="?", default=DEFAULT_SCENE, metavar="SCENE")
    parser.add_argument("--overview", default="facade_bullet")
    parser.add_argument("--ptz", default="pole_ptz")
    parser.add_argument("--target", default="walker_03")
    parser.add_argument("--resolution", default="160x90", metavar="WxH")
    parser.add_argument("--out", type=Path, metavar="DIR", help="write every 10th frame pair (overview | dome)")
    args = parser.parse_args(argv)
    width_px, height_px = (int(v) for v in args.resolution.lower().split("x"))
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
    with Simulation(args.scene, ground_truth=True, resolution_px=(width_px, height_px)) as sim:
        result = run(sim, args.overview, args.ptz, args.target, args.out)
        fps = sim.fps
    if result["cue_frame"] is None:
        print(f"{args.overview} never saw {args.target}: no cue")
        return 1
    if result["hold_frame"] is None:
        print(f"{args.ptz} never took {args.target} over in {result['frames']} frames")
        return 1
    latency_s = (result["hold_frame"] - result["cue_frame"]) / fps
    scores = control_metrics(result["dome_boxes"], (width_px, height_px), fps)
    print(
        f"hand-off of {args.target} from {args.overview} to {args.ptz}: {latency_s:.2f} s after the first cue "
        f"(frame {result['cue_frame']} → {result['hold_frame']}); after it the target was in the dome's frame "
        f"{scores.in_frame_frac:.1%} of {scores.frames} frames, centring error {scores.centring_error_px:.2f} px "
        f"({scores.centring_error_frac:.3f} of the half-diagonal), height {scores.height_frac:.3f} of the frame; "
        f"{result['gap_frames']} frame(s) with neither camera holding it"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
