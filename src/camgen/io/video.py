"""Encode 8-bit RGB frames into an H.264, H.265 or MJPEG file the way a surveillance camera streams them.

The encoder follows the camera's `Codec` profile: rate control (target bitrate or constant quality), a
fixed key-frame interval, and the chroma subsampling of the stream. Encoding goes through PyAV (FFmpeg's
libx264, libx265 and mjpeg encoders). The file appears under its final name only once it is complete.

`join_videos` joins videos written in segments (a render's, one per checkpoint, so that a stopped render
can resume) into one without re-encoding. `read_video_rgb8` reads a video back as RGB frames;
`webm_vp9_writer` writes a VP9 WebM for looking at in a browser (`camgen preview`), not as a camera streams.

Conventions
-----------
* Colour: H.264 and H.265 streams are BT.709, limited range (Y' 16–235), and say so in the stream's VUI;
  MJPEG is BT.601 full range as JFIF requires. The RGB input is taken to be already gamma-encoded
  (the ISP's output); no transfer function is applied here.
* Time: frame ``i`` has presentation time ``i / fps`` seconds exactly (pts ``i`` in a time base of
  ``1 / fps``), with ``fps`` held as a fraction so that NTSC rates such as 30000/1001 stay exact.
* Frames: I and P frames only, no B-frames, as IP cameras stream for low latency; key frames fall
  exactly every `Codec.gop_frames` frames (closed GOPs, no scene-cut key frames).
* Reproducibility: the file's bytes are a function of the frames, the `Codec` profile, the preset and the
  versions of PyAV/FFmpeg/x264/x265, not of the machine's core count, CPU features or thread timing (see
  `_reproducible`). The price is single-threaded x264 and MJPEG encoding; `camgen bench` measures it.
"""

from __future__ import annotations

import math
import numbers
import os
import tempfile
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from fractions import Fraction
from pathlib import Path
from types import MappingProxyType, TracebackType
from typing import Self

import av
import numpy as np
from av.codec.codec import UnknownCodecError
from av.video.reformatter import ColorRange, Colorspace

from camgen.config.profile import Codec
from camgen.errors import ConfigError
from camgen.io.files import atomic_path, file_mode

ENCODERS = MappingProxyType({"h264": "libx264", "h265": "libx265", "mjpeg": "mjpeg"})
"""FFmpeg encoder behind each `Codec.name`."""

X26X_PRESETS = ("ultrafast", "superfast", "veryfast", "faster", "fast", "medium", "slow", "slower", "veryslow")
"""Speed/quality presets shared by libx264 and libx265 (fastest first)."""

H273_BT709 = 1
"""ITU-T H.273 code point of BT.709 colour primaries and transfer characteristics (AVCOL_PRI/TRC_BT709)."""

VBV_BUFFER_S = 1.0
"""Decoder buffer of the bitrate mode, seconds of the target bitrate (see `VideoWriter`)."""

ENCODER_THREADS = 1
"""Threads of the libx264 and MJPEG encoders. Under VBV rate control, x264's slice threads and frame threads
each plan a frame's size from the other threads' running estimates, so the bits depend on thread timing;
and the thread count FFmpeg picks by default follows the core count, which sets x264's slices and MJPEG's
restart intervals. One thread removes both."""

X264_REPRODUCIBLE = "cpu-independent=1"
"""x264 parameters that make its output the same on every CPU: canonical algorithms instead of the
CPU-specific ones (with AVX2 and newer, those change the bits)."""

X265_REPRODUCIBLE = "frame-threads=1:info=0"
"""x265 parameters that make its output independent of timing and machine: one frame at a time (frame
threads plan VBV sizes from one another's running estimates, and their auto count follows the cores), and
no encoder-info SEI (it records the CPU's feature mask and the thread-pool size). The thread pool is set
by `_reproducible`."""

CHROMA_SUBSAMPLING = MappingProxyType({"yuv420p": (2, 2), "yuv422p": (2, 1), "yuv444p": (1, 1)})
"""Chroma subsampling (horizontal, vertical) of each pixel format; the frame size must be a multiple."""


