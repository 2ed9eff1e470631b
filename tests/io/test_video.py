"""VideoWriter: round trips through PyAV's decoder, GOP placement, rate control, timing and atomic output."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from types import MappingProxyType

import av
import numpy as np
import pytest
from av.video.frame import PictureType
from av.video.reformatter import ColorRange, Colorspace

from camgen.config.profile import Codec
from camgen.io import video
from camgen.io.video import VideoWriter

WIDTH_PX, HEIGHT_PX = 320, 240


def moving_gradient(n_frames: int, width_px: int = WIDTH_PX, height_px: int = HEIGHT_PX) -> np.ndarray:
    """(n, H, W, 3) uint8: a colour gradient that slides 4 px right per frame."""
    y, x = np.mgrid[0:height_px, 0:width_px]
    t = np.arange(n_frames)[:, None, None]
    r = (x * 200 // width_px + 4 * t) % 256
    g = np.broadcast_to(y * 200 // height_px + 30, r.shape)
    b = (x + y + 3 * t) // 4 % 200 + 20
    return np.stack([r, g, b], axis=-1).astype(np.uint8)


def noisy(frames: np.ndarray, sigma_dn: float = 20.0, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.clip(frames + rng.normal(0.0, sigma_dn, frames.shape), 0, 255).astype(np.uint8)


def encode(
    path: Path, frames: np.ndarray, *, fps: float = 25.0, codec: Codec | None = None, preset: str = "ultrafast"
) -> None:
    """Write (n, H, W, 3) uint8 `frames`; ultrafast keeps the suite quick."""
    height_px, width_px = frames.shape[1:3]
    codec = codec if codec is not None else Codec()
    with VideoWriter(path, width_px=width_px, height_px=height_px, fps=fps, codec=codec, preset=preset) as writer:
        for frame in frames:
            writer.write(frame)
    assert writer.frames_written == len(frames)


def decode(path: Path) -> tuple[av.video.stream.VideoStream, list[av.VideoFrame]]:
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        return stream, list(container.decode(stream))


def to_rgb8(frame: av.VideoFrame) -> np.ndarray:
    """Decode to RGB with the matrix and range the stream is tagged with, as a player does.

    Explicit because PyAV 12 ignores the tags in `to_ndarray` and assumes BT.601 (PyAV 18 follows them).
    """
    return frame.reformat(
        format="rgb24",
        src_colorspace=frame.colorspace,
        src_color_range=frame.color_range,
        dst_color_range=ColorRange.JPEG,
    ).to_ndarray()


def mean_abs_error_dn(decoded: list[av.VideoFrame], frames: np.ndarray) -> float:
    out = np.stack([to_rgb8(frame) for frame in decoded]).astype(float)
    return float(np.mean(np.abs(out - frames)))


def test_h264_round_trip(tmp_path: Path) -> None:
    frames = moving_gradient(30)
    path = tmp_path / "cam.mp4"
    encode(path, frames, codec=Codec(name="h264", bitrate_kbps=None, crf=18))
    stream, decoded = decode(path)
    assert len(decoded) == 30
    assert stream.codec_context.name == "h264"
    assert stream.codec_context.pix_fmt == "yuv420p"
    assert (stream.codec_context.width, stream.codec_context.height) == (WIDTH_PX, HEIGHT_PX)
    assert stream.average_rate == 25
    assert [frame.time for frame in decoded] == pytest.approx(np.arange(30) / 25)
    assert decoded[0].colorspace == Colorspace.ITU709
    assert decoded[0].color_range == ColorRange.MPEG
    assert mean_abs_error_dn(decoded, frames) < 3.0


def test_h264_high_bitrate_is_close(tmp_path: Path) -> None:
    frames = moving_gradient(10)
    path = tmp_path / "cam.mkv"
    encode(path, frames, codec=Codec(bitrate_kbps=20_000, pixel_format="yuv444p"))
    stream, decoded = decode(path)
    assert stream.codec_context.pix_fmt == "yuv444p"
    assert mean_abs_error_dn(decoded, frames) < 3.0


@pytest.mark.parametrize("name", ["h264", "h265"])
def test_key_frames_every_gop(tmp_path: Path, name: str) -> None:
    frames = moving_gradient(30)
    frames[13:] = 255 - frames[13:]  # a hard cut: a scene-cut detector would put a key frame at 13
    path = tmp_path / "cam.mp4"
    # medium, not ultrafast: ultrafast turns scene cuts and B-frames off by itself
    encode(path, frames, codec=Codec(name=name, gop_frames=10), preset="medium")
    _, decoded = decode(path)
    assert [i for i, frame in enumerate(decoded) if frame.key_frame] == [0, 10, 20]
    assert {int(frame.pict_type) for frame in decoded} == {int(PictureType.I), int(PictureType.P)}  # no B-frames


@pytest.mark.parametrize("name", ["h264", "h265"])
def test_bitrate_follows_target(tmp_path: Path, name: str) -> None:
    frames = noisy(moving_gradient(50))  # 2 s at 25 fps; noise makes every bitrate binding
    rate_kbps = {}
    for target_kbps in (150, 3000):
        path = tmp_path / f"{target_kbps}.mp4"
        encode(path, frames, codec=Codec(name=name, bitrate_kbps=target_kbps))
        rate_kbps[target_kbps] = path.stat().st_size * 8 / 1000 / 2.0
    assert rate_kbps[3000] > 10 * rate_kbps[150]
    for target_kbps, kbps in rate_kbps.items():
        assert 0.7 * target_kbps < kbps < 1.4 * target_kbps


@pytest.mark.parametrize("name", ["h264", "h265"])
def test_vbv_caps_the_rate_after_a_static_scene(tmp_path: Path, name: str) -> None:
    # 2.4 s of flat grey then 1.6 s of noise: plain ABR spends the bits saved on the grey part (about
    # 3–6× the target); the camera-like VBV (peak = target, 1 s buffer) bounds any window of T seconds
    # by target · T + buffer.
    fps, n_static, n_busy, target_kbps = 25, 60, 40, 200
    frames = np.full((n_static + n_busy, 120, 160, 3), 128, np.uint8)
    frames[n_static:] = noisy(frames[n_static:], sigma_dn=25.0)
    path = tmp_path / "cam.mp4"
    encode(path, frames, fps=fps, codec=Codec(name=name, bitrate_kbps=target_kbps))
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        busy_bits = sum(
            8 * packet.size
            for packet in container.demux(stream)
            if packet.size and packet.pts * stream.time_base >= Fraction(n_static, fps)
        )
    busy_s = n_busy / fps
    assert busy_bits / busy_s / 1000 < 1.05 * target_kbps * (1 + video.VBV_BUFFER_S / busy_s)


@pytest.mark.parametrize(("fps", "rate"), [(29.97, Fraction(30000, 1001)), (12.5, Fraction(25, 2))])
def test_fractional_fps_round_trips(tmp_path: Path, fps: float, rate: Fraction) -> None:
    path = tmp_path / "cam.mp4"
    encode(path, moving_gradient(12, 64, 48), fps=fps)
    stream, decoded = decode(path)
    assert stream.average_rate == rate
    assert [frame.time for frame in decoded] == pytest.approx(np.arange(12) / float(rate), abs=1e-6)


def test_output_appears_only_on_close(tmp_path: Path) -> None:
    path = tmp_path / "deep" / "er" / "cam.mp4"
    writer = VideoWriter(path, width_px=64, height_px=48, fps=25)
    for frame in moving_gradient(5, 64, 48):
        writer.write(frame)
    assert not path.exists()
    partial = list(path.parent.iterdir())
    assert len(partial) == 1
    assert partial[0].name.startswith(".cam.mp4.")
    assert partial[0].name.endswith(".partial.mp4")
    writer.close()
    assert list(path.parent.iterdir()) == [path]
    assert len(decode(path)[1]) == 5


def test_exception_leaves_nothing(tmp_path: Path) -> None:
    path = tmp_path / "cam.mp4"
    with pytest.raises(RuntimeError, match="boom"), VideoWriter(path, width_px=64, height_px=48, fps=25) as writer:
        for frame in moving_gradient(5, 64, 48):
            writer.write(frame)
        raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []


def test_abort_leaves_nothing(tmp_path: Path) -> None:
    path = tmp_path / "cam.mp4"
    writer = VideoWriter(path, width_px=64, height_px=48, fps=25)
    writer.write(moving_gradient(1, 64, 48)[0])
    writer.abort()
    writer.abort()
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ValueError, match="closed"):
        writer.write(moving_gradient(1, 64, 48)[0])


def test_no_frames_is_an_error_and_leaves_nothing(tmp_path: Path) -> None:
    with (
        pytest.raises(ValueError, match="no frames"),
        VideoWriter(tmp_path / "cam.mp4", width_px=64, height_px=48, fps=25),
    ):
        pass
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("frame", "words"),
    [
        (np.zeros((48, 64, 3), np.float32), r"dtype uint8.*got float32"),
        (np.zeros((48, 64), np.uint8), r"shape \(height_px, width_px, 3\) = \(48, 64, 3\).*got \(48, 64\)"),
        (np.zeros((64, 48, 3), np.uint8), r"got \(64, 48, 3\)"),
        (np.zeros((48, 64, 4), np.uint8), r"got \(48, 64, 4\)"),
    ],
)
def test_bad_frame_is_rejected(tmp_path: Path, frame: np.ndarray, words: str) -> None:
    with (
        pytest.raises(ValueError, match=words),
        VideoWriter(tmp_path / "cam.mp4", width_px=64, height_px=48, fps=25) as w,
    ):
        w.write(frame)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("width_px", "height_px"), [(321, 240), (320, 241)])
def test_odd_size_with_420_is_rejected(tmp_path: Path, width_px: int, height_px: int) -> None:
    with pytest.raises(ValueError, match=r"4:2:0.*even width and height.*yuv444p"):
        VideoWriter(tmp_path / "cam.mp4", width_px=width_px, height_px=height_px, fps=25)
    assert list(tmp_path.iterdir()) == []


def test_odd_size_with_444_round_trips(tmp_path: Path) -> None:
    frames = moving_gradient(3, 65, 49)
    path = tmp_path / "cam.mp4"
    encode(path, frames, codec=Codec(pixel_format="yuv444p"))
    stream, decoded = decode(path)
    assert (stream.codec_context.width, stream.codec_context.height) == (65, 49)
    assert mean_abs_error_dn(decoded, frames) < 3.0


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"fps": 0.0}, "fps must be a finite number > 0"),
        ({"fps": float("nan")}, "fps must be a finite number > 0"),
        ({"preset": "medum"}, "preset must be one of .*medium"),
        ({"path": "cam.yuv4"}, "container format.*'.yuv4'.*.mp4"),
    ],
)
def test_bad_settings_are_rejected(tmp_path: Path, kwargs: dict, words: str) -> None:
    settings = {"path": "cam.mp4", "width_px": 64, "height_px": 48, "fps": 25.0} | kwargs
    settings["path"] = tmp_path / settings["path"]
    with pytest.raises(ValueError, match=words):
        VideoWriter(**settings)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not video._has_encoder("libx265"), reason="this PyAV build has no libx265")
def test_h265_round_trip(tmp_path: Path) -> None:
    frames = moving_gradient(10)
    path = tmp_path / "cam.mp4"
    encode(path, frames, codec=Codec(name="h265", bitrate_kbps=None, crf=18))
    stream, decoded = decode(path)
    assert len(decoded) == 10
    assert stream.codec_context.name == "hevc"
    assert stream.codec_context.pix_fmt == "yuv420p"
    assert mean_abs_error_dn(decoded, frames) < 3.0


def test_missing_encoder_is_named(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(video, "ENCODERS", MappingProxyType({**video.ENCODERS, "h265": "libx265_not_built"}))
    with pytest.raises(
        ValueError, match=r"h265 needs FFmpeg's libx265_not_built encoder.*available here: h264 \(libx264\)"
    ):
        VideoWriter(tmp_path / "cam.mp4", width_px=64, height_px=48, fps=25, codec=Codec(name="h265"))
    assert list(tmp_path.iterdir()) == []


def test_mjpeg_frames_are_all_key_frames(tmp_path: Path) -> None:
    frames = moving_gradient(5)
    path = tmp_path / "cam.mkv"
    encode(path, frames, codec=Codec(name="mjpeg", bitrate_kbps=None, crf=10, gop_frames=50))
    stream, decoded = decode(path)
    assert stream.codec_context.name == "mjpeg"
    assert all(frame.key_frame for frame in decoded)
    assert mean_abs_error_dn(decoded, frames) < 3.0


def test_mjpeg_crf_sets_the_quantiser(tmp_path: Path) -> None:
    frames = noisy(moving_gradient(3), sigma_dn=10.0)
    sizes = {}
    for crf in (0, 30):
        path = tmp_path / f"{crf}.mkv"
        encode(path, frames, codec=Codec(name="mjpeg", bitrate_kbps=None, crf=crf))
        sizes[crf] = path.stat().st_size
    assert sizes[0] > 2 * sizes[30]
