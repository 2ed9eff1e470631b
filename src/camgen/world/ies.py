"""Luminaire photometry from IES LM-63 files: the candela table, its symmetries, its flux, and the
regular (γ, C) grid the renderer looks intensities up in.

ANSI/IES LM-63-2002 (and -1995, -1991), "Standard File Format for the Electronic Transfer of Photometric
Data": after the keyword lines and ``TILT=NONE`` come, as whitespace-separated numbers over any lines,
the number of lamps, lumens per lamp (−1: absolute photometry), the candela multiplier, the numbers of
vertical and horizontal angles, the photometric type (1 = C, the type of street and area luminaires),
the units and the luminous opening's size; the ballast factor, a future-use/ballast-lamp factor and the
input watts; the vertical angles, the horizontal angles, and the candela values, one run of vertical
values per horizontal angle. Candela = value × multiplier × ballast factor.

Type C angles: the vertical angle γ from the nadir (0° straight down, 90° horizontal, 180° up) and the
horizontal angle C about the vertical axis, counter-clockwise seen from above; C = 0° lies along the
luminaire's length (along the road for a street lantern; 90° is the street side). Horizontal angles
given over 0° only (rotationally symmetric), 0–90° (symmetric in each quadrant), 0–180° (symmetric about
the C0–C180 plane) or 0–360° (none) are accepted; TILT other than NONE is refused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

GRID_STEP_GAMMA_DEG = 1.0
"""The renderer's table: γ every 1° over 0–180°…"""
GRID_STEP_C_DEG = 5.0
"""…and C every 5° over 0–360° (linear interpolation in both; IES files step 2.5–10° in C)."""


@dataclass(frozen=True)
class Photometry:
    """A luminaire's candela table as the file gives it (type C)."""

    vertical_deg: np.ndarray
    """γ, increasing, within [0, 180]."""
    horizontal_deg: np.ndarray
    """C, increasing, starting at 0 and ending at 0, 90, 180 or 360."""
    candela: np.ndarray
    """(len(horizontal_deg), len(vertical_deg)) intensities, cd (multiplier and ballast factor applied)."""

    def intensity_cd(self, gamma_deg: np.ndarray, c_deg: np.ndarray) -> np.ndarray:
        """I(γ, C), cd: the file's symmetry applied, then bilinear in (C, γ); 0 beyond its γ range."""
        gamma = np.asarray(gamma_deg, dtype=np.float64)
        c = np.mod(np.asarray(c_deg, dtype=np.float64), 360.0)
        last = float(self.horizontal_deg[-1])
        if last == 90.0:
            c = np.mod(c, 180.0)
            c = np.where(c > 90.0, 180.0 - c, c)
        elif last == 180.0:
            c = np.where(c > 180.0, 360.0 - c, c)
        gamma, c = np.broadcast_arrays(gamma, c)
        v = self.vertical_deg
        inside = (gamma >= v[0] - 1e-9) & (gamma <= v[-1] + 1e-9)
        if len(self.horizontal_deg) == 1:
            out = np.interp(gamma, v, self.candela[0])
        else:
            h = self.horizontal_deg
            i = np.clip(np.searchsorted(h, c, side="right") - 1, 0, len(h) - 2)
            t = np.clip((c - h[i]) / (h[i + 1] - h[i]), 0.0, 1.0)
            rows = self.candela
            below = np.array([np.interp(g, v, rows[k]) for g, k in zip(gamma.ravel(), i.ravel(), strict=True)])
            above = np.array([np.interp(g, v, rows[k + 1]) for g, k in zip(gamma.ravel(), i.ravel(), strict=True)])
            out = ((1 - t.ravel()) * below + t.ravel() * above).reshape(gamma.shape)
        return np.where(inside, out, 0.0)