class VideoWriter:
    """Encodes 8-bit RGB frames as a camera's stream would (codec, rate control, GOP, chroma subsampling).

    Frames go into a temporary file beside `path` (``.<name>.<random>.partial<suffix>``); `close` renames
    it to `path` in one step, `abort` deletes it. Used as a context manager, the writer closes on success
    and aborts when the block raises, so `path` never holds a partial video.

    Parameters
    ----------
    path : str or Path
        Output file. The suffix chooses the container (``.mp4``, ``.mkv``, ``.mov``, ``.avi``).
        Missing parent directories are created.
    width_px, height_px : int
        Frame size, pixels. 4:2:0 needs both even, 4:2:2 an even width.
    fps : float
        Frame rate, frames per second (> 0). Rates within 0.01 % of an integer or of an NTSC rate
        ``n · 1000/1001`` (29.97, 59.94, 23.976) are stored as that exact fraction; others as the
        nearest fraction with denominator ≤ 1001.
    codec : Codec
        The camera's codec profile:

        * ``name``: ``h264`` (libx264), ``h265`` (libx265) or ``mjpeg``.
        * ``bitrate_kbps``: target bitrate, kbit/s. For H.264/H.265 this is a VBV-constrained average
          like a camera's CBR mode: peak rate (``maxrate``) = target, decoder buffer (``bufsize``) =
          `VBV_BUFFER_S` seconds of the target; no filler data is inserted, so a static scene may use
          less. For MJPEG it is the mpegvideo rate controller's target.
        * ``crf`` (when ``bitrate_kbps`` is None): constant quality, 0 (best) to 51 (worst).
          MJPEG has no CRF; it maps linearly onto a fixed quantiser scale,
          ``q = 2 + round(29 · crf / 51)`` (2 best, 31 worst).
        * ``gop_frames``: key-frame interval, frames. Frame ``k · gop_frames`` is a key (IDR) frame and
          no other is (scene-cut detection off). MJPEG frames are all key frames.
        * ``pixel_format``: chroma subsampling of the stream (``yuv420p``, ``yuv422p``, ``yuv444p``).
    preset : str
        libx264/libx265 speed preset, ``ultrafast`` … ``veryslow``; ignored by MJPEG.
    reproducible : bool
        True (the default): the file's bytes depend only on the frames, the codec settings and the library
        versions (`ENCODER_THREADS`, `X264_REPRODUCIBLE`, `X265_REPRODUCIBLE`). False lets FFmpeg thread the
        encoder as it likes: somewhat faster on a multi-core machine, but two runs of the same frames give
        different bytes (a bitrate-mode stream's sizes drift by a few per cent). For speed comparisons.

    Raises
    ------
    ConfigError
        (a ValueError) for a frame size the pixel format cannot hold, a non-positive frame rate, an
        unknown preset, a container the suffix does not name, or a codec this FFmpeg build lacks.

    Examples
    --------
    >>> with VideoWriter("out/cam.mp4", width_px=320, height_px=240, fps=25) as writer:  # doctest: +SKIP
    ...     for frame in frames_rgb8:
    ...         writer.write(frame)
    """

    def __init__(
        self,
        path: str | Path,
        *,
        width_px: int,
        height_px: int,
        fps: float,
        codec: Codec = Codec(),  # noqa: B008 - frozen pydantic model, safe to share
        preset: str = "medium",
        reproducible: bool = True,
    ) -> None:
        self._path = Path(path)
        self._width_px = width_px
        self._height_px = height_px
        self._frames_written = 0
        self._closed = False
        rate, encoder = _checked_settings(width_px, height_px, fps, codec, preset)
        self._colour = _colour(codec.name)

        self._path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(
            prefix=f".{self._path.name}.", suffix=f".partial{self._path.suffix}", dir=self._path.parent
        )
        os.close(fd)
        self._tmp_path = Path(tmp)
        try:
            try:
                self._container = av.open(str(self._tmp_path), mode="w")
            except ValueError as error:
                raise ConfigError(
                    f"{self._path}: cannot tell the container format from the suffix {self._path.suffix!r}; "
                    "use .mp4, .mkv, .mov or .avi"
                ) from error
            self._stream = _opened_stream(
                self._container, encoder, rate, codec, width_px, height_px, preset, self._colour, reproducible
            )
        except BaseException:
            self._discard()
            raise

    @property
    def frames_written(self) -> int:
        """Frames passed to `write` so far."""
        return self._frames_written

    def write(self, frame_rgb8: np.ndarray) -> None:
        """Encode one frame; it is shown for ``1 / fps`` seconds after the previous one.

        Parameters
        ----------
        frame_rgb8 : ndarray, shape (height_px, width_px, 3), uint8
            Gamma-encoded RGB, channels in R, G, B order, 0–255 DN.

        Raises
        ------
        ValueError
            If the writer is closed, or the frame is not a uint8 array of shape (height_px, width_px, 3).
        """
        if self._closed:
            raise ValueError(f"{self._path}: the writer is closed; open a new VideoWriter to write more frames")
        _check_frame(frame_rgb8, self._width_px, self._height_px)
        frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(frame_rgb8), format="rgb24")
        colorspace, color_range = self._colour
        frame = frame.reformat(
            format=self._stream.codec_context.pix_fmt,
            dst_colorspace=colorspace,
            dst_color_range=color_range,
        )
        frame.pts = self._frames_written
        self._container.mux(self._stream.encode(frame))
        self._frames_written += 1

    def close(self) -> None:
        """Flush the encoder, finish the container and rename the file to `path`.

        Closing twice does nothing. If finishing fails, the temporary file is deleted and the error
        propagates; `path` is left as it was.

        Raises
        ------
        ValueError
            If no frame was written: containers drop an empty video track, so there is no video to save.
            The temporary file is deleted; use `abort` to stop without output on purpose.
        """
        if self._closed:
            return
        if self._frames_written == 0:
            self._discard()
            raise ValueError(f"{self._path}: no frames were written, so there is no video to save; write a frame first")
        try:
            self._container.mux(self._stream.encode(None))
            self._container.close()
            os.chmod(self._tmp_path, file_mode())  # mkstemp made it private (0600)
            os.replace(self._tmp_path, self._path)
        except BaseException:
            self._discard()
            raise
        self._closed = True

    def abort(self) -> None:
        """Stop without producing `path`: close the container and delete the temporary file.

        Safe to call more than once, and after `close` (then it does nothing).
        """
        if not self._closed:
            self._discard()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()

    def _discard(self) -> None:
        self._closed = True
        container = getattr(self, "_container", None)
        try:
            if container is not None:
                container.close()
        except (av.FFmpegError, OSError, ValueError):
            pass  # the file is deleted next; a failed trailer on it does not matter
        finally:
            self._tmp_path.unlink(missing_ok=True)


