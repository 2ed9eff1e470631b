"""write_frame and write_depth: round trips through OpenCV and OpenImageIO, colour order, depth in mm, errors."""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import cv2
import numpy as np
import OpenImageIO as oiio  # noqa: N813 - the alias its documentation uses
import pytest

from camgen.errors import ConfigError
from camgen.io.frames import PNG_COMPRESSION_LEVEL, PNG_ROW_FILTER, depth_mm_u16, write_depth, write_frame

HEIGHT_PX, WIDTH_PX = 24, 32
SUFFIX = {"png": ".png", "tiff": ".tiff", "exr": ".exr"}


def random_image(dtype: type, channels: int | None = 3, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    shape = (HEIGHT_PX, WIDTH_PX) if channels is None else (HEIGHT_PX, WIDTH_PX, channels)
    if np.issubdtype(dtype, np.integer):
        return rng.integers(0, np.iinfo(dtype).max, shape, dtype=dtype, endpoint=True)
    return rng.lognormal(0.0, 3.0, shape).astype(dtype)  # linear HDR: 1e-4 … 1e4


def read_oiio(path: Path) -> tuple[np.ndarray, oiio.ImageSpec]:
    """Pixels in the file's own sample type, (H, W, C), and the file's spec."""
    image_input = oiio.ImageInput.open(str(path))
    assert image_input is not None, oiio.geterror()
    try:
        return image_input.read_image(format="unknown"), image_input.spec()
    finally:
        image_input.close()


def read_cv2_rgb(path: Path) -> np.ndarray:
    """OpenCV's own decoders (libpng, libtiff), an implementation independent of OpenImageIO's writer."""
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    assert image is not None
    return image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2RGB)


@pytest.mark.parametrize("format", ["png", "tiff"])
@pytest.mark.parametrize("dtype", [np.uint8, np.uint16])
@pytest.mark.parametrize("channels", [None, 1, 3])
def test_integer_round_trip_is_exact(tmp_path: Path, format: str, dtype: type, channels: int | None) -> None:
    image = random_image(dtype, channels)
    path = tmp_path / f"frame{SUFFIX[format]}"
    write_frame(path, image, format=format)
    expected = image if channels is not None else image[..., np.newaxis]
    decoded = read_cv2_rgb(path)
    assert decoded.dtype == dtype
    np.testing.assert_array_equal(decoded.reshape(expected.shape), expected)
    pixels, _ = read_oiio(path)
    assert pixels.dtype == dtype
    np.testing.assert_array_equal(pixels, expected)


@pytest.mark.parametrize("format", ["png", "tiff"])
def test_pure_red_reads_back_red(tmp_path: Path, format: str) -> None:
    red = np.zeros((HEIGHT_PX, WIDTH_PX, 3), np.uint8)
    red[..., 0] = 255
    path = tmp_path / f"red{SUFFIX[format]}"
    write_frame(path, red, format=format)
    assert tuple(cv2.imread(str(path), cv2.IMREAD_COLOR)[5, 7]) == (0, 0, 255)  # OpenCV reads B, G, R
    assert tuple(read_cv2_rgb(path)[5, 7]) == (255, 0, 0)
    assert tuple(read_oiio(path)[0][5, 7]) == (255, 0, 0)


def test_exr_red_is_in_the_r_channel(tmp_path: Path) -> None:
    red = np.zeros((HEIGHT_PX, WIDTH_PX, 3), np.float32)
    red[..., 0] = 2.5
    write_frame(tmp_path / "red.exr", red, format="exr")
    pixels, spec = read_oiio(tmp_path / "red.exr")
    assert tuple(spec.channelnames) == ("R", "G", "B")
    assert tuple(pixels[5, 7]) == (2.5, 0.0, 0.0)


@pytest.mark.parametrize("channels", [1, 3])
def test_exr_float_round_trip_is_exact(tmp_path: Path, channels: int) -> None:
    image = random_image(np.float32, channels)
    image[0, 0] = np.inf
    image[0, 1] = np.nan
    image[0, 2] = 1e30
    write_frame(tmp_path / "hdr.exr", image, format="exr")
    pixels, spec = read_oiio(tmp_path / "hdr.exr")
    assert spec.format == oiio.TypeDesc(oiio.FLOAT)
    assert pixels.dtype == np.float32
    np.testing.assert_array_equal(pixels, image)
    assert tuple(spec.channelnames) == (("Y",) if channels == 1 else ("R", "G", "B"))


def test_exr_half_keeps_11_significant_bits(tmp_path: Path) -> None:
    image = random_image(np.float32) / 100  # within half range
    write_frame(tmp_path / "half.exr", image, format="exr", exr_pixel_type="half")
    pixels, spec = read_oiio(tmp_path / "half.exr")
    assert spec.format == oiio.TypeDesc(oiio.HALF)
    np.testing.assert_array_equal(pixels, image.astype(np.float16))  # round to nearest even, as numpy


