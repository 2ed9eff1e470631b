"""camgen fit noise|lens|match: profiles from real hardware.

Each writes profile YAML (a fragment, or with ``--profile BASE`` a profile that extends the base and
is checked by loading it) and a PNG report, and prints what it measured with uncertainties.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from contextlib import nullcontext
from pathlib import Path

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from camgen.cli.common import check_output_file
from camgen.config.profile import Profile
from camgen.errors import ConfigError, Problem

CFA_CHOICES = ("RGGB", "BGGR", "GRBG", "GBRG", "mono")
SHADING_CHOICES = ("none", "highpass", "polynomial")
"""`camgen.fit.noise_spatial.SHADING_CORRECTIONS` (not imported: the parser is built without the fit's dependencies)."""


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "fit",
        help="build a profile from real hardware: noise (raw frames), lens (board images), match (its video)",
        description="Build profile YAML from measurements of a real camera.",
    )
    kinds = parser.add_subparsers(title="what to fit", metavar="KIND", required=True)

    noise = kinds.add_parser(
        "noise",
        help="sensor noise after EMVA 1288 from raw dark (and flat) frames",
        description="Sensor noise after EMVA 1288 release 4.0 from stacks of raw dark and flat frames. Frames "
        "taken at the same exposure time, temperature and light form one stack (a sub-folder is a stack of its "
        "own); exposure time and temperature come from frames.csv in the folder (columns "
        "file,exposure_time_s,temperature_c, and for flats optionally photons_per_pixel or irradiance_w_per_m2), "
        "else from the files' EXIF. DSNU and PRNU come from the largest stacks (PRNU from the one nearest half "
        "saturation); illumination shading is not corrected unless --shading-correction says so. With the "
        "flats' light (photons, or irradiance and wavelength) the quantum efficiency and the dynamic range "
        "are measured too.",
    )
    noise.add_argument("--dark", type=Path, required=True, metavar="DIR", help="folder of dark frames (lens capped)")
    noise.add_argument("--flat", type=Path, metavar="DIR", help="folder of flat-field frames at several light levels")
    noise.add_argument("--metadata", type=Path, metavar="CSV", help="side file for both folders (default: frames.csv)")
    noise.add_argument("--cfa", choices=CFA_CHOICES, help="mosaic of linear TIFF/PNG frames (default mono)")
    noise.add_argument("--bit-depth", type=int, metavar="BITS", help="ADC bits of linear frames (default: container)")
    noise.add_argument(
        "--gain-dn-per-e", type=float, metavar="K", help="system gain when no flats are given (datasheet), DN/e⁻"
    )
    noise.add_argument(
        "--shading-correction",
        choices=SHADING_CHOICES,
        default="none",
        help="correct the PRNU flat for uneven illumination: none (default: EMVA's PRNU1288, as the emva1288 "
        "reference implementation; a non-uniform light adds to it), highpass (EMVA 1288 4.0's high-pass filter) "
        "or polynomial (a quadratic illumination surface divided out)",
    )
    light = noise.add_mutually_exclusive_group()
    light.add_argument(
        "--irradiance-w-per-m2",
        type=float,
        metavar="E",
        help="irradiance on the sensor during every flat (unless frames.csv gives it), W/m²; with --wavelength-nm "
        "it gives the photons per pixel, hence the quantum efficiency and the dynamic range",
    )
    light.add_argument(
        "--photons-per-pixel-per-s",
        type=float,
        metavar="RATE",
        help="photons reaching a pixel per second during every flat (unless frames.csv gives photons_per_pixel)",
    )
    noise.add_argument("--wavelength-nm", type=float, metavar="NM", help="wavelength of the flats' light, nm")
    noise.add_argument(
        "--pixel-pitch-um",
        type=float,
        metavar="P",
        help="pixel pitch, µm, for the pixel area an irradiance falls on (default: --profile's)",
    )
    _add_output_options(noise, "noise")
    noise.set_defaults(run=run_noise)

    lens = kinds.add_parser(
        "lens",
        help="intrinsics and distortion from checkerboard or ChArUco images",
        description="Lens intrinsics and Brown–Conrady distortion from images of a board (OpenCV), with "
        "outlier views rejected and the distortion model chosen by held-out reprojection error.",
    )
    lens.add_argument("--images", type=Path, required=True, metavar="DIR", help="folder of board images")
    lens.add_argument(
        "--board",
        required=True,
        metavar="SPEC",
        help="checkerboard:COLSxROWS:SIZE (inner corners, e.g. checkerboard:9x6:25mm) or "
        "charuco:SQUARESXxSQUARESY:SQUARE:MARKER:DICT (e.g. charuco:11x8:30mm:22mm:DICT_5X5_100)",
    )
    lens.add_argument("--pixel-pitch-um", type=float, metavar="P", help="sensor pixel pitch, µm (for mm figures)")
    lens.add_argument(
        "--accept-poor-fit",
        action="store_true",
        help="write the profile even when the fit shows the views disagree (RMS over 1 px, fx or fy more "
        "uncertain than 2 %%); the doubts become warnings, also in the profile's header (distortion that "
        "folds over inside the image is refused all the same: no profile can hold it)",
    )
    _add_output_options(lens, "lens")
    lens.set_defaults(run=run_lens)

    match = kinds.add_parser(
        "match",
        help="noise and tone parameters from a camera's ordinary 8-bit output",
        description="For a camera whose raw frames are not available: measure the noise level function of "
        "its 8-bit output and fit the base profile's noise and ISP parameters to reproduce it. The matched "
        "profile pins the exposure and gain the fit assumed (manual exposure), is rendered once more at that "
        "operating point with an independent seed, and is refused unless its noise level function (every "
        "intensity bin with enough samples), temporal noise spectrum and blockiness agree with the reference's "
        "within 15 %%.",
    )
    match.add_argument(
        "--reference",
        type=Path,
        nargs="+",
        required=True,
        metavar="FILE",
        help="video file(s), 8-bit images, or folders of them",
    )
    match.add_argument(
        "--max-frames", type=int, default=200, metavar="N", help="frames read from the reference (default %(default)s)"
    )
    match.add_argument("--seed", type=int, default=0, help="seed (≥ 0) of the simulation the fit compares with")
    match.add_argument(
        "--method",
        choices=("auto", "temporal", "spatial"),
        default="auto",
        help="noise estimate: temporal (a static view over frames), spatial (flat patches), auto (default)",
    )
    match.add_argument("--bins", type=int, default=32, metavar="N", help="intensity bins (default %(default)s)")
    match.add_argument(
        "--gain-db",
        type=float,
        metavar="DB",
        help="analog gain the reference was taken at, dB (invisible in 8-bit output, so assumed: default the base "
        "profile's; the matched profile pins it with the exposure time as a manual exposure)",
    )
    match.add_argument("--fit-denoise", action="store_true", help="also fit isp.denoise_strength")
    match.add_argument(
        "--no-codec",
        action="store_true",
        help="leave the profile's codec out of the fit's simulation (by default a video reference is "
        "compared with camgen's output encoded by the profile's codec)",
    )
    match.add_argument(
        "--accept-poor-fit",
        action="store_true",
        help="write the profile even when, rendered at the operating point, it misses the reference by more than "
        "15 %% (an NLF bin with enough samples, the temporal noise spectrum or blockiness); the doubts become "
        "warnings, also in the profile's header",
    )
    _add_output_options(match, "match", profile_required=True)
    match.set_defaults(run=run_match)


