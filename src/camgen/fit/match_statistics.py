"""One pass over 8-bit RGB frames, collecting what a noise level function (Liu et al. 2006) and the tone
estimate need.

The reference's frames, and camgen's simulated output alike, are read once and in order (`_collect`):
each frame is checked (`_check_frame`) and its histogram counted; for the spatial method its 8 × 8
blocks are reduced to a mean, plane slopes and a residual variance (`_block_statistics`); for the
temporal method its sums, squares and squared successive differences, its clipped samples and its
moving pixels are accumulated (`_Statistics`), and the same of the frames averaged over 2 × 2 pixels
when the denoise strength is fitted. With ``spectrum``, the temporal pass also sums the squared
differences of frames `SPECTRUM_LAGS` apart and the squared steps of the successive-frame differences
across and inside the 8 × 8 block grid, from which `camgen.fit.match_verify` measures the noise's temporal
correlation and its blockiness. `camgen.fit.match_nlf` turns them into a noise level function,
`camgen.fit.match_tone` into the clips of the output.

References
----------
C. Liu, W. T. Freeman, R. Szeliski and S. B. Kang, "Noise estimation from a single image", CVPR 2006;
C. Liu, R. Szeliski, S. B. Kang, C. L. Zitnick and W. T. Freeman, "Automatic estimation and removal of
noise from a single image", IEEE TPAMI 30(2), 299–314 (2008).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field

import cv2
import numpy as np

from camgen.errors import ConfigError


class ReferenceContentError(ConfigError):
    """The reference cannot be fitted because of what it shows (no frames, no noise, too few unclipped
    samples): the caller, who knows its files, names them."""


MOTION_BOX_PX = 16
"""Side of the box mean of the luma that the motion test compares between frames, px."""
MOTION_THRESHOLD_CODES = 3.0
"""A change of the box-mean luma above this between two frames marks motion, 8-bit codes (noise of
σ = 10 codes moves a 16 × 16 box mean by 0.9 codes rms)."""
BLOCK_PX = 8
"""Side of the blocks of the spatial method, px."""
SPATIAL_FRAMES_MAX = 64
"""The spatial method reads blocks from at most this many frames."""
SPECTRUM_LAGS = 4
"""Frame lags 1…4 of the temporal correlation the spectrum pass measures (`camgen.fit.match_verify`)."""


def _check_frame(index: int, frame: object) -> np.ndarray:
    if not isinstance(frame, np.ndarray):
        raise ConfigError(f"reference frame {index} is a {type(frame).__name__}, not an (H, W, 3) uint8 image array")
    if frame.dtype != np.uint8:
        raise ConfigError(
            f"reference frame {index} holds {frame.dtype} samples; `fit match` reads a camera's 8-bit output as "
            "(H, W, 3) uint8 RGB (raw or 16-bit frames belong to `camgen fit noise`)"
        )
    if frame.ndim != 3 or frame.shape[2] != 3:
        raise ConfigError(
            f"reference frame {index} has shape {frame.shape}; expected (H, W, 3) RGB (a grey image can be "
            "repeated into three channels; a single frame must still be passed as a list of frames)"
        )
    if min(frame.shape[:2]) < MOTION_BOX_PX:
        raise ConfigError(
            f"reference frame {index} is {frame.shape[1]}×{frame.shape[0]} px; the noise estimate needs at "
            f"least {MOTION_BOX_PX}×{MOTION_BOX_PX} px"
        )
    return frame


def _block_statistics(frame: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per 8 × 8 block and channel: mean, plane slopes (x, y), residual variance, and whether a sample
    is 0 or 255. Each (N, 3); the blocks cover the frame's top-left multiple of 8 px.

    The plane a + b·x + c·y over centred coordinates x, y ∈ {−3.5 … 3.5}: the three basis functions are
    orthogonal on the block, so b = Σx·v / Σx², c = Σy·v / Σy² and RSS = Σ(v − m)² − b²Σx² − c²Σy².
    """
    rows, cols = frame.shape[0] // BLOCK_PX, frame.shape[1] // BLOCK_PX
    blocks = (
        frame[: rows * BLOCK_PX, : cols * BLOCK_PX]
        .reshape(rows, BLOCK_PX, cols, BLOCK_PX, 3)
        .transpose(0, 2, 4, 1, 3)
        .reshape(rows * cols, 3, BLOCK_PX, BLOCK_PX)
    )
    saturated = ((blocks == 0) | (blocks == 255)).any(axis=(2, 3))
    values = blocks.astype(np.float32)
    mean = values.mean(axis=(2, 3))
    values -= mean[..., None, None]
    coordinate = np.arange(BLOCK_PX, dtype=np.float32) - (BLOCK_PX - 1) / 2
    sum_x2 = BLOCK_PX * float(np.sum(coordinate**2))
    slope_x = np.einsum("ncyx,x->nc", values, coordinate) / sum_x2
    slope_y = np.einsum("ncyx,y->nc", values, coordinate) / sum_x2
    rss = np.einsum("ncyx,ncyx->nc", values, values) - (slope_x**2 + slope_y**2) * sum_x2
    variance = np.maximum(rss, 0.0) / (BLOCK_PX * BLOCK_PX - 3)
    return mean, slope_x, slope_y, variance, saturated


