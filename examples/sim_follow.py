"""Follow a walker with a PTZ dome through camgen's stepping API, and score how well it was kept.

Written only against the documented API (`camgen.sim`: `Simulation`, `AbsoluteMove`, the command log
and `camgen.sim.metrics.control_metrics`). Two trackers steer the same controller:

- ``--tracker truth`` (box centring): the target's ground-truth visible box in each delivered frame
  (``observation.ground_truth``), as a perfect detector would give it.
- ``--tracker camshift``: OpenCV CamShift on the delivered 8-bit frames alone (Bradski 1998,
  "Computer vision face tracking for use in a perceptual user interface"), started from the target's
  box in the first frame it is seen (the cue an operator's click or a detector gives) with a hue-
  saturation histogram; between frames its window is moved by the image motion the head's own change
  of pan, tilt and zoom causes (from each frame's camera state), as PTZ trackers compensate ego-motion,
  and it searches only half a box around there. Mean shift (CamShift's core) moves the window onto the
  colour; the box keeps the first box's offset from the colour (the jacket sits high on the body) and
  its size follows the zoom alone (CamShift's own size estimate spread over the red parked car, the
  jacket's colour, and was not used). Passing in front of that car, the window can still stick to it.
  The ground truth is used only to score it.

The controller: each frame it turns the box's offset from the principal point into angles
(atan(dx / fx), divided by cos(tilt) for pan), estimates the target's angular velocity from the last
two frames, and sends ONVIF AbsoluteMove to where the target will be one `--lead-s` later (the head's
command latency plus a frame); it zooms so the box spans `--height-frac` of the frame (at most ±20 %
a frame, and only while the target is near the centre). An AbsoluteMove, unlike a relative one, does
not add up when several are in flight during the latency.

Usage::

    python examples/sim_follow.py [SCENE] [--tracker truth|camshift] [--resolution WxH] [--steps N]
                                  [--log FILE] [--out DIR]

prints the fraction of frames with the target in frame, the mean centring error (px and as a fraction
of the half-diagonal) and the target's mean height; `--log` saves the command log (replay it with
``camgen sim replay LOG SCENE -o OUT``), `--out` writes every 25th frame with the tracker's box.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np

from camgen.sim import AbsoluteMove, Simulation, command_log, save_command_log
from camgen.sim.metrics import control_metrics

REPO = Path(__file__).resolve().parents[1]
DEFAULT_SCENE = REPO / "scenes" / "ptz_follow.yaml"
LEAD_S = 0.14
"""How far ahead the head is aimed: the profile's command latency (0.1 s) plus about one frame."""
HEIGHT_FRAC = 0.3
"""Wanted target height as a fraction of the frame (the scene's own follow program's)."""


def box_of(observation, target: str):
    """The target's ground-truth visible box (x0, y0, x1, y1), pixel edges, or None."""
    return next((o.visible_box for o in observation.ground_truth.objects if o.name == target), None)


