"""Write a raw sensor frame as a DNG 1.4 file, the digital negative a raw-capable camera would save.

The file holds one uncompressed 16-bit image in IFD 0 (NewSubFileType 0, a single strip): a Bayer mosaic
with PhotometricInterpretation CFA (32803), or a monochrome frame as one-sample LinearRaw (34892), which
is how DNG stores a sensor without colour filters. The DNG tags say how to read the digital numbers:
which colour each site sees, the black and white levels, and the colour of the camera's channels.
Adobe, "Digital Negative (DNG) Specification", version 1.4.0.0, 2012.

Conventions
-----------
* CFA: camgen names a pattern by its top-left 2×2 block read row by row (``RGGB``, ``BGGR``, ``GRBG``,
  ``GBRG``); DNG's CFAPattern lists the same four sites in the same order, with colours 0 = red,
  1 = green, 2 = blue (CFAPlaneColor 0, 1, 2), which are camgen's channel indices.
* Levels: `black_level_dn` is the offset the ADC adds, one value for every site; `white_level_dn` the
  largest meaningful DN. A reader's linear signal is ``(DN − black) / (white − black)``.
* The file is byte-identical for identical arguments (no time stamp is written), and appears under its
  final name only once complete.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from fractions import Fraction
from pathlib import Path

import numpy as np
import tifffile
from tifffile import DATATYPE

import camgen
from camgen.errors import ConfigError
from camgen.io.files import atomic_path
from camgen.sensor.cfa import CFA_NAMES, cfa_phase_channels

DNG_VERSION = (1, 4, 0, 0)
"""DNGVersion written."""
DNG_BACKWARD_VERSION = (1, 1, 0, 0)
"""DNGBackwardVersion written: the oldest reader that can read these files (nothing here needs 1.2+)."""

ILLUMINANT_D65 = 21
"""EXIF LightSource code of CIE standard illuminant D65 (the CalibrationIlluminant1 written)."""

SRGB_FROM_XYZ = np.linalg.inv(
    np.array(
        [
            [0.4124, 0.3576, 0.1805],
            [0.2126, 0.7152, 0.0722],
            [0.0193, 0.1192, 0.9505],
        ]
    )
)
"""XYZ (D65, Y = 1 for white) → linear sRGB (BT.709 primaries): the inverse of IEC 61966-2-1's matrix.