def _plane_image(frame: np.ndarray) -> np.ndarray:
    """The frame's top-left multiple of 8 px with each 8 × 8 block replaced by its fitted plane (float32)."""
    rows, cols = frame.shape[0] // BLOCK_PX, frame.shape[1] // BLOCK_PX
    mean, slope_x, slope_y, _, _ = _block_statistics(frame)
    coordinate = np.arange(BLOCK_PX, dtype=np.float32) - (BLOCK_PX - 1) / 2
    planes = (
        mean[:, :, None, None]
        + slope_x[:, :, None, None] * coordinate[None, None, None, :]
        + slope_y[:, :, None, None] * coordinate[None, None, :, None]
    )
    return (
        planes.reshape(rows, cols, 3, BLOCK_PX, BLOCK_PX)
        .transpose(0, 3, 1, 4, 2)
        .reshape(rows * BLOCK_PX, cols * BLOCK_PX, 3)
    )


@dataclass
class _Statistics:
    """What one pass over the reference collects (mutable while it reads; private)."""

    temporal: bool
    spatial: bool
    histogram: bool
    frames: int = 0
    shape: tuple[int, ...] | None = None
    sizes_differ: bool = False
    total: np.ndarray | None = None
    squares: np.ndarray | None = None
    squared_differences: np.ndarray | None = None
    pairs: int = 0
    skipped_pairs: int = 0
    saturated: np.ndarray | None = None
    moving: np.ndarray | None = None
    first: np.ndarray | None = None
    blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = field(default_factory=list)
    """Per frame read by the spatial method: block means, residual variances, clipped flags, (N, 3) each."""
    counts: np.ndarray = field(default_factory=lambda: np.zeros((3, 256), np.int64))
    half: _Statistics | None = None
    """The same statistics of the frames averaged over 2 × 2 pixels (temporal only), or None."""
    spectrum: bool = False
    lag_squared_differences: list[np.ndarray] = field(default_factory=list)
    """With ``spectrum``: per lag k = 2 … `SPECTRUM_LAGS`, Σ_t (x_{t+k} − x_t)² per pixel and channel (lag 1
    is `squared_differences`)."""
    block_steps: dict[str, np.ndarray] = field(default_factory=dict)
    """With ``spectrum``: Σ over successive pairs of the squared step of the frame difference d between a
    pixel at an odd offset and the next one, ``"x"`` (H, ⌊(W − 1)/2⌋, 3) along rows between columns
    (2i + 1, 2i + 2), ``"y"`` likewise along columns."""
    _previous: np.ndarray | None = None
    _history: deque = field(default_factory=deque)
    _previous_luma: np.ndarray | None = None

    def add(self, frame: np.ndarray) -> None:
        frame = _check_frame(self.frames, frame)
        if self.first is None:
            self.first = frame.copy()
            self.shape = frame.shape
        elif frame.shape != self.shape:
            self.sizes_differ = True
        self.frames += 1
        if self.histogram:
            for c in range(3):
                self.counts[c] += np.bincount(frame[..., c].ravel(), minlength=256)
        if self.spatial and len(self.blocks) < SPATIAL_FRAMES_MAX:
            mean, _, _, variance, saturated = _block_statistics(frame)
            self.blocks.append((mean, variance, saturated))
        if self.temporal and not self.sizes_differ:
            self._add_temporal(frame)
            if self.half is not None:
                self.half.add(_half_scale(frame))

    def _add_temporal(self, frame: np.ndarray) -> None:
        # OpenCV's accumulators add 8-bit samples (and squares) into float64 in one pass, exactly.
        luma = cv2.boxFilter(cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY), cv2.CV_32F, (MOTION_BOX_PX, MOTION_BOX_PX))
        if self.total is None:
            self.total = np.zeros(frame.shape, np.float64)
            self.squares = np.zeros(frame.shape, np.float64)
            self.squared_differences = np.zeros(frame.shape, np.float64)
            self.saturated = np.zeros(frame.shape, bool)
            self.moving = np.zeros(frame.shape[:2], bool)
        cv2.accumulate(frame, self.total)
        cv2.accumulateSquare(frame, self.squares)
        # 0 and 255 are the two values that 8-bit wrap-around of v − 1 sends to 254 and above.
        self.saturated |= (frame - np.uint8(1)) >= 254
        if self._previous is not None:
            change = cv2.absdiff(luma, self._previous_luma)
            # Most of the frame changed at once: a light or exposure step, not noise; leave the pair out.
            if float(np.median(change[::4, ::4])) > MOTION_THRESHOLD_CODES:
                self.skipped_pairs += 1
            else:
                self.moving |= change > MOTION_THRESHOLD_CODES
                cv2.accumulateSquare(cv2.absdiff(frame, self._previous), self.squared_differences)
                self.pairs += 1
                if self.spectrum:
                    _add_block_steps(self.block_steps, frame.astype(np.int16) - self._previous)
        if self.spectrum:
            self._add_lags(frame)
        self._previous = frame.copy()  # a reader may refill the array it yielded
        self._previous_luma = luma

    def _add_lags(self, frame: np.ndarray) -> None:
        """Σ (x_t − x_{t−k})² for k = 2 … `SPECTRUM_LAGS`, from the frames kept in `_history`."""
        if not self.lag_squared_differences:
            self.lag_squared_differences = [np.zeros(frame.shape, np.float64) for _ in range(SPECTRUM_LAGS - 1)]
        for k, earlier in enumerate(reversed(self._history), start=1):
            if k >= 2:
                cv2.accumulateSquare(cv2.absdiff(frame, earlier), self.lag_squared_differences[k - 2])
        self._history.append(frame.copy())
        if len(self._history) > SPECTRUM_LAGS:
            self._history.popleft()

    @property
    def static_fraction(self) -> float:
        if self.moving is None or self.pairs == 0:
            return math.nan
        return 1.0 - float(np.mean(self.moving))


