"""camgen plan SCENE: the stages, passes and frames a render would run, and why each was chosen."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from camgen.cli.common import add_profile_dirs_option, check_output_file, profile_dirs
from camgen.config import load_scene
from camgen.io.files import write_text_atomic
from camgen.plan import PlanSettings, compile_scene


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("plan", help="compile a scene into a render job and explain it")
    parser.add_argument("scene", type=Path, metavar="SCENE")
    parser.add_argument("--json", type=Path, metavar="FILE", help="also write the job as JSON")
    parser.add_argument("--force-all", action="store_true", help="plan every stage, skipping nothing")
    add_profile_dirs_option(parser)
    parser.set_defaults(run=run)


def run(args: argparse.Namespace, out: Console, err: Console) -> int:
    if args.json:
        check_output_file(args.json, "--json", "give a file name for the job's JSON")
    loaded = load_scene(args.scene, profile_dirs(args))
    job = compile_scene(loaded, PlanSettings(force_all_stages=args.force_all))
    out.print(
        f"[bold]{escape(job.scene_name)}[/bold]  job {job.job_id[:16]}  {job.frame_count} frames at {job.fps:g} fps, "
        f"seed {job.seed}, {len(job.cameras)} camera(s)",
        highlight=False,
    )
    for camera in job.cameras:
        r = camera.render
        state = camera.states[0]
        out.print(
            f"\n[bold]{camera.name}[/bold] ({escape(camera.profile_name)}): "
            f"output {camera.width_px}×{camera.height_px}, "
            f"render {r.width_px}×{r.height_px} (margin l/t/r/b {'/'.join(map(str, r.margin_px))} px, "
            f"supersampling {r.supersampling}×), passes: {', '.join(r.passes) or 'none'}\n"
            f"  f = {state.focal_length_mm:.3g} mm, N = {state.f_number:.3g}, focus {state.focus_distance_m:.3g} m, "
            f"fx = {state.K_px[0][0]:.1f} px, exposure {camera.exposure_mode}",
            highlight=False,
        )
        stages = Table(title="stages", title_justify="left")
        stages.add_column("#", justify="right")
        stages.add_column("stage")
        stages.add_column("passes")
        stages.add_column("params")
        for i, stage in enumerate(camera.stages, 1):
            params = ", ".join(f"{k}={_short(v)}" for k, v in stage.params.items())
            stages.add_row(str(i), stage.name, ", ".join(stage.passes), escape(params))
        out.print(stages)
        decisions = Table(title="decisions", title_justify="left")
        decisions.add_column("")
        decisions.add_column("stage or pass")
        decisions.add_column("effect", justify="right")
        decisions.add_column("threshold", justify="right")
        decisions.add_column("reason")
        for d in camera.decisions:
            effect = f"{d.effect:.3g} {d.unit}" if d.effect is not None else ""
            threshold = f"{d.threshold:g} {d.unit}" if d.threshold is not None else ""
            mark = "[green]run[/green]" if d.included else "[dim]skip[/dim]"
            decisions.add_row(mark, d.stage, effect, threshold, escape(d.reason))
        out.print(decisions)
    if args.json:
        write_text_atomic(args.json, job.to_json())
        out.print(f"wrote {args.json}", markup=False)
    return 0


LISTED_VALUES = 8
"""Longer lists of numbers (one per frame, say) are printed as a summary."""


def _short(value) -> str:
    if isinstance(value, float | np.floating):
        return f"{value:.3g}"
    if isinstance(value, list | tuple):
        numbers = all(isinstance(v, int | float | np.number) and not isinstance(v, bool) for v in value)
        if numbers and len(value) > LISTED_VALUES:
            return _summary(np.asarray(value, dtype=float))
        return "[" + ", ".join(map(_short, value)) + "]"
    return str(value)


def _summary(values: np.ndarray) -> str:
    """``[200 values, all 0]`` or ``[300 values: min 0, median 36.3, max 62.6]``."""
    low, high = np.min(values), np.max(values)
    if low == high:
        return f"[{values.size} values, all {low:.3g}]"
    return f"[{values.size} values: min {low:.3g}, median {np.median(values):.3g}, max {high:.3g}]"
