"""`join_videos`: videos written in segments (a fresh encoder from each render checkpoint on, issue 23) and
joined by copying packets decode as their segments do, one after the other, with key frames a GOP apart
and presentation times i / fps; joining a single video gives back its very bytes (the header comes from
an encoder opened with the same settings, as `VideoWriter` writes it)."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import av
import numpy as np
import pytest

from camgen.config.profile import Codec
from camgen.io.video import VideoWriter, join_videos

WIDTH_PX, HEIGHT_PX, FPS = 64, 48, 10
SEGMENT_FRAMES = (3, 3, 2)


def frames_rgb8(count: int) -> list[np.ndarray]:
    """A gradient sliding right 2 px a frame, with a little fixed noise: content that changes frame to frame."""
    y, x = np.mgrid[:HEIGHT_PX, :WIDTH_PX]
    noise = np.random.default_rng(1).integers(0, 12, (HEIGHT_PX, WIDTH_PX, 3))
    return [
        np.clip(np.stack([(x + 2 * i) * 3, y * 4, (x + y + i) * 2], axis=-1) % 256 + noise, 0, 255).astype(np.uint8)
        for i in range(count)
    ]


def write_video(path: Path, frames: list[np.ndarray], codec: Codec) -> Path:
    with VideoWriter(path, width_px=WIDTH_PX, height_px=HEIGHT_PX, fps=FPS, codec=codec, preset=codec.preset) as out:
        for frame in frames:
            out.write(frame)
    return path


def decoded(path: Path) -> list[np.ndarray]:
    with av.open(str(path)) as container:
        return [frame.to_ndarray(format="rgb24") for frame in container.decode(video=0)]


def join(segments: list[Path], path: Path, codec: Codec) -> int:
    return join_videos(
        segments, path, width_px=WIDTH_PX, height_px=HEIGHT_PX, fps=FPS, codec=codec, preset=codec.preset
    )


@pytest.mark.parametrize("name", ["h264", "h265", "mjpeg"])
def test_joined_segments_decode_as_the_segments_with_key_frames_a_gop_apart(tmp_path, name):
    codec = Codec(name=name, gop_frames=3)
    frames = frames_rgb8(sum(SEGMENT_FRAMES))
    starts = np.cumsum((0, *SEGMENT_FRAMES[:-1]))
    segments = [
        write_video(tmp_path / f"segment{start}.mp4", frames[start : start + count], codec)
        for start, count in zip(starts, SEGMENT_FRAMES, strict=True)
    ]
    assert join(segments, tmp_path / "joined.mp4", codec) == len(frames)
    expected = [frame for segment in segments for frame in decoded(segment)]
    joined = decoded(tmp_path / "joined.mp4")
    assert len(joined) == len(frames) and all(np.array_equal(a, b) for a, b in zip(joined, expected, strict=True))
    assert np.abs(np.array(joined, dtype=int) - np.array(frames)).mean() < 6.0  # and they are the frames
    with av.open(str(tmp_path / "joined.mp4")) as container:
        stream = container.streams.video[0]
        packets = [packet for packet in container.demux(stream) if packet.size]
        ticks = Fraction(1, FPS) / stream.time_base
        assert stream.frames == len(frames)
        assert [packet.pts for packet in packets] == [i * ticks for i in range(len(frames))]
        keys = [i for i, packet in enumerate(packets) if packet.is_keyframe]
    assert keys == (list(range(len(frames))) if name == "mjpeg" else [0, 3, 6])


@pytest.mark.parametrize("codec", [Codec(gop_frames=3), Codec(name="h265", bitrate_kbps=None), Codec(name="mjpeg")])
def test_joining_one_video_gives_its_bytes(tmp_path, codec):
    whole = write_video(tmp_path / "whole.mp4", frames_rgb8(7), codec)
    join([whole], tmp_path / "joined.mp4", codec)
    assert (tmp_path / "joined.mp4").read_bytes() == whole.read_bytes()


def test_a_segment_of_another_size_is_refused(tmp_path):
    codec = Codec(gop_frames=3)
    segment = write_video(tmp_path / "segment.mp4", frames_rgb8(2), codec)
    with pytest.raises(ValueError, match=r"h264 64×48, not the h264 32×48 being joined"):
        join_videos([segment], tmp_path / "joined.mp4", width_px=32, height_px=HEIGHT_PX, fps=FPS, codec=codec)
    assert list(tmp_path.iterdir()) == [segment]  # nothing under the joined video's name, no temporary file