def _add_block_steps(steps: dict[str, np.ndarray], difference: np.ndarray) -> None:
    """Add the squared steps of a frame difference between odd-offset pixels and their next neighbours
    (`_Statistics.block_steps`): at offset 7 of 8 the step crosses a block edge, at 1, 3, 5 it stays inside
    one, and both pair a CFA phase of one parity with the other."""
    for axis, name in ((1, "x"), (0, "y")):
        length = (difference.shape[axis] - 1) // 2
        left = np.take(difference, np.arange(1, 2 * length, 2), axis=axis)
        right = np.take(difference, np.arange(2, 2 * length + 1, 2), axis=axis)
        step = (right - left).astype(np.float64)
        if name not in steps:
            steps[name] = np.zeros(step.shape, np.float64)
        steps[name] += step * step


def _half_scale(frame: np.ndarray) -> np.ndarray:
    """The frame averaged over 2 × 2 pixels (rounded to 8 bits), at least 16 px a side."""
    height, width = max(MOTION_BOX_PX, frame.shape[0] // 2), max(MOTION_BOX_PX, frame.shape[1] // 2)
    return cv2.resize(frame, (width, height), interpolation=cv2.INTER_AREA)


def _collect(
    frames_rgb8: Iterable[np.ndarray],
    *,
    temporal: bool,
    spatial: bool,
    histogram: bool,
    half_scale: bool = False,
    spectrum: bool = False,
) -> _Statistics:
    if isinstance(frames_rgb8, np.ndarray) and frames_rgb8.ndim == 3:
        raise ConfigError(
            f"the reference is one array of shape {frames_rgb8.shape}; pass a sequence of (H, W, 3) frames "
            "(or a (T, H, W, 3) array)"
        )
    statistics = _Statistics(temporal=temporal, spatial=spatial, histogram=histogram, spectrum=spectrum and temporal)
    if half_scale and temporal:
        statistics.half = _Statistics(temporal=True, spatial=False, histogram=False)
    for frame in frames_rgb8:
        statistics.add(frame)
    if statistics.frames == 0:
        raise ReferenceContentError(
            "the reference holds no frames; give a video or 8-bit images of the camera's output"
        )
    return statistics
