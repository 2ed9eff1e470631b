"""Reading the frames a fit starts from: raw files through rawpy, linear files through OpenImageIO, the
CFA and levels they state, EXIF exposure time and temperature, and the frames.csv side file."""

from __future__ import annotations

import numpy as np
import pytest
import tifffile

from camgen.errors import ConfigError
from camgen.fit.frames import FrameReadError, read_frame, read_metadata_file, scan_stacks
from camgen.io.dng import write_dng

RAW = (np.arange(48 * 64).reshape(48, 64) * 7 % 4000).astype(np.uint16)


@pytest.mark.parametrize("cfa", ["RGGB", "BGGR", "GRBG", "GBRG", "mono"])
def test_a_dng_reads_back_with_its_cfa_levels_and_exif(tmp_path, cfa):
    path = tmp_path / "f.dng"
    write_dng(
        path,
        RAW,
        cfa=cfa,
        black_level_dn=64,
        white_level_dn=4095,
        bit_depth=12,
        exposure_time_s=1 / 60,
        temperature_c=-12.5,
    )
    frame = read_frame(path)
    np.testing.assert_array_equal(frame.raw_dn, RAW)
    assert frame.cfa == cfa
    assert (frame.black_level_dn, frame.white_level_dn, frame.bit_depth) == (64, 4095, 12)
    assert frame.metadata.exposure_time_s == pytest.approx(1 / 60, rel=1e-9)
    assert frame.metadata.temperature_c == pytest.approx(-12.5)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16])
def test_linear_tiff_and_png_keep_their_integer_values(tmp_path, dtype):
    import cv2

    values = (RAW % np.iinfo(dtype).max).astype(dtype)
    tifffile.imwrite(tmp_path / "f.tif", values)
    cv2.imwrite(str(tmp_path / "f.png"), values)
    for name in ("f.tif", "f.png"):
        frame = read_frame(tmp_path / name, cfa="GRBG")
        np.testing.assert_array_equal(frame.raw_dn, values)
        assert frame.raw_dn.dtype == np.uint16
        assert frame.cfa == "GRBG"
        assert frame.white_level_dn == np.iinfo(dtype).max


def test_rgb_and_float_files_are_not_frames(tmp_path):
    tifffile.imwrite(tmp_path / "rgb.tif", np.zeros((8, 8, 3), np.uint16))
    tifffile.imwrite(tmp_path / "float.tif", np.zeros((8, 8), np.float32))
    with pytest.raises(FrameReadError, match="3 channels"):
        read_frame(tmp_path / "rgb.tif")
    with pytest.raises(FrameReadError, match="float32"):
        read_frame(tmp_path / "float.tif")


def test_the_side_file_wins_over_exif_and_groups_by_settings(tmp_path):
    for i, t in enumerate([0.01, 0.01, 0.02, 0.02, 0.02, 0.02]):
        write_dng(
            tmp_path / f"d{i}.dng",
            RAW,
            cfa="RGGB",
            black_level_dn=64,
            white_level_dn=4095,
            bit_depth=12,
            exposure_time_s=t,
        )
    (tmp_path / "frames.csv").write_text("file,exposure_time_s,temperature_c\nd4.dng,0.5,30\nd5.dng,0.5,30\n")
    scan = scan_stacks(tmp_path, "dark", Count)
    counts = {(g.exposure_time_s, g.temperature_c): g.stats.frames for g in scan.groups.values()}
    assert counts == {(0.01, None): 2, (0.02, None): 2, (0.5, 30.0): 2}


def test_a_side_file_without_the_columns(tmp_path):
    (tmp_path / "frames.csv").write_text("name,time\na.dng,0.1\n")
    with pytest.raises(ConfigError, match="file,exposure_time_s"):
        read_metadata_file(tmp_path / "frames.csv")


def test_sub_folders_are_stacks_of_their_own(tmp_path):
    for level in ("low", "high"):
        for i in range(2):
            write_dng(
                tmp_path / level / f"{i}.dng",
                RAW,
                cfa="RGGB",
                black_level_dn=64,
                white_level_dn=4095,
                bit_depth=12,
                exposure_time_s=0.01,
            )
    scan = scan_stacks(tmp_path, "flat", Count)
    assert sorted(g.label for g in scan.groups.values()) == [
        f"{tmp_path.name}/high t=0.01 s",
        f"{tmp_path.name}/low t=0.01 s",
    ]


class Count:
    def __init__(self, shape):
        self.frames = 0

    def add(self, frame):
        self.frames += 1


def test_a_drifting_temperature_stays_one_stack(tmp_path):
    """EXIF temperatures drift by tenths of a degree over a stack; 10 °C apart are two stacks."""
    for i, temperature_c in enumerate([40.0, 40.3, 40.6, 39.8, 50.0, 50.4]):
        write_dng(
            tmp_path / f"d{i}.dng",
            RAW,
            cfa="RGGB",
            black_level_dn=64,
            white_level_dn=4095,
            bit_depth=12,
            exposure_time_s=0.01,
            temperature_c=temperature_c,
        )
    scan = scan_stacks(tmp_path, "dark", Count)
    stacks = sorted((g.temperature_c, g.stats.frames) for g in scan.groups.values())
    assert [n for _, n in stacks] == [4, 2]
    assert [t for t, _ in stacks] == pytest.approx([40.175, 50.2])


