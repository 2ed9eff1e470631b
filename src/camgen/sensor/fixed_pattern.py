"""Fixed-pattern maps of one physical sensor: PRNU, DSNU, row/column offsets, hot and dead pixels.

The maps are a function of the camera's `serial` alone (DESIGN.md "Randomness"): the same camera keeps
its pattern across frames, sequences and datasets. Each term draws from its own stream
(`SeedSequence(serial, spawn_key=(term,))`), so switching one term on or off leaves the others as
they were. The maps cover the whole sensor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from camgen.config.profile import Noise

_TERM_KEYS = {"prnu": 1, "dsnu": 2, "row": 3, "column": 4, "hot": 5, "dead": 6}


def term_rng(serial: int, term: str) -> np.random.Generator:
    """The generator of one fixed-pattern term of the sensor with this serial."""
    return np.random.default_rng(np.random.SeedSequence(serial, spawn_key=(_TERM_KEYS[term],)))


@dataclass(frozen=True)
class FixedPattern:
    """Per-photosite fixed patterns, (H, W) float32 each; None where the term is off."""

    response: np.ndarray | None
    """Relative photo response 1 + PRNU (0 at dead pixels); None = 1 everywhere."""
    offset_e: np.ndarray | None
    """Dark offset: DSNU + row + column fixed-pattern noise, electrons (zero mean)."""
    dark_current_e_per_s: np.ndarray | None
    """Dark current of each pixel at the profile's reference temperature, e⁻/s (hot pixels stand out);
    None = the profile's `dark_current_e_per_s` everywhere."""
    hot_pixels: int = 0
    dead_pixels: int = 0


def _sites(fraction: float, count: int, rng: np.random.Generator) -> np.ndarray:
    """Indices of round(fraction·count) distinct sites."""
    n = round(fraction * count)
    return rng.choice(count, size=n, replace=False) if n else np.zeros(0, np.int64)


def fixed_pattern(noise: Noise, height_px: int, width_px: int, serial: int) -> FixedPattern:
    """The fixed patterns of the sensor with this `serial`.

    - PRNU: response 1 + N(0, (prnu_pct/100)²) per pixel, clipped at 0.
    - DSNU: offset N(0, dsnu_e²) per pixel; row (column) FPN: N(0, row_fpn_e²) per row (column).
    - Hot pixels: a fraction `hot_pixel_fraction` of the sites, whose dark current is
      `hot_pixel_dark_current_e_per_s` instead of `dark_current_e_per_s` (both at the reference
      temperature, so both double alike).
    - Dead pixels: a fraction `dead_pixel_fraction` of the sites with response 0.
    """
    shape = (height_px, width_px)
    count = height_px * width_px
    response = None
    if noise.prnu_pct > 0:
        response = term_rng(serial, "prnu").standard_normal(shape, dtype=np.float32)
        response *= np.float32(noise.prnu_pct / 100.0)
        response += np.float32(1.0)
        np.maximum(response, 0.0, out=response)
    dead = _sites(noise.dead_pixel_fraction, count, term_rng(serial, "dead"))
    if dead.size:
        if response is None:
            response = np.ones(shape, np.float32)
        response.ravel()[dead] = 0.0
    offset = None
    if noise.dsnu_e > 0:
        offset = term_rng(serial, "dsnu").standard_normal(shape, dtype=np.float32) * np.float32(noise.dsnu_e)
    if noise.row_fpn_e > 0:
        rows = term_rng(serial, "row").standard_normal(height_px, dtype=np.float32) * np.float32(noise.row_fpn_e)
        offset = rows[:, None] + (offset if offset is not None else np.zeros(shape, np.float32))
    if noise.column_fpn_e > 0:
        columns = term_rng(serial, "column").standard_normal(width_px, dtype=np.float32) * np.float32(
            noise.column_fpn_e
        )
        offset = columns[None, :] + (offset if offset is not None else np.zeros(shape, np.float32))
    dark = None
    hot = _sites(noise.hot_pixel_fraction, count, term_rng(serial, "hot"))
    if hot.size:
        dark = np.full(shape, noise.dark_current_e_per_s, np.float32)
        dark.ravel()[hot] = noise.hot_pixel_dark_current_e_per_s
    return FixedPattern(
        response=response,
        offset_e=None if offset is None else offset.astype(np.float32, copy=False),
        dark_current_e_per_s=dark,
        hot_pixels=int(hot.size),
        dead_pixels=int(dead.size),
    )