def _add_output_options(parser: argparse.ArgumentParser, kind: str, *, profile_required: bool = False) -> None:
    parser.add_argument(
        "--profile",
        type=Path,
        required=profile_required,
        metavar="BASE",
        help="base profile: the output extends it and is validated"
        + ("" if profile_required else " (without it the output is a fragment to merge into a profile)"),
    )
    parser.add_argument(
        "-o", "--output", type=Path, default=Path(f"fit-{kind}.yaml"), metavar="YAML", help="default: %(default)s"
    )
    parser.add_argument("--report", type=Path, metavar="PNG", help="report plot (default: beside the output, .png)")


def _report_path(args: argparse.Namespace) -> Path:
    return args.report if args.report is not None else args.output.with_suffix(".png")


def _progress(err: Console) -> Progress:
    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn())
    return Progress(*columns, console=err, transient=True, disable=not err.is_terminal)


def _significant(value: float, uncertainty: float | None) -> str:
    """`value ± uncertainty` with the uncertainty to two significant digits and the value to match."""
    if uncertainty is None or not math.isfinite(uncertainty) or not uncertainty > 0:
        return f"{value:.4g}"
    decimals = max(0, 1 - math.floor(math.log10(uncertainty)))
    return f"{value:.{decimals}f} ± {uncertainty:.{decimals}f}"