The default ColorMatrix1: a camera whose raw channels are linear sRGB, as camgen's renderer produces
radiance in, maps D65 white to equal raw values (1, 1, 1) within 1e-4."""

RATIONAL_MAX_DENOMINATOR = 1_000_000
"""Rationals are the closest fraction with a denominator up to this (1/3 stays 1/3; 1e-6 at worst)."""

_PHOTOMETRIC_CFA = 32803
_PHOTOMETRIC_LINEAR_RAW = 34892
_CFA_LAYOUT_RECTANGULAR = 1

_TAG = {
    "Make": 271,
    "Model": 272,
    "ExposureTime": 33434,
    "FNumber": 33437,
    "Temperature": 37888,
    "CFARepeatPatternDim": 33421,
    "CFAPattern": 33422,
    "DNGVersion": 50706,
    "DNGBackwardVersion": 50707,
    "UniqueCameraModel": 50708,
    "CFAPlaneColor": 50710,
    "CFALayout": 50711,
    "BlackLevelRepeatDim": 50713,
    "BlackLevel": 50714,
    "WhiteLevel": 50717,
    "ColorMatrix1": 50721,
    "AsShotNeutral": 50728,
    "CalibrationIlluminant1": 50778,
}


def write_dng(
    path: str | Path,
    raw_dn: np.ndarray,
    *,
    cfa: str,
    black_level_dn: float,
    white_level_dn: int,
    bit_depth: int,
    color_matrix_xyz_to_camera: np.ndarray | Sequence[Sequence[float]] | None = None,
    as_shot_neutral_rgb: Sequence[float] | None = None,
    camera_name: str = "camgen",
    exposure_time_s: float | None = None,
    f_number: float | None = None,
    temperature_c: float | None = None,
) -> None:
    """Write one raw frame, Bayer mosaic or monochrome, as an uncompressed DNG 1.4 file.

    Tags written (besides the baseline TIFF ones, BitsPerSample 16 and Compression 1):

    * all frames: DNGVersion 1.4.0.0, DNGBackwardVersion 1.1.0.0, UniqueCameraModel and Model
      (`camera_name`), Make ``camgen``, Software ``camgen <version>``, BlackLevelRepeatDim (1, 1),
      BlackLevel, WhiteLevel, and ExposureTime / FNumber / Temperature when given;
    * Bayer (PhotometricInterpretation 32803): CFARepeatPatternDim (2, 2), CFAPattern, CFAPlaneColor
      (0, 1, 2), CFALayout 1 (rectangular), ColorMatrix1, CalibrationIlluminant1 21 (D65),
      AsShotNeutral;
    * mono (PhotometricInterpretation 34892, LinearRaw, one sample): no colour tags, since DNG
      defines none for a single colour plane.

    Parameters
    ----------
    path : str or Path
        Output file (``.dng``). Missing parent directories are created; the file is written under a
        temporary name beside it and renamed into place when complete.
    raw_dn : ndarray, shape (H, W), uint16
        Raw digital numbers as the ADC outputs them, black level included; site (y, x) sees the colour
        of ``cfa[2·(y mod 2) + (x mod 2)]``.
    cfa : {"RGGB", "BGGR", "GRBG", "GBRG", "mono"}
        Colour filter array, named by its top-left 2×2 block read row by row; "mono" for none.
    black_level_dn : float
        Offset in every site's DN, ≥ 0 and < `white_level_dn`. Written as a LONG when integral, else as a
        RATIONAL (which LibRaw, and so rawpy, truncates to an integer).
    white_level_dn : int
        Largest meaningful DN (clipping point), ≤ 2^bit_depth − 1; usually exactly 2^bit_depth − 1.
    bit_depth : int
        ADC resolution, 1–16 bits. Samples are stored in 16 bits regardless; every DN must be
        ≤ 2^bit_depth − 1.
    color_matrix_xyz_to_camera : array_like, shape (3, 3), optional
        ColorMatrix1: CIE XYZ (D65 illuminant) → raw camera RGB, rows R, G, B. Default `SRGB_FROM_XYZ`
        (XYZ → linear sRGB), right for raw channels that are linear sRGB as camgen's renderer produces.
        A sensor with quantum efficiency ``qe = (η_R, η_G, η_B)`` per channel over that radiance has
        ``diag(qe) · SRGB_FROM_XYZ``. Not allowed for mono.
    as_shot_neutral_rgb : sequence of 3 float, optional
        AsShotNeutral: raw R, G, B of a neutral (white) surface in the scene's light, each > 0, usually
        scaled so the largest is 1 (the inverse of the white-balance gains). Default (1, 1, 1). Not
        allowed for mono.
    camera_name : str
        UniqueCameraModel and Model: the camera, e.g. the profile's name. Printable ASCII, not empty.
    exposure_time_s : float, optional
        ExposureTime, seconds (> 0).
    f_number : float, optional
        FNumber of the lens (> 0).
    temperature_c : float, optional
        Sensor temperature, °C, in EXIF 2.31's Temperature tag (37888, SRATIONAL), which `camgen fit
        noise` reads back to fit the dark current's temperature dependence.

    Raises
    ------
    ValueError
        If `raw_dn` is not a 2-D uint16 array, or holds a DN above 2^bit_depth − 1.
    ConfigError
        (a ValueError) for an unknown `cfa`, inconsistent levels or bit depth, a colour matrix or
        neutral of the wrong shape or out of range, or colour tags for a mono sensor.

    Examples
    --------
    >>> write_dng("out/cam/raw/000000.dng", raw, cfa="RGGB", black_level_dn=64,  # doctest: +SKIP
    ...           white_level_dn=4095, bit_depth=12)
    """
    _check_raw(raw_dn)
    if not isinstance(cfa, str) or cfa not in CFA_NAMES:
        raise ConfigError(f"cfa must be one of {', '.join(CFA_NAMES)}, got {cfa!r}")
    _check_levels(black_level_dn, white_level_dn, bit_depth)
    peak_dn = int(raw_dn.max())
    if peak_dn > 2**bit_depth - 1:
        raise ValueError(
            f"raw_dn holds {peak_dn} DN, above the {2**bit_depth - 1} DN a {bit_depth}-bit ADC can output; "
            "pass the sensor's bit_depth, or clip the frame"
        )
    if not isinstance(camera_name, str) or not camera_name or not (camera_name.isascii() and camera_name.isprintable()):
        raise ConfigError(f"camera_name must be non-empty printable ASCII (a TIFF ASCII tag), got {camera_name!r}")

    tags = [
        (_TAG["DNGVersion"], DATATYPE.BYTE, 4, DNG_VERSION),
        (_TAG["DNGBackwardVersion"], DATATYPE.BYTE, 4, DNG_BACKWARD_VERSION),
        (_TAG["Make"], DATATYPE.ASCII, 0, "camgen"),
        (_TAG["Model"], DATATYPE.ASCII, 0, camera_name),
        (_TAG["UniqueCameraModel"], DATATYPE.ASCII, 0, camera_name),
        (_TAG["BlackLevelRepeatDim"], DATATYPE.SHORT, 2, (1, 1)),
        _black_level_tag(black_level_dn),
        (_TAG["WhiteLevel"], DATATYPE.LONG, 1, int(white_level_dn)),
    ]
    if exposure_time_s is not None:
        tags.append((_TAG["ExposureTime"], DATATYPE.RATIONAL, 1, _rationals("exposure_time_s", [exposure_time_s])))
    if f_number is not None:
        tags.append((_TAG["FNumber"], DATATYPE.RATIONAL, 1, _rationals("f_number", [f_number])))
    if temperature_c is not None:
        tags.append(
            (_TAG["Temperature"], DATATYPE.SRATIONAL, 1, _rationals("temperature_c", [temperature_c], signed=True))
        )
    if cfa == "mono":
        if color_matrix_xyz_to_camera is not None or as_shot_neutral_rgb is not None:
            raise ConfigError(
                "cfa 'mono' has one colour plane, so color_matrix_xyz_to_camera and as_shot_neutral_rgb "
                "do not apply; leave them None"
            )
        photometric = _PHOTOMETRIC_LINEAR_RAW
    else:
        photometric = _PHOTOMETRIC_CFA
        tags += [
            (_TAG["CFARepeatPatternDim"], DATATYPE.SHORT, 2, (2, 2)),
            (_TAG["CFAPattern"], DATATYPE.BYTE, 4, cfa_phase_channels(cfa)),
            (_TAG["CFAPlaneColor"], DATATYPE.BYTE, 3, (0, 1, 2)),
            (_TAG["CFALayout"], DATATYPE.SHORT, 1, _CFA_LAYOUT_RECTANGULAR),
            (_TAG["ColorMatrix1"], DATATYPE.SRATIONAL, 9, _color_matrix(color_matrix_xyz_to_camera)),
            (_TAG["CalibrationIlluminant1"], DATATYPE.SHORT, 1, ILLUMINANT_D65),
            (_TAG["AsShotNeutral"], DATATYPE.RATIONAL, 3, _neutral(as_shot_neutral_rgb)),
        ]

    height_px = raw_dn.shape[0]
    with atomic_path(path) as tmp:
        tifffile.imwrite(
            tmp,
            np.ascontiguousarray(raw_dn),
            # tifffile refuses one-sample LinearRaw; write MinIsBlack and patch the tag below.
            photometric=photometric if photometric == _PHOTOMETRIC_CFA else tifffile.PHOTOMETRIC.MINISBLACK,
            subfiletype=0,
            rowsperstrip=height_px,
            compression=None,
            metadata=None,
            software=f"camgen {camgen.__version__}",
            extratags=[(code, dtype, count, value, True) for code, dtype, count, value in tags],
        )
        if photometric == _PHOTOMETRIC_LINEAR_RAW:
            with tifffile.TiffFile(tmp, mode="r+b") as tif:
                tif.pages.first.tags["PhotometricInterpretation"].overwrite(_PHOTOMETRIC_LINEAR_RAW)


def _check_raw(raw_dn: object) -> None:
    if not isinstance(raw_dn, np.ndarray):
        raise ValueError(f"raw_dn must be a numpy array, got {type(raw_dn).__name__}")
    if raw_dn.dtype != np.uint16:
        raise ValueError(
            f"raw_dn must have dtype uint16 (raw DN as the ADC outputs them), got {raw_dn.dtype}; "
            "the sensor stage's raw output is uint16 already, and DN are never scaled here"
        )
    if raw_dn.ndim != 2 or raw_dn.size == 0:
        raise ValueError(f"raw_dn must have shape (H, W), one DN per photosite (a mosaic, not RGB), got {raw_dn.shape}")


def _check_levels(black_level_dn: object, white_level_dn: object, bit_depth: object) -> None:
    if isinstance(bit_depth, bool) or not isinstance(bit_depth, numbers.Integral) or not 1 <= bit_depth <= 16:
        raise ConfigError(f"bit_depth must be an integer from 1 to 16 bits, got {bit_depth!r}")
    full_scale_dn = 2**bit_depth - 1
    if isinstance(white_level_dn, bool) or not isinstance(white_level_dn, numbers.Integral):
        raise ConfigError(f"white_level_dn must be an integer DN, got {white_level_dn!r}")
    if not 0 < white_level_dn <= full_scale_dn:
        raise ConfigError(
            f"white_level_dn must be in 1 … {full_scale_dn} (2^bit_depth − 1 for a {bit_depth}-bit ADC), "
            f"got {white_level_dn}"
        )
    if (
        isinstance(black_level_dn, bool)
        or not isinstance(black_level_dn, numbers.Real)
        or not math.isfinite(black_level_dn)
        or not 0 <= black_level_dn < white_level_dn
    ):
        raise ConfigError(
            f"black_level_dn must be a number ≥ 0 and below white_level_dn {white_level_dn}, got {black_level_dn!r}"
        )


def _black_level_tag(black_level_dn: float) -> tuple[int, DATATYPE, int, object]:
    if float(black_level_dn).is_integer():
        return (_TAG["BlackLevel"], DATATYPE.LONG, 1, int(black_level_dn))
    return (_TAG["BlackLevel"], DATATYPE.RATIONAL, 1, _rationals("black_level_dn", [black_level_dn]))


def _color_matrix(matrix: object) -> tuple[int, ...]:
    values = SRGB_FROM_XYZ if matrix is None else np.asarray(matrix, dtype=np.float64)
    if values.shape != (3, 3):
        raise ConfigError(
            f"color_matrix_xyz_to_camera must have shape (3, 3) (XYZ → camera R, G, B), got {values.shape}"
        )
    return _rationals("color_matrix_xyz_to_camera", values.ravel(), signed=True)


def _neutral(neutral: object) -> tuple[int, ...]:
    values = np.ones(3) if neutral is None else np.asarray(neutral, dtype=np.float64)
    if values.shape != (3,) or not np.all(np.isfinite(values) & (values > 0)):
        raise ConfigError(
            f"as_shot_neutral_rgb must be 3 finite numbers > 0 (raw R, G, B of a white surface), got {neutral!r}"
        )
    return _rationals("as_shot_neutral_rgb", values)


def _rationals(name: str, values: Sequence[float] | np.ndarray, *, signed: bool = False) -> tuple[int, ...]:
    """Flattened (numerator, denominator) pairs of TIFF RATIONAL (unsigned) or SRATIONAL (signed) values."""
    lo, hi = (-(2**31), 2**31 - 1) if signed else (0, 2**32 - 1)
    pairs: list[int] = []
    for value in values:
        value = float(value)
        if not math.isfinite(value) or (not signed and value <= 0):
            need = "finite" if signed else "finite and > 0"
            raise ConfigError(f"{name} must be {need}, got {value!r}")
        # the largest denominator that keeps the numerator within 32 bits
        max_denominator = max(1, min(RATIONAL_MAX_DENOMINATOR, int(hi // max(abs(value), 1.0))))
        fraction = Fraction(value).limit_denominator(max_denominator)
        if not lo <= fraction.numerator <= hi:
            raise ConfigError(f"{name} value {value!r} does not fit a 32-bit TIFF rational")
        pairs += [fraction.numerator, fraction.denominator]
    return tuple(pairs)
