"""Write single frames and depth maps as image files: PNG, TIFF and OpenEXR, through OpenImageIO.

Conventions
-----------
* Images are (H, W) or (H, W, C) arrays with channels in R, G, B order (C = 1 or 3); they are stored as
  they are. PNG and TIFF hold uint8 or uint16 samples and EXR linear float32 (stored as half or float);
  nothing is rescaled or converted between integer and float, so the caller quantises first.
* Depth is camera z in metres, +inf where no geometry is hit (`camgen.render`).
* A file appears under its final name only once complete, and identical arguments give identical bytes:
  the time stamp OpenImageIO would add (TIFF and EXR DateTime) is left empty.
"""

from __future__ import annotations

from pathlib import Path
from types import MappingProxyType
from typing import Literal

import numpy as np
import OpenImageIO as oiio  # noqa: N813 - the alias its documentation uses

from camgen.errors import ConfigError
from camgen.io.files import atomic_path

FRAME_FORMATS = ("png", "tiff", "exr")
"""Formats of `write_frame`."""
DEPTH_FORMATS = ("png16", "exr")
"""Formats of `write_depth`."""
SUFFIXES = MappingProxyType({"png": (".png",), "png16": (".png",), "tiff": (".tif", ".tiff"), "exr": (".exr",)})
"""File name suffixes each format accepts (any case)."""

PNG_COMPRESSION_LEVEL = 2
"""zlib level of PNG frames and depth maps (0–9): fast, lossless (see `PNG_ROW_FILTER`)."""
PNG_ROW_FILTER = MappingProxyType({3: "average", 1: "up"})
"""The one PNG row filter (ISO/IEC 15948, 9.2) every row of a PNG gets, by channel count: three (R, G, B)
or one (grey, depth, raw mosaic). libpng otherwise tries all five on every row and keeps the best guess,
which took as long as the compression itself. Measured at zlib level 2 against libpng's adaptive choice
at the former level 1 (interleaved, same process, load 8–9 on 2 cores, on rendered frames: the parking
lot's 1080p frame and depth, the night street's 2688×1520 IR frame, 16-bit radiance and raw mosaic, two
vehicle close-ups, a checkerboard view): RGB with "average" in 31–50 % of the time, −5.5 to +1.4 % in
size; one channel with "up" in 48–51 % (depth, −4 %), 50–54 % (8-bit grey, +0.7 to +4.5 %) and 70–76 %
(16-bit raw mosaic, +1.4 to +2.3 %). "average" predicts a pixel from the mean of its left and upper
neighbours, which halves the variance of the sensor noise in the prediction; on one channel it made
files up to 24 % larger, so those get "up". The pixels are the same whichever filter: PNG is lossless."""
DEPTH_PNG_MAX_M = 65.535
"""Largest depth a 16-bit millimetre PNG holds, m (65535 mm); deeper points saturate there."""
HALF_MAX = float(np.finfo(np.float16).max)
"""Largest finite half-float value (65504); EXR half channels cannot hold more."""

_OIIO_FORMAT = MappingProxyType({"png": "png", "png16": "png", "tiff": "tiff", "exr": "openexr"})
_EXR_PIXEL_TYPES = MappingProxyType({"half": oiio.HALF, "float": oiio.FLOAT})
_INTEGER_TYPES = MappingProxyType({np.dtype(np.uint8): oiio.UINT8, np.dtype(np.uint16): oiio.UINT16})
_LIBPNG_FILTER_FLAGS = MappingProxyType({"none": 0x08, "sub": 0x10, "up": 0x20, "average": 0x40, "paeth": 0x80})
"""libpng's PNG_FILTER_* flags (png.h), which OpenImageIO's png:filter attribute passes to png_set_filter."""