def _print_rows(out: Console, title: str, rows: Sequence[tuple[str, float, float, str]]) -> None:
    table = Table(title=title, title_justify="left")
    table.add_column("quantity")
    table.add_column("value ± 1σ", justify="right")
    table.add_column("unit")
    for name, value, uncertainty, unit in rows:
        table.add_row(escape(name), _significant(value, uncertainty), escape(unit))
    out.print(table)


def _label(fit, name: str) -> str:
    """A candidate's name, marked when it is the chosen model or OpenCV's default."""
    from camgen.fit.lens import OPENCV_DEFAULT_MODEL

    tags = [
        tag for tag, on in (("chosen", name == fit.model), ("OpenCV's default", name == OPENCV_DEFAULT_MODEL)) if on
    ]
    return f"{name} ({', '.join(tags)})" if tags else name


def _candidate_lines(fit) -> list[str]:
    """Each candidate model's errors and intrinsics, and how far its fx, fy lie from the chosen one's."""
    fx0, fy0 = fit.K_px[0, 0], fit.K_px[1, 1]
    lines = []
    for c in fit.candidates:
        fx, fy, cx, cy = c.intrinsics_px
        lines.append(
            f"candidate {_label(fit, c.name)}: held-out RMS {c.held_out_rms_px:.4g} px, "
            f"RMS {c.training_rms_px:.4g} px, fx {fx:.6g} px ({fx / fx0 - 1:+.2%}), fy {fy:.6g} px "
            f"({fy / fy0 - 1:+.2%}), cx {cx:.5g} px, cy {cy:.5g} px"
        )
    return lines


def _print_candidates(out: Console, fit) -> None:
    """The candidate models side by side, OpenCV's default among them, and why the chosen one was chosen."""
    fx0, fy0, cx0, cy0 = fit.K_px[0, 0], fit.K_px[1, 1], fit.K_px[0, 2], fit.K_px[1, 2]
    table = Table(title="distortion models", title_justify="left")
    for column in (
        "model",
        "parameters",
        "held-out RMS px",
        "RMS px",
        "fx − chosen",
        "fy − chosen",
        "cx − chosen",
        "cy − chosen",
    ):
        table.add_column(column, justify="left" if column == "model" else "right")
    for c in fit.candidates:
        fx, fy, cx, cy = c.intrinsics_px
        table.add_row(
            escape(_label(fit, c.name)),
            str(c.parameters),
            f"{c.held_out_rms_px:.4g}",
            f"{c.training_rms_px:.4g}",
            f"{fx / fx0 - 1:+.2%}",
            f"{fy / fy0 - 1:+.2%}",
            f"{cx - cx0:+.2f} px",
            f"{cy - cy0:+.2f} px",
        )
    out.print(table)
    out.print(f"chosen: {escape(fit.selection)}", soft_wrap=True)


def _warn(err: Console, messages: Sequence[str]) -> None:
    for message in messages:
        err.print(f"[yellow]warning[/yellow] {escape(message)}", soft_wrap=True)


def _check_positive(value: float | None, option: str) -> None:
    if value is not None and not value > 0:
        raise ConfigError(f"{option} must be > 0, got {value:g}")


