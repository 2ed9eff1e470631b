"""Reading the frames that fitting starts from: raw and linear frame stacks, board images, reference video.

`camgen.fit` is, with `camgen.io`, the only place that reads files (DESIGN.md). Here:

- **Raw frames** through rawpy (LibRaw: DNG, NEF, CR2, CR3, ARW, RAF, ORF, RW2, …): the visible
  area's DN, the CFA read from the file, its black and white levels, and per CFA channel the mean and
  spread of the masked optical-black border where the format has one.
- **Linear frames** (8–16-bit mono or Bayer TIFF/PNG, as industrial cameras deliver them) through
  OpenImageIO, in their native integer type (never rescaled: nothing infers scale from dtype). Their
  CFA is not in the file; the caller names it.
- **Exposure time and temperature** of every frame come from a side file when one is given (or
  ``frames.csv`` lies in the folder), else from the file's EXIF (ExposureTime 33434, Temperature
  37888, as camgen's DNG writer stores them). An EXIF exposure time of 0 is not taken for a real
  0-second exposure: the fit asks for the side file. The side file may also give a flat's light: the
  photons per pixel of its exposure (``photons_per_pixel``, EMVA 1288's μ_p) or the irradiance on the
  sensor (``irradiance_w_per_m2``), for the quantum efficiency.
- **Grouping**: frames taken at the same settings form one group (one stack). Sub-folders of the
  folder are groups of their own (flats at several light levels but one exposure time); otherwise
  frames are grouped by exposure time, temperature and light (photon count or irradiance).

Every problem with the input is a `ConfigError` or a warning that names the files, never a traceback.
"""

from __future__ import annotations

import csv
import math
from collections import defaultdict
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from camgen.errors import ConfigError
from camgen.io.files import input_file_problem

