"""Metrics that papers report, from camgen's ground truth.

Multi-object tracking (a tracker's MOTChallenge output against a sequence's ``gt/gt.txt``):

- CLEAR MOT (Bernardin & Stiefelhagen 2008, "Evaluating multiple object tracking performance: the
  CLEAR MOT metrics"): MOTA = 1 − (FN + FP + IDSW) / GT and MOTP, here as MOTChallenge reports it for
  boxes, the mean IoU of the matched pairs; computed by py-motmetrics with a match at IoU ≥ 0.5.
- IDF1 (Ristani et al. 2016, "Performance measures and a data set for multi-target, multi-camera
  tracking"): 2·IDTP / (2·IDTP + IDFP + IDFN) under the best one-to-one assignment of whole tracks;
  py-motmetrics.
- HOTA (Luiten et al. 2021, "HOTA: a higher order metric for evaluating multi-object tracking", IJCV):
  √(DetA·AssA) averaged over IoU thresholds α = 0.05, 0.10, …, 0.95, matched per frame by the
  Hungarian algorithm on IoU weighted by the pair's global alignment, as TrackEval does; implemented
  here (TrackEval's package requires opencv-python, which would overwrite the project's OpenCV
  build) and checked against TrackEval's `HOTA` in the tests.

MOTChallenge's preprocessing (Dendorfer et al. 2021, "MOTChallenge: a benchmark for single-camera
multiple target tracking", IJCV §4.1.3): a ground-truth box marked ``conf = 0`` (camgen: nothing of the
object visible) or of a class not evaluated is ignored, and a tracker box matched to it (Hungarian,
IoU ≥ 0.5) is removed rather than counted a false positive.

Active tracking by a PTZ camera (`control_metrics`): the fraction of frames the target is in frame,
the centring error (px and as a fraction of the half-diagonal), the target's height in the frame and
its resolution in px/m, and the time to reacquire it after a loss (the measures of active-tracking
papers; the names follow issue 21).

A camera network (`network_metrics`): per target, the share of frames some camera holds it, the gaps
no camera does, and the hand-offs between cameras with the gap each left.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import motmetrics
import numpy as np
from scipy.optimize import linear_sum_assignment

MATCH_IOU = 0.5
"""CLEAR MOT's and IDF1's match threshold for boxes (MOTChallenge's)."""
HOTA_ALPHAS = np.arange(0.05, 0.99, 0.05)
"""HOTA's localisation thresholds (Luiten et al. 2021, eq. 9: 19 values)."""
_EPS = np.finfo(float).eps


def iou_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """IoU of every box in `a` (N, 4) with every box in `b` (M, 4), boxes as (left, top, width, height)."""
    a, b = np.asarray(a, float).reshape(-1, 4), np.asarray(b, float).reshape(-1, 4)
    left = np.maximum(a[:, None, 0], b[None, :, 0])
    top = np.maximum(a[:, None, 1], b[None, :, 1])
    right = np.minimum(a[:, None, 0] + a[:, None, 2], b[None, :, 0] + b[None, :, 2])
    bottom = np.minimum(a[:, None, 1] + a[:, None, 3], b[None, :, 1] + b[None, :, 3])
    inter = np.clip(right - left, 0, None) * np.clip(bottom - top, 0, None)
    union = (a[:, 2] * a[:, 3])[:, None] + (b[:, 2] * b[:, 3])[None, :] - inter
    return np.where(union > 0, inter / np.where(union > 0, union, 1), 0.0)


@dataclass(frozen=True)
class TrackingScores:
    """A tracker's scores on one sequence (fractions, not percent)."""

    mota: float
    motp_iou: float
    """Mean IoU of the matched pairs (MOTChallenge's MOTP for boxes)."""
    idf1: float
    id_switches: int
    false_positives: int
    misses: int
    ground_truth_boxes: int
    hota: float
    deta: float
    assa: float
    loca: float


def _frames(rows: np.ndarray) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Frame → (ids, boxes (left, top, width, height))."""
    out = {}
    for frame in np.unique(rows[:, 0]).astype(int):
        chosen = rows[rows[:, 0] == frame]
        out[int(frame)] = chosen[:, 1].astype(np.int64), chosen[:, 2:6]
    return out


def preprocess(gt: np.ndarray, pred: np.ndarray, classes: Sequence[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """MOTChallenge's preprocessing: drop ignored ground truth (conf 0, or a class not in `classes`) and
    the tracker boxes matched to it. Rows as `camgen.io.mot.read_mot` gives them."""
    ignored = gt[:, 6] == 0
    if classes is not None:
        ignored |= ~np.isin(gt[:, 7], list(classes))
    kept_pred = np.ones(len(pred), bool)
    for frame in np.unique(gt[ignored, 0]):
        in_frame = gt[:, 0] == frame
        candidates = np.flatnonzero(pred[:, 0] == frame)
        if not len(candidates):
            continue
        # Matched against all the frame's ground truth, so a box that belongs to a kept object stays.
        iou = iou_matrix(gt[in_frame, 2:6], pred[candidates, 2:6])
        rows, cols = linear_sum_assignment(-iou)
        ignored_here = ignored[in_frame]
        for r, c in zip(rows, cols, strict=True):
            if iou[r, c] >= MATCH_IOU and ignored_here[r]:
                kept_pred[candidates[c]] = False
    return gt[~ignored], pred[kept_pred]


def evaluate_tracking(gt: np.ndarray, pred: np.ndarray, classes: Sequence[int] | None = None) -> TrackingScores:
    """Score a tracker's boxes `pred` against the ground truth `gt` (rows of `camgen.io.mot.read_mot`),
    after MOTChallenge's preprocessing (`preprocess`)."""
    gt, pred = preprocess(gt, pred, classes)
    gt_frames, pred_frames = _frames(gt), _frames(pred)
    empty = (np.zeros(0, np.int64), np.zeros((0, 4)))
    frames = sorted(set(gt_frames) | set(pred_frames))
    accumulator = motmetrics.MOTAccumulator(auto_id=False)
    for frame in frames:
        gt_ids, gt_boxes = gt_frames.get(frame, empty)
        pred_ids, pred_boxes = pred_frames.get(frame, empty)
        distances = 1.0 - iou_matrix(gt_boxes, pred_boxes)
        distances[distances > 1.0 - MATCH_IOU + _EPS] = np.nan
        accumulator.update(gt_ids, pred_ids, distances, frameid=frame)
    names = ["mota", "motp", "idf1", "num_switches", "num_false_positives", "num_misses", "num_objects"]
    summary = motmetrics.metrics.create().compute(accumulator, metrics=names, name="sequence").iloc[0]
    hota = hota_scores([gt_frames.get(f, empty) for f in frames], [pred_frames.get(f, empty) for f in frames])
    motp = float(summary["motp"])
    return TrackingScores(
        mota=float(summary["mota"]),
        motp_iou=1.0 - motp if math.isfinite(motp) else math.nan,
        idf1=float(summary["idf1"]),
        id_switches=int(summary["num_switches"]),
        false_positives=int(summary["num_false_positives"]),
        misses=int(summary["num_misses"]),
        ground_truth_boxes=int(summary["num_objects"]),
        **hota,
    )


def hota_scores(
    gt: Sequence[tuple[np.ndarray, np.ndarray]], pred: Sequence[tuple[np.ndarray, np.ndarray]]
) -> dict[str, float]:
    """HOTA, DetA, AssA, LocA (each averaged over `HOTA_ALPHAS`) of per-frame (ids, boxes) lists."""
    gt_labels = {i: k for k, i in enumerate(sorted({int(i) for ids, _ in gt for i in ids}))}
    pred_labels = {i: k for k, i in enumerate(sorted({int(i) for ids, _ in pred for i in ids}))}
    n_gt = sum(len(ids) for ids, _ in gt)
    n_pred = sum(len(ids) for ids, _ in pred)
    if n_gt == 0 or n_pred == 0:
        return {"hota": 0.0, "deta": 0.0, "assa": 0.0, "loca": 1.0}
    frames = []
    potential = np.zeros((len(gt_labels), len(pred_labels)))
    gt_count = np.zeros((len(gt_labels), 1))
    pred_count = np.zeros((1, len(pred_labels)))
    for (g_ids, g_boxes), (p_ids, p_boxes) in zip(gt, pred, strict=True):
        g = np.array([gt_labels[int(i)] for i in g_ids], np.int64)
        p = np.array([pred_labels[int(i)] for i in p_ids], np.int64)
        similarity = iou_matrix(g_boxes, p_boxes)
        frames.append((g, p, similarity))
        # Each pair's share of its two detections' total similarity (TrackEval's soft potential matches).
        denominator = similarity.sum(0)[None, :] + similarity.sum(1)[:, None] - similarity
        share = np.where(denominator > _EPS, similarity / np.where(denominator > _EPS, denominator, 1), 0.0)
        potential[g[:, None], p[None, :]] += share
        gt_count[g] += 1
        pred_count[0, p] += 1
    alignment = potential / (gt_count + pred_count - potential)
    A = len(HOTA_ALPHAS)
    tp, fn, fp, loc = np.zeros(A), np.zeros(A), np.zeros(A), np.zeros(A)
    matches = np.zeros((A, len(gt_labels), len(pred_labels)))
    for g, p, similarity in frames:
        if len(g) == 0 or len(p) == 0:
            fn += len(g)
            fp += len(p)
            continue
        rows, cols = linear_sum_assignment(-(alignment[g[:, None], p[None, :]] * similarity))
        for a, alpha in enumerate(HOTA_ALPHAS):
            ok = similarity[rows, cols] >= alpha - _EPS
            matched = int(ok.sum())
            tp[a] += matched
            fn[a] += len(g) - matched
            fp[a] += len(p) - matched
            loc[a] += similarity[rows[ok], cols[ok]].sum()
            matches[a, g[rows[ok]], p[cols[ok]]] += 1
    assa = np.array(
        [
            np.sum(m * m / np.maximum(1, gt_count + pred_count - m)) / max(1.0, t)
            for m, t in zip(matches, tp, strict=True)
        ]
    )
    deta = tp / np.maximum(1.0, tp + fn + fp)
    loca = np.maximum(1e-10, loc) / np.maximum(1e-10, tp)
    return {
        "hota": float(np.mean(np.sqrt(deta * assa))),
        "deta": float(np.mean(deta)),
        "assa": float(np.mean(assa)),
        "loca": float(np.mean(loca)),
    }


@dataclass(frozen=True)
class ControlScores:
    """How well a camera kept one target (see `control_metrics`)."""

    frames: int
    in_frame_frac: float
    """Frames with some of the target visible, as a fraction of all."""
    centring_error_px: float
    """Mean distance of the visible box's centre from the image centre over the frames it is seen, px."""
    centring_error_frac: float
    """The same as a fraction of the half-diagonal (1: a corner)."""
    height_frac: float
    """Mean visible box height over the frame height, seen frames."""
    resolution_px_per_m: float
    """Mean visible box height over the target's height, px/m (NaN without heights)."""
    losses: int
    """Times the target left the frame after it was first seen."""
    reacquire_s: float
    """Mean time from losing the target to seeing it again, over the losses that ended, s (NaN: none)."""


def control_metrics(
    boxes: Sequence[tuple[float, float, float, float] | None],
    size_px: tuple[int, int],
    fps: float,
    heights_m: Sequence[float | None] | None = None,
) -> ControlScores:
    """Score one camera's frames of one target: `boxes`, per frame, the target's visible box (x0, y0, x1,
    y1) in pixel-edge coordinates or None where it is unseen; `size_px` the frame's (W, H); `heights_m`
    the target's height per frame (for px/m)."""
    width_px, height_px = size_px
    seen = [box is not None for box in boxes]
    errors, heights, resolutions = [], [], []
    for k, box in enumerate(boxes):
        if box is None:
            continue
        x0, y0, x1, y1 = box
        errors.append(math.hypot((x0 + x1) / 2 - width_px / 2, (y0 + y1) / 2 - height_px / 2))
        heights.append((y1 - y0) / height_px)
        if heights_m is not None and heights_m[k]:
            resolutions.append((y1 - y0) / heights_m[k])
    losses, gaps, lost_at, first = 0, [], None, None
    for k, visible in enumerate(seen):
        if visible and first is None:
            first = k
        elif first is not None and not visible and lost_at is None:
            lost_at, losses = k, losses + 1
        elif visible and lost_at is not None:
            gaps.append((k - lost_at) / fps)
            lost_at = None
    half_diagonal_px = math.hypot(width_px, height_px) / 2
    mean = float(np.mean(errors)) if errors else math.nan
    return ControlScores(
        frames=len(boxes),
        in_frame_frac=float(np.mean(seen)) if boxes else math.nan,
        centring_error_px=mean,
        centring_error_frac=mean / half_diagonal_px,
        height_frac=float(np.mean(heights)) if heights else math.nan,
        resolution_px_per_m=float(np.mean(resolutions)) if resolutions else math.nan,
        losses=losses,
        reacquire_s=float(np.mean(gaps)) if gaps else math.nan,
    )


def target_boxes(observations, camera: str, target: str) -> tuple[list, list]:
    """From a run's `camgen.sim.Observations` (ground truth on): per frame, `target`'s visible box in
    `camera` (None where unseen) and its height, m (the z extent of its 3-D box; None where unseen)."""
    boxes, heights_m = [], []
    for observed in observations:
        truth = observed[camera].ground_truth
        if truth is None:
            raise ValueError("the run has no ground truth; run the simulation with ground_truth=True")
        obj = next((o for o in truth.objects if o.name == target), None)
        box = None if obj is None else obj.visible_box
        boxes.append(box)
        heights_m.append(None if box is None else float(np.ptp(np.asarray(obj.box_3d_world_m)[:, 2])))
    return boxes, heights_m


@dataclass(frozen=True)
class Handoff:
    """A target taken over by a camera that was not holding it: `gap_s` after the last holder lost it
    (0 when the two held it at once)."""

    frame: int
    target: str
    from_cameras: tuple[str, ...]
    to_camera: str
    gap_s: float


@dataclass(frozen=True)
class NetworkScores:
    """How a camera network kept one target (see `network_metrics`)."""

    target: str
    held_frac: float
    """Frames some camera held the target, from the first frame any did, as a fraction of them."""
    gaps: int
    """Runs of frames no camera held it, after the first held frame (a run still open at the end counts)."""
    mean_gap_s: float
    handoffs: tuple[Handoff, ...]


def network_metrics(
    held: Sequence[dict[str, Sequence[str] | set[str]]], targets: Sequence[str], fps: float
) -> list[NetworkScores]:
    """Hand-offs and gaps of a camera network: `held`, per frame, camera → the targets it holds (as
    `camgen.sim.multi_env.CameraNetworkEnv`'s ``infos[camera]["held"]``).

    A hand-off is camera B starting to hold a target that another camera held on the frame before
    (gap 0) or, after a gap, that other cameras held last and B did not (gap = the frames between,
    in s); a camera taking back what it held last is a reacquisition, not a hand-off."""
    scores = []
    for target in targets:
        holders = [{camera for camera, names in frame.items() if target in names} for frame in held]
        first = next((k for k, h in enumerate(holders) if h), None)
        if first is None:
            scores.append(NetworkScores(target, 0.0, 0, math.nan, ()))
            continue
        handoffs, gaps, run, last, last_frame = [], [], 0, holders[first], first
        for k in range(first + 1, len(holders)):
            now, before = holders[k], holders[k - 1]
            if not now:
                run += 1
                continue
            if run:
                gaps.append(run / fps)
            for camera in sorted(now - before):
                if before:
                    handoffs.append(Handoff(k, target, tuple(sorted(before)), camera, 0.0))
                elif camera not in last:
                    handoffs.append(Handoff(k, target, tuple(sorted(last)), camera, (k - last_frame - 1) / fps))
            run, last, last_frame = 0, now, k
        if run:
            gaps.append(run / fps)
        span = len(holders) - first
        held_frames = sum(1 for h in holders[first:] if h)
        scores.append(
            NetworkScores(
                target, held_frames / span, len(gaps), float(np.mean(gaps)) if gaps else math.nan, tuple(handoffs)
            )
        )
    return scores
