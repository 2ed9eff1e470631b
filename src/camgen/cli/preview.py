"""camgen preview OUT: draw a render's annotations over its frames (boxes, track ids in stable colours,
keypoint skeletons, masks, the PTZ state, ground-truth track tails) into a video and a contact sheet, and
with --html one self-contained page that also plots the camera's state over time and shows the dataset card.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

from camgen.cli.common import check_output_directory
from camgen.cli.progress import ProgressLines
from camgen.errors import ConfigError
from camgen.preview.run import MAX_WIDTH_PX, write_preview
from camgen.preview.source import check_camera_output, find_camera_outputs, load_sequence

PREVIEW_DIRECTORY = "preview"


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "preview", help="draw a render's annotations over its frames: video, contact sheet, page"
    )
    parser.add_argument(
        "path",
        type=Path,
        metavar="OUT",
        help="what camgen render -o or camgen batch -o wrote, one job directory in it, or one camera's directory",
    )
    parser.add_argument("--camera", action="append", metavar="NAME", help="preview only this camera (repeatable)")
    parser.add_argument(
        "-o",
        "--out",
        type=Path,
        metavar="DIR",
        help=f"where the preview files go (default: {PREVIEW_DIRECTORY}/ beside the job directories)",
    )
    parser.add_argument(
        "--html", action="store_true", help="also write one self-contained HTML page per camera (video embedded)"
    )
    parser.add_argument(
        "--max-width",
        type=int,
        default=MAX_WIDTH_PX,
        metavar="PX",
        help=f"scale wider frames down to this width before drawing (default {MAX_WIDTH_PX})",
    )
    parser.set_defaults(run=run)


def run(args: argparse.Namespace, out: Console, err: Console) -> int:
    if args.max_width < 16:
        raise ConfigError(f"--max-width must be ≥ 16 px, got {args.max_width}")
    outputs = find_camera_outputs(args.path, args.camera)
    for output in outputs:
        check_camera_output(output)
    directory = args.out if args.out is not None else outputs[0].job_directory.parent / PREVIEW_DIRECTORY
    option = "-o" if args.out is not None else "the default preview directory"
    check_output_directory(directory, option, "give a directory you can write to with -o")
    sequences = [load_sequence(output) for output in outputs]
    labels = [f"{s.output.job_directory.name}/{s.output.name}" for s in sequences]
    with _frame_progress(err, labels, [len(s.frame_indices) for s in sequences]) as on_frame:
        results = [
            write_preview(s, directory, html=args.html, max_width_px=args.max_width, on_frame=lambda k=k: on_frame(k))
            for k, s in enumerate(sequences)
        ]
    for label, files in zip(labels, results, strict=True):
        out.print(f"{escape(label)}: {files.frames} frames", highlight=False)
        for path in (files.video, files.contact_sheet, files.html):
            if path is not None:
                out.print(f"  {escape(str(path))}", highlight=False)
    return 0


@contextmanager
def _frame_progress(err: Console, labels: list[str], counts: list[int]) -> Iterator[Callable[[int], None]]:
    """on_frame(k) for the k-th sequence: a bar per sequence on a terminal, periodic lines in a log."""
    if not err.is_terminal:
        with ProgressLines(err, "preview", sum(counts), "frames") as lines:
            yield lambda k: lines.advance()
        return
    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn())
    with Progress(*columns, console=err) as progress:
        tasks = [progress.add_task(escape(label), total=count) for label, count in zip(labels, counts, strict=True)]
        yield lambda k: progress.advance(tasks[k])