def _checked_settings(width_px: int, height_px: int, fps: float, codec: Codec, preset: str) -> tuple[Fraction, str]:
    """(frame rate as a fraction, FFmpeg encoder name) of a writer's settings; ConfigError for a size the pixel
    format cannot hold, a bad rate, a codec this FFmpeg lacks or an unknown preset (`VideoWriter`)."""
    _check_size(width_px, height_px, codec.pixel_format)
    rate = _frame_rate(fps)
    encoder = _encoder(codec.name)
    if codec.name != "mjpeg" and preset not in X26X_PRESETS:
        raise ConfigError(f"preset must be one of {', '.join(X26X_PRESETS)}, got {preset!r}")
    return rate, encoder


def _opened_stream(container, encoder: str, rate: Fraction, codec: Codec, width_px: int, height_px: int,
                   preset: str, colour, reproducible: bool):  # fmt: skip
    """A video stream added to `container` and its encoder configured (`_configure`) and opened."""
    stream = container.add_stream(encoder, rate=rate)
    _configure(stream.codec_context, codec, rate, width_px, height_px, preset, colour, reproducible)
    stream.codec_context.open()
    return stream


def join_videos(
    segments: Sequence[str | Path],
    path: str | Path,
    *,
    width_px: int,
    height_px: int,
    fps: float,
    codec: Codec = Codec(),  # noqa: B008 - frozen pydantic model, safe to share
    preset: str = "medium",
) -> int:
    """Join videos that `VideoWriter` wrote with these settings, one after another, into one video at
    `path` (written atomically), copying their packets: nothing is decoded or encoded again. Returns the
    number of frames.

    Each segment's first frame must be a key frame (every segment a writer wrote starts with one, and its
    GOPs are closed), so the joined stream decodes as its segments do, one after the other, frame for
    frame. Frame ``i`` of the whole gets presentation time ``i / fps``. A segment of n · `Codec.gop_frames`
    frames keeps the key frames every gop_frames frames across the joins.

    The container is set up as `VideoWriter` sets it up, from an opened encoder of the same settings, so
    that the header (``avcC``/``hvcC``, the ``btrt`` buffer size from the encoder's rate control, colour
    tags) is what a writer writes: joining the one segment of a video gives the bytes of that video. The
    packets, which the MP4 segments hold length-prefixed, are handed to the muxer in Annex B form, as an
    encoder hands them over (the muxer converts back; handed over length-prefixed they would be misread).

    Raises
    ------
    ValueError
        For no segments, a segment that holds no video, another codec or frame size, a first frame that
        is not a key frame, a frame out of order, or NAL lengths of other than 4 bytes.
    """
    if not segments:
        raise ValueError(f"{path}: no segments to join")
    rate, encoder = _checked_settings(width_px, height_px, fps, codec, preset)
    frame_time_base = Fraction(1) / rate
    done = 0
    with atomic_path(path) as tmp, av.open(str(tmp), mode="w") as container:
        stream = _opened_stream(container, encoder, rate, codec, width_px, height_px, preset, _colour(codec.name), True)
        container.start_encoding()  # the header from the opened encoder, before any packet
        for segment in segments:
            with av.open(str(segment)) as source:
                if not source.streams.video:
                    raise ValueError(f"{segment}: holds no video stream")
                video = source.streams.video[0]
                context = video.codec_context
                if context.name != JOINED_DECODERS[codec.name] or (context.width, context.height) != (
                    width_px,
                    height_px,
                ):
                    raise ValueError(
                        f"{segment}: {context.name} {context.width}×{context.height}, not the "
                        f"{codec.name} {width_px}×{height_px} being joined"
                    )
                length_size = _nal_length_size(codec.name, context.extradata)
                ticks = frame_time_base / video.time_base
                first = done
                for packet in source.demux(video):
                    if packet.size == 0:
                        continue  # the demuxer's end-of-stream marker
                    if done == first and not packet.is_keyframe:
                        raise ValueError(f"{segment}: does not start with a key frame, so it cannot be joined")
                    if packet.pts != (done - first) * ticks:
                        raise ValueError(f"{segment}: frame {done - first} has pts {packet.pts}, not in order")
                    data = bytes(packet)
                    copy = av.Packet(data if length_size is None else _annex_b(data, length_size))
                    copy.pts = copy.dts = done
                    copy.time_base = frame_time_base
                    copy.is_keyframe = packet.is_keyframe
                    copy.stream = stream
                    container.mux(copy)
                    done += 1
                if done == first:
                    raise ValueError(f"{segment}: holds no frames")
    return done


