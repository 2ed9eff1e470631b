"""Frames/s of the speed issue's two reference cameras on whatever OpenGL this process gets: llvmpipe on a
machine without a GPU, the GPU's own driver through EGL where there is one (`Renderer.gl_renderer` names it).

    python -m camgen.bench.device_frames [--frames N] [--json FILE]

The cases are `camgen bench`'s end-to-end ones (`camgen.bench.e2e_cases.measure`: every output the scene
plans, consecutive frames from the sequence's middle, the first a warm-up that is not timed): the parking lot's PTZ at
1080p and the intersection's 4K box camera at its native 3840 × 2160. Where PyAV is not installed (a GPU
machine that was lent bare), the video output is dropped and the table says so; the rest of the camera
model (lens, sensor, ISP, frames, annotations) runs as always. The same command on both machines gives
the comparison recorded in BENCHMARKS.md: each run's ``--json`` file goes into `RECORDS_DIR`, and `make
bench`'s ``device`` section prints them (it does not measure them: the figures of this machine, the other
sections, are the contract).
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import json
import os
import platform
from pathlib import Path

from camgen.bench.e2e_cases import measure

RECORDS_DIR = Path("docs/bench/device_frames")
"""Where the recorded runs live (JSON, one per machine and run), relative to the repository."""

CASES = (
    ("parking_lot", "pole_ptz", (1920, 1080)),
    ("intersection_two_cameras", "box_4k_sw", (3840, 2160)),
)
"""(example scene, camera, stream size): the speed issue's goals (≥ 5 frames/s and ≥ 1 frame/s on two cores)."""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m camgen.bench.device_frames", description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=5, help="frames per case, the first untimed (default 5)")
    parser.add_argument("--json", type=Path, help=f"also write the figures here (kept in {RECORDS_DIR}/NAME.json)")
    parser.add_argument("--note", default="", help="what to say about this run (the commit, what else ran)")
    args = parser.parse_args(argv)
    if args.frames < 2:
        parser.error(f"--frames must be at least 2 (a warm-up and a timed frame), got {args.frames}")
    from camgen.render.renderer import Renderer

    repo = Path(__file__).resolve().parents[3]
    video = importlib.util.find_spec("av") is not None
    with Renderer() as renderer:  # the OpenGL implementation each case's draws get
        gl_renderer = renderer.gl_renderer
    records = [
        measure(repo / "scenes" / f"{scene}.yaml", camera, size, frames=args.frames, video=video)
        for scene, camera, size in CASES
    ]
    where = f"OpenGL: {gl_renderer}; {os.cpu_count()} CPUs; {platform.processor() or platform.machine()}"
    print(where + ("" if video else "; video output left out (PyAV is not installed)"))
    print("| scene | camera | stream | frames/s | ms per frame | stages (ms per frame) |")
    print("|---|---|---|---:|---:|---|")
    for r in records:
        stages = ", ".join(f"{name} {ms:.0f}" for name, ms in sorted(r.stage_ms.items(), key=lambda kv: -kv[1]))
        print(f"| {r.scene} | {r.camera} | {r.size} | {r.frames_per_s:.2f} | {r.frame_ms:.0f} | {stages} |")
    if args.json is not None:
        rows = [{**dataclasses.asdict(r), "frames_per_s": r.frames_per_s} for r in records]
        record = {"where": where, "video": video, "note": args.note, "frames": args.frames, "cases": rows}
        args.json.write_text(json.dumps(record, indent=1), encoding="utf-8")
    return 0


def recorded_table(directory: Path) -> str:
    """The recorded runs in `directory` as BENCHMARKS.md's text: one row per case and run."""
    files = sorted(directory.glob("*.json")) if directory.is_dir() else []
    intro = (
        "`python -m camgen.bench.device_frames --json FILE` times the speed issue's two reference cameras end "
        "to end (the parking lot's PTZ at 1080p, the intersection's 4K box camera at 3840 × 2160; the first "
        "frame a warm-up; frames spread over the sequence in the runs of 2026-11-25, consecutive from its "
        "middle since, as a render draws them) on whatever OpenGL the process gets. Runs recorded on "
        f"other machines are kept in `{RECORDS_DIR}/` and listed here as they were measured; `make bench` does "
        "not re-measure them. Machines and loads differ: compare rows of one run, and this machine's own "
        "sections above."
    )
    if not files:
        return intro + "\n\nNo run is recorded yet."
    rows = ["| run | OpenGL, CPUs | scene | camera | stream | frames/s | ms per frame | largest stages (ms) |",
            "|---|---|---|---|---|---:|---:|---|"]  # fmt: skip
    notes = []
    for path in files:
        record = json.loads(path.read_text(encoding="utf-8"))
        machine = record["where"].split("; ")
        where = f"{machine[0].removeprefix('OpenGL: ')}, {machine[1]}" if len(machine) > 1 else record["where"]
        for case in record["cases"]:
            stages = sorted(case["stage_ms"].items(), key=lambda kv: -kv[1])[:4]
            rows.append(
                f"| {path.stem} | {where} | {case['scene']} | {case['camera']} | {case['size']} | "
                f"{case['frames_per_s']:.2f} | {case['frame_ms']:.0f} | "
                + ", ".join(f"{name} {ms:.0f}" for name, ms in stages)
                + " |"
            )
        note = record.get("note") or ""
        video = "" if record.get("video", True) else " Video encoding left out (PyAV was not installed there)."
        notes.append(f"- `{path.stem}`: {note}{video}")
    return intro + "\n\n" + "\n".join(rows) + "\n\n" + "\n".join(notes)


if __name__ == "__main__":
    raise SystemExit(main())
