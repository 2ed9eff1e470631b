"""The contrast stretch as a camera's 8-bit output shows it: where, and how much, the output clips
(`estimate_tone`), read from the histograms that `camgen.fit.match_statistics` counts. `camgen.fit.match`
adopts what it sees into the fitted profile; the noise level function beside it follows Liu et al. 2006
(`camgen.fit.match_nlf`).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from camgen.fit.match_statistics import _collect

PILE_UP_MIN_FRAC = 2e-4
"""A clip at an output extreme must hold at least this fraction of the samples …"""
PILE_UP_RATIO = 2.0
"""… and this many times the count of the next code inwards …"""
PILE_UP_OUTSIDE_FRAC = 5e-3
"""… with at most this fraction of the samples beyond it (sharpening overshoots past a clip)."""


def _pile_up(counts: np.ndarray, codes: Sequence[int], step: int) -> int | None:
    """The clip code, walking `codes` inwards (by `step`) from an extreme: the first code holding
    ≥ `PILE_UP_MIN_FRAC` of the samples and ≥ `PILE_UP_RATIO` times the next code inwards, while the
    samples beyond it (sharpening overshoots) stay under `PILE_UP_OUTSIDE_FRAC`; None if there is none."""
    total = float(counts.sum())
    beyond = 0.0
    for code in codes:
        here = float(counts[code])
        inner = code + step
        if here >= PILE_UP_MIN_FRAC * total and 0 <= inner < 256 and here >= PILE_UP_RATIO * counts[inner]:
            return code
        beyond += here
        if beyond > PILE_UP_OUTSIDE_FRAC * total:
            return None
    return None


def _tone_from_counts(counts: np.ndarray) -> dict:
    """`estimate_tone` from the (3, 256) histograms of the channels."""
    totals = counts.sum(axis=1)
    cumulative = np.cumsum(counts, axis=1)
    low_codes, high_codes = [], []
    for c in range(3):
        median = int(np.searchsorted(cumulative[c], totals[c] / 2))
        low_codes.append(_pile_up(counts[c], range(0, median), +1))
        high_codes.append(_pile_up(counts[c], range(255, median, -1), -1))
    low = min((code for code in low_codes if code is not None), default=None)
    high = max((code for code in high_codes if code is not None), default=None)
    low_frac = [float(cumulative[c, low] / totals[c]) if low is not None else 0.0 for c in range(3)]
    high_frac = [float(1.0 - cumulative[c, high - 1] / totals[c]) if high is not None else 0.0 for c in range(3)]
    return {
        "clipped_low_frac": low_frac,
        "clipped_high_frac": high_frac,
        "output_low_code": low,
        "output_high_code": high,
        "low_percentile_max": 100.0 * float(np.mean(low_frac)) if low is not None else None,
        "high_percentile_min": 100.0 * (1.0 - float(np.mean(high_frac))) if high is not None else None,
        "output_range_low_frac": low / 255.0 if low is not None else None,
        "output_range_high_frac": high / 255.0 if high is not None else None,
    }


def estimate_tone(frames_rgb8: Iterable[np.ndarray]) -> dict:
    """The contrast stretch as the output shows it: where, and how much, the output clips.

    A stretch maps its low (high) percentile of the linear samples to the bottom (top) of its output
    range, so everything beyond piles up on one code. Walking each channel's histogram in from an
    extreme, the first code holding ≥ `PILE_UP_MIN_FRAC` of the samples and ≥ `PILE_UP_RATIO` times the
    next code inwards is taken as the clip (sharpening overshoots past it, so counts beyond it count as
    clipped).

    The clipped fraction of the output *bounds* the stretch's percentile rather than measuring it: the
    stretch counts linear samples below its limit, and the CCM, demosaicing and sharpening after it
    spread the noise, which sends more output samples over the clip (for `profiles/bullet_4mp_2p8mm.yaml`,
    a 1 % low percentile clips 1.75 % of the output without sharpening or denoise and 2.1 % with them).
    A denoise that averages across the clip hides it (the pile-up smears).

    Parameters
    ----------
    frames_rgb8 : iterable of (H, W, 3) uint8

    Returns
    -------
    dict
        ``clipped_low_frac``, ``clipped_high_frac``: per channel (R, G, B), fraction of the samples at or
        beyond the clip code (0 without a clip); ``output_low_code``, ``output_high_code``: the clip codes
        (None where the output does not pile up); ``low_percentile_max``: the largest low percentile
        consistent with the output (the mean clipped fraction over the channels, ×100, as the stretch
        pools its colours), ``high_percentile_min`` likewise; ``output_range_low_frac``,
        ``output_range_high_frac``: the clip codes over 255. Each is None where no clip is seen.

    Raises
    ------
    ConfigError
        For frames that are not (H, W, 3) uint8, or none.
    """
    statistics = _collect(frames_rgb8, temporal=False, spatial=False, histogram=True)
    return _tone_from_counts(statistics.counts)