JOINED_DECODERS = MappingProxyType({"h264": "h264", "h265": "hevc", "mjpeg": "mjpeg"})
"""The FFmpeg decoder that reads each `Codec.name`'s stream."""


def _nal_length_size(codec_name: str, extradata: bytes | None) -> int | None:
    """Bytes of each NAL unit's length prefix in an MP4's H.264/H.265 packets (from the ``avcC`` or
    ``hvcC`` record, ISO/IEC 14496-15 §5.3.3 and §8.3.3); None for packets already in Annex B or MJPEG."""
    if codec_name == "mjpeg" or not extradata or extradata[0] != 1:
        return None
    size = (extradata[4 if codec_name == "h264" else 21] & 3) + 1
    if size != 4:
        raise ValueError(f"NAL units with {size}-byte lengths; only the 4 bytes FFmpeg writes are joined")
    return size


def _annex_b(data: bytes, length_size: int) -> bytes:
    """Length-prefixed NAL units (MP4) → the same units each after a 4-byte start code (Annex B)."""
    out = bytearray()
    position = 0
    while position < len(data):
        length = int.from_bytes(data[position : position + length_size], "big")
        start = position + length_size
        if length == 0 or start + length > len(data):
            raise ValueError(f"a NAL unit of {length} bytes at byte {position} of a {len(data)}-byte packet")
        out += b"\0\0\0\1" + data[start : start + length]
        position = start + length
    return bytes(out)


