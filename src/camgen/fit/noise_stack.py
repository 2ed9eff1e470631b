"""Frame stacks of a sensor noise measurement, after EMVA 1288 release 4.0 [1]_: the frames taken at one
setting streamed into per-pixel statistics, and the group they form.

`StackStatistics` reduces a stack to a per-pixel mean and temporal variance while the frames stream past
(a 4K stack is never held in memory); `FrameGroup` is such a stack with its kind, exposure time,
temperature and light. `camgen.fit.frames.scan_stacks` fills them from files and
`camgen.fit.noise.fit_noise` fits them.

References
----------
.. [1] EMVA Standard 1288, "Standard for Characterization of Image Sensors and Cameras", release 4.0
   Linear, European Machine Vision Association, 2021.
.. [2] B. P. Welford, "Note on a method for calculating corrected sums of squares and products",
   Technometrics 4(3), pp. 419–420, 1962 (shifted sums for a stable one-pass variance).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from camgen.errors import ConfigError


class StackStatistics:
    """Per-pixel mean and temporal variance of frames taken at one setting, accumulated frame by frame.

    Shifted sums [2]_: each frame is stored as d = frame − s, with s the first frame (float32), and
    Σd, Σd² are kept in float64, so memory is 20 bytes per pixel whatever the number of frames; for
    integer frames the sums are exact. Each frame's mean per Bayer phase is kept too (EMVA's frame-mean
    correction, see `frame_mean_variance_dn2`).

    Parameters
    ----------
    shape_px : (int, int)
        (H, W) of the frames, px.
    """

    def __init__(self, shape_px: tuple[int, int]):
        height, width = (int(n) for n in shape_px)
        if height < 1 or width < 1:
            raise ConfigError(f"a frame stack needs a shape of at least 1×1 px, got {shape_px}")
        self.shape_px = (height, width)
        self.count = 0
        self.integer_frames = True
        self.maximum_dn = -math.inf
        self._shift = np.zeros(self.shape_px, np.float32)
        self._sum = np.zeros(self.shape_px, np.float64)
        self._sum_sq = np.zeros(self.shape_px, np.float64)
        self._phase_means: list[np.ndarray] = []

    def add(self, frame_dn: np.ndarray) -> None:
        """Add one frame.

        Parameters
        ----------
        frame_dn : (H, W) uint16, other integer, or float array
            Raw values, DN.

        Raises
        ------
        ConfigError
            For a frame of another shape, or one with NaN or infinite values.
        """
        frame = np.asarray(frame_dn)
        if frame.shape != self.shape_px:
            raise ConfigError(
                f"a frame of shape {frame.shape} cannot join a stack of {self.shape_px[0]}×{self.shape_px[1]} "
                "(H×W) frames; keep one sensor mode per folder"
            )
        if frame.dtype.kind == "f":
            if not np.isfinite(frame).all():
                raise ConfigError("a frame holds NaN or infinite values; raw frames must be finite numbers")
            self.integer_frames = self.integer_frames and bool(np.all(frame == np.round(frame)))
        elif frame.dtype.kind not in "ui":
            raise ConfigError(f"frames must be integer or float arrays, got dtype {frame.dtype}")
        if self.count == 0:
            self._shift[...] = frame
        deviation = frame.astype(np.float64)
        deviation -= self._shift
        self._sum += deviation
        deviation *= deviation
        self._sum_sq += deviation
        self.count += 1
        self.maximum_dn = max(self.maximum_dn, float(frame.max()))
        self._phase_means.append(
            np.array([[np.mean(frame[py::2, px::2], dtype=np.float64) for px in (0, 1)] for py in (0, 1)])
        )

    @property
    def mean_dn(self) -> np.ndarray:
        """(H, W) float64: per-pixel mean over the stack, DN."""
        if self.count == 0:
            raise ConfigError("a frame stack without frames has no mean; add frames first")
        return self._shift + self._sum / self.count

    @property
    def temporal_variance_dn2(self) -> np.ndarray:
        """(H, W) float64: per-pixel variance over the stack (ddof = 1), DN².

        With 2 frames A, B this is (A − B)²/2, whose spatial mean is EMVA's frame-difference estimate
        σ²_y = ⟨(y_A − y_B)²⟩/2 before the frame-mean correction; more frames generalise it.
        """
        if self.count < 2:
            raise ConfigError(f"a temporal variance needs at least 2 frames, the stack has {self.count}")
        variance = self._sum_sq - self._sum * self._sum / self.count
        variance /= self.count - 1
        return np.maximum(variance, 0.0, out=variance)

    @property
    def frame_means_dn(self) -> np.ndarray:
        """(count, 2, 2) float64: each frame's spatial mean per Bayer phase (y mod 2, x mod 2), DN."""
        return np.array(self._phase_means).reshape(self.count, 2, 2)

    def frame_mean_variance_dn2(self, phase: tuple[int, int] | None) -> float:
        """Variance (ddof = 1) over the frames of their spatial mean, DN², for one Bayer phase or (None)
        all sites.

        A global offset that changes from frame to frame (black-level drift, light flicker) adds this to
        every pixel's temporal variance; EMVA's σ²_y = ⟨(y_A − y_B − (μ_A − μ_B))²⟩/2 subtracts it
        ((μ_A − μ_B)²/2 for two frames).
        """
        if self.count < 2:
            return 0.0
        means = self.frame_means_dn
        if phase is None:
            height, width = self.shape_px
            counts = np.array(
                [[((height - py + 1) // 2) * ((width - px + 1) // 2) for px in (0, 1)] for py in (0, 1)], float
            )
            series = np.tensordot(means, counts, axes=([1, 2], [0, 1])) / counts.sum()
        else:
            series = means[:, phase[0], phase[1]]
        return float(np.var(series, ddof=1))


@dataclass(frozen=True)
class FrameGroup:
    """Frames of one kind taken at one exposure time and temperature, reduced to their statistics."""

    kind: Literal["dark", "flat"]
    exposure_time_s: float
    temperature_c: float | None
    """Sensor temperature, °C; None when the frames do not record it."""
    stats: StackStatistics
    label: str
    """Names the group in messages and the report (folder, sub-folder or file range)."""
    photons_per_pixel: float | None = None
    """μ_p: mean number of photons reaching a pixel during one exposure of a flat (`photons_per_pixel`
    converts an irradiance); None when not known. Flats with it give the quantum efficiency."""
