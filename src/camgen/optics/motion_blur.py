"""Motion blur: the exposure integrated as the mean of sub-frames.

A pixel collects light over the whole exposure; a moving actor (or a panning camera) smears into a
streak as long as its image motion during it. The renderer approximates the integral by the mean of
n sub-frames at evenly spread times in the exposure, centred on the frame time (so the blur is
centred on where annotations place the object). n is chosen so that consecutive sub-frames are at
most `step_px` apart in the image: a box filter of the motion sampled finely enough that the
discrete copies merge into a continuous streak.
"""

from __future__ import annotations

import math

import numpy as np


def sub_frame_count(
    displacement_max_px: float, *, step_px: float = 1.0, samples_max: int = 32, threshold_px: float = 0.5
) -> int:
    """Sub-frames for an exposure whose largest image motion is `displacement_max_px`: 1 (no blur)
    below `threshold_px`, else ⌈displacement / step⌉ between 2 and `samples_max`."""
    if not displacement_max_px > threshold_px:
        return 1
    return min(samples_max, max(2, math.ceil(displacement_max_px / step_px)))


def sub_frame_offsets(count: int) -> np.ndarray:
    """Times of `count` sub-frames as fractions of the exposure, relative to its centre: in (−½, ½)."""
    return (np.arange(count) + 0.5) / count - 0.5