RAW_SUFFIXES = frozenset(
    ".dng .nef .nrw .cr2 .cr3 .crw .arw .srf .sr2 .raf .orf .rw2 .pef .srw .3fr .fff .iiq .erf .kdc .dcr .mos .mrw "
    ".x3f .rwl .raw".split()
)
"""File name endings read through rawpy (LibRaw)."""
LINEAR_SUFFIXES = frozenset({".tif", ".tiff", ".png", ".pgm", ".pnm"})
"""File name endings read as linear integer frames through OpenImageIO."""
VIDEO_SUFFIXES = frozenset({".mp4", ".mkv", ".mov", ".avi", ".ts", ".m4v", ".webm", ".h264", ".h265", ".hevc"})
IMAGE_SUFFIXES = frozenset({".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".pgm", ".ppm", ".webp"})
METADATA_FILE = "frames.csv"
"""Side file looked for in a frame folder: columns ``file,exposure_time_s[,temperature_c]`` and, for
flats, optionally ``photons_per_pixel`` or ``irradiance_w_per_m2``."""
ADD_SIDE_FILE = f"add {METADATA_FILE} to the folder with the columns file,exposure_time_s,temperature_c"
"""The fix for frames whose exposure time the files do not give."""
LIGHT_COLUMNS = ("photons_per_pixel", "irradiance_w_per_m2")
"""Side-file columns that give a flat frame's light: μ_p of its exposure, or the irradiance E, W/m²."""
BAYER_NAMES = ("RGGB", "BGGR", "GRBG", "GBRG")
EXIF_EXPOSURE_TIME = 33434
EXIF_TEMPERATURE = 37888
SATURATED_DARK_FRAC = 0.9
"""A "dark" frame whose median is above this fraction of the white level is taken to be saturated."""
LISTED = 5
"""File names listed in a message before "and N more"."""


def listing(names: Sequence[str]) -> str:
    """`a, b, c` — at most `LISTED` names, then how many more."""
    shown = ", ".join(names[:LISTED])
    return shown + (f" and {len(names) - LISTED} more" if len(names) > LISTED else "")


def mixed_sizes_error(directory: Path, what: str, sizes_px: dict[tuple[int, int], list[str]], fix: str) -> ConfigError:
    """The error for a folder whose files differ in size: the most common (width, height) and every
    other file with its own."""
    ((width, height), common), *others = sorted(sizes_px.items(), key=lambda item: -len(item[1]))
    odd = listing([f"{name} ({w}×{h} px)" for (w, h), names in others for name in names])
    return ConfigError(f"{directory}: {what}: {len(common)} are {width}×{height} px, but {odd}; {fix}")


@dataclass(frozen=True)
class FrameMetadata:
    exposure_time_s: float | None = None
    temperature_c: float | None = None
    photons_per_pixel: float | None = None
    """μ_p: mean photons reaching a pixel during the exposure (side file only)."""
    irradiance_w_per_m2: float | None = None
    """E on the sensor during the exposure, W/m² (side file only)."""


@dataclass
class BorderStatistics:
    """Per-channel sums over the masked optical-black border of one or more raw frames.

    Sensors keep rows and columns shielded from light around the active area; their per-channel mean is
    the black level the camera measures itself, and their spread its dark noise plus fixed pattern.
    Channels are named by the CFA letter of each site (the two greens G1, G2, in LibRaw's order).
    """

    count: dict[str, int] = field(default_factory=dict)
    sum_dn: dict[str, float] = field(default_factory=dict)
    sum_squares_dn2: dict[str, float] = field(default_factory=dict)

    def add(self, channel: str, values_dn: np.ndarray) -> None:
        values = values_dn.astype(np.float64)
        self.count[channel] = self.count.get(channel, 0) + values.size
        self.sum_dn[channel] = self.sum_dn.get(channel, 0.0) + float(values.sum())
        self.sum_squares_dn2[channel] = self.sum_squares_dn2.get(channel, 0.0) + float(np.sum(values**2))

    def merge(self, other: BorderStatistics) -> None:
        for channel, n in other.count.items():
            self.count[channel] = self.count.get(channel, 0) + n
            self.sum_dn[channel] = self.sum_dn.get(channel, 0.0) + other.sum_dn[channel]
            self.sum_squares_dn2[channel] = self.sum_squares_dn2.get(channel, 0.0) + other.sum_squares_dn2[channel]

    def mean_dn(self) -> dict[str, float]:
        return {c: self.sum_dn[c] / n for c, n in self.count.items()}

    def std_dn(self) -> dict[str, float]:
        """Standard deviation of the border's samples per channel (over sites and frames), DN."""
        mean = self.mean_dn()
        return {
            c: math.sqrt(max(self.sum_squares_dn2[c] / n - mean[c] ** 2, 0.0) * n / max(n - 1, 1))
            for c, n in self.count.items()
        }


def _border_statistics(raw) -> BorderStatistics | None:
    """The masked border of a LibRaw image (the rows above and columns left of the visible area)."""
    sizes = raw.sizes
    if not (sizes.top_margin or sizes.left_margin):
        return None
    masked = np.zeros(raw.raw_image.shape, dtype=bool)
    masked[: sizes.top_margin, :] = True
    masked[:, : sizes.left_margin] = True
    letters = raw.color_desc.decode("ascii")
    colours = raw.raw_colors
    names = {index: letters[index] for index in range(len(letters))}
    if letters.count("G") > 1:
        greens = [i for i, letter in enumerate(letters) if letter == "G"]
        names.update({index: f"G{k + 1}" for k, index in enumerate(greens)})
    statistics = BorderStatistics()
    for index in np.unique(colours[masked]):
        statistics.add(names[int(index)], raw.raw_image[masked & (colours == index)])
    return statistics


@dataclass(frozen=True)
class RawFrame:
    """One raw or linear frame as the sensor delivered it."""

    path: Path
    raw_dn: np.ndarray
    """(H, W) uint16, DN as read (black level included)."""
    cfa: str
    """"RGGB", "BGGR", "GRBG", "GBRG" or "mono"."""
    white_level_dn: int | None
    """Largest DN the file says it can hold (LibRaw's white level; 2^bits − 1 for linear files)."""
    black_level_dn: float | None
    """Black level the file states (mean over the CFA channels); None for linear files."""
    optical_black: BorderStatistics | None
    """Per-channel statistics of the masked optical-black border, where the format keeps one."""
    metadata: FrameMetadata

    @property
    def bit_depth(self) -> int | None:
        return None if self.white_level_dn is None else max(1, math.ceil(math.log2(self.white_level_dn + 1)))


class FrameReadError(Exception):
    """A file that could not be read as a frame (the message says why, without the path)."""


def _cfa_from_rawpy(raw) -> str:
    pattern = np.asarray(raw.raw_pattern)
    if raw.num_colors == 1 or pattern.shape == (1, 1):
        return "mono"
    if pattern.shape != (2, 2):
        raise FrameReadError(
            f"has a {pattern.shape[0]}×{pattern.shape[1]} colour filter array (X-Trans?); only 2×2 Bayer and "
            "mono are supported"
        )
    letters = raw.color_desc.decode("ascii")
    name = "".join(letters[i] for i in pattern.ravel())
    if name not in BAYER_NAMES:
        raise FrameReadError(f"has a colour filter array {name!r}; only RGGB, BGGR, GRBG, GBRG and mono are supported")
    return name


def _tiff_metadata(path: Path) -> FrameMetadata:
    """ExposureTime and Temperature from a TIFF-based file's first IFD or its EXIF IFD (None if absent)."""
    import tifffile

    def number(value) -> float | None:
        if isinstance(value, tuple) and len(value) == 2 and value[1]:
            return value[0] / value[1]
        return float(value) if isinstance(value, int | float) else None

    try:
        with tifffile.TiffFile(path) as tif:
            tags = tif.pages.first.tags
            exif = tags.get("ExifTag")
            exif = exif.value if exif is not None and isinstance(exif.value, dict) else {}
            found = {}
            for key, code, name in (
                ("exposure_time_s", EXIF_EXPOSURE_TIME, "ExposureTime"),
                ("temperature_c", EXIF_TEMPERATURE, "Temperature"),
            ):
                tag = tags.get(code)
                value = number(tag.value) if tag is not None else number(exif.get(name))
                found[key] = value
            return FrameMetadata(**found)
    except Exception:  # not a TIFF container (CR3, RAF…), or no EXIF: the side file must say
        return FrameMetadata()


def _read_rawpy(path: Path) -> RawFrame:
    import rawpy

    try:
        with rawpy.imread(str(path)) as raw:
            cfa = _cfa_from_rawpy(raw)
            visible = np.array(raw.raw_image_visible, dtype=np.uint16)
            optical_black = _border_statistics(raw)
            black = float(np.mean(raw.black_level_per_channel))
            white = int(raw.white_level)
    except (rawpy.LibRawError, OSError, ValueError) as exc:
        raise FrameReadError(f"is not a raw file LibRaw can read ({type(exc).__name__}: {exc})") from None
    if visible.ndim != 2:
        raise FrameReadError(f"holds a {visible.ndim}-D raw image; a one-plane mosaic or mono frame is needed")
    return RawFrame(path, visible, cfa, white, black, optical_black, _tiff_metadata(path))


def _read_linear(path: Path, cfa: str) -> RawFrame:
    import OpenImageIO as oiio  # noqa: N813 — the library's documented alias

    image_input = oiio.ImageInput.open(str(path))
    if image_input is None:
        raise FrameReadError(f"cannot be opened ({oiio.geterror().strip() or 'unknown format'})")
    try:
        spec = image_input.spec()
        if spec.nchannels != 1:
            raise FrameReadError(
                f"has {spec.nchannels} channels; a linear sensor frame has one (mono, or a Bayer mosaic named "
                "with --cfa). Processed RGB images belong to `camgen fit match`"
            )
        pixels = image_input.read_image(spec.format)  # native type: no rescaling
        bits = spec.get_int_attribute("oiio:BitsPerSample", 0)
        exposure = spec.get_float_attribute("ExposureTime", 0.0) or None
    finally:
        image_input.close()
    if pixels is None or pixels.dtype not in (np.uint8, np.uint16):
        kind = "no pixels" if pixels is None else f"{pixels.dtype} samples"
        raise FrameReadError(f"holds {kind}; a linear sensor frame holds 8–16-bit unsigned integers")
    bits = bits or pixels.dtype.itemsize * 8
    metadata = FrameMetadata(exposure_time_s=exposure)
    if path.suffix.lower() in {".tif", ".tiff"}:
        tiff = _tiff_metadata(path)
        metadata = FrameMetadata(tiff.exposure_time_s or exposure, tiff.temperature_c)
    frame = pixels.reshape(pixels.shape[0], pixels.shape[1]).astype(np.uint16)
    return RawFrame(path, frame, cfa, 2**bits - 1, None, None, metadata)


def read_frame(path: Path, *, cfa: str | None = None) -> RawFrame:
    """One raw (rawpy) or linear (OpenImageIO) frame; `cfa` names a linear file's mosaic (default mono).

    Raises `FrameReadError` with the reason when the file is not a frame camgen can fit from.
    """
    suffix = path.suffix.lower()
    if suffix in RAW_SUFFIXES:
        frame = _read_rawpy(path)
        if cfa is not None and cfa != frame.cfa:
            raise FrameReadError(f"is a {frame.cfa} raw file, but --cfa says {cfa}; leave --cfa out for raw files")
        return frame
    if suffix in LINEAR_SUFFIXES:
        return _read_linear(path, cfa or "mono")
    raise FrameReadError(f"has an unknown ending {suffix!r}")


def frame_files(directory: Path) -> list[Path]:
    """Frame files in `directory` and its immediate sub-folders, sorted; a missing folder is a ConfigError."""
    if not directory.is_dir():
        state = "is not a folder" if directory.exists() else "does not exist"
        raise ConfigError(f"{directory} {state}; give the folder that holds the frames")
    suffixes = RAW_SUFFIXES | LINEAR_SUFFIXES
    files = [p for p in sorted(directory.iterdir()) if p.is_file() and p.suffix.lower() in suffixes]
    for sub in sorted(p for p in directory.iterdir() if p.is_dir() and not p.name.startswith(".")):
        files += [p for p in sorted(sub.iterdir()) if p.is_file() and p.suffix.lower() in suffixes]
    if not files:
        raise ConfigError(
            f"{directory} holds no frame files (looked for raw files such as .dng/.nef/.cr2/.arw and linear "
            ".tif/.png, in the folder and its sub-folders)"
        )
    return files


def read_metadata_file(path: Path) -> dict[str, FrameMetadata]:
    """Per-file exposure time, temperature and light from a CSV side file
    (``file,exposure_time_s[,temperature_c][,photons_per_pixel][,irradiance_w_per_m2]``), keyed by the
    file's path as written (relative to the folder scanned, e.g. ``low/0001.tif``). An empty cell is
    not known; a photon count or irradiance must be ≥ 0 (0 for a dark frame)."""

    def number(row: dict, key: str, line: int) -> float | None:
        text = (row.get(key) or "").strip()
        if not text:
            return None
        try:
            value = float(text)
        except ValueError:
            raise ConfigError(f"{path}:{line}: {key} must be a number, got {text!r}") from None
        if not math.isfinite(value) or (key == "exposure_time_s" and value <= 0):
            raise ConfigError(
                f"{path}:{line}: {key} must be a finite number{' > 0' if key == 'exposure_time_s' else ''}, got {text}"
            )
        if key in LIGHT_COLUMNS and value < 0:
            raise ConfigError(f"{path}:{line}: {key} must be ≥ 0, got {text}")
        return value

    try:
        # utf-8-sig: spreadsheets save CSV with a byte-order mark.
        with path.open(newline="", encoding="utf-8-sig") as handle:
            rows = list(csv.DictReader(handle))
            columns = set(rows[0]) if rows else set()
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path}: cannot read as UTF-8 CSV: {exc}") from None
    if "file" not in columns or not columns & {"exposure_time_s", "temperature_c", *LIGHT_COLUMNS}:
        raise ConfigError(
            f"{path}: needs a header line with the columns file,exposure_time_s[,temperature_c]"
            f"[,photons_per_pixel][,irradiance_w_per_m2], got "
            f"{', '.join(sorted(c for c in columns if c)) or 'no columns'}"
        )
    entries: dict[str, FrameMetadata] = {}
    for line, row in enumerate(rows, start=2):
        name = (row.get("file") or "").strip()
        if not name:
            raise ConfigError(f"{path}:{line}: the file column is empty; every row names one frame file")
        key = Path(name).as_posix()
        if key in entries:
            raise ConfigError(f"{path}:{line}: {name} is listed twice")
        entries[key] = FrameMetadata(
            *(number(row, column, line) for column in ("exposure_time_s", "temperature_c", *LIGHT_COLUMNS))
        )
    return entries


def _side_entry(side: dict[str, FrameMetadata], directory: Path, path: Path) -> FrameMetadata:
    """The side file's entry for `path`: by its path relative to `directory`, else by its bare name when
    that is unambiguous."""
    relative = path.relative_to(directory).as_posix()
    if relative in side:
        return side[relative]
    by_name = [key for key in side if Path(key).name == path.name]
    if len(by_name) == 1 and "/" not in by_name[0]:
        return side[by_name[0]]
    return FrameMetadata()


@dataclass
class FrameStack:
    """The frames of one group: one folder, one exposure time, temperatures within `TEMPERATURE_TOLERANCE_C`."""

    label: str
    exposure_time_s: float
    temperature_c: float | None
    """Mean over the stack's frames, °C."""
    stats: object
    """The accumulator the frames were added to."""
    files: list[str]
    folder: str
    photons_per_pixel: float | None = None
    """μ_p of every frame of the stack (side file), or None."""
    irradiance_w_per_m2: float | None = None
    """Irradiance of every frame of the stack, W/m² (side file), or None."""


@dataclass
class FrameStackScan:
    """What `scan_stacks` found in one folder: one stack per group, and what it had to skip."""

    groups: dict[str, FrameStack]
    """By label."""
    cfa: str
    white_level_dn: int | None
    black_level_dn: float | None
    optical_black: BorderStatistics = field(default_factory=BorderStatistics)
    """The masked borders of every frame read, pooled per channel (empty where the files keep none)."""
    skipped: list[tuple[str, str]] = field(default_factory=list)
    """(file name, reason) of files that could not be read."""


TEMPERATURE_TOLERANCE_C = 1.0
"""Frames of one folder and exposure time whose temperatures lie within this of a stack's mean join it:
a sensor drifts by tenths of a degree over a stack."""


def _stack_for(groups: dict[str, FrameStack], directory: Path, path: Path, meta: FrameMetadata, make) -> FrameStack:
    """The stack a frame joins: same folder, exposure time and light (photon count and irradiance),
    temperature within the tolerance of the stack's running mean; a new stack otherwise."""
    folder = directory.name if path.parent == directory else f"{directory.name}/{path.parent.name}"
    light = (meta.photons_per_pixel, meta.irradiance_w_per_m2)
    for stack in groups.values():
        if stack.folder != folder or not math.isclose(stack.exposure_time_s, meta.exposure_time_s, rel_tol=1e-6):
            continue
        if not all(
            (a is None and b is None) or (a is not None and b is not None and math.isclose(a, b, rel_tol=1e-6))
            for a, b in zip((stack.photons_per_pixel, stack.irradiance_w_per_m2), light, strict=True)
        ):
            continue
        if (stack.temperature_c is None) != (meta.temperature_c is None):
            continue
        if meta.temperature_c is None or abs(stack.temperature_c - meta.temperature_c) <= TEMPERATURE_TOLERANCE_C:
            if meta.temperature_c is not None:
                n = len(stack.files)
                stack.temperature_c = (stack.temperature_c * n + meta.temperature_c) / (n + 1)
            return stack
    label = f"{folder} t={meta.exposure_time_s:.6g} s"
    if meta.temperature_c is not None:
        label += f" T={meta.temperature_c:.1f} °C"
    if meta.photons_per_pixel is not None:
        label += f" μ_p={meta.photons_per_pixel:.6g}"
    if meta.irradiance_w_per_m2 is not None:
        label += f" E={meta.irradiance_w_per_m2:.6g} W/m²"
    while label in groups:
        label += "′"
    groups[label] = FrameStack(label, meta.exposure_time_s, meta.temperature_c, make(), [], folder, *light)
    return groups[label]


def scan_stacks(
    directory: Path,
    kind: str,
    accumulator: Callable[[tuple[int, int]], object],
    *,
    metadata_file: Path | None = None,
    cfa: str | None = None,
    white_level_dn: int | None = None,
    on_frame: Callable[[int, int], None] | None = None,
) -> FrameStackScan:
    """Read every frame of `directory` once, adding each to its group's accumulator (frames are never
    all in memory).

    Parameters
    ----------
    directory : Path
        Folder of frames; sub-folders are groups of their own.
    kind : {"dark", "flat"}
        Dark folders are checked for saturated frames.
    accumulator : callable
        ``accumulator((H, W))`` makes a stack accumulator with an ``add(frame_dn)`` method.
    metadata_file : Path, optional
        CSV side file; default ``directory/frames.csv`` when present.
    cfa : str, optional
        Mosaic of linear files (raw files carry their own).
    white_level_dn : int, optional
        Replaces the files' white level (a 12-bit ADC in a 16-bit TIFF).
    on_frame : callable, optional
        ``on_frame(done, total)`` after each file, for progress.
    """
    files = frame_files(directory)
    if metadata_file is None and (directory / METADATA_FILE).is_file():
        metadata_file = directory / METADATA_FILE
    side = read_metadata_file(metadata_file) if metadata_file is not None else {}
    groups: dict[str, FrameStack] = {}
    shapes: dict[tuple[int, int], list[str]] = defaultdict(list)
    cfas: dict[str, list[str]] = defaultdict(list)
    no_exposure: list[str] = []
    zero_exposure: list[str] = []
    saturated: list[str] = []
    scan = FrameStackScan(groups, "mono", None, None)
    for done, path in enumerate(files, start=1):
        try:
            frame = read_frame(path, cfa=cfa)
        except FrameReadError as exc:
            scan.skipped.append((path.name, str(exc)))
            continue
        finally:
            if on_frame is not None:
                on_frame(done, len(files))
        if white_level_dn is not None:
            frame = replace(frame, white_level_dn=white_level_dn)
        meta = _side_entry(side, directory, path)
        from_file = frame.metadata
        meta = replace(
            meta,
            exposure_time_s=from_file.exposure_time_s if meta.exposure_time_s is None else meta.exposure_time_s,
            temperature_c=from_file.temperature_c if meta.temperature_c is None else meta.temperature_c,
        )
        shapes[frame.raw_dn.shape].append(path.name)
        cfas[frame.cfa].append(path.name)
        if meta.exposure_time_s is None:
            no_exposure.append(path.name)
            continue
        if not meta.exposure_time_s > 0:  # EXIF ExposureTime 0: the camera did not record it
            zero_exposure.append(path.name)
            continue
        if (
            kind == "dark"
            and frame.white_level_dn
            and np.median(frame.raw_dn) > SATURATED_DARK_FRAC * frame.white_level_dn
        ):
            saturated.append(path.name)
            continue
        if len(shapes) > 1 or len(cfas) > 1:
            continue
        scan.cfa, scan.white_level_dn = frame.cfa, frame.white_level_dn
        scan.black_level_dn = frame.black_level_dn
        if frame.optical_black is not None:
            scan.optical_black.merge(frame.optical_black)
        group = _stack_for(groups, directory, path, meta, lambda shape=frame.raw_dn.shape: accumulator(shape))
        group.stats.add(frame.raw_dn)
        group.files.append(path.name)
    _check_scan(directory, kind, scan, shapes, cfas, no_exposure, zero_exposure, saturated, metadata_file)
    return scan


def _check_scan(directory, kind, scan, shapes, cfas, no_exposure, zero_exposure, saturated, metadata_file) -> None:
    if not shapes:
        reasons = listing([f"{name} {reason}" for name, reason in scan.skipped])
        raise ConfigError(f"{directory}: no readable frames: {reasons}")
    if len(shapes) > 1:
        sizes_px = {(w, h): names for (h, w), names in shapes.items()}
        raise mixed_sizes_error(
            directory, "frames of mixed resolutions", sizes_px, "a fit needs one sensor mode — move the others out"
        )
    if len(cfas) > 1:
        detail = "; ".join(f"{c}: {listing(ns)}" for c, ns in cfas.items())
        raise ConfigError(f"{directory}: frames with different colour filter arrays ({detail})")
    if saturated:
        raise ConfigError(
            f"{directory}: {listing(saturated)} saturated (median above {SATURATED_DARK_FRAC:.0%} of the white "
            f"level), so {'it is' if len(saturated) == 1 else 'they are'} not dark frames — cap the lens, or move "
            "them to the flats"
        )
    if no_exposure:
        where = f"not in {metadata_file}" if metadata_file else "no side file"
        raise ConfigError(
            f"{directory}: no exposure time for {listing(no_exposure)} (not in the file's EXIF, {where}); "
            f"{ADD_SIDE_FILE}"
        )
    if zero_exposure:
        raise ConfigError(
            f"{directory}: {listing(zero_exposure)} state an exposure time of 0 s in their EXIF, which is no "
            f"real exposure (the camera did not record it); {ADD_SIDE_FILE}"
        )
    few = {label: group.files for label, group in scan.groups.items() if len(group.files) < 2}
    if few:
        detail = "; ".join(f"{label}: {listing(names)}" for label, names in few.items())
        raise ConfigError(
            f"{directory}: temporal noise needs at least 2 frames taken at the same settings, but a group has "
            f"only 1 ({detail}); take two or more frames at each exposure time and temperature"
        )


def read_gray8(path: Path) -> np.ndarray:
    """An 8-bit grey image for board detection: raw files are demosaiced by LibRaw (sRGB gamma),
    other images read by OpenCV (16-bit images reduced to 8 bits). Raises `FrameReadError`."""
    import cv2

    if path.suffix.lower() in RAW_SUFFIXES:
        import rawpy

        try:
            with rawpy.imread(str(path)) as raw:
                rgb = raw.postprocess(output_bps=8, user_flip=0)  # sensor orientation, as calibrated
        except (rawpy.LibRawError, OSError, ValueError) as exc:
            raise FrameReadError(f"is not a raw file LibRaw can read ({type(exc).__name__}: {exc})") from None
        return cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
    return _read_image(path, cv2.IMREAD_GRAYSCALE | cv2.IMREAD_IGNORE_ORIENTATION)


def _read_image(path: Path, flags: int) -> np.ndarray:
    """An image decoded by OpenCV with `flags`. Raises `FrameReadError` for a file that is not a regular
    file, a truncated JPEG or PNG (`truncation`: libjpeg would fill the missing rows with grey and print
    only its own warning to stderr), or one OpenCV cannot decode."""
    import cv2

    problem = input_file_problem(path)
    if problem:
        raise FrameReadError(problem)
    data = path.read_bytes()
    truncated = truncation(data)
    if truncated:
        raise FrameReadError(f"{truncated}; copy it from the camera again")
    image = cv2.imdecode(np.frombuffer(data, np.uint8), flags)
    if image is None:
        raise FrameReadError("is not an image OpenCV can read")
    return image


JPEG_STANDALONE_MARKERS = frozenset({0x01, *range(0xD0, 0xD8)})
"""JPEG markers without a length field: TEM and the restart markers RST0–RST7."""


def truncation(data: bytes) -> str | None:
    """Why the bytes of a JPEG or PNG file end before the image does; None when they do not (or the
    data is neither format, or its structure is not recognised: the decoder then judges).

    A JPEG's marker segments are walked by their lengths to its first scan (SOS, FF DA), after which its
    end-of-image marker (EOI, FF D9) must follow (ITU-T T.81, B.1.1.2–B.2.1; entropy-coded data stuffs
    each FF byte, so FF D9 cannot occur inside it). A PNG must hold its IEND chunk.
    """
    if data.startswith(b"\xff\xd8"):
        offset = 2
        while offset + 4 <= len(data):
            if data[offset] != 0xFF:
                return None
            marker = data[offset + 1]
            if marker == 0xFF:  # fill byte before a marker
                offset += 1
            elif marker in JPEG_STANDALONE_MARKERS:
                offset += 2
            elif marker == 0xDA:
                scan = offset + 2 + int.from_bytes(data[offset + 2 : offset + 4], "big")
                if data.find(b"\xff\xd9", scan) >= 0:
                    return None
                break
            else:
                offset += 2 + int.from_bytes(data[offset + 2 : offset + 4], "big")
        return f"is truncated: its JPEG data ends after {len(data)} bytes, before the end-of-image marker"
    if data.startswith(b"\x89PNG\r\n\x1a\n") and data.rfind(b"IEND") < 0:
        return f"is truncated: its PNG data ends after {len(data)} bytes, before the IEND chunk"
    return None


def image_files(directory: Path) -> list[Path]:
    """Board images in `directory` (any image or raw file), sorted. Where it holds none, the views of a
    camgen render below it: a job directory (CAMERA/frames/) or a render's -o directory holding one job
    (JOB/CAMERA/frames/), so `fit lens` takes the checkerboard scene's output (one camera per view) as it
    is. Each camera gives its first frame: its later frames repeat the view (the board does not move), and
    a repeated view would sit in training and held-out folds alike."""
    if not directory.is_dir():
        state = "is not a folder" if directory.exists() else "does not exist"
        raise ConfigError(f"{directory} {state}; give the folder that holds the board images")
    suffixes = IMAGE_SUFFIXES | RAW_SUFFIXES
    files = [p for p in sorted(directory.iterdir()) if p.suffix.lower() in suffixes]
    if not files:
        files = _first_frame_per_camera(directory.glob("*/frames/*"), suffixes)
    if not files:
        files = _first_frame_per_camera(directory.glob("*/*/frames/*"), suffixes)
        jobs = sorted({p.relative_to(directory).parts[0] for p in files})
        if len(jobs) > 1:
            raise ConfigError(
                f"{directory} holds the renders of {len(jobs)} jobs ({listing(jobs)}), which may differ in lens; "
                "give one job's directory"
            )
    if not files:
        raise ConfigError(
            f"{directory} holds no images ({', '.join(sorted(suffixes))}), nor a camgen render's CAMERA/frames/ "
            "folders with such images"
        )
    return files


def _first_frame_per_camera(frames: Iterable[Path], suffixes: frozenset[str]) -> list[Path]:
    """The first (by name) image file of each frames/ folder among `frames`, sorted."""
    first: dict[Path, Path] = {}
    for path in sorted(frames):
        if path.suffix.lower() in suffixes and path.is_file():
            first.setdefault(path.parent, path)
    return list(first.values())


def read_rgb8_frames(paths: Sequence[Path], *, max_frames: int) -> Iterator[tuple[str, np.ndarray]]:
    """(name, (H, W, 3) uint8 RGB) for each frame of the reference: every decoded frame of a video (up to
    `max_frames` in all), or each 8-bit image. Raises ConfigError naming a file that is not 8-bit RGB
    video or image."""
    import cv2

    count = 0
    for path in reference_files(paths):
        if path.suffix.lower() in VIDEO_SUFFIXES:
            import av

            from camgen.io.video import decoded_rgb8

            try:
                with av.open(str(path)) as container:
                    if not container.streams.video:
                        raise ConfigError(f"{path}: holds no video stream")
                    for index, frame in enumerate(container.decode(video=0)):
                        if count >= max_frames:
                            return
                        count += 1
                        yield f"{path.name}#{index}", decoded_rgb8(frame)
            except av.FFmpegError as exc:
                raise ConfigError(f"{path}: cannot decode the video ({exc})") from None
            continue
        try:
            image = _read_image(path, cv2.IMREAD_UNCHANGED | cv2.IMREAD_IGNORE_ORIENTATION)
        except FrameReadError as error:
            raise ConfigError(f"{path}: {error} (a reference is videos or 8-bit images)") from None
        if image.dtype != np.uint8:
            raise ConfigError(
                f"{path}: holds {image.dtype} samples; `fit match` reads a camera's 8-bit output (raw or 16-bit "
                "frames belong to `camgen fit noise`)"
            )
        if image.ndim == 2:
            image = cv2.cvtColor(image, cv2.COLOR_GRAY2RGB)
        elif image.shape[2] == 4:
            image = cv2.cvtColor(image, cv2.COLOR_BGRA2RGB)
        else:
            image = cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
        if count >= max_frames:
            return
        count += 1
        yield path.name, image


def reference_files(paths: Sequence[Path]) -> list[Path]:
    """The reference's files: each path given, a folder standing for its videos and images (sorted)."""
    files = []
    for path in paths:
        if path.is_dir():
            inside = [p for p in sorted(path.iterdir()) if p.suffix.lower() in VIDEO_SUFFIXES | IMAGE_SUFFIXES]
            if not inside:
                raise ConfigError(f"{path} is a folder without videos or images of the camera's output")
            files += inside
        elif path.is_file():
            files.append(path)
        else:
            raise ConfigError(f"{path} does not exist; give videos or 8-bit images of the camera's output")
    return files


def video_frame_rate(path: Path) -> float | None:
    """The average frame rate of a video's first stream, Hz (None when the container does not say)."""
    import av

    try:
        with av.open(str(path)) as container:
            rate = container.streams.video[0].average_rate if container.streams.video else None
    except av.FFmpegError:
        return None
    return float(rate) if rate else None