def write_frame(
    path: str | Path,
    image: np.ndarray,
    *,
    format: Literal["png", "tiff", "exr"],
    exr_pixel_type: Literal["half", "float"] = "float",
) -> None:
    """Write one image as PNG, TIFF (deflate, lossless) or OpenEXR (zip, lossless).

    Parameters
    ----------
    path : str or Path
        Output file; its suffix must fit `format` (``.png``; ``.tif`` or ``.tiff``; ``.exr``). Missing
        parent directories are created.
    image : ndarray, shape (H, W), (H, W, 1) or (H, W, 3)
        Channels R, G, B (or one grey channel, named Y in EXR). For ``png`` and ``tiff``: uint8 or uint16
        DN, stored as given. For ``exr``: float32 linear values (e.g. radiance); NaN and ±inf are kept.
    format : {"png", "tiff", "exr"}
        File format.
    exr_pixel_type : {"half", "float"}
        Sample type of an EXR file: 16-bit half (11 significant bits, finite up to 65504, half the size)
        or 32-bit float (exact). Ignored for PNG and TIFF.

    Raises
    ------
    ValueError
        If the image has another shape, a float dtype for PNG/TIFF or a non-float32 dtype for EXR, or
        finite values beyond ±65504 for a half EXR.
    ConfigError
        (a ValueError) for an unknown format or EXR pixel type, or a suffix that does not fit the format.
    OSError
        If OpenImageIO cannot write the file.
    """
    _check_format(format, FRAME_FORMATS, "write_frame", path)
    image = _channels_last(image, "image")
    if format == "exr":
        if exr_pixel_type not in _EXR_PIXEL_TYPES:
            raise ConfigError(f"exr_pixel_type must be 'half' or 'float', got {exr_pixel_type!r}")
        if image.dtype != np.float32:
            raise ValueError(
                f"an EXR frame must be float32 (linear values), got {image.dtype}; "
                "convert it explicitly, e.g. image.astype(np.float32), or write integer DN as png or tiff"
            )
        if exr_pixel_type == "half":
            finite = image[np.isfinite(image)]
            if finite.size and float(np.abs(finite).max()) > HALF_MAX:
                raise ValueError(
                    f"image holds {float(np.abs(finite).max()):g}, beyond the ±{HALF_MAX:g} a half EXR holds "
                    "(it would become inf); use exr_pixel_type='float' or scale the image"
                )
        pixel_type = _EXR_PIXEL_TYPES[exr_pixel_type]
    else:
        if image.dtype not in _INTEGER_TYPES:
            raise ValueError(
                f"a {format.upper()} frame must be uint8 or uint16 DN, got {image.dtype}; quantise it first, "
                "e.g. np.clip(np.rint(image * 255), 0, 255).astype(np.uint8) for 0–1 floats, "
                "or write linear floats as exr"
            )
        pixel_type = _INTEGER_TYPES[image.dtype]
    channel_names = ("Y",) if image.shape[2] == 1 else ("R", "G", "B")
    _write(path, image, oiio_format=_OIIO_FORMAT[format], pixel_type=pixel_type, channel_names=channel_names)


def write_depth(path: str | Path, depth_m: np.ndarray, *, format: Literal["png16", "exr"]) -> int:
    """Write a depth map as a 16-bit millimetre PNG or a float32 OpenEXR in metres.

    ``png16`` stores ``round(1000 · depth_m)`` (half to even) as one uint16 grey channel, mm:

    * 0 means no geometry (+inf); a finite depth under 0.5 mm, which would round to 0, is stored as
      1 mm so that 0 keeps that meaning;
    * depths beyond `DEPTH_PNG_MAX_M` (65.535 m) saturate at 65535 mm; the function returns how many
      pixels did, so a caller can warn that the PNG's depth range is too short for the scene.

    ``exr`` stores depth_m as float32 metres in one channel named Z (OpenEXR's depth channel), +inf kept
    as +inf; nothing saturates.

    Parameters
    ----------
    path : str or Path
        Output file, ``.png`` or ``.exr`` to fit `format`. Missing parent directories are created.
    depth_m : ndarray, shape (H, W) or (H, W, 1), floating
        Camera z, m: > 0, or +inf where no geometry is hit. float64 is stored as float32 in EXR.
    format : {"png16", "exr"}
        File format.

    Returns
    -------
    int
        Pixels whose depth saturated at 65535 mm (always 0 for ``exr``).

    Raises
    ------
    ValueError
        If depth_m is not a floating (H, W) array, or holds NaN, 0, a negative value or −inf.
    ConfigError
        (a ValueError) for an unknown format or a suffix that does not fit it.
    OSError
        If OpenImageIO cannot write the file.
    """
    _check_format(format, DEPTH_FORMATS, "write_depth", path)
    depth_m = _channels_last(depth_m, "depth_m")
    if depth_m.shape[2] != 1 or not np.issubdtype(depth_m.dtype, np.floating):
        raise ValueError(
            f"depth_m must be a floating array of shape (H, W), camera z in metres, got {depth_m.dtype} "
            f"of shape {depth_m.shape}"
        )
    if np.isnan(depth_m).any() or not (depth_m > 0).all():
        raise ValueError(
            "depth_m must be > 0 m everywhere, with +inf where no geometry is hit; it holds NaN, 0 or "
            "negative values (mark background pixels with np.inf)"
        )
    if format == "exr":
        _write(path, depth_m.astype(np.float32), oiio_format="openexr", pixel_type=oiio.FLOAT, channel_names=("Z",))
        return 0
    depth_mm, saturated = depth_mm_u16(depth_m)
    _write(path, depth_mm, oiio_format="png", pixel_type=oiio.UINT16, channel_names=("Y",))
    return saturated


