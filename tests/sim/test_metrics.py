"""camgen.sim.metrics: ground truth scored against itself is perfect; dropping a track and swapping two
ids change MOTA, IDF1 and HOTA by their closed forms; HOTA agrees with TrackEval's; the PTZ control
metrics on hand-made boxes."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from camgen.sim.metrics import control_metrics, evaluate_tracking, hota_scores, iou_matrix

FRAMES = 20


def ground_truth() -> np.ndarray:
    """Three walkers 100 px apart moving right 3 px a frame (never overlapping), the third leaving after
    frame 12; one fully hidden box (conf 0) of a fourth object on frames 1-5. Rows as read_mot gives."""
    rows = []
    for frame in range(1, FRAMES + 1):
        for track, y in ((1, 10.0), (2, 110.0), (3, 210.0)):
            if track == 3 and frame > 12:
                continue
            rows.append([frame, track, 5.0 + 3 * frame, y, 40.0, 80.0, 1, 1, 1.0])
        if frame <= 5:
            rows.append([frame, 4, 300.0, 300.0, 30.0, 30.0, 0, 1, 0.0])
    return np.array(rows)


def tracker_copy(gt: np.ndarray) -> np.ndarray:
    """The ground truth as a perfect tracker would output it (every box, conf 1, no class)."""
    pred = gt.copy()
    pred[:, 6], pred[:, 7], pred[:, 8] = 1.0, -1.0, -1.0
    return pred


def test_ground_truth_against_itself_is_perfect():
    gt = ground_truth()
    scores = evaluate_tracking(gt, tracker_copy(gt))
    # The hidden object's box (conf 0) is ignored: the tracker's box on it is neither TP nor FP.
    assert scores.ground_truth_boxes == int((gt[:, 6] == 1).sum()) == 52
    assert (scores.mota, scores.idf1, scores.hota, scores.deta, scores.assa) == (1.0, 1.0, 1.0, 1.0, 1.0)
    assert scores.motp_iou == pytest.approx(1.0) and scores.loca == pytest.approx(1.0)
    assert (scores.id_switches, scores.false_positives, scores.misses) == (0, 0, 0)


def test_dropping_a_track_costs_its_boxes():
    gt = ground_truth()
    pred = tracker_copy(gt)
    pred = pred[pred[:, 1] != 3]  # track 3: 12 boxes of 52
    scores = evaluate_tracking(gt, pred)
    n, dropped = 52, 12
    assert scores.misses == dropped and scores.false_positives == 0
    assert scores.mota == pytest.approx(1 - dropped / n)
    assert scores.idf1 == pytest.approx(2 * (n - dropped) / (2 * n - dropped))
    # DetA = TP / (TP + FN) at every α, AssA = 1 (the kept tracks are perfectly associated).
    assert scores.deta == pytest.approx((n - dropped) / n) and scores.assa == pytest.approx(1.0)
    assert scores.hota == pytest.approx(math.sqrt((n - dropped) / n))


def test_swapping_two_ids_midway_costs_two_switches():
    gt = ground_truth()
    pred = tracker_copy(gt)
    later = pred[:, 0] >= 15  # frames 15-20: tracks 1 and 2 swap labels (6 frames each)
    ones, twos = later & (pred[:, 1] == 1), later & (pred[:, 1] == 2)
    pred[ones, 1], pred[twos, 1] = 2, 1
    scores = evaluate_tracking(gt, pred)
    n = 52
    assert scores.id_switches == 2
    assert scores.mota == pytest.approx(1 - 2 / n)
    # The best whole-track assignment keeps labels 1→1, 2→2 (14 frames each) and loses the 6 + 6 swapped.
    assert scores.idf1 == pytest.approx((n - 12) / n)
    assert scores.deta == pytest.approx(1.0) and scores.assa < 1.0


def test_hota_agrees_with_trackeval():
    trackeval_hota = pytest.importorskip("trackeval.metrics").HOTA
    rng = np.random.default_rng(7)
    gt = ground_truth()
    gt = gt[gt[:, 6] == 1]
    pred = tracker_copy(gt)
    pred[:, 2:4] += rng.normal(0, 6, (len(pred), 2))  # localisation error
    pred = pred[rng.random(len(pred)) > 0.15]  # missed boxes
    pred[(pred[:, 0] > 10) & (pred[:, 1] == 2), 1] = 7  # a fragment
    frames = list(range(1, FRAMES + 1))
    g = [(gt[gt[:, 0] == f, 1].astype(int), gt[gt[:, 0] == f, 2:6]) for f in frames]
    p = [(pred[pred[:, 0] == f, 1].astype(int), pred[pred[:, 0] == f, 2:6]) for f in frames]
    ours = hota_scores(g, p)
    gt_ids = {i: k for k, i in enumerate(sorted({int(i) for ids, _ in g for i in ids}))}
    pr_ids = {i: k for k, i in enumerate(sorted({int(i) for ids, _ in p for i in ids}))}
    data = {
        "num_gt_dets": len(gt),
        "num_tracker_dets": len(pred),
        "num_gt_ids": len(gt_ids),
        "num_tracker_ids": len(pr_ids),
        "gt_ids": [np.array([gt_ids[int(i)] for i in ids], int) for ids, _ in g],
        "tracker_ids": [np.array([pr_ids[int(i)] for i in ids], int) for ids, _ in p],
        "similarity_scores": [iou_matrix(gb, pb) for (_, gb), (_, pb) in zip(g, p, strict=True)],
    }
    theirs = trackeval_hota().eval_sequence(data)
    assert 0.3 < ours["hota"] < 0.95
    for key, name in (("hota", "HOTA"), ("deta", "DetA"), ("assa", "AssA"), ("loca", "LocA")):
        assert ours[key] == pytest.approx(float(np.mean(theirs[name])), abs=1e-12)


def test_iou_matches_the_closed_form():
    a = np.array([[0.0, 0.0, 10.0, 10.0]])
    b = np.array([[5.0, 0.0, 10.0, 10.0], [20.0, 20.0, 1.0, 1.0]])
    assert iou_matrix(a, b) == pytest.approx(np.array([[50 / 150, 0.0]]))


def test_control_metrics_on_hand_made_boxes():
    # 100 × 50 frame, 10 fps: centred, 10 px right, lost for 3 frames, seen again 20 px low.
    boxes = [(40, 15, 60, 35), (50, 15, 70, 35), None, None, None, (40, 35, 60, 55)]
    scores = control_metrics(boxes, (100, 50), 10.0, heights_m=[2.0] * 6)
    assert scores.in_frame_frac == pytest.approx(0.5)
    assert scores.centring_error_px == pytest.approx((0 + 10 + 20) / 3)
    assert scores.centring_error_frac == pytest.approx(10 / math.hypot(50, 25))
    assert scores.height_frac == pytest.approx(20 / 50)
    assert scores.resolution_px_per_m == pytest.approx(10.0)
    assert (scores.losses, scores.reacquire_s) == (1, pytest.approx(0.3))


def _write_mot(path, rows, columns):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(",".join(f"{v:g}" for v in row[:columns]) + "\n" for row in rows))
    return path


def test_camgen_evaluate_scores_a_tracker_file(tmp_path, capsys):
    from camgen.cli.main import main

    gt = ground_truth()
    _write_mot(tmp_path / "seq" / "gt" / "gt.txt", gt, 9)
    (tmp_path / "seq" / "seqinfo.ini").write_text(
        "[Sequence]\nname=seq\nimDir=img1\nframeRate=10\nseqLength=20\nimWidth=400\nimHeight=400\nimExt=.png\n"
    )
    pred = tracker_copy(gt)
    pred = pred[pred[:, 1] != 3]
    pred[:, 7:9] = -1
    tracker = _write_mot(tmp_path / "tracker.txt", np.c_[pred[:, :7], -np.ones((len(pred), 3))], 10)
    out = tmp_path / "scores.json"
    assert main(["evaluate", str(tmp_path / "seq"), str(tracker), "--target-id", "3", "--json", str(out)]) == 0
    scores = json.loads(out.read_text())
    assert scores["tracking"]["mota"] == pytest.approx(1 - 12 / 52) and scores["tracking"]["misses"] == 12
    # Track 3 is seen on frames 1-12 of 20 and never lost in between.
    assert scores["control"]["in_frame_frac"] == pytest.approx(12 / 20) and scores["control"]["losses"] == 1
    assert "MOTA" in capsys.readouterr().out


def test_camgen_evaluate_names_a_bad_line(tmp_path, capsys):
    from camgen.cli.main import main

    gt = _write_mot(tmp_path / "gt" / "gt.txt", ground_truth(), 9)
    bad = tmp_path / "tracker.txt"
    bad.write_text("1,1,10,10,5,5,1,-1,-1,-1\n2,1,ten,10,5,5,1,-1,-1,-1\n")
    assert main(["evaluate", str(gt), str(bad)]) == 2
    assert "tracker.txt:2: not numbers" in capsys.readouterr().err
    assert main(["evaluate", str(gt)]) == 2
    assert "nothing to evaluate" in capsys.readouterr().err


def test_network_metrics_find_handoffs_and_gaps():
    from camgen.sim.metrics import network_metrics

    a, b, none = {"a": ["p"], "b": []}, {"a": [], "b": ["p"]}, {"a": [], "b": []}
    both = {"a": ["p"], "b": ["p"]}
    # Frames: unseen, a, a+b (hand-off to b, overlap), b, gap ×2, a (hand-off back after 0.2 s), a,
    # gap, a again (a reacquisition, not a hand-off).
    frames = [none, a, both, b, none, none, a, a, none, a]
    (scores,) = network_metrics(frames, ["p"], fps=10.0)
    assert scores.held_frac == pytest.approx(6 / 9)
    assert (scores.gaps, scores.mean_gap_s) == (2, pytest.approx((0.2 + 0.1) / 2))
    assert [(h.frame, h.from_cameras, h.to_camera, h.gap_s) for h in scores.handoffs] == [
        (2, ("a",), "b", 0.0),
        (6, ("b",), "a", pytest.approx(0.2)),
    ]
