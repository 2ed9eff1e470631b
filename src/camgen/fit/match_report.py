"""The plot of `camgen fit match`: the reference's noise level function against camgen's, per channel."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from camgen.fit.match import MatchFit
from camgen.fit.match_nlf import NoiseLevelFunction
from camgen.io.files import atomic_path

CHANNELS = (("R", "tab:red"), ("G", "tab:green"), ("B", "tab:blue"))
TOLERANCE_FRAC = 0.05
"""The band drawn around zero in the error panels (the acceptance figure of the round-trip test)."""


def _positions(nlf: NoiseLevelFunction, channel: int) -> np.ndarray:
    """Each bin's mean intensity where measured, else its centre, codes."""
    return np.where(np.isfinite(nlf.mean[channel]), nlf.mean[channel], nlf.bin_centres)


def _summary(fit: MatchFit) -> str:
    values = ", ".join(f"{key.rsplit('.', 1)[-1]} {value:.4g}" for key, value in fit.parameters.items())
    light = "" if fit.light_rgb == (1.0, 1.0, 1.0) else " · light R:G:B {:.2f}:{:.2f}:{:.2f}".format(*fit.light_rgb)
    return f"{fit.reference.method} NLF of {fit.reference.frames} reference frames{light}\n{values}"


def write_match_report(fit: MatchFit, path: str | Path) -> None:
    """Write one PNG: per channel, the NLF of the reference and of camgen with the fitted and the base
    profile on the same axes (variance, codes², against mean intensity, codes), and under each the
    relative error of the fitted NLF per bin, %.

    Parameters
    ----------
    fit : MatchFit
    path : str or Path
        The PNG; written under a temporary name and renamed when complete.
    """
    figure = Figure(figsize=(14, 7.5), layout="constrained")
    grid = figure.add_gridspec(2, 3, height_ratios=(2.2, 1))
    reference, fitted, base = fit.reference, fit.fitted, fit.base
    error_pct = 100.0 * fit.relative_error_per_bin
    finite = error_pct[np.isfinite(error_pct)]
    limit = max(10.0, 1.15 * float(np.max(np.abs(finite)))) if finite.size else 10.0
    for c, (name, colour) in enumerate(CHANNELS):
        top = figure.add_subplot(grid[0, c])
        top.plot(_positions(reference, c), reference.variance[c], "o", color="black", ms=4, label="reference")
        top.plot(_positions(fitted, c), fitted.variance[c], "-", color=colour, lw=2, label="camgen, fitted profile")
        top.plot(_positions(base, c), base.variance[c], "--", color="0.55", lw=1.2, label="camgen, base profile")
        top.set_yscale("log")
        top.set_xlim(0, 255)
        top.set_title(f"{name} channel")
        top.set_xlabel("mean intensity, 8-bit codes")
        top.set_ylabel("noise variance, codes²")
        top.grid(True, which="both", alpha=0.3)
        if c == 0:
            top.legend(loc="best", fontsize="small")
        bottom = figure.add_subplot(grid[1, c], sharex=top)
        bottom.axhspan(-100 * TOLERANCE_FRAC, 100 * TOLERANCE_FRAC, color=colour, alpha=0.12, lw=0)
        bottom.axhline(0.0, color="0.3", lw=0.8)
        bottom.plot(_positions(reference, c), error_pct[c], "o-", color=colour, ms=4)
        bottom.set_ylim(-limit, limit)
        bottom.set_xlabel("mean intensity, 8-bit codes")
        bottom.set_ylabel("fitted / reference − 1, %")
        bottom.grid(True, alpha=0.3)
    figure.suptitle(_summary(fit), fontsize="medium")
    with atomic_path(path) as tmp:
        figure.savefig(tmp, dpi=110, format="png")