def decoded_rgb8(frame: av.VideoFrame) -> np.ndarray:
    """(H, W, 3) uint8 full-range RGB of a decoded frame, converted with the colour matrix and range its
    stream is tagged with (a limited-range stream read as full range would stretch its levels and noise)."""
    rgb = frame.reformat(
        format="rgb24",
        src_colorspace=frame.colorspace,
        src_color_range=frame.color_range,
        dst_color_range=ColorRange.JPEG,
    )
    return rgb.to_ndarray()


def read_video_rgb8(path: str | Path) -> Iterator[np.ndarray]:
    """The frames of a video file in order, each as (H, W, 3) uint8 full-range RGB (`decoded_rgb8`).

    Raises
    ------
    ConfigError
        (a ValueError) when FFmpeg cannot open or decode the file; frames decoded before the fault
        have been yielded.
    """
    try:
        with av.open(str(path)) as container:
            if not container.streams.video:
                raise ConfigError(f"{path}: holds no video stream; give the video.mp4 a render wrote")
            for frame in container.decode(container.streams.video[0]):
                yield decoded_rgb8(frame)
    except av.FFmpegError as error:
        raise ConfigError(f"{path}: cannot be decoded as video ({error}); render it again") from error


WEBM_VP9_CRF = 32
"""Constant quality of `webm_vp9_writer`, 0 (best) to 63: annotation lines and text stay sharp at a
few hundred kB per second of 720p."""


@contextmanager
def webm_vp9_writer(
    path: str | Path, *, width_px: int, height_px: int, fps: float, crf: int = WEBM_VP9_CRF
) -> Iterator[Callable[[np.ndarray], None]]:
    """A WebM (VP9, 4:2:0, BT.709 limited range) file that every current browser plays, Chromium builds
    without H.264 included; the block gets a function that encodes one (height_px, width_px, 3) uint8 RGB
    frame. For looking at, not for a camera's stream: libvpx's realtime mode, one thread, no rate control.
    The file appears under `path` only when the block ends without an error, with at least one frame.

    Raises
    ------
    ConfigError
        (a ValueError) for an odd frame size (4:2:0 needs it even) or a non-positive frame rate.
    ValueError
        If a frame has another shape or dtype, or none was written.
    """
    _check_size(width_px, height_px, "yuv420p")
    rate = _frame_rate(fps)
    colour = (Colorspace.ITU709, ColorRange.MPEG)
    written = 0
    with atomic_path(path) as tmp, av.open(str(tmp), mode="w", format="webm") as container:
        stream = container.add_stream("libvpx-vp9", rate=rate)
        context = stream.codec_context
        context.width, context.height, context.pix_fmt = width_px, height_px, "yuv420p"
        context.time_base = 1 / rate
        context.colorspace, context.color_range = colour
        context.color_primaries = context.color_trc = H273_BT709
        context.bit_rate = 0
        context.thread_count = 1
        context.options = {"crf": str(crf), "b": "0", "deadline": "realtime", "cpu-used": "8"}

        def write(frame_rgb8: np.ndarray) -> None:
            nonlocal written
            _check_frame(frame_rgb8, width_px, height_px)
            frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(frame_rgb8), format="rgb24")
            frame = frame.reformat(format="yuv420p", dst_colorspace=colour[0], dst_color_range=colour[1])
            frame.pts = written
            container.mux(stream.encode(frame))
            written += 1

        yield write
        if written == 0:
            raise ValueError(f"{path}: no frames were written, so there is no video to save; write a frame first")
        container.mux(stream.encode(None))