def _check_outputs(args: argparse.Namespace) -> Profile | None:
    """Before any frame is read: the base profile loads (returned; None without --profile), and the
    output names can be files."""
    base = None
    if args.profile is not None:
        from camgen.config.loader import load_profile

        base = load_profile(args.profile).profile
    report = _report_path(args)
    if report.suffix.lower() != ".png":
        raise ConfigError(f"--report {report}: the report is a PNG image; give a name ending in .png")
    for option, path in (("-o", args.output), ("--report", report)):
        check_output_file(path, option)
    return base


def _write_outputs(args, out: Console, fragment: dict, header: list[str], write_report) -> None:
    """The report, then the profile (each under a temporary name until complete); a file that cannot
    be written is a ConfigError naming it."""
    from camgen.fit.profile_yaml import write_profile

    report = _report_path(args)
    for path, write in ((report, write_report), (args.output, None)):
        try:
            if write is not None:
                write(path)
            else:
                write_profile(path, fragment, header=header, base=args.profile)
        except OSError as exc:
            raise ConfigError(f"{path}: cannot write: {exc.strerror or exc}") from None
    kind = "profile" if args.profile is not None else "fragment"
    out.print(f"wrote {kind} {escape(str(args.output))} and report {escape(str(report))}")


def _pixel_area_um2(args: argparse.Namespace, base: Profile | None) -> float | None:
    """The pixel's area, µm², from --pixel-pitch-um or the base profile (None without either)."""
    if args.pixel_pitch_um is not None:
        return args.pixel_pitch_um**2
    if base is not None:
        return base.sensor.pixel_pitch_um * base.sensor.pitch_y_um
    return None


def _flat_photons(stack, args: argparse.Namespace, pixel_area_um2: float | None) -> float | None:
    """μ_p of a flat stack: frames.csv's photons_per_pixel, else its (or --irradiance-w-per-m2's) irradiance
    turned into photons, else --photons-per-pixel-per-s × t; None when nothing gives the light."""
    from camgen.fit.noise import photons_per_pixel

    if stack.photons_per_pixel is not None:
        return stack.photons_per_pixel
    irradiance = stack.irradiance_w_per_m2 if stack.irradiance_w_per_m2 is not None else args.irradiance_w_per_m2
    if irradiance is not None:
        where = "frames.csv" if stack.irradiance_w_per_m2 is not None else "--irradiance-w-per-m2"
        if args.wavelength_nm is None:
            raise ConfigError(
                f"{stack.label}: an irradiance ({where}) becomes photons only with the light's wavelength; "
                "give --wavelength-nm"
            )
        if pixel_area_um2 is None:
            raise ConfigError(
                f"{stack.label}: an irradiance ({where}) becomes photons per pixel only with the pixel's area; "
                "give --pixel-pitch-um or --profile"
            )
        return photons_per_pixel(irradiance, stack.exposure_time_s, args.wavelength_nm, pixel_area_um2)
    if args.photons_per_pixel_per_s is not None:
        return args.photons_per_pixel_per_s * stack.exposure_time_s
    return None


