"""camgen coverage SCENE: where each camera sees a person, at what pixel density and IEC 62676-4 class;
the network's figures; coverage.json, coverage.npz and plots."""

from __future__ import annotations

import argparse
import io
import json
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from camgen.cli.common import add_profile_dirs_option, check_output_directory, profile_dirs
from camgen.config import LoadedScene, load_scene
from camgen.config.scene import FileMesh
from camgen.coverage.dori import DORI_CLASSES
from camgen.coverage.plots import plot_image_plane, plot_site
from camgen.coverage.report import arrays, check_settings, report, scene_coverage
from camgen.errors import ConfigError, Problem
from camgen.io.files import atomic_path, write_text_atomic


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "coverage", help="pixel density and IEC 62676-4 DORI classes of every camera on a ground grid"
    )
    parser.add_argument("scene", type=Path, metavar="SCENE")
    parser.add_argument("-o", "--out", type=Path, default=Path("coverage"), metavar="DIR", help="output directory")
    parser.add_argument("--cell-m", type=float, default=0.25, metavar="M", help="grid cell size, m (default 0.25)")
    parser.add_argument(
        "--height-m",
        type=float,
        action="append",
        metavar="M",
        help="height of a grid plane, m: 0 the ground, 1.6 a face (repeatable; default 0)",
    )
    parser.add_argument(
        "--ptz-reach",
        action="store_true",
        help="also what each PTZ head reaches over its pan/tilt range (a virtual PTZ: any window of its sensor), "
        "at wide and at tele zoom",
    )
    parser.add_argument("--no-plots", action="store_true", help="write the report and arrays only")
    add_profile_dirs_option(parser)
    parser.set_defaults(run=run)


def file_triangles_m(loaded: LoadedScene) -> dict[str, np.ndarray]:
    """Triangles (T, 3, 3) of every environment mesh file, in the file's units (trimesh reads them)."""
    import trimesh

    out = {}
    for mesh in loaded.scene.environment.meshes:
        if isinstance(mesh, FileMesh) and mesh.path not in out:
            solid = trimesh.load(loaded.path.parent / mesh.path, force="mesh")
            out[mesh.path] = np.asarray(solid.triangles, dtype=np.float64)
    return out


def located(loaded: LoadedScene, error: ConfigError) -> ConfigError:
    """`error`'s problems about scene keys, pointed into the scene file."""
    return ConfigError(
        [Problem(p.path, p.message, loaded.locate(p.path)) if p.path and not p.location else p for p in error.problems]
    )


def run(args: argparse.Namespace, out: Console, err: Console) -> int:
    heights = args.height_m or [0.0]
    check_settings(args.cell_m, heights)
    check_output_directory(args.out, "-o")
    loaded = load_scene(args.scene, profile_dirs(args))
    try:
        coverage = scene_coverage(
            loaded.scene,
            loaded.profile_models,
            cell_m=args.cell_m,
            heights_m=heights,
            with_ptz_reach=args.ptz_reach,
            file_bounds=loaded.file_bounds,
            file_triangles_m=file_triangles_m(loaded),
        )
    except ConfigError as error:
        raise located(loaded, error) from None
    document = report(coverage, loaded.name)
    args.out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(args.out / "coverage.json", json.dumps(document, indent=2, ensure_ascii=False) + "\n")
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **arrays(coverage))
    with atomic_path(args.out / "coverage.npz") as tmp:
        tmp.write_bytes(buffer.getvalue())
    written = ["coverage.json", "coverage.npz"]
    if not args.no_plots:
        for k, plane in enumerate(coverage.planes):
            tag = f"{plane.grid.height_m:g}m"
            written.append(plot_site(coverage, k, args.out / f"site_{tag}.png").name)
            if args.ptz_reach and plane.reaches:
                written.append(plot_site(coverage, k, args.out / f"site_{tag}_ptz_tele.png", zoom="tele").name)
            for i, view in enumerate(coverage.views):
                written.append(
                    plot_image_plane(coverage, i, plane.grid.height_m, args.out / f"image_{view.name}_{tag}.png").name
                )
    _print_summary(out, document)
    out.print(f"wrote {', '.join(written)} to {args.out}", markup=False)
    return 0


def _print_summary(out: Console, document: dict) -> None:
    for plane in document["planes"]:
        network = plane["network"]
        table = Table(title=f"z = {plane['height_m']:g} m: site {network['site_area_m2']:.0f} m²", title_justify="left")
        table.add_column("class")
        table.add_column("area m²", justify="right")
        table.add_column("share", justify="right")
        table.add_column("≥ 2 cameras m²", justify="right")
        for name in DORI_CLASSES:
            at = network["area_at_least_class"][name]
            by = network["area_by_camera_count_m2"][name]
            table.add_row(name, f"{at['area_m2']:.0f}", f"{at['share']:.1%}", f"{by['2'] + by['3+']:.0f}")
        out.print(table)
        blind = network["blind"]
        out.print(f"blind (below detect): {blind['area_m2']:.0f} m² ({blind['share']:.1%})", markup=False)
        for region in plane["regions"]:
            share = region["share_meeting_required"]
            out.print(
                f"region {escape(region['name'])}: needs {region['required_class']}, best {region['best_class']}, "
                f"{'n/a' if share is None else f'{share:.0%}'} meets it",
                highlight=False,
            )
