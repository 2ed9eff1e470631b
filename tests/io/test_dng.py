"""write_dng: read back by LibRaw (rawpy) and tifffile — pixels bit-exact, CFA, levels, colour tags, errors."""

from __future__ import annotations

from pathlib import Path

import colour
import numpy as np
import pytest
import rawpy
import tifffile

from camgen.errors import ConfigError
from camgen.io.dng import SRGB_FROM_XYZ, write_dng
from camgen.sensor.cfa import CFA_PATTERNS, cfa_channel_index, mosaic

HEIGHT_PX, WIDTH_PX = 48, 64
BLACK_LEVEL_DN, BIT_DEPTH = 64, 12
WHITE_LEVEL_DN = 2**BIT_DEPTH - 1


def random_mosaic(seed: int = 0, height_px: int = HEIGHT_PX, width_px: int = WIDTH_PX) -> np.ndarray:
    """Every DN of a 12-bit ADC is possible, so a swapped byte or bit shows."""
    return np.random.default_rng(seed).integers(0, WHITE_LEVEL_DN + 1, (height_px, width_px), dtype=np.uint16)


def write(path: Path, raw: np.ndarray, cfa: str, **kwargs) -> Path:
    write_dng(
        path,
        raw,
        cfa=cfa,
        black_level_dn=kwargs.pop("black_level_dn", BLACK_LEVEL_DN),
        white_level_dn=kwargs.pop("white_level_dn", WHITE_LEVEL_DN),
        bit_depth=kwargs.pop("bit_depth", BIT_DEPTH),
        **kwargs,
    )
    return path


def tags_of(path: Path) -> dict[str, object]:
    with tifffile.TiffFile(path) as tif:
        return {tag.name: tag.value for tag in tif.pages.first.tags}


def libraw_channels(raw: rawpy.RawPy) -> np.ndarray:
    """camgen channel (0 = R, 1 = G, 2 = B) of each of LibRaw's colour indices, through `color_desc`."""
    return np.array(["RGB".index(chr(letter)) for letter in raw.color_desc])


@pytest.mark.parametrize("cfa", CFA_PATTERNS)
def test_bayer_round_trip_through_libraw(tmp_path: Path, cfa: str) -> None:
    raw_dn = random_mosaic()
    path = write(tmp_path / f"{cfa}.dng", raw_dn, cfa)
    with rawpy.imread(str(path)) as raw:
        assert raw.raw_type == rawpy.RawType.Flat
        assert raw.num_colors == 3
        assert raw.raw_image.dtype == np.uint16
        np.testing.assert_array_equal(raw.raw_image, raw_dn)
        channels = libraw_channels(raw)
        pattern = "".join("RGB"[c] for c in channels[raw.raw_pattern].ravel())
        assert pattern == cfa
        # every site, not only the 2×2 pattern: a wrong CFAPattern or an offset origin fails here
        np.testing.assert_array_equal(channels[raw.raw_colors], cfa_channel_index(cfa, HEIGHT_PX, WIDTH_PX))
        assert raw.black_level_per_channel == [BLACK_LEVEL_DN] * 4
        assert raw.white_level == WHITE_LEVEL_DN
        assert raw.camera_whitebalance[:3] == pytest.approx([1.0, 1.0, 1.0])
        rgb = raw.postprocess()
    assert rgb.shape == (HEIGHT_PX, WIDTH_PX, 3)


def test_mono_round_trip_through_libraw(tmp_path: Path) -> None:
    raw_dn = random_mosaic(seed=1)
    path = write(tmp_path / "mono.dng", raw_dn, "mono")
    with rawpy.imread(str(path)) as raw:
        np.testing.assert_array_equal(raw.raw_image, raw_dn)
        # LibRaw reports one colour; its raw_pattern/color_desc for it are placeholders ([[6]], "GMCY")
        assert raw.num_colors == 1
        assert raw.black_level_per_channel == [BLACK_LEVEL_DN] * 4
        assert raw.white_level == WHITE_LEVEL_DN
        grey = raw.postprocess()
    assert grey.shape == (HEIGHT_PX, WIDTH_PX, 1)
    tags = tags_of(path)
    assert tags["PhotometricInterpretation"] == 34892
    assert tags["SamplesPerPixel"] == 1
    assert not {"CFAPattern", "ColorMatrix1", "AsShotNeutral"} & tags.keys()


