"""The plot of `camgen fit match`: the reference's noise level function against camgen's, per channel,
and the verification of the matched profile at its operating point (`camgen.fit.match_verify`): its
noise level function, temporal noise structure and blockiness beside the reference's."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from camgen.fit.match import MatchFit
from camgen.fit.match_nlf import NoiseLevelFunction
from camgen.fit.match_verify import TOLERANCE
from camgen.io.files import atomic_path

CHANNELS = (("R", "tab:red"), ("G", "tab:green"), ("B", "tab:blue"))
TOLERANCE_FRAC = TOLERANCE
"""The band drawn around zero in the error panels: the verification's tolerance."""


def _positions(nlf: NoiseLevelFunction, channel: int) -> np.ndarray:
    """Each bin's mean intensity where measured, else its centre, codes."""
    return np.where(np.isfinite(nlf.mean[channel]), nlf.mean[channel], nlf.bin_centres)


def _summary(fit: MatchFit) -> str:
    values = ", ".join(f"{key.rsplit('.', 1)[-1]} {value:.4g}" for key, value in fit.parameters.items())
    light = "" if fit.light_rgb == (1.0, 1.0, 1.0) else " · light R:G:B {:.2f}:{:.2f}:{:.2f}".format(*fit.light_rgb)
    return f"{fit.reference.method} NLF of {fit.reference.frames} reference frames{light}\n{values}"


def _verification_panels(figure: Figure, grid, fit: MatchFit) -> None:
    """The last row: temporal structure function, blockiness, and the verdict in words."""
    verification = fit.verification
    lags = np.arange(1, verification.structure.size + 1)
    spectrum = figure.add_subplot(grid[2, 0])
    if np.isfinite(verification.reference_structure).any():
        spectrum.plot(lags, verification.reference_structure, "o-", color="black", label="reference")
        spectrum.plot(lags, verification.structure, "s--", color="tab:purple", mfc="none", label="matched profile")
        spectrum.fill_between(
            lags,
            verification.reference_structure * (1 - TOLERANCE),
            verification.reference_structure * (1 + TOLERANCE),
            color="0.5",
            alpha=0.15,
            lw=0,
        )
        spectrum.legend(loc="best", fontsize="small")
    else:
        spectrum.text(0.5, 0.5, "not measured\n(spatial method, or too few frames)", ha="center", va="center")
    spectrum.set_xticks(lags)
    spectrum.set_xlabel("frame lag k")
    spectrum.set_ylabel("temporal structure D_k / D_1")
    spectrum.set_title("temporal noise spectrum (1: independent frames)")
    spectrum.grid(True, alpha=0.3)
    blocks = figure.add_subplot(grid[2, 1])
    values = (verification.reference_blockiness, verification.blockiness)
    if all(np.isfinite(values)):
        blocks.bar(["reference", "matched profile"], values, color=("0.3", "tab:purple"))
        blocks.axhspan(values[0] * (1 - TOLERANCE), values[0] * (1 + TOLERANCE), color="0.5", alpha=0.15, lw=0)
    else:
        blocks.text(0.5, 0.5, "not measured", ha="center", va="center")
    blocks.set_ylabel("block-edge / interior step², noise")
    blocks.set_title("blockiness (1: no 8 × 8 structure)")
    verdict = figure.add_subplot(grid[2, 2])
    verdict.axis("off")
    lines = [
        "reproduces the reference" if verification.reproduces else "does NOT reproduce the reference",
        f"exposure {verification.exposure_time_s:.4g} s at {verification.gain_db:.3g} dB, seed {verification.seed}",
        *verification.summary().split("; "),
    ]
    verdict.text(0, 1, "\n".join(textwrap.fill(line, 60) for line in lines), va="top", fontsize="small")


def write_match_report(fit: MatchFit, path: str | Path) -> None:
    """Write one PNG: per channel, the NLF of the reference and of camgen with the fitted and the base
    profile, and of the matched profile rendered at its operating point with an independent seed (the
    verification), on the same axes (variance, codes², against mean intensity, codes); under each the
    relative error of the fitted and of the verified NLF per bin, %, with the ±15 % band (checked bins
    filled); in a last row the temporal noise structure function D_k/D_1 against the frame lag and the
    blockiness of the reference and of the verification, and the verdict.

    Parameters
    ----------
    fit : MatchFit
    path : str or Path
        The PNG; written under a temporary name and renamed when complete.
    """
    figure = Figure(figsize=(14, 10.5), layout="constrained")
    grid = figure.add_gridspec(3, 3, height_ratios=(2.2, 1, 1.3))
    reference, fitted, base = fit.reference, fit.fitted, fit.base
    verification = fit.verification
    error_pct = 100.0 * fit.relative_error_per_bin
    verified_pct = 100.0 * verification.relative_error_per_bin if verification is not None else None
    both = error_pct if verified_pct is None else np.concatenate([error_pct, verified_pct])
    finite = both[np.isfinite(both)]
    limit = max(10.0, 1.15 * float(np.max(np.abs(finite)))) if finite.size else 10.0
    for c, (name, colour) in enumerate(CHANNELS):
        top = figure.add_subplot(grid[0, c])
        top.plot(_positions(reference, c), reference.variance[c], "o", color="black", ms=4, label="reference")
        top.plot(_positions(fitted, c), fitted.variance[c], "-", color=colour, lw=2, label="camgen, fitted profile")
        top.plot(_positions(base, c), base.variance[c], "--", color="0.55", lw=1.2, label="camgen, base profile")
        if verification is not None:
            top.plot(
                _positions(verification.nlf, c),
                verification.nlf.variance[c],
                "s",
                mfc="none",
                color=colour,
                ms=6,
                label="matched profile at its operating point, new seed",
            )
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
        bottom.plot(_positions(reference, c), error_pct[c], "o-", color=colour, ms=4, label="fit")
        if verification is not None:
            x = _positions(reference, c)
            bottom.plot(x, verified_pct[c], "s--", mfc="none", color=colour, ms=5, label="verification")
            checked = verification.checked[c]
            bottom.plot(x[checked], verified_pct[c][checked], "s", color=colour, ms=5)
            if c == 0:
                bottom.legend(loc="best", fontsize="small")
        bottom.set_ylim(-limit, limit)
        bottom.set_xlabel("mean intensity, 8-bit codes")
        bottom.set_ylabel("camgen / reference − 1, %")
        bottom.grid(True, alpha=0.3)
    if verification is not None:
        _verification_panels(figure, grid, fit)
    figure.suptitle(_summary(fit), fontsize="medium")
    with atomic_path(path) as tmp:
        figure.savefig(tmp, dpi=110, format="png")