def run_noise(args: argparse.Namespace, out: Console, err: Console) -> int:
    from camgen.fit.frames import listing, scan_stacks
    from camgen.fit.noise import fit_noise
    from camgen.fit.noise_report import write_noise_report
    from camgen.fit.noise_stack import FrameGroup, StackStatistics

    _check_positive(args.gain_dn_per_e, "--gain-dn-per-e")
    for value, option in (
        (args.irradiance_w_per_m2, "--irradiance-w-per-m2"),
        (args.photons_per_pixel_per_s, "--photons-per-pixel-per-s"),
        (args.wavelength_nm, "--wavelength-nm"),
        (args.pixel_pitch_um, "--pixel-pitch-um"),
    ):
        _check_positive(value, option)
    if args.bit_depth is not None and not 8 <= args.bit_depth <= 16:
        raise ConfigError(f"--bit-depth must be 8–16 (the profile's range), got {args.bit_depth}")
    if args.irradiance_w_per_m2 is not None and args.wavelength_nm is None:
        raise ConfigError(
            "--irradiance-w-per-m2 becomes photons only with the light's wavelength; give --wavelength-nm"
        )
    base = _check_outputs(args)
    pixel_area_um2 = _pixel_area_um2(args, base)
    if args.irradiance_w_per_m2 is not None and pixel_area_um2 is None:
        raise ConfigError(
            "--irradiance-w-per-m2 becomes photons per pixel only with the pixel's area; give --pixel-pitch-um or "
            "--profile"
        )
    scans = {}
    with _progress(err) as progress:
        for kind, directory in (("dark", args.dark), ("flat", args.flat)):
            if directory is None:
                continue
            task = progress.add_task(f"reading {kind} frames", total=None)
            scans[kind] = scan_stacks(
                directory,
                kind,
                StackStatistics,
                metadata_file=args.metadata,
                cfa=args.cfa,
                white_level_dn=None if args.bit_depth is None else 2**args.bit_depth - 1,
                on_frame=lambda done, total, task=task: progress.update(task, completed=done, total=total),
            )
    dark = scans["dark"]
    if "flat" in scans:
        flat = scans["flat"]
        if flat.cfa != dark.cfa:
            raise ConfigError(f"the dark frames are {dark.cfa} but the flat frames {flat.cfa}; use one camera mode")
        dark_shape = next(iter(dark.groups.values())).stats.mean_dn.shape
        flat_shape = next(iter(flat.groups.values())).stats.mean_dn.shape
        if dark_shape != flat_shape:
            raise ConfigError(
                f"the dark frames are {dark_shape[1]}×{dark_shape[0]} px but the flat frames "
                f"{flat_shape[1]}×{flat_shape[0]} px; use one sensor mode for both"
            )
    raw_file = dark.black_level_dn is not None
    bit_depth = args.bit_depth or (dark.white_level_dn.bit_length() if dark.white_level_dn else 16)
    groups = [
        FrameGroup(
            kind,
            stack.exposure_time_s,
            stack.temperature_c,
            stack.stats,
            stack.label,
            _flat_photons(stack, args, pixel_area_um2) if kind == "flat" else None,
        )
        for kind, scan in scans.items()
        for stack in scan.groups.values()
    ]
    fit = fit_noise(
        groups,
        cfa=dark.cfa,
        bit_depth=bit_depth,
        gain_dn_per_e=args.gain_dn_per_e,
        shading_correction=args.shading_correction,
    )

    warnings = [f"skipped {name}: it {reason}" for scan in scans.values() for name, reason in scan.skipped]
    warnings += list(fit.warnings)
    lit = [g for g in groups if g.photons_per_pixel is not None]
    if args.wavelength_nm is not None and not lit:
        warnings.append("--wavelength-nm is used only to turn an irradiance into photons, and no flat has one")
    fragment = fit.profile_fragment()
    if args.bit_depth is None and not raw_file:
        # A linear file's container (16 bits) says nothing of the ADC: keep the base profile's.
        fragment["sensor"].pop("bit_depth", None)
        warnings.append(f"bit depth unknown (the files are {bit_depth}-bit containers): give --bit-depth to set it")
    fitted_black = fragment["sensor"].get("black_level_dn")
    if raw_file and fitted_black is not None and abs(fitted_black - dark.black_level_dn) > 1.0:
        warnings.append(
            f"the files state a black level of {dark.black_level_dn:g} DN but the dark frames read {fitted_black:g} DN"
        )
    _warn(err, warnings)
    if dark.optical_black.count:
        mean, std = dark.optical_black.mean_dn(), dark.optical_black.std_dn()
        channels = ", ".join(f"{c} {mean[c]:.2f} ± {std[c]:.2f}" for c in sorted(mean))
        out.print(
            f"masked optical-black border, mean ± standard deviation per channel: {escape(channels)} DN "
            f"(for comparison with the fitted black level)",
            soft_wrap=True,
        )
    frames = sum(len(stack.files) for scan in scans.values() for stack in scan.groups.values())
    _print_rows(out, f"sensor noise ({dark.cfa}, {len(groups)} stacks, {frames} frames)", fit.summary_rows())
    notes = list(fit.notes)
    flats = [g for g in groups if g.kind == "flat"]
    if lit:
        wavelength = f" at {args.wavelength_nm:g} nm" if args.wavelength_nm is not None else ""
        notes.append(
            f"photon counts for {len(lit)} of {len(flats)} flat stacks{wavelength}: quantum efficiency and dynamic "
            "range in photons (η is not written to the profile, whose quantum_efficiency is per colour at its peak)"
        )
    elif flats:
        notes.append(
            "no photon counts for the flats: no quantum efficiency, and the dynamic range is μ_e.sat/μ_e.min; give "
            "--irradiance-w-per-m2 with --wavelength-nm, --photons-per-pixel-per-s, or a photons_per_pixel or "
            "irradiance_w_per_m2 column in frames.csv"
        )
    for note in notes:
        out.print(escape(note), soft_wrap=True)
    sources = [f"--dark {args.dark}"] + ([f"--flat {args.flat}"] if args.flat else [])
    header = [
        f"camgen fit noise {' '.join(sources)} --shading-correction {args.shading_correction}",
        f"{len(groups)} stacks: "
        + listing([f"{g.label} ({len(g.files)})" for s in scans.values() for g in s.groups.values()]),
        *(f"{name}: {_significant(value, unc)} {unit}" for name, value, unc, unit in fit.summary_rows()),
        *notes,
    ]
    _write_outputs(args, out, fragment, header, lambda path: write_noise_report(fit, path))
    return 0