@pytest.mark.parametrize("cfa", CFA_PATTERNS)
def test_libraw_demosaics_a_red_scene_to_red(tmp_path: Path, cfa: str) -> None:
    """Semantics of CFAPattern end to end: only red sites lit must come out red after LibRaw's pipeline."""
    scene = np.zeros((HEIGHT_PX, WIDTH_PX, 3), np.uint16)
    scene[..., 0] = 3000
    raw_dn = mosaic(scene, cfa) + np.uint16(BLACK_LEVEL_DN)
    path = write(tmp_path / "red.dng", raw_dn, cfa)
    with rawpy.imread(str(path)) as raw:
        rgb = raw.postprocess(use_camera_wb=True, no_auto_bright=True, output_bps=16).astype(float)
    centre = rgb[8:-8, 8:-8].reshape(-1, 3).mean(axis=0)
    assert centre[0] > 20 * max(centre[1], centre[2])


def test_tags(tmp_path: Path) -> None:
    matrix = np.diag([0.9, 1.0, 0.8]) @ SRGB_FROM_XYZ
    path = write(
        tmp_path / "cam.dng",
        random_mosaic(),
        "GRBG",
        color_matrix_xyz_to_camera=matrix,
        as_shot_neutral_rgb=(0.5, 1.0, 0.25),
        camera_name="dome-4mp",
        exposure_time_s=1 / 120,
        f_number=2.8,
    )
    tags = tags_of(path)
    assert tags["DNGVersion"] == bytes([1, 4, 0, 0])
    assert tags["DNGBackwardVersion"] == bytes([1, 1, 0, 0])
    assert tags["UniqueCameraModel"] == "dome-4mp"
    assert tags["Model"] == "dome-4mp"
    assert tags["NewSubfileType"] == 0
    assert tags["PhotometricInterpretation"] == 32803
    assert tags["BitsPerSample"] == 16
    assert tags["Compression"] == 1
    assert tags["CFARepeatPatternDim"] == (2, 2)
    assert tags["CFAPattern"] == bytes([1, 0, 2, 1])
    assert tags["CFAPlaneColor"] == bytes([0, 1, 2])
    assert tags["CFALayout"] == 1
    assert tags["BlackLevelRepeatDim"] == (1, 1)
    assert tags["BlackLevel"] == BLACK_LEVEL_DN
    assert tags["WhiteLevel"] == WHITE_LEVEL_DN
    assert tags["CalibrationIlluminant1"] == 21
    assert tags["ExposureTime"] == (1, 120)
    assert tags["FNumber"] == (14, 5)
    pairs = np.array(tags["ColorMatrix1"], float).reshape(9, 2)
    np.testing.assert_allclose((pairs[:, 0] / pairs[:, 1]).reshape(3, 3), matrix, atol=1e-6)
    pairs = np.array(tags["AsShotNeutral"], float).reshape(3, 2)
    np.testing.assert_allclose(pairs[:, 0] / pairs[:, 1], [0.5, 1.0, 0.25])


def test_libraw_reads_the_neutral_as_white_balance(tmp_path: Path) -> None:
    path = write(tmp_path / "wb.dng", random_mosaic(), "RGGB", as_shot_neutral_rgb=(0.5, 1.0, 0.25))
    with rawpy.imread(str(path)) as raw:
        wb = np.array(raw.camera_whitebalance[:3])
    np.testing.assert_allclose(wb / wb[1], [2.0, 1.0, 4.0], rtol=1e-4)