def test_exr_half_rejects_values_it_would_turn_to_inf(tmp_path: Path) -> None:
    image = np.full((4, 4, 3), 7e4, np.float32)
    with pytest.raises(ValueError, match="exr_pixel_type='float'"):
        write_frame(tmp_path / "half.exr", image, format="exr", exr_pixel_type="half")
    image[:] = np.inf  # inf is inf in both
    write_frame(tmp_path / "half.exr", image, format="exr", exr_pixel_type="half")


PNG_FILTER_TYPES = {"none": 0, "sub": 1, "up": 2, "average": 3, "paeth": 4}
"""The filter-type byte that starts each row of PNG image data (ISO/IEC 15948, 9.2)."""


def png_rows(path: Path) -> tuple[int, list[int]]:
    """The zlib stream's FLEVEL (RFC 1950: 0 for level 1, 1 for 2–5, 2 for 6, 3 for 7–9) and the filter type
    of each row, read from the file's chunks by hand (8-bit or 16-bit, not interlaced)."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    offset, idat, header = 8, b"", None
    while offset < len(data):
        length, kind = struct.unpack(">I4s", data[offset : offset + 8])
        body = data[offset + 8 : offset + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        offset += 12 + length
    width_px, height_px, bit_depth, colour_type, _, _, interlace = header
    assert interlace == 0
    channels = {0: 1, 2: 3}[colour_type]
    row_bytes = 1 + width_px * channels * bit_depth // 8
    raw = zlib.decompress(idat)
    assert len(raw) == height_px * row_bytes
    return idat[1] >> 6, [raw[row * row_bytes] for row in range(height_px)]


@pytest.mark.parametrize(("dtype", "channels"), [(np.uint8, 3), (np.uint16, 3), (np.uint8, None), (np.uint16, 1)])
def test_png_rows_all_get_the_documented_filter(tmp_path: Path, dtype: type, channels: int | None) -> None:
    """Every row is filtered with PNG_ROW_FILTER's choice for its channel count, at PNG_COMPRESSION_LEVEL,
    and decodes to the array written (test_integer_round_trip_is_exact has the small random cases)."""
    rng = np.random.default_rng(5)
    shape = (96, 128) + (() if channels is None else (channels,))
    ramp = np.linspace(0, 0.8 * np.iinfo(dtype).max, shape[1])[np.newaxis, :]
    image = ramp + rng.normal(0, 0.02 * np.iinfo(dtype).max, (shape[0], shape[1]))
    image = np.clip(image, 0, np.iinfo(dtype).max).astype(dtype)
    image = image if channels is None else np.repeat(image[..., np.newaxis], channels, axis=2)
    write_frame(tmp_path / "frame.png", image, format="png")
    level, filters = png_rows(tmp_path / "frame.png")
    assert set(filters) == {PNG_FILTER_TYPES[PNG_ROW_FILTER[channels or 1]]}
    assert level == {1: 0, 2: 1, 3: 1, 4: 1, 5: 1, 6: 2}.get(PNG_COMPRESSION_LEVEL, 3)
    np.testing.assert_array_equal(read_cv2_rgb(tmp_path / "frame.png").reshape(image.shape), image)
    np.testing.assert_array_equal(read_oiio(tmp_path / "frame.png")[0].reshape(image.shape), image)


def test_depth_png_rows_use_the_up_filter(tmp_path: Path) -> None:
    """A depth map is one channel: "up" on every row, and the millimetres read back as depth_mm_u16 gives."""
    rows_m = np.linspace(3.0, 60.0, 90)[:, np.newaxis]
    depth_m = np.repeat(rows_m, 120, axis=1) + np.random.default_rng(6).uniform(0, 0.01, (90, 120))
    depth_m[:10] = np.inf
    write_depth(tmp_path / "depth.png", depth_m, format="png16")
    _, filters = png_rows(tmp_path / "depth.png")
    assert PNG_ROW_FILTER[1] == "up" and set(filters) == {PNG_FILTER_TYPES["up"]}
    np.testing.assert_array_equal(
        cv2.imread(str(tmp_path / "depth.png"), cv2.IMREAD_UNCHANGED), depth_mm_u16(depth_m)[0]
    )


def test_same_input_same_bytes(tmp_path: Path) -> None:
    """No time stamp: a re-run produces identical files (manifest hashes stay stable)."""
    for format, dtype in (("png", np.uint8), ("tiff", np.uint16), ("exr", np.float32)):
        image = random_image(dtype)
        a, b = tmp_path / f"a{SUFFIX[format]}", tmp_path / f"b{SUFFIX[format]}"
        write_frame(a, image, format=format)
        write_frame(b, image, format=format)
        assert a.read_bytes() == b.read_bytes(), format


def test_tif_suffix_and_parent_directories(tmp_path: Path) -> None:
    path = tmp_path / "cam" / "frames" / "000001.TIF"
    write_frame(path, random_image(np.uint8), format="tiff")
    assert path.is_file()
    assert [p.name for p in path.parent.iterdir()] == ["000001.TIF"]


@pytest.mark.parametrize(
    ("format", "image", "match"),
    [
        ("png", np.zeros((4, 4, 3), np.float32), "must be uint8 or uint16"),
        ("tiff", np.zeros((4, 4, 3), np.float64), "must be uint8 or uint16"),
        ("png", np.zeros((4, 4, 3), np.int16), "must be uint8 or uint16"),
        ("png", np.zeros((4, 4, 3), bool), "must be uint8 or uint16"),
        ("exr", np.zeros((4, 4, 3), np.float64), "must be float32"),
        ("exr", np.zeros((4, 4, 3), np.uint16), "must be float32"),
        ("png", np.zeros((4, 4, 4), np.uint8), r"\(H, W, 3\)"),
        ("png", np.zeros((4,), np.uint8), r"\(H, W, 3\)"),
        ("png", np.zeros((0, 4, 3), np.uint8), r"\(H, W, 3\)"),
        ("png", [[0, 1]], "numpy array"),
    ],
)
def test_bad_images_are_rejected(tmp_path: Path, format: str, image: object, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        write_frame(tmp_path / f"bad{SUFFIX[format]}", image, format=format)
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("name", "format", "kwargs", "match"),
    [
        ("a.jpg", "jpeg", {}, "format must be one of png, tiff, exr"),
        ("a.exr", "png", {}, "does not fit format 'png'"),
        ("a", "tiff", {}, r"\.tif or \.tiff"),
        ("a.exr", "exr", {"exr_pixel_type": "double"}, "exr_pixel_type"),
    ],
)
def test_bad_settings_are_config_errors(tmp_path: Path, name: str, format: str, kwargs: dict, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        write_frame(tmp_path / name, np.zeros((4, 4, 3), np.float32), format=format, **kwargs)
    assert not any(tmp_path.iterdir())


def test_depth_mm_closed_form() -> None:
    """round(1000 · depth_m), half to even (0.0625 m and 0.1875 m are exact binary halves of a mm)."""
    depth_m = np.array([0.0001, 0.0004, 0.0006, 0.25, 0.0625, 0.1875, 12.3456, 65.535, 65.5355, 100.0, np.inf])
    depth_mm, saturated = depth_mm_u16(depth_m)
    expected = [1, 1, 1, 250, 62, 188, 12346, 65535, 65535, 65535, 0]
    np.testing.assert_array_equal(depth_mm, expected)
    assert depth_mm.dtype == np.uint16
    assert saturated == 2  # 65.5355 m rounds to 65536 mm; 100 m; not +inf, not exactly 65.535 m


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_depth_png16_round_trip(tmp_path: Path, dtype: type) -> None:
    rng = np.random.default_rng(3)
    depth_m = rng.uniform(0.3, 60.0, (HEIGHT_PX, WIDTH_PX)).astype(dtype)
    depth_m[:4] = np.inf
    depth_m[4, :5] = 80.0
    saturated = write_depth(tmp_path / "depth.png", depth_m, format="png16")
    assert saturated == 5
    decoded = cv2.imread(str(tmp_path / "depth.png"), cv2.IMREAD_UNCHANGED)
    assert decoded.dtype == np.uint16
    assert decoded.shape == (HEIGHT_PX, WIDTH_PX)
    np.testing.assert_array_equal(decoded, depth_mm_u16(depth_m)[0])
    assert (decoded[:4] == 0).all()
    assert (decoded[4, :5] == 65535).all()
    finite = decoded > 0
    np.testing.assert_allclose(decoded[finite] / 1000, np.minimum(depth_m[finite], 65.535), atol=5e-4 + 1e-9)


def test_depth_exr_keeps_metres_and_inf(tmp_path: Path) -> None:
    rng = np.random.default_rng(4)
    depth_m = rng.uniform(0.3, 500.0, (HEIGHT_PX, WIDTH_PX)).astype(np.float32)
    depth_m[:3] = np.inf
    assert write_depth(tmp_path / "depth.exr", depth_m[..., np.newaxis], format="exr") == 0
    pixels, spec = read_oiio(tmp_path / "depth.exr")
    assert tuple(spec.channelnames) == ("Z",)
    assert pixels.dtype == np.float32
    np.testing.assert_array_equal(pixels[..., 0], depth_m)


@pytest.mark.parametrize(
    ("depth_m", "match"),
    [
        (np.array([[1.0, np.nan]]), "NaN, 0 or negative"),
        (np.array([[1.0, 0.0]]), "NaN, 0 or negative"),
        (np.array([[1.0, -2.0]]), "NaN, 0 or negative"),
        (np.array([[1.0, -np.inf]]), "NaN, 0 or negative"),
        (np.array([[1000, 2000]], np.uint16), "floating"),
        (np.ones((2, 2, 3)), "floating array of shape"),
    ],
)
@pytest.mark.parametrize("format", ["png16", "exr"])
def test_bad_depth_is_rejected(tmp_path: Path, depth_m: np.ndarray, match: str, format: str) -> None:
    with pytest.raises(ValueError, match=match):
        write_depth(tmp_path / ("d.exr" if format == "exr" else "d.png"), depth_m, format=format)
    assert not any(tmp_path.iterdir())


def test_depth_format_errors(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="png16, exr"):
        write_depth(tmp_path / "d.png", np.ones((2, 2)), format="png")
    with pytest.raises(ConfigError, match="does not fit"):
        write_depth(tmp_path / "d.tiff", np.ones((2, 2)), format="png16")