def write_exr(path: str | Path, image: np.ndarray, *, channel_names: tuple[str, ...]) -> None:
    """Write a float32 (H, W, C) array as an OpenEXR of float channels with the given names (e.g. X, Y,
    Z for a vector field), values kept as they are (NaN and ±inf included).

    Raises
    ------
    ValueError
        If `image` is not float32 (H, W) or (H, W, C), or `channel_names` does not name C channels.
    ConfigError
        (a ValueError) if the suffix is not ``.exr``.
    """
    _check_format("exr", FRAME_FORMATS, "write_exr", path)
    image = image[:, :, np.newaxis] if isinstance(image, np.ndarray) and image.ndim == 2 else image
    if not isinstance(image, np.ndarray) or image.ndim != 3 or image.dtype != np.float32:
        raise ValueError(f"write_exr needs a float32 (H, W) or (H, W, C) array, got {getattr(image, 'shape', image)}")
    if len(channel_names) != image.shape[2]:
        raise ValueError(f"write_exr got {image.shape[2]} channels but {len(channel_names)} names {channel_names}")
    _write(path, image, oiio_format="openexr", pixel_type=oiio.FLOAT, channel_names=tuple(channel_names))


def depth_mm_u16(depth_m: np.ndarray) -> tuple[np.ndarray, int]:
    """Depth in metres → uint16 millimetres as `write_depth` stores it in a PNG.

    ``mm = clip(round(1000 · depth_m), 1, 65535)`` for finite depths (round half to even), 0 for +inf.

    Parameters
    ----------
    depth_m : ndarray, floating
        Depth, m: > 0 or +inf (not checked here).

    Returns
    -------
    depth_mm : ndarray, same shape, uint16
        Depth, mm; 0 for no geometry.
    saturated : int
        Finite depths that rounded above 65535 mm and were clipped to it.
    """
    depth_mm = np.multiply(depth_m, 1000.0, dtype=np.float64)  # in one float64 buffer, worked in place
    np.rint(depth_mm, out=depth_mm)
    finite = np.isfinite(depth_mm)
    saturated = int(np.count_nonzero(finite & (depth_mm > 65535)))
    np.clip(depth_mm, 1, 65535, out=depth_mm)
    depth_mm[~finite] = 0
    return depth_mm.astype(np.uint16), saturated


def _check_format(format: object, formats: tuple[str, ...], function: str, path: str | Path) -> None:
    if not isinstance(format, str) or format not in formats:
        raise ConfigError(f"{function} format must be one of {', '.join(formats)}, got {format!r}")
    suffix = Path(path).suffix.lower()
    if suffix not in SUFFIXES[format]:
        raise ConfigError(
            f"{path}: the suffix {suffix or '(none)'!r} does not fit format {format!r}; "
            f"name the file with {' or '.join(SUFFIXES[format])}"
        )


def _channels_last(array: object, name: str) -> np.ndarray:
    """`array` as (H, W, C) with C = 1 or 3, or ValueError naming the accepted shapes."""
    if not isinstance(array, np.ndarray):
        raise ValueError(f"{name} must be a numpy array, got {type(array).__name__}")
    if array.ndim == 2:
        array = array[:, :, np.newaxis]
    if array.ndim != 3 or array.shape[2] not in (1, 3) or array.shape[0] == 0 or array.shape[1] == 0:
        raise ValueError(
            f"{name} must have shape (H, W), (H, W, 1) or (H, W, 3) (channels last, R, G, B), got {array.shape}"
        )
    return array


def _write(
    path: str | Path, image: np.ndarray, *, oiio_format: str, pixel_type: object, channel_names: tuple[str, ...]
) -> None:
    """Write an (H, W, C) array through OpenImageIO into a temporary file, then rename it to `path`."""
    height_px, width_px, n_channels = image.shape
    spec = oiio.ImageSpec(width_px, height_px, n_channels, pixel_type)
    spec.channelnames = channel_names
    spec.attribute("DateTime", "")  # OpenImageIO stamps the current time otherwise
    if oiio_format == "png":
        # zlib level 2 with one row filter (PNG_ROW_FILTER): OpenImageIO's default, level 6 with libpng's
        # adaptive filter, made writing frames the parking lot's largest stage end to end (BENCHMARKS.md);
        # level 1 took a third of its time for 6 % larger files (174 against 517 ms), the single filter
        # about half of that again. Lossless either way.
        spec.attribute("png:compressionLevel", PNG_COMPRESSION_LEVEL)
        spec.attribute("png:filter", _LIBPNG_FILTER_FLAGS[PNG_ROW_FILTER[n_channels]])
    with atomic_path(path) as tmp:
        output = oiio.ImageOutput.create(oiio_format)
        if output is None:
            raise OSError(f"{path}: OpenImageIO has no {oiio_format} writer: {oiio.geterror()}")
        if not output.open(str(tmp), spec):
            raise OSError(f"{path}: OpenImageIO cannot open {tmp} for writing: {output.geterror()}")
        try:
            written = output.write_image(np.ascontiguousarray(image))
            error = output.geterror()
        finally:
            closed = output.close()
        if not (written and closed):
            raise OSError(f"{path}: OpenImageIO failed writing {oiio_format}: {error or output.geterror()}")