def run_lens(args: argparse.Namespace, out: Console, err: Console) -> int:
    from camgen.fit.frames import listing
    from camgen.fit.lens import detect_in_folder, fit_lens, parse_board
    from camgen.fit.lens_report import write_lens_report

    _check_positive(args.pixel_pitch_um, "--pixel-pitch-um")
    board = parse_board(args.board)
    base = _check_outputs(args)
    pixel_pitch_um = args.pixel_pitch_um
    if base is not None:
        if base.lens.focal_length_range_mm is not None or base.lens.zoom_table:
            raise ConfigError(
                f"--profile {args.profile} is a zoom lens (focal_length_range_mm / zoom_table), but board images "
                "calibrate one focal length; leave --profile out and put the fragment's focal length and "
                "distortion into a zoom_table entry"
            )
        if pixel_pitch_um is None:
            pixel_pitch_um = base.sensor.pixel_pitch_um
    with _progress(err) as progress:
        task = progress.add_task("finding the board", total=None)
        images = detect_in_folder(args.images, board, on_image=lambda path: progress.advance(task))
    fit = fit_lens(
        images.detections,
        images.size_px,
        unusable=images.unusable,
        pixel_pitch_um=pixel_pitch_um,
        accept_poor_fit=args.accept_poor_fit,
    )
    for name, reason in fit.rejected:
        err.print(f"[yellow]rejected[/yellow] {escape(name)}: {escape(reason)}", soft_wrap=True)
    warnings = list(fit.warnings)
    if pixel_pitch_um is None:
        warnings.append("no --pixel-pitch-um (or --profile): the focal length in mm is not written, only fx, fy in px")
    _warn(err, warnings)
    views = len(fit.per_view_rms_px)
    _print_rows(out, f"lens ({fit.model}, {views} views, RMS {fit.rms_px:.3f} px)", fit.summary_rows())
    _print_candidates(out, fit)
    header = [
        f"camgen fit lens --images {args.images} --board {args.board}",
        f"model {fit.model}, RMS {fit.rms_px:.4f} px over {views} views; "
        f"rejected: {listing([name for name, _ in fit.rejected]) or 'none'}",
        f"chosen: {fit.selection}",
        *(f"warning: {warning}" for warning in fit.warnings),
        *(f"{name}: {_significant(value, std)} {unit}" for name, value, std, unit in fit.summary_rows()),
        *_candidate_lines(fit),
        "values below at full precision: the coefficients are correlated, so none may be rounded alone",
    ]
    _write_outputs(
        args, out, fit.profile_fragment(), header, lambda path: write_lens_report(fit, images.detections, path)
    )
    return 0


