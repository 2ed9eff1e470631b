"""camgen layout SCENE --candidates FILE --budget N: choose mounts, orientations and profiles that see
the scene's regions of interest at their required class; writes a scene YAML fragment and a report."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from rich.console import Console

from camgen.cli.common import add_profile_dirs_option, check_output_directory, profile_dirs
from camgen.cli.coverage import file_triangles_m, located
from camgen.config import load_scene
from camgen.config.layout import LayoutCandidates
from camgen.config.loader import find_profile, load_profile
from camgen.config.scene import Camera, Mount, PtzPosition
from camgen.config.validation import validate
from camgen.config.yaml_source import load_yaml
from camgen.coverage.grid import make_grid, region_masks, region_problems, site_extent_m
from camgen.coverage.layout import optimise_layout, region_cells
from camgen.coverage.occlusion import scene_occluders
from camgen.coverage.plots import plot_site
from camgen.coverage.report import check_settings, scene_coverage
from camgen.errors import ConfigError, Problem
from camgen.io.files import write_text_atomic


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("layout", help="choose camera mounts, orientations and profiles for the regions")
    parser.add_argument("scene", type=Path, metavar="SCENE")
    parser.add_argument("--candidates", type=Path, required=True, metavar="FILE", help="candidate mounts and profiles")
    parser.add_argument("--budget", type=int, required=True, metavar="N", help="number of cameras to place")
    parser.add_argument("-o", "--out", type=Path, default=Path("layout"), metavar="DIR", help="output directory")
    parser.add_argument("--cell-m", type=float, default=0.5, metavar="M", help="grid cell size, m (default 0.5)")
    add_profile_dirs_option(parser)
    parser.set_defaults(run=run)


def run(args: argparse.Namespace, out: Console, err: Console) -> int:
    check_settings(args.cell_m, [0.0])
    if args.budget < 1:
        raise ConfigError(f"--budget must be ≥ 1 camera, got {args.budget}; give how many cameras to place")
    check_output_directory(args.out, "-o")
    dirs = profile_dirs(args)
    loaded = load_scene(args.scene, dirs)
    scene = loaded.scene
    if not scene.regions:
        raise located(loaded, ConfigError([Problem(("regions",), _NO_REGIONS)]))
    document = load_yaml(args.candidates)
    candidates: LayoutCandidates = validate(LayoutCandidates, document)
    names = {r.name for r in scene.regions}
    problems = [
        Problem(
            ("region_weights", name),
            f"names region {name!r}, which the scene does not have",
            document.locate(("region_weights", name)),
        )
        for name in candidates.region_weights
        if name not in names
    ]
    profiles = {}
    for i, reference in enumerate(candidates.profiles):
        key = ("profiles", i)
        try:
            path = find_profile(reference, args.candidates, dirs, document.locate(key), key)
            profiles[reference] = load_profile(path, dirs)
        except ConfigError as error:
            problems += error.problems
    if problems:
        raise ConfigError(problems)
    extent = site_extent_m(scene, loaded.file_bounds)
    try:
        if problems := region_problems(scene, extent):
            raise ConfigError(problems)
        grid = make_grid(extent, args.cell_m, 0.0)
        masks = region_masks(scene, grid)
    except ConfigError as error:
        raise located(loaded, error) from None
    occluders = scene_occluders(scene, file_triangles_m(loaded))
    cells = region_cells(scene.regions, masks, grid, candidates.region_weights, occluders)
    models = {name: p.profile for name, p in profiles.items()}
    try:
        result = optimise_layout(candidates, cells, models, occluders, args.budget)
    except ConfigError as error:
        raise located(loaded, error) from None

    cameras = _cameras(result, result.chosen, models)
    args.out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(args.out / "layout.yaml", _fragment(cameras, result))
    report = {
        "scene": loaded.name,
        "budget": args.budget,
        "options_tried": len(result.options),
        "objective_m2": result.objective_m2,
        "greedy_objective_m2": result.greedy_objective_m2,
        "upper_bound_m2": result.upper_bound_m2,
        "total_region_weight_m2": result.total_weight_m2,
        "guarantee": result.guarantee,
        "baseline": {
            "rule": "evenly spaced mounts, each turned towards the regions' weighted centroid (within its "
            "heading range) at the middle of its pitch range, first profile at its wide end",
            "objective_m2": result.baseline_objective_m2,
            "cameras": [vars(result.options[i]) for i in result.baseline],
        },
        "cameras": [vars(result.options[i]) for i in result.chosen],
    }
    write_text_atomic(args.out / "layout.json", json.dumps(report, indent=2, ensure_ascii=False) + "\n")
    for name, chosen in (
        ("site_layout.png", cameras),
        ("site_baseline.png", _cameras(result, result.baseline, models)),
    ):
        laid_out = scene.model_copy(update={"cameras": chosen})
        coverage = scene_coverage(
            laid_out,
            {c.name: models[c.profile] for c in chosen},
            cell_m=args.cell_m,
            file_bounds=loaded.file_bounds,
            file_triangles_m=file_triangles_m(loaded),
        )
        plot_site(coverage, 0, args.out / name)
    bound = f", bound {result.upper_bound_m2:.1f} m²" if result.upper_bound_m2 is not None else ""
    out.print(
        f"objective {result.objective_m2:.1f} of {result.total_weight_m2:.1f} weighted m² (greedy "
        f"{result.greedy_objective_m2:.1f}{bound}); evenly spaced baseline {result.baseline_objective_m2:.1f}",
        markup=False,
    )
    for camera in cameras:
        m = camera.mount
        focal = f" at {camera.focal_length_mm:.3g} mm" if camera.focal_length_mm is not None else ""
        zoom = f" at zoom {camera.ptz.zoom_x:.3g}×" if camera.ptz is not None else ""
        out.print(
            f"  {camera.name}: {camera.profile}{focal}{zoom} yaw {m.yaw_deg:g}° pitch {m.pitch_deg:g}°", markup=False
        )
    out.print(f"wrote layout.yaml, layout.json, site_layout.png, site_baseline.png to {args.out}", markup=False)
    return 0


def _cameras(result, indices, models) -> list[Camera]:
    """The scene cameras of the options `indices`, named after their mounts: a varifocal lens set to the
    option's focal length, a PTZ head at pan 0, tilt 0 and the option's zoom (the mount aims it)."""
    cameras = []
    for k, i in enumerate(indices, 1):
        option = result.options[i]
        extra = {}
        if option.focal_length_mm is not None:
            profile = models[option.profile]
            if profile.ptz is not None:
                extra["ptz"] = PtzPosition(zoom_x=option.focal_length_mm / profile.lens.focal_length_min_mm)
            else:
                extra["focal_length_mm"] = option.focal_length_mm
        cameras.append(
            Camera(
                name=f"{option.mount}_{k}",
                profile=option.profile,
                mount=Mount(position_m=option.position_m, yaw_deg=option.yaw_deg, pitch_deg=option.pitch_deg),
                **extra,
            )
        )
    return cameras


_NO_REGIONS = "must list at least one region of interest ({name, polygon_m, required_class}) for camgen layout to cover"


def _fragment(cameras: list[Camera], result) -> str:
    lines = [
        "# camgen layout: cameras chosen for the scene's regions of interest; paste under the scene's cameras:",
        f"# objective {result.objective_m2:.2f} weighted m² "
        f"(evenly spaced baseline {result.baseline_objective_m2:.2f})",
        "cameras:",
    ]
    for camera in cameras:
        m = camera.mount
        position = ", ".join(f"{v:g}" for v in m.position_m)
        lines += [
            f"  - name: {camera.name}",
            f"    profile: {camera.profile}",
            f"    mount: {{position_m: [{position}], yaw_deg: {m.yaw_deg:g}, pitch_deg: {m.pitch_deg:g}}}",
        ]
        if camera.focal_length_mm is not None:
            lines.append(f"    focal_length_mm: {camera.focal_length_mm:.4g}")
        if camera.ptz is not None:
            lines.append(f"    ptz: {{pan_deg: 0, tilt_deg: 0, zoom_x: {camera.ptz.zoom_x:.4g}}}")
    return "\n".join(lines) + "\n"