def _frame_rate(fps: float) -> Fraction:
    """`fps` as an exact fraction: integer, NTSC ``n · 1000/1001``, or nearest with denominator ≤ 1001."""
    if isinstance(fps, bool) or not isinstance(fps, numbers.Real) or not (math.isfinite(fps) and fps > 0):
        raise ConfigError(f"fps must be a finite number > 0, got {fps!r}")
    fps = float(fps)
    for candidate in (Fraction(round(fps)), Fraction(round(fps * 1.001) * 1000, 1001)):
        if candidate > 0 and abs(fps - candidate) <= 1e-4 * fps:
            return candidate
    rate = Fraction(fps).limit_denominator(1001)
    if rate <= 0:
        raise ConfigError(f"fps must be ≥ 1/1001 frames per second, got {fps!r}")
    return rate


def _check_size(width_px: int, height_px: int, pixel_format: str) -> None:
    """Raise ConfigError unless the frame size is positive and fits the chroma subsampling."""
    for name, value in (("width_px", width_px), ("height_px", height_px)):
        if not isinstance(value, int | np.integer) or isinstance(value, bool) or value <= 0:
            raise ConfigError(f"{name} must be a positive integer, got {value!r}")
    step_x, step_y = CHROMA_SUBSAMPLING[pixel_format]
    if width_px % step_x or height_px % step_y:
        needs = "even width and height" if step_y == 2 else "an even width"
        name = {"yuv420p": "4:2:0", "yuv422p": "4:2:2"}[pixel_format]
        raise ConfigError(
            f"codec.pixel_format {pixel_format} ({name} chroma subsampling) needs {needs}, "
            f"got {width_px}×{height_px} px; crop or pad the frames to an even size, or use yuv444p"
        )


def _check_frame(frame_rgb8: np.ndarray, width_px: int, height_px: int) -> None:
    """Raise ValueError unless `frame_rgb8` is a uint8 array of shape (height_px, width_px, 3)."""
    if not isinstance(frame_rgb8, np.ndarray):
        raise ValueError(f"frame_rgb8 must be a numpy array, got {type(frame_rgb8).__name__}")
    if frame_rgb8.dtype != np.uint8:
        raise ValueError(
            f"frame_rgb8 must have dtype uint8 (8-bit RGB, 0–255 DN), got {frame_rgb8.dtype}; "
            "quantise it first, e.g. np.clip(np.rint(frame * 255), 0, 255).astype(np.uint8) for 0–1 floats"
        )
    expected = (height_px, width_px, 3)
    if frame_rgb8.shape != expected:
        raise ValueError(
            f"frame_rgb8 must have shape (height_px, width_px, 3) = {expected} (RGB, channels last), "
            f"got {frame_rgb8.shape}"
        )


def _encoder(name: str) -> str:
    """The FFmpeg encoder for `name`, or ConfigError listing the camgen codecs this build can encode."""
    encoder = ENCODERS[name]
    if _has_encoder(encoder):
        return encoder
    available = [f"{codec} ({enc})" for codec, enc in ENCODERS.items() if _has_encoder(enc)]
    raise ConfigError(
        f"codec.name {name} needs FFmpeg's {encoder} encoder, which this PyAV build (FFmpeg "
        f"libavcodec {'.'.join(map(str, av.library_versions['libavcodec']))}) lacks; encoders available "
        f"here: {', '.join(available) or 'none'}. Choose one of those, or install a PyAV/FFmpeg build "
        f"with {encoder}"
    )


