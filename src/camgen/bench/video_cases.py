"""Encode speed of the reproducible encoder settings against FFmpeg's own threading (`VideoWriter`).

`VideoWriter(reproducible=True)` runs libx264 and MJPEG on one thread and libx265 one frame at a time
(without its thread pool under VBV), so that the same frames always give the same bytes. Each pair of
cases encodes the same noisy, moving 1080p frames in the default profile's bitrate mode both ways; the
reproducible case gives its ratio to the threaded one.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from camgen.bench.harness import Case
from camgen.config.profile import Codec
from camgen.io.video import VideoWriter, _has_encoder

FRAMES = 24
WIDTH_PX, HEIGHT_PX = 1920, 1080
ENCODERS = {"h264": "libx264", "h265": "libx265"}


def video_cases() -> list[Case]:
    frames_rgb8 = _frames(np.random.default_rng(0))

    def run(codec: Codec, reproducible: bool) -> None:
        with tempfile.TemporaryDirectory(prefix="camgen-bench-video-") as workspace:
            with VideoWriter(
                Path(workspace) / "video.mp4",
                width_px=WIDTH_PX,
                height_px=HEIGHT_PX,
                fps=25,
                codec=codec,
                preset=codec.preset,
                reproducible=reproducible,
            ) as writer:
                for frame_rgb8 in frames_rgb8:
                    writer.write(frame_rgb8)

    cases = []
    for name, encoder in ENCODERS.items():
        if not _has_encoder(encoder):
            continue
        codec = Codec(name=name)
        label = f"encode {FRAMES} frames {WIDTH_PX}×{HEIGHT_PX} {name} {codec.bitrate_kbps:g} kbit/s {codec.preset}"
        cases.append(Case(name=f"{label}, threaded (bytes vary)", run=lambda c=codec: run(c, False), repeats=3))
        cases.append(
            Case(
                name=f"{label}, reproducible",
                run=lambda c=codec: run(c, True),
                repeats=3,
                baseline=f"{label}, threaded (bytes vary)",
            )
        )
    return cases


def _frames(rng: np.random.Generator) -> np.ndarray:
    """(FRAMES, H, W, 3) uint8: a gradient sliding 6 px per frame under ±12 DN noise (rate control works)."""
    y_px, x_px = np.mgrid[0:HEIGHT_PX, 0:WIDTH_PX]
    base = np.stack([x_px * 255 // WIDTH_PX, y_px * 255 // HEIGHT_PX, (x_px + y_px) % 256], axis=-1)
    frames = np.empty((FRAMES, HEIGHT_PX, WIDTH_PX, 3), np.uint8)
    for i in range(FRAMES):
        noise = rng.integers(-12, 13, size=base.shape)
        frames[i] = np.clip(np.roll(base, 6 * i, axis=1) + noise, 0, 255)
    return frames