class CamShiftTracker:
    """A colour tracker on hue and saturation: CamShift's mean shift on the histogram back-projection,
    its window carried along the head's own motion between frames."""

    def __init__(self):
        self.box = None  # the whole target (x, y, w, h) in the last frame, px
        self.offset = None  # the box centre less the colour's centroid, in box sizes
        self.histogram = None
        self.state = None

    @staticmethod
    def _back_projection(hsv: np.ndarray, histogram) -> np.ndarray:
        back = cv2.calcBackProject([hsv], [0, 1], histogram, [0, 180, 0, 256], 1)
        return back & cv2.inRange(hsv, (0, 60, 32), (180, 255, 255))

    def start(self, rgb8: np.ndarray, box, state) -> None:
        x0, y0, x1, y1 = (round(v) for v in box)
        hsv = cv2.cvtColor(rgb8, cv2.COLOR_RGB2HSV)
        roi = hsv[y0:y1, x0:x1]
        mask = cv2.inRange(roi, (0, 60, 32), (180, 255, 255))
        self.histogram = cv2.calcHist([roi], [0, 1], mask, [30, 16], [0, 180, 0, 256])
        cv2.normalize(self.histogram, self.histogram, 0, 255, cv2.NORM_MINMAX)
        w, h = max(x1 - x0, 2), max(y1 - y0, 2)
        moments = cv2.moments(self._back_projection(roi, self.histogram))
        if moments["m00"] > 0:  # where the colour sits in the box (a jacket: the upper half)
            self.offset = (0.5 - moments["m10"] / moments["m00"] / w, 0.5 - moments["m01"] / moments["m00"] / h)
        else:
            self.offset = (0.0, 0.0)
        self.box = (float(x0), float(y0), float(w), float(h))
        self.state = state

    def _carried(self, state):
        """The box moved by the head's change of view since the last frame (pinhole, small angles)."""
        x, y, w, h = self.box
        K0, K1 = np.array(self.state.K_px), np.array(state.K_px)
        u, v = x + w / 2 - 0.5, y + h / 2 - 0.5
        # The box centre's direction in pan/tilt angles from the optical axis; a target at rest in the
        # world keeps pan − angle and tilt − angle as the head turns.
        a_pan = math.atan((u - K0[0, 2]) / K0[0, 0]) / math.cos(math.radians(self.state.tilt_deg))
        a_tilt = math.atan((v - K0[1, 2]) / K0[1, 1])
        d_pan = a_pan + math.radians(state.pan_deg - self.state.pan_deg)
        d_tilt = a_tilt + math.radians(state.tilt_deg - self.state.tilt_deg)
        u1 = K1[0, 2] + K1[0, 0] * math.tan(d_pan * math.cos(math.radians(state.tilt_deg)))
        v1 = K1[1, 2] + K1[1, 1] * math.tan(d_tilt)
        scale = K1[0, 0] / K0[0, 0]
        w1, h1 = w * scale, h * scale
        return (u1 + 0.5 - w1 / 2, v1 + 0.5 - h1 / 2, w1, h1)

    def update(self, rgb8: np.ndarray, state):
        height_px, width_px = rgb8.shape[:2]
        x, y, w, h = self._carried(state)
        self.state = state
        self.box = (x, y, w, h)
        # The colour's window: the box moved so that its centre sits on the colour, clipped to the image.
        cx, cy = x + w / 2 - self.offset[0] * w, y + h / 2 - self.offset[1] * h
        ww, wh = max(round(w), 2), max(round(h / 2), 2)
        wx, wy = round(cx - ww / 2), round(cy - wh / 2)
        if wx + ww <= 0 or wy + wh <= 0 or wx >= width_px or wy >= height_px:
            return None  # carried out of the frame
        hsv = cv2.cvtColor(rgb8, cv2.COLOR_RGB2HSV)
        back = self._back_projection(hsv, self.histogram)
        # Search only half a box around the carried position, so that a larger object of the same colour
        # nearby (the red parked car here) cannot pull the window away.
        keep = np.zeros_like(back)
        keep[max(wy - wh // 2, 0) : wy + wh + wh // 2, max(wx - ww // 2, 0) : wx + ww + ww // 2] = 1
        back *= keep
        x0, y0 = min(max(wx, 0), width_px - 2), min(max(wy, 0), height_px - 2)
        window = (x0, y0, max(min(ww, width_px - x0), 2), max(min(wh, height_px - y0), 2))
        if back[window[1] : window[1] + window[3], window[0] : window[0] + window[2]].sum() == 0:
            return None  # nothing of the colour where the target should be: coast on the carry
        criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 10, 1)
        _, (fx, fy, fw, fh) = cv2.meanShift(back, window, criteria)
        cx, cy = fx + fw / 2, fy + fh / 2  # the colour window's centre (clipped at the image edge)
        cx, cy = cx + self.offset[0] * w, cy + self.offset[1] * h
        self.box = (cx - w / 2, cy - h / 2, w, h)
        return (cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2)


def follow(sim: Simulation, camera: str, target: str, tracker: str, steps: int, lead_s: float, height_frac: float, out):
    """Run one episode; returns per frame the ground-truth box (for scoring) and the tracker's box."""
    observed = sim.reset(seed=0)
    truth_boxes, tracked_boxes = [], []
    history = []  # (time_s, target pan, target tilt) in degrees
    camshift = CamShiftTracker() if tracker == "camshift" else None
    for k in range(steps + 1):
        view = observed[camera]
        state = view.state
        truth = box_of(view, target)
        truth_boxes.append(truth)
        if camshift is None:
            box = truth
        elif camshift.histogram is None:
            box = truth
            if truth is not None:
                camshift.start(view.rgb8, truth, state)
        else:
            box = camshift.update(view.rgb8, state)
        tracked_boxes.append(box)
        if out is not None and k % 25 == 0:
            image = cv2.resize(view.rgb8, None, fx=4, fy=4, interpolation=cv2.INTER_NEAREST)[..., ::-1].copy()
            if box is not None:
                x0, y0, x1, y1 = (round(4 * v) for v in box)
                cv2.rectangle(image, (x0, y0), (x1, y1), (0, 255, 0), 1)
            cv2.imwrite(str(out / f"{tracker}_{k:04d}.png"), image)
        if k == steps or observed.frame + 1 >= sim.frame_count:
            break
        commands = []
        if box is not None:
            K = np.array(state.K_px)
            height_px, width_px = view.rgb8.shape[:2]
            u, v = (box[0] + box[2]) / 2 - 0.5, (box[1] + box[3]) / 2 - 0.5
            pan = state.pan_deg - math.degrees(math.atan((u - K[0, 2]) / K[0, 0])) / math.cos(
                math.radians(state.tilt_deg)
            )
            tilt = state.tilt_deg - math.degrees(math.atan((v - K[1, 2]) / K[1, 1]))
            history.append((view.time_s, pan, tilt))
            if len(history) >= 2 and history[-1][0] - history[-2][0] > 0:
                dt = history[-1][0] - history[-2][0]
                pan += lead_s * (history[-1][1] - history[-2][1]) / dt
                tilt += lead_s * (history[-1][2] - history[-2][2]) / dt
            zoom_x = None
            centred = abs(u - width_px / 2) < width_px / 6 and abs(v - height_px / 2) < height_px / 6
            box_height = box[3] - box[1]
            inside = box[1] > 1 and box[3] < height_px - 1
            if centred and inside and box_height > 0:
                zoom_x = state.zoom_x * min(max(height_frac * height_px / box_height, 0.8), 1.2)
            commands.append(AbsoluteMove(pan_deg=pan, tilt_deg=tilt, zoom_x=zoom_x))
        else:
            history.clear()
        observed = sim.step({camera: commands} if commands else {})
    return truth_boxes, tracked_boxes


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", type=Path, nargs="?", default=DEFAULT_SCENE, metavar="SCENE")
    parser.add_argument("--camera", default="pole_ptz")
    parser.add_argument("--target", default="walker_1")
    parser.add_argument("--tracker", choices=("truth", "camshift"), default="truth")
    parser.add_argument("--resolution", default="160x90", metavar="WxH")
    parser.add_argument("--steps", type=int, default=299, metavar="N", help="steps (default 299: the scene's 12 s)")
    parser.add_argument("--lead-s", type=float, default=LEAD_S)
    parser.add_argument("--height-frac", type=float, default=HEIGHT_FRAC)
    parser.add_argument("--log", type=Path, metavar="FILE", help="save the command log here")
    parser.add_argument("--out", type=Path, metavar="DIR", help="write every 25th frame with the tracked box")
    args = parser.parse_args(argv)
    width_px, height_px = (int(v) for v in args.resolution.lower().split("x"))
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
    with Simulation(args.scene, ground_truth=True, resolution_px=(width_px, height_px), cameras=[args.camera]) as sim:
        truth, tracked = follow(
            sim, args.camera, args.target, args.tracker, args.steps, args.lead_s, args.height_frac, args.out
        )
        if args.log is not None:
            save_command_log(command_log(sim), args.log)
        fps = sim.fps
    scores = control_metrics(truth, (width_px, height_px), fps)
    print(
        f"{args.tracker}: {args.target} in frame {scores.in_frame_frac:.1%} of {scores.frames} frames; centring error "
        f"{scores.centring_error_px:.2f} px = {scores.centring_error_frac:.3f} of the half-diagonal "
        f"({width_px}×{height_px}); height {scores.height_frac:.3f} of the frame; {scores.losses} loss(es)"
    )
    if args.tracker == "camshift":
        lost = sum(1 for t, b in zip(truth, tracked, strict=True) if t is not None and b is None)
        print(f"camshift: no window on {lost} frame(s) with the target in frame")
    return 0


if __name__ == "__main__":
    sys.exit(main())
