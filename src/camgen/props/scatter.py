"""Where a scatter rule puts its props: every `spacing_m` along a polyline, or `count` of them thrown at
random into a rectangle, no two feet closer than `min_gap_m`; a pure function of the rule (its seed).

Along a polyline the props stand at arc lengths 0, s, 2s, … ≤ the line's length, heading along their leg;
one that comes within `min_gap_m` of an earlier one across a bend is left out. In a region the positions
are drawn by dart throwing (random sequential adsorption: each candidate uniform in the rectangle, kept if
it keeps the gap to every kept one) from the rule's seed, headings uniform unless given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from camgen.config.props import ScatterRule
from camgen.errors import ConfigError

TRIES_PER_PROP = 2000
"""Dart-throwing candidates allowed per prop before the rule is refused."""


@dataclass(frozen=True)
class ScatterSpot:
    position_m: tuple[float, float]
    heading_deg: float
    seed: int
    """The prop's identity seed, drawn from the rule's."""


def _along(rule: ScatterRule) -> list[tuple[np.ndarray, float]]:
    points = np.asarray(rule.along, dtype=np.float64)
    legs = np.diff(points, axis=0)
    lengths = np.linalg.norm(legs, axis=1)
    starts = np.concatenate([[0.0], np.cumsum(lengths)])
    spots, s = [], 0.0
    while s <= starts[-1] + 1e-9:
        leg = min(int(np.searchsorted(starts, s, side="right")) - 1, len(legs) - 1)
        while lengths[leg] == 0 and leg > 0:
            leg -= 1
        t = (s - starts[leg]) / lengths[leg] if lengths[leg] > 0 else 0.0
        heading = math.degrees(math.atan2(legs[leg][1], legs[leg][0]))
        spots.append((points[leg] + t * legs[leg], heading))
        s += rule.spacing_m
    return spots


def scatter_spots(rule: ScatterRule, *, where: str = "scatter") -> list[ScatterSpot]:
    """The props' feet, headings and identity seeds that `rule` places, the same for the same rule.

    `where` names the rule in the error raised when its region cannot hold `count` props `min_gap_m` apart."""
    rng = np.random.default_rng(np.random.SeedSequence(rule.seed))
    kept: list[np.ndarray] = []
    headings: list[float] = []
    gap = rule.min_gap_m
    if rule.along is not None:
        for point, heading in _along(rule):
            if all(np.linalg.norm(point - other) >= gap - 1e-9 for other in kept):
                kept.append(point)
                headings.append(heading if rule.heading_deg is None else rule.heading_deg)
    else:
        (x0, y0), (x1, y1) = rule.region_m
        low = np.array([min(x0, x1), min(y0, y1)])
        high = np.array([max(x0, x1), max(y0, y1)])
        tries = 0
        while len(kept) < rule.count:
            tries += 1
            if tries > TRIES_PER_PROP * rule.count:
                raise ConfigError(
                    f"{where}.count: only {len(kept)} of {rule.count} props {gap:g} m apart fitted in region_m "
                    f"after {tries - 1} random tries; lower count or min_gap_m, or enlarge region_m"
                )
            point = rng.uniform(low, high)
            if kept and np.min(np.linalg.norm(np.asarray(kept) - point, axis=1)) < gap:
                continue
            kept.append(point)
            headings.append(float(rng.uniform(-180.0, 180.0)) if rule.heading_deg is None else rule.heading_deg)
    seeds = rng.integers(0, 2**31, size=len(kept))
    return [
        ScatterSpot((float(p[0]), float(p[1])), float(h), int(s)) for p, h, s in zip(kept, headings, seeds, strict=True)
    ]
