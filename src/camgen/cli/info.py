"""camgen info PROFILE: derived figures — intrinsics and field of view per zoom step, DR, saturation."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from camgen.cli.common import add_profile_dirs_option, profile_dirs
from camgen.config import load_profile
from camgen.config.loader import find_profile, is_profile_name
from camgen.plan.info import profile_info


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("info", help="derived figures of a camera profile")
    parser.add_argument(
        "profile",
        type=Path,
        metavar="PROFILE",
        help="a profile file, or a profile name looked up in --profiles, $CAMGEN_PROFILE_PATH, then ./profiles",
    )
    add_profile_dirs_option(parser)
    parser.set_defaults(run=run)


def run(args: argparse.Namespace, out: Console, err: Console) -> int:
    dirs = profile_dirs(args)
    path = args.profile
    if not path.exists() and is_profile_name(str(path)):
        path = find_profile(str(path), None, dirs, key_path=("PROFILE",))
    loaded = load_profile(path, dirs)
    profile, info = loaded.profile, profile_info(loaded.profile)
    s = profile.sensor
    out.print(f"[bold]{escape(loaded.name)}[/bold] — {escape(profile.description)}")
    sensor = Table(title="Sensor", show_header=False, title_justify="left")
    rows = [
        ("resolution", f"{s.width_px} × {s.height_px} px, {s.cfa}, {s.bit_depth}-bit"),
        (
            "sensor size",
            f"{info.sensor_width_mm:.3f} × {info.sensor_height_mm:.3f} mm (diagonal {info.sensor_diagonal_mm:.3f} mm)",
        ),
        ("pixel", f"{s.pixel_pitch_um:g} × {s.pitch_y_um:g} µm, area {info.pixel_area_um2:.3g} µm²"),
        ("saturation", f"{info.saturation_e:.0f} e⁻ (limited by the {info.saturation_limit})"),
        ("dark current", f"{info.dark_current_e_per_s:.3g} e⁻/s at {s.temperature_c:g} °C"),
        ("temporal dark noise", f"{info.dark_noise_e:.3g} e⁻ rms at {info.dynamic_range_exposure_s:.3g} s, 0 dB"),
        ("dynamic range", f"{info.dynamic_range_db:.1f} dB = 20·log10(saturation / dark noise)"),
        ("circle of confusion", f"{info.coc_um:.3g} µm (for the hyperfocal distance)"),
    ]
    for key, value in rows:
        sensor.add_row(key, value)
    out.print(sensor)
    optics = Table(title="Optics per zoom step", title_justify="left")
    for column in ("zoom ×", "f mm", "fx px", "fy px", "HFOV °", "VFOV °", "DFOV °", "N", "hyperfocal m"):
        optics.add_column(column, justify="right")
    for z in info.zoom_steps:
        optics.add_row(
            f"{z.zoom_x:g}",
            f"{z.focal_length_mm:.2f}",
            f"{z.fx_px:.1f}",
            f"{z.fy_px:.1f}",
            f"{z.hfov_deg:.2f}",
            f"{z.vfov_deg:.2f}",
            f"{z.dfov_deg:.2f}",
            f"{z.f_number:.2f}",
            f"{z.hyperfocal_m:.2f}",
        )
    out.print(optics)
    return 0