def test_default_color_matrix_is_xyz_to_linear_srgb() -> None:
    """Reference from colour-science; D65 white maps to equal raw values."""
    reference = colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB
    np.testing.assert_allclose(SRGB_FROM_XYZ, reference, atol=2e-3)
    white_xyz = colour.xy_to_XYZ(colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"])
    np.testing.assert_allclose(SRGB_FROM_XYZ @ white_xyz, [1.0, 1.0, 1.0], atol=1e-3)


def test_fractional_black_level_is_a_rational(tmp_path: Path) -> None:
    path = write(tmp_path / "frac.dng", random_mosaic(), "RGGB", black_level_dn=64.5)
    assert tags_of(path)["BlackLevel"] == (129, 2)
    with rawpy.imread(str(path)) as raw:
        assert raw.black_level_per_channel == [64] * 4  # LibRaw truncates a rational black level


def test_full_16_bit_range_and_odd_size(tmp_path: Path) -> None:
    raw_dn = np.random.default_rng(2).integers(0, 2**16, (37, 53), dtype=np.uint16)
    raw_dn[0, 0], raw_dn[-1, -1] = 0, 65535
    path = write(tmp_path / "b16.dng", raw_dn, "BGGR", black_level_dn=0, white_level_dn=65535, bit_depth=16)
    with rawpy.imread(str(path)) as raw:
        np.testing.assert_array_equal(raw.raw_image, raw_dn)
        assert raw.white_level == 65535


def test_same_input_same_bytes_and_no_partial_files(tmp_path: Path) -> None:
    raw_dn = random_mosaic()
    a = write(tmp_path / "a.dng", raw_dn, "RGGB").read_bytes()
    b = write(tmp_path / "b.dng", raw_dn, "RGGB").read_bytes()
    assert a == b
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.dng", "b.dng"]


def test_creates_parent_directories(tmp_path: Path) -> None:
    path = write(tmp_path / "cam" / "raw" / "000000.dng", random_mosaic(), "RGGB")
    assert path.is_file()


@pytest.mark.parametrize(
    ("raw_dn", "match"),
    [
        (np.zeros((4, 4), np.uint8), "uint16"),
        (np.zeros((4, 4), np.float32), "uint16"),
        (np.zeros((4, 4, 3), np.uint16), r"shape \(H, W\)"),
        (np.zeros((0, 4), np.uint16), r"shape \(H, W\)"),
        ([[0, 1], [2, 3]], "numpy array"),
        (np.full((4, 4), 4096, np.uint16), "above the 4095 DN"),
    ],
)
def test_bad_raw_is_rejected(tmp_path: Path, raw_dn: object, match: str) -> None:
    path = tmp_path / "bad.dng"
    with pytest.raises(ValueError, match=match):
        write(path, raw_dn, "RGGB")
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("cfa", "kwargs", "match"),
    [
        ("RGBG", {}, "cfa must be one of RGGB, BGGR, GRBG, GBRG, mono"),
        ("rggb", {}, "cfa must be one of"),
        ("RGGB", {"bit_depth": 17}, "bit_depth"),
        ("RGGB", {"white_level_dn": 4096}, "white_level_dn must be in 1 … 4095"),
        ("RGGB", {"white_level_dn": 4095.0}, "white_level_dn must be an integer"),
        ("RGGB", {"black_level_dn": 4095}, "black_level_dn"),
        ("RGGB", {"black_level_dn": -1}, "black_level_dn"),
        ("RGGB", {"black_level_dn": float("nan")}, "black_level_dn"),
        ("RGGB", {"color_matrix_xyz_to_camera": np.eye(4)}, r"shape \(3, 3\)"),
        ("RGGB", {"color_matrix_xyz_to_camera": np.full((3, 3), np.nan)}, "finite"),
        ("RGGB", {"as_shot_neutral_rgb": (1.0, 0.0, 1.0)}, "as_shot_neutral_rgb"),
        ("RGGB", {"as_shot_neutral_rgb": (1.0, 1.0)}, "as_shot_neutral_rgb"),
        ("RGGB", {"exposure_time_s": 0.0}, "exposure_time_s"),
        ("RGGB", {"camera_name": ""}, "camera_name"),
        ("RGGB", {"camera_name": "kamera-ü"}, "camera_name"),
        ("mono", {"color_matrix_xyz_to_camera": np.eye(3)}, "mono"),
        ("mono", {"as_shot_neutral_rgb": (1.0, 1.0, 1.0)}, "mono"),
    ],
)
def test_bad_settings_are_config_errors(tmp_path: Path, cfa: str, kwargs: dict, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        write(tmp_path / "bad.dng", np.zeros((4, 4), np.uint16), cfa, **kwargs)
    assert not any(tmp_path.iterdir())