def test_the_side_file_tells_sub_folders_apart(tmp_path):
    """Frame numbers restart in each sub-folder; the side file names them by their relative path."""
    for level in ("low", "high"):
        for i in range(2):
            write_dng(
                tmp_path / level / f"{i}.dng", RAW, cfa="RGGB", black_level_dn=64, white_level_dn=4095, bit_depth=12
            )
    rows = [f"{level}/{i}.dng,{t}" for level, t in (("low", 0.01), ("high", 0.04)) for i in range(2)]
    # A spreadsheet's CSV: byte-order mark, CRLF line ends.
    (tmp_path / "frames.csv").write_bytes(("\ufefffile,exposure_time_s\r\n" + "\r\n".join(rows)).encode("utf-8"))
    scan = scan_stacks(tmp_path, "flat", Count)
    assert {g.folder: g.exposure_time_s for g in scan.groups.values()} == {
        f"{tmp_path.name}/low": 0.01,
        f"{tmp_path.name}/high": 0.04,
    }


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("exposure_time_s,file\n0.5\n", "frames.csv:2: the file column is empty"),
        ("file,exposure_time_s\na.dng,0.1\na.dng,0.2\n", "frames.csv:3: a.dng is listed twice"),
        ("file,exposure_time_s\na.dng,fast\n", "frames.csv:2: exposure_time_s must be a number"),
    ],
)
def test_side_file_rows_that_are_wrong_name_their_line(tmp_path, text, match):
    (tmp_path / "frames.csv").write_text(text)
    with pytest.raises(ConfigError, match=match):
        read_metadata_file(tmp_path / "frames.csv")


def test_a_side_file_that_is_not_utf8(tmp_path):
    (tmp_path / "frames.csv").write_bytes("file,exposure_time_s,temperature_c\na.dng,0.1,40 \xb0C\n".encode("latin-1"))
    with pytest.raises(ConfigError, match="UTF-8"):
        read_metadata_file(tmp_path / "frames.csv")


def retagged_dng(path, raw, *, active_area=None, exposure=None) -> None:
    """A camgen DNG rewritten with an ActiveArea (a masked border, as real sensors keep) or another
    ExposureTime, tags write_dng does not offer."""
    write_dng(path, raw, cfa="RGGB", black_level_dn=64, white_level_dn=4095, bit_depth=12, exposure_time_s=0.01)
    with tifffile.TiffFile(path) as tif:
        page = tif.pages.first
        tags = [(t.code, t.dtype, t.count, t.value, True) for t in page.tags.values() if t.code >= 33000]
        data = page.asarray()
    if exposure is not None:
        tags = [t for t in tags if t[0] != 33434] + [(33434, 5, 1, exposure, True)]
    if active_area is not None:
        tags.append((50829, 4, 4, active_area, True))  # ActiveArea: top, left, bottom, right
    tifffile.imwrite(path, data, photometric=32803, rowsperstrip=raw.shape[0], compression=None, extratags=tags)


def test_the_masked_border_is_reported_per_channel(tmp_path):
    rng = np.random.default_rng(3)
    raw = np.clip(rng.normal(300, 4, (72, 80)), 0, 4095)
    levels = {(0, 0): 60.0, (0, 1): 62.0, (1, 0): 66.0, (1, 1): 64.0}  # R, G1, G2, B of an RGGB mosaic
    border = np.zeros(raw.shape, dtype=bool)
    border[:8, :], border[:, :8] = True, True
    for (dy, dx), level in levels.items():
        site = np.zeros(raw.shape, dtype=bool)
        site[dy::2, dx::2] = True
        raw[border & site] = rng.normal(level, 1.0 + dy + dx, np.count_nonzero(border & site))
    path = tmp_path / "masked.dng"
    retagged_dng(path, np.round(raw).astype(np.uint16), active_area=(8, 8, 72, 80))
    frame = read_frame(path)
    assert frame.raw_dn.shape == (64, 72)
    mean, std = frame.optical_black.mean_dn(), frame.optical_black.std_dn()
    assert set(mean) == {"R", "G1", "G2", "B"}
    # each channel's own level, not one number over all four
    assert mean == pytest.approx({"R": 60.0, "G1": 62.0, "G2": 66.0, "B": 64.0}, abs=0.25)
    assert std == pytest.approx({"R": 1.0, "G1": 2.0, "G2": 2.0, "B": 3.0}, rel=0.15)


def test_an_exif_exposure_of_zero_asks_for_the_side_file(tmp_path):
    for i in range(2):
        retagged_dng(tmp_path / f"d{i}.dng", RAW, exposure=(0, 1))
    assert read_frame(tmp_path / "d0.dng").metadata.exposure_time_s == 0.0
    with pytest.raises(ConfigError, match=r"d0.dng, d1.dng state an exposure time of 0 s .* frames\.csv"):
        scan_stacks(tmp_path, "dark", Count)
    (tmp_path / "frames.csv").write_text("file,exposure_time_s\nd0.dng,0.02\nd1.dng,0.02\n")
    scan = scan_stacks(tmp_path, "dark", Count)
    assert [g.exposure_time_s for g in scan.groups.values()] == [0.02]
