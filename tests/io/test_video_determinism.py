"""Same frames, same codec settings → the same video bytes, in separate processes.

x264 and x265 under VBV rate control used to plan frame sizes from other threads' running estimates, so
two runs of one job differed once the stream was long enough for rate control to matter (a dozen
frames). Each encode here runs in a fresh interpreter so thread start-up and timing differ between them.
"""

from __future__ import annotations

import stat
import subprocess
import sys
import textwrap

import pytest

from camgen.io.video import _has_encoder

FRAMES = 64
"""Long enough for VBV rate control and the lookahead to act (3 frames did not show the problem)."""
WIDTH_PX, HEIGHT_PX = 320, 240

ENCODE = textwrap.dedent(
    """
    import sys
    import numpy as np
    from camgen.config.profile import Codec
    from camgen.io.video import VideoWriter

    path, name, bitrate = sys.argv[1], sys.argv[2], sys.argv[3]
    width_px, height_px, frames = {width_px}, {height_px}, {frames}
    codec = Codec(name=name, bitrate_kbps=None if bitrate == "crf" else float(bitrate), gop_frames=25)
    rng = np.random.default_rng(20240611)
    y_px, x_px = np.mgrid[0:height_px, 0:width_px]
    with VideoWriter(path, width_px=width_px, height_px=height_px, fps=25, codec=codec, preset=codec.preset) as w:
        for i in range(frames):
            gradient = np.stack([(x_px + 5 * i) % 256, (y_px + 3 * i) % 256, (x_px + y_px - 7 * i) % 256], axis=-1)
            noise = rng.integers(-24, 25, size=gradient.shape)
            w.write(np.clip(gradient + noise, 0, 255).astype(np.uint8))
    """
).format(width_px=WIDTH_PX, height_px=HEIGHT_PX, frames=FRAMES)


def _encode(path, name: str, bitrate: str) -> bytes:
    subprocess.run([sys.executable, "-c", ENCODE, str(path), name, bitrate], check=True, timeout=120)
    return path.read_bytes()


@pytest.mark.parametrize(
    ("name", "bitrate"),
    # H.265 at a bit rate is the slow variant (`make test-slow`): H.265 at CRF and H.264 at a bit rate cover it.
    [
        ("h264", "2048"),
        ("h264", "crf"),
        pytest.param("h265", "2048", marks=pytest.mark.slow),
        ("h265", "crf"),
        ("mjpeg", "8192"),
    ],
)
def test_two_processes_write_the_same_bytes(tmp_path, name, bitrate):
    if not _has_encoder({"h264": "libx264", "h265": "libx265", "mjpeg": "mjpeg"}[name]):
        pytest.skip(f"this FFmpeg build has no {name} encoder")
    first = _encode(tmp_path / "a" / "video.mp4", name, bitrate)
    second = _encode(tmp_path / "b" / "video.mp4", name, bitrate)
    assert len(first) > 10_000
    assert first == second, f"{name} {bitrate}: {len(first)} against {len(second)} bytes"


def test_the_video_gets_the_mode_of_every_other_output(tmp_path):
    from camgen.io.files import file_mode

    _encode(tmp_path / "video.mp4", "h264", "crf")
    assert stat.S_IMODE((tmp_path / "video.mp4").stat().st_mode) == file_mode()