def run_match(args: argparse.Namespace, out: Console, err: Console) -> int:
    from camgen.fit.frames import VIDEO_SUFFIXES, listing, read_rgb8_frames, reference_files, video_frame_rate
    from camgen.fit.match import fit_match
    from camgen.fit.match_report import write_match_report
    from camgen.fit.match_statistics import ReferenceContentError
    from camgen.fit.match_verify import MatchNotReproducedError

    if args.max_frames < 1:
        raise ConfigError(f"--max-frames must be ≥ 1, got {args.max_frames}")
    if args.seed < 0:
        raise ConfigError(f"--seed must be ≥ 0, got {args.seed}")
    if not 2 <= args.bins <= 256:
        raise ConfigError(f"--bins must be 2–256 (8-bit codes), got {args.bins}")
    if args.gain_db is not None and not 0 <= args.gain_db <= 72:
        raise ConfigError(f"--gain-db must be 0–72 dB (the profile's range), got {args.gain_db:g}")
    base = _check_outputs(args)  # --profile is required here
    videos = [path for path in reference_files(args.reference) if path.suffix.lower() in VIDEO_SUFFIXES]
    codec = base.codec if videos and not args.no_codec else None
    codec_fps = video_frame_rate(videos[0]) if codec is not None else None
    frames_read = 0

    def frames():
        """The reference's frames, streamed (an hour of 1080p does not fit in memory)."""
        nonlocal frames_read
        first = None
        for name, frame in read_rgb8_frames(args.reference, max_frames=args.max_frames):
            if first is None:
                first = (name, frame.shape)
            elif frame.shape != first[1]:
                (h, w), (h0, w0) = frame.shape[:2], first[1][:2]
                raise ConfigError(
                    f"the reference frames differ in size: {first[0]} is {w0}×{h0} px but {name} is {w}×{h} px; "
                    "give frames of one camera mode"
                )
            frames_read += 1
            yield frame

    with err.status("reading the reference and fitting", spinner="dots") if err.is_terminal else nullcontext():
        try:
            fit = fit_match(
                frames(),
                base,
                seed=args.seed,
                method=args.method,
                bins=args.bins,
                gain_db=args.gain_db,
                fit_denoise=args.fit_denoise,
                codec=codec,
                codec_fps=codec_fps,
                accept_poor_fit=args.accept_poor_fit,
            )
        except ReferenceContentError as exc:  # fit_match sees arrays only: say which reference it was
            where = listing([str(path) for path in args.reference])
            problems = [Problem((), f"--reference {where}: {problem}") for problem in exc.problems]
            if isinstance(exc, MatchNotReproducedError) and exc.fit is not None:
                # The refused match's report shows where it misses; the profile is not written.
                report = _report_path(args)
                try:
                    write_match_report(exc.fit, report)
                    problems.append(Problem((), f"the report {report} shows both curves; no profile was written"))
                except OSError:
                    pass
            raise ConfigError(problems) from None
    _warn(err, list(fit.warnings))
    rows = [(key, value, fit.uncertainties.get(key, math.nan), "") for key, value in fit.parameters.items()]
    worst = fit.worst_relative_error
    _print_rows(out, f"fitted to {frames_read} reference frames (worst NLF bin {worst:.1%})", rows)
    point, verification = fit.operating_point, fit.verification
    out.print(escape(point.describe()), soft_wrap=True)
    verdict = "reproduces the reference" if verification.reproduces else "does NOT reproduce the reference"
    out.print(
        escape(
            f"rendered at the operating point (independent seed {verification.seed}), the matched profile {verdict}: "
            f"{verification.summary()}"
        ),
        soft_wrap=True,
    )
    header = [
        f"camgen fit match --reference {' '.join(str(p) for p in args.reference)} --profile {args.profile}"
        + (" --accept-poor-fit" if args.accept_poor_fit else ""),
        f"noise level function ({fit.reference.method}) fitted within {worst:.1%} in every compared bin",
        point.describe(),
        f"verified by rendering at the operating point with an independent seed: {verification.summary()}",
        *(f"warning: {warning}" for warning in fit.warnings),
    ]
    _write_outputs(args, out, fit.profile_fragment(), header, lambda path: write_match_report(fit, path))
    return 0
