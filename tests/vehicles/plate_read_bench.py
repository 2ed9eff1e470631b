"""How well an OCR reads camgen's plates back: per-character accuracy against the annotated text over
seeded plates, by character height, by the camera's angle off the plate's axis, by day and at night in
IR mode (the views and the reading of tests/vehicles/test_plate_read_back.py).

    .venv/bin/python -m tests.vehicles.plate_read_bench [--plates 24] [--only LABEL] [--out FILE.md]

Needs RapidOCR (`make setup`). Prints a Markdown table: for each condition the plates read exactly
(after `plate_syntax`), the characters read right (1 − edit distance / length, summed over plates), the
plates read exactly without it (the read's letters and digits as they are: no capitals, no O/0 by
position), the median IoU of the detector's text box with the annotated quad's text box, and where the
reads went wrong.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

BODIES = ("sedan", "hatchback", "estate", "suv", "pickup", "van")


def edit_distance(a: str, b: str) -> int:
    """Levenshtein distance (insertions, deletions and substitutions cost 1)."""
    row = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        previous, row[0] = row[0], i
        for j, cb in enumerate(b, 1):
            previous, row[j] = row[j], min(row[j] + 1, row[j - 1] + 1, previous + (ca != cb))
    return row[-1]


def conditions(plates: int):
    """(label, views, night) of each measured condition."""
    from tests.vehicles.test_plate_read_back import PlateView

    def views(height_px: float, yaw_deg: float) -> list:
        # Alternate rear and front plates and the side the camera stands on; ANPR-like 10° down, 10 m away.
        sides, signs = ("rear", "front"), (1, 1, -1, -1)
        return [
            PlateView(BODIES[i % len(BODIES)], sides[i % 2], height_px, yaw_deg * signs[i % 4], 10, 10.0)
            for i in range(plates)
        ]

    for height in (10, 13, 16, 20, 28):
        yield f"day, {height} px, 10°", views(height, 10), False
    for yaw in (30, 45, 60):
        yield f"day, 20 px, {yaw}°", views(20, yaw), False
    for height in (10, 13, 20, 28):
        yield f"night IR, {height} px, 10°", views(height, 10), True


def measure(renderer, reader, label, views, night, root: Path, seed: int) -> dict:
    from camgen.plan.execute import execute
    from tests.vehicles.test_plate_read_back import (
        delivered_plates,
        detected_text_box_px,
        iou,
        plate_syntax,
        plate_views_job,
        read_plate,
        text_box_px,
    )

    start = time.perf_counter()
    results = execute(plate_views_job(views, seed=seed, night=night), root / label.replace(" ", "_"), renderer=renderer)
    render_s = time.perf_counter() - start
    exact = raw_exact = characters = wrong = 0
    ious, misreads = [], []
    for view, result in zip(views, results, strict=True):
        frame, plates = delivered_plates(result.directory)
        own = [p for p in plates if p["side"] == view.side]
        truth = None
        if own:
            plate = own[0]
            truth = plate["text"].replace(" ", "")
            read = read_plate(reader, frame, plate, view.body_type)
            found = detected_text_box_px(reader, frame, plate)
            ious.append(0.0 if found is None else iou(found, text_box_px(plate, view.body_type, view.side)))
        if truth is None:
            misreads.append("(plate not annotated visible)")
            continue
        syntax = plate_syntax(read)
        exact += syntax == truth
        raw_exact += "".join(c for c in read if c.isalnum()) == truth
        errors = min(edit_distance(syntax, truth), len(truth))
        wrong += errors
        characters += len(truth)
        if errors:
            misreads.append(f"{truth}→{syntax or '∅'}")
    return {
        "label": label,
        "plates": len(views),
        "exact": exact,
        "raw_exact": raw_exact,
        "character_accuracy": 1 - wrong / max(characters, 1),
        "iou_median": float(np.median(ious)) if ious else float("nan"),
        "render_s": render_s,
        "misreads": misreads,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plates", type=int, default=24)
    parser.add_argument("--seed", type=int, default=1000)
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--only", default="", help="measure only the conditions whose label contains this")
    args = parser.parse_args()
    from rapidocr_onnxruntime import RapidOCR

    from camgen.render.renderer import Renderer

    reader = RapidOCR()
    lines = [
        "| condition | plates | read exactly | characters right | exact without the syntax check "
        "| text box IoU (median) | misreads (truth→read) |",
        "|---|---|---|---|---|---|---|",
    ]
    with Renderer() as renderer, tempfile.TemporaryDirectory(prefix="plate_read_bench") as root:
        for label, views, night in conditions(args.plates):
            if args.only not in label:
                continue
            row = measure(renderer, reader, label, views, night, Path(root), args.seed)
            shown = ", ".join(row["misreads"][:6]) + (" …" if len(row["misreads"]) > 6 else "")
            lines.append(
                f"| {row['label']} | {row['plates']} | {row['exact']} | {100 * row['character_accuracy']:.1f} % "
                f"| {row['raw_exact']} | {row['iou_median']:.2f} | {shown} |"
            )
            print(lines[-1], flush=True)
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out is not None:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
