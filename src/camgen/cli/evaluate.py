"""camgen evaluate GT [PRED]: score a tracker's MOTChallenge output against camgen's ground truth
(MOTA, MOTP, IDF1, ID switches, HOTA; `camgen.sim.metrics`) and, for a --target-id, how well the
camera kept that object in frame (the PTZ control metrics)."""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from camgen.cli.common import check_output_file
from camgen.errors import ConfigError


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("evaluate", help="score a tracker's MOT output against camgen's ground truth")
    parser.add_argument(
        "gt", type=Path, metavar="GT", help="a camera's MOT directory (holding gt/gt.txt, seqinfo.ini) or a gt.txt"
    )
    parser.add_argument("pred", type=Path, nargs="?", metavar="PRED", help="the tracker's output, MOTChallenge text")
    parser.add_argument(
        "--class",
        dest="classes",
        type=int,
        action="append",
        metavar="ID",
        help="evaluate only these MOT class ids (1 pedestrian, 3 car, 4 bicycle...; repeatable; default all); "
        "the others are ignored as MOTChallenge ignores distractors",
    )
    parser.add_argument(
        "--target-id", type=int, metavar="ID", help="also report how the camera kept this track id (PTZ control)"
    )
    parser.add_argument("--json", type=Path, metavar="FILE", help="also write the scores as JSON")
    parser.set_defaults(run=run)


def _ground_truth_paths(path: Path) -> tuple[Path, Path]:
    """(gt.txt, the sequence directory)."""
    if path.is_dir():
        return path / "gt" / "gt.txt", path
    return path, path.parent.parent if path.parent.name == "gt" else path.parent


def run(args: argparse.Namespace, out: Console, err: Console) -> int:
    from camgen.io.files import write_text_atomic
    from camgen.io.mot import read_mot, read_seqinfo
    from camgen.sim.metrics import control_metrics, evaluate_tracking

    if args.pred is None and args.target_id is None:
        raise ConfigError("nothing to evaluate: give the tracker's output (PRED), --target-id, or both")
    if args.json:
        check_output_file(args.json, "--json", "give a file name for the scores")
    gt_path, sequence = _ground_truth_paths(args.gt)
    gt = read_mot(gt_path, ground_truth=True)
    report: dict = {}
    if args.pred is not None:
        scores = evaluate_tracking(gt, read_mot(args.pred), args.classes)
        report["tracking"] = dataclasses.asdict(scores)
        table = Table(title=f"{escape(str(args.pred))} against {escape(str(gt_path))}", title_justify="left")
        names = ("MOTA", "MOTP", "IDF1", "IDSW", "FP", "FN", "GT", "HOTA", "DetA", "AssA", "LocA")
        for name in names:
            table.add_column(name, justify="right")
        table.add_row(
            *(f"{v:.1%}" for v in (scores.mota, scores.motp_iou, scores.idf1)),
            *(str(v) for v in (scores.id_switches, scores.false_positives, scores.misses, scores.ground_truth_boxes)),
            *(f"{v:.1%}" for v in (scores.hota, scores.deta, scores.assa, scores.loca)),
        )
        out.print(table)
    if args.target_id is not None:
        info = read_seqinfo(sequence)
        try:
            width_px, height_px = int(info["imWidth"]), int(info["imHeight"])
            frames, fps = int(info["seqLength"]), float(info["frameRate"])
        except (KeyError, ValueError):
            raise ConfigError(
                f"{sequence / 'seqinfo.ini'}: needed for --target-id (image size, length, frame rate); "
                "give the camera's MOT directory as camgen writes it"
            ) from None
        rows = gt[(gt[:, 1] == args.target_id) & (gt[:, 6] == 1)]
        if not len(rows):
            ids = ", ".join(str(int(i)) for i in np.unique(gt[:, 1]))
            raise ConfigError(f"--target-id {args.target_id}: never visible in {gt_path} (track ids: {ids})")
        boxes = [None] * frames
        for frame, _, left, top, w, h, *_ in rows:
            # MOT's 1-based, unclipped whole-object box → pixel edges, clipped to the image.
            x0, y0 = min(max(left - 1, 0), width_px), min(max(top - 1, 0), height_px)
            x1, y1 = min(max(left - 1 + w, 0), width_px), min(max(top - 1 + h, 0), height_px)
            if 1 <= frame <= frames:
                boxes[int(frame) - 1] = (x0, y0, x1, y1)
        control = control_metrics(boxes, (width_px, height_px), fps)
        report["control"] = {k: None if v != v else v for k, v in dataclasses.asdict(control).items()}
        out.print(
            f"track {args.target_id}: in frame {control.in_frame_frac:.1%} of {control.frames} frames, centring error "
            f"{control.centring_error_px:.1f} px ({control.centring_error_frac:.3f} of the half-diagonal), height "
            f"{control.height_frac:.3f} of the frame, {control.losses} loss(es), reacquired after "
            f"{control.reacquire_s:.2f} s on average (the whole object's box clipped to the image)"
        )
    if args.json:
        write_text_atomic(args.json, json.dumps(report, indent=1) + "\n")
    return 0