def _has_encoder(encoder: str) -> bool:
    try:
        av.codec.Codec(encoder, "w")
    except UnknownCodecError:
        return False
    return True


def _colour(codec_name: str) -> tuple[Colorspace, ColorRange]:
    """YUV matrix and range of the stream: BT.709 limited for H.264/H.265, BT.601 full (JFIF) for MJPEG."""
    if codec_name == "mjpeg":
        return Colorspace.ITU601, ColorRange.JPEG
    return Colorspace.ITU709, ColorRange.MPEG


def _configure(
    context: av.video.codeccontext.VideoCodecContext,
    codec: Codec,
    rate: Fraction,
    width_px: int,
    height_px: int,
    preset: str,
    colour: tuple[Colorspace, ColorRange],
    reproducible: bool,
) -> None:
    """Set size, timing, pixel format, colour tags, GOP, rate control and threading on an unopened encoder."""
    context.width = width_px
    context.height = height_px
    context.pix_fmt = codec.pixel_format
    context.framerate = rate
    context.time_base = 1 / rate
    context.gop_size = codec.gop_frames
    context.max_b_frames = 0
    colorspace, color_range = colour
    context.colorspace = colorspace  # swscale's ITU709/ITU601 equal the H.273 matrix codes BT709/BT470BG
    context.color_range = color_range
    if codec.name != "mjpeg":
        context.color_primaries = H273_BT709
        context.color_trc = H273_BT709

    options: dict[str, str] = {}
    if codec.bitrate_kbps is not None:
        bit_rate = round(codec.bitrate_kbps * 1000)
        context.bit_rate = bit_rate
        if codec.name != "mjpeg":
            options["maxrate"] = str(bit_rate)
            options["bufsize"] = str(round(bit_rate * VBV_BUFFER_S))
    elif codec.name == "mjpeg":
        # qmin = qmax pins the quantiser; the qscale flag would need a per-frame quality, which PyAV lacks
        options["qmin"] = options["qmax"] = str(2 + round(29 * codec.crf / 51))
    else:
        context.bit_rate = 0
        options["crf"] = str(codec.crf)

    if reproducible:
        context.thread_count = ENCODER_THREADS  # libx265 ignores it; its threads are set by _reproducible
    if codec.name != "mjpeg":
        # min-keyint only bounds scene-cut key frames, which are off; keyint alone fixes the interval.
        params = [f"keyint={codec.gop_frames}:scenecut=0:bframes=0"]
        if codec.name == "h265":
            params.append("open-gop=0:log-level=error")
        if reproducible:
            params.append(_reproducible(codec))
        options["x264-params" if codec.name == "h264" else "x265-params"] = ":".join(params)
        options["preset"] = preset
    context.options = options


def _reproducible(codec: Codec) -> str:
    """x264/x265 parameters (``key=value:…``) that make the stream a function of its input and settings.

    With `ENCODER_THREADS` on the codec context, the bytes no longer depend on thread timing, core count or
    CPU features (two processes agree byte for byte: tests/io/test_video_determinism.py).

    x265's thread pool runs the wavefront rows of a frame in parallel. Under VBV (``bitrate_kbps`` set) the
    row-level rate control reads the rows other threads have finished, so a tight bitrate gives different
    bytes run to run: no pool (``pools=none``) then. On 2 cores this cost 0.9–1.6× the pooled encode time
    at 1080p over repeated runs (noisy); ``camgen bench`` reports it beside the threaded encoder.
    In constant quality the rows do not interact and the pool stays, one thread per CPU, named explicitly
    because what changes the bits is whether a pool exists (the lookahead slices its cost estimates only
    with one), not its size.
    """
    if codec.name == "h264":
        return X264_REPRODUCIBLE
    pools = "none" if codec.bitrate_kbps is not None else str(os.cpu_count() or 1)
    return f"{X265_REPRODUCIBLE}:pools={pools}"