def parse_ies(text: str) -> Photometry:
    """The candela table of an IES LM-63 file's text (module docstring); ValueError naming what is wrong."""
    lines = text.splitlines()
    tilt = next((i for i, line in enumerate(lines) if line.strip().upper().startswith("TILT")), None)
    if tilt is None:
        raise ValueError("no TILT= line: not an IES LM-63 file")
    if lines[tilt].split("=", 1)[1].strip().upper() != "NONE":
        raise ValueError(f"{lines[tilt].strip()!r}: only TILT=NONE is supported (lamp tilt tables are not)")
    try:
        numbers = [float(token) for line in lines[tilt + 1 :] for token in line.replace(",", " ").split()]
    except ValueError as exc:
        raise ValueError(f"a value after TILT=NONE is not a number ({exc})") from None
    if len(numbers) < 13:
        raise ValueError(f"only {len(numbers)} numbers after TILT=NONE; the header alone has 13")
    _, _, multiplier, n_vertical, n_horizontal, kind = numbers[:6]
    ballast_factor = numbers[10]
    n_v, n_h = int(n_vertical), int(n_horizontal)
    if kind != 1:
        raise ValueError(
            f"photometric type {kind:g}: only type C (1), that of street and area luminaires, is supported"
        )
    expected = 13 + n_v + n_h + n_v * n_h
    if n_v < 2 or n_h < 1 or len(numbers) < expected:
        raise ValueError(
            f"{n_v} vertical and {n_h} horizontal angles need {expected} numbers after TILT=NONE, got {len(numbers)}"
        )
    body = np.array(numbers[13:expected])
    vertical, horizontal = body[:n_v], body[n_v : n_v + n_h]
    candela = body[n_v + n_h :].reshape(n_h, n_v) * multiplier * ballast_factor
    if np.any(np.diff(vertical) <= 0) or vertical[0] < 0 or vertical[-1] > 180:
        raise ValueError(f"the vertical angles must increase within 0–180°, got {vertical.tolist()}")
    if n_h > 1 and np.any(np.diff(horizontal) <= 0):
        raise ValueError(f"the horizontal angles must increase, got {horizontal.tolist()}")
    if horizontal[0] != 0 or horizontal[-1] not in (0.0, 90.0, 180.0, 360.0):
        raise ValueError(
            f"horizontal angles {horizontal[0]:g}–{horizontal[-1]:g}°: supported are 0 alone, 0–90, 0–180 or 0–360°"
        )
    if np.any(candela < 0):
        raise ValueError("negative candela values")
    return Photometry(vertical, horizontal, candela)


def grid_angles_deg() -> tuple[np.ndarray, np.ndarray]:
    """(γ (181,), C (72,)) of the renderer's regular table."""
    gamma = np.arange(0.0, 180.0 + 1e-9, GRID_STEP_GAMMA_DEG)
    c = np.arange(0.0, 360.0, GRID_STEP_C_DEG)
    return gamma, c


def intensity_grid_cd(photometry: Photometry) -> np.ndarray:
    """I on the renderer's regular grid, (len(γ), len(C)) cd."""
    gamma, c = grid_angles_deg()
    G, C = np.meshgrid(gamma, c, indexing="ij")
    return photometry.intensity_cd(G, C)


def grid_intensity_cd(grid: np.ndarray, gamma_deg: np.ndarray, c_deg: np.ndarray) -> np.ndarray:
    """Bilinear lookup in the regular grid, as the renderer's texture filter does (C wraps at 360°)."""
    g = np.clip(np.asarray(gamma_deg, dtype=np.float64) / GRID_STEP_GAMMA_DEG, 0, grid.shape[0] - 1)
    c = np.mod(np.asarray(c_deg, dtype=np.float64), 360.0) / GRID_STEP_C_DEG
    g0 = np.minimum(np.floor(g).astype(int), grid.shape[0] - 2)
    c0 = np.floor(c).astype(int) % grid.shape[1]
    c1 = (c0 + 1) % grid.shape[1]
    tg, tc = g - g0, c - np.floor(c)
    return (1 - tg) * ((1 - tc) * grid[g0, c0] + tc * grid[g0, c1]) + tg * (
        (1 - tc) * grid[g0 + 1, c0] + tc * grid[g0 + 1, c1]
    )


def flux_lm(grid: np.ndarray) -> float:
    """Φ = ∫∫ I(γ, C) sin γ dγ dC of a regular grid (trapezoids in γ, the periodic sum in C), lm."""
    gamma, _ = grid_angles_deg()
    weights = np.sin(np.radians(gamma)) * math.radians(GRID_STEP_GAMMA_DEG)
    weights[[0, -1]] *= 0.5
    return float(np.sum(grid * weights[:, None]) * math.radians(GRID_STEP_C_DEG))
