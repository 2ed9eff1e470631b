"""`camgen fit` on bad input: one clear error (or warning) naming the files, exit status 2, no traceback,
and nothing written under the output name."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from camgen.cli.main import main
from camgen.io.dng import write_dng


def dng(path: Path, raw: np.ndarray, t: float | None = 0.01) -> None:
    write_dng(path, raw, cfa="RGGB", black_level_dn=64, white_level_dn=4095, bit_depth=12, exposure_time_s=t)


def dark_frame(shape=(64, 64), level=64, seed=0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.clip(rng.normal(level, 2.0, shape), 0, 4095).astype(np.uint16)


def fit_noise(tmp_path: Path, capsys, *extra: str) -> tuple[int, str]:
    output = tmp_path / "out.yaml"
    code = main(["fit", "noise", "--dark", str(tmp_path / "dark"), *extra, "-o", str(output)])
    assert code != 0 or output.exists()
    if code != 0:
        assert not output.exists()
        assert not list(tmp_path.glob("*.partial*"))
    return code, capsys.readouterr().err


def test_a_folder_with_no_frames(tmp_path, capsys):
    (tmp_path / "dark").mkdir()
    (tmp_path / "dark" / "notes.txt").write_text("lens capped")
    code, err = fit_noise(tmp_path, capsys)
    assert code == 2
    assert "holds no frame files" in err and "Traceback" not in err


def test_a_missing_folder(tmp_path, capsys):
    code, err = fit_noise(tmp_path, capsys)
    assert code == 2 and "does not exist" in err


def test_a_folder_of_unreadable_frames(tmp_path, capsys):
    (tmp_path / "dark").mkdir()
    (tmp_path / "dark" / "a.dng").write_bytes(b"not a raw file")
    (tmp_path / "dark" / "b.tif").write_bytes(b"II*\x00garbage")
    code, err = fit_noise(tmp_path, capsys)
    assert code == 2
    assert "no readable frames" in err and "a.dng" in err and "b.tif" in err


def test_mixed_resolutions_name_the_odd_files(tmp_path, capsys):
    for i in range(3):
        dng(tmp_path / "dark" / f"big_{i}.dng", dark_frame(seed=i))
    dng(tmp_path / "dark" / "small.dng", dark_frame((32, 32)))
    code, err = fit_noise(tmp_path, capsys)
    assert code == 2
    assert "mixed resolutions" in err and "small.dng (32×32 px)" in err and "big_0" not in err


def test_a_saturated_dark_frame_is_named(tmp_path, capsys):
    for i in range(3):
        dng(tmp_path / "dark" / f"d_{i}.dng", dark_frame(seed=i))
    dng(tmp_path / "dark" / "bright.dng", np.full((64, 64), 4095, np.uint16))
    code, err = fit_noise(tmp_path, capsys)
    assert code == 2
    assert "bright.dng" in err and "saturated" in err and "d_0" not in err


def test_fewer_than_two_frames(tmp_path, capsys):
    dng(tmp_path / "dark" / "only.dng", dark_frame())
    code, err = fit_noise(tmp_path, capsys)
    assert code == 2
    assert "at least 2 frames" in err and "only.dng" in err


def test_no_exposure_time_asks_for_the_side_file(tmp_path, capsys):
    for i in range(2):
        dng(tmp_path / "dark" / f"d_{i}.dng", dark_frame(seed=i), t=None)
    code, err = fit_noise(tmp_path, capsys)
    assert code == 2
    assert "no exposure time" in err and "d_0.dng" in err and "frames.csv" in err


def test_a_bad_side_file_value_names_its_line(tmp_path, capsys):
    for i in range(2):
        dng(tmp_path / "dark" / f"d_{i}.dng", dark_frame(seed=i))
    (tmp_path / "dark" / "frames.csv").write_text("file,exposure_time_s\nd_0.dng,0.01\nd_1.dng,-1\n")
    code, err = fit_noise(tmp_path, capsys)
    assert code == 2
    assert "frames.csv:3" in err and "exposure_time_s" in err


@pytest.mark.parametrize(("option", "value"), [("--gain-dn-per-e", "0"), ("--bit-depth", "20")])
def test_bad_options(tmp_path, capsys, option, value):
    for i in range(2):
        dng(tmp_path / "dark" / f"d_{i}.dng", dark_frame(seed=i))
    code, err = fit_noise(tmp_path, capsys, option, value)
    assert code == 2 and option in err


def test_lens_board_not_found_in_most_images(tmp_path, capsys):
    images = tmp_path / "images"
    images.mkdir()
    rng = np.random.default_rng(0)
    for i in range(4):
        cv2.imwrite(str(images / f"blank_{i}.png"), rng.integers(0, 255, (120, 160), dtype=np.uint8))
    code = main(
        ["fit", "lens", "--images", str(images), "--board", "checkerboard:9x6:25mm", "-o", str(tmp_path / "l.yaml")]
    )
    err = capsys.readouterr().err
    assert code == 2
    assert "found in 0 of 4 images" in err and "blank_0.png" in err
    assert not (tmp_path / "l.yaml").exists()


def test_lens_images_of_mixed_sizes(tmp_path, capsys):
    images = tmp_path / "images"
    images.mkdir()
    cv2.imwrite(str(images / "a.png"), np.zeros((120, 160), np.uint8))
    cv2.imwrite(str(images / "b.png"), np.zeros((120, 160), np.uint8))
    cv2.imwrite(str(images / "c.png"), np.zeros((60, 80), np.uint8))
    code = main(["fit", "lens", "--images", str(images), "--board", "checkerboard:9x6:25mm"])
    err = capsys.readouterr().err
    assert code == 2 and "mixed sizes" in err and "c.png (80×60 px)" in err


def test_match_reference_of_16_bit_images(tmp_path, capsys, request):
    from tests.conftest import FIXED_PROFILE

    profile = tmp_path / "base.yaml"
    profile.write_text(FIXED_PROFILE)
    image = tmp_path / "frame.png"
    cv2.imwrite(str(image), np.zeros((48, 64, 3), np.uint16))
    code = main(["fit", "match", "--reference", str(image), "--profile", str(profile), "-o", str(tmp_path / "m.yaml")])
    err = capsys.readouterr().err
    assert code == 2 and "frame.png" in err and "uint16" in err


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--profile", "missing.yaml"], "no such file"),
        (["--report", "report.pdf"], "give a name ending in .png"),
        (["-o", "."], "is a directory"),
    ],
)
def test_output_problems_are_found_before_reading_frames(tmp_path, capsys, extra, message):
    for i in range(2):
        dng(tmp_path / "dark" / f"d_{i}.dng", dark_frame(seed=i))
    extra = [str(tmp_path / e) if e in ("missing.yaml", "report.pdf", ".") else e for e in extra]
    code = main(["fit", "noise", "--dark", str(tmp_path / "dark"), *(["-o", str(tmp_path / "o.yaml")]), *extra])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err
    assert not (tmp_path / "o.yaml").exists()


def test_match_reference_problems(tmp_path, capsys):
    """An audio-only file, a negative seed and an empty folder: each a clear error naming it."""
    import av

    from tests.conftest import FIXED_PROFILE

    profile = tmp_path / "base.yaml"
    profile.write_text(FIXED_PROFILE)
    audio = tmp_path / "sound.mp4"
    with av.open(str(audio), "w") as container:
        stream = container.add_stream("aac", rate=8000)
        frame = av.AudioFrame.from_ndarray(np.zeros((1, 1024), np.float32), format="fltp", layout="mono")
        frame.sample_rate = 8000
        for packet in stream.encode(frame):
            container.mux(packet)
        for packet in stream.encode(None):
            container.mux(packet)
    (tmp_path / "empty").mkdir()
    cases = [
        ([str(audio)], [], "sound.mp4: holds no video stream"),
        ([str(tmp_path / "empty")], [], "is a folder without videos or images"),
        ([str(audio)], ["--seed", "-1"], "--seed must be ≥ 0"),
    ]
    for reference, extra, message in cases:
        argv = ["fit", "match", "--reference", *reference, "--profile", str(profile), "-o", str(tmp_path / "m.yaml")]
        assert main([*argv, *extra]) == 2
        err = capsys.readouterr().err
        assert message in err and "Traceback" not in err


def test_lens_against_a_zoom_profile_is_refused_before_reading(tmp_path, capsys):
    from tests.conftest import PTZ_PROFILE

    profile = tmp_path / "ptz.yaml"
    profile.write_text(PTZ_PROFILE)
    (tmp_path / "images").mkdir()
    argv = ["fit", "lens", "--images", str(tmp_path / "images"), "--board", "checkerboard:9x6:25mm"]
    assert main([*argv, "--profile", str(profile), "-o", str(tmp_path / "l.yaml")]) == 2
    err = capsys.readouterr().err
    assert "is a zoom lens" in err and "zoom_table entry" in err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["lens", "--images", "IMAGES", "--board", "checkerboard:9x6:25mm", "--pixel-pitch-um", "0"],
            "--pixel-pitch-um must be > 0",
        ),
        (["match", "--reference", "IMAGES", "--profile", "PROFILE", "--max-frames", "0"], "--max-frames must be ≥ 1"),
        (["match", "--reference", "IMAGES", "--profile", "PROFILE", "--bins", "1"], "--bins must be 2–256"),
        (["match", "--reference", "IMAGES", "--profile", "PROFILE", "--gain-db", "80"], "--gain-db must be 0–72 dB"),
    ],
)
def test_bad_lens_and_match_options(tmp_path, capsys, argv, message):
    from tests.conftest import FIXED_PROFILE

    (tmp_path / "images").mkdir()
    (tmp_path / "base.yaml").write_text(FIXED_PROFILE)
    paths = {"IMAGES": str(tmp_path / "images"), "PROFILE": str(tmp_path / "base.yaml")}
    argv = [paths.get(arg, arg) for arg in argv]
    assert main(["fit", *argv, "-o", str(tmp_path / "o.yaml")]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert not (tmp_path / "o.yaml").exists()
