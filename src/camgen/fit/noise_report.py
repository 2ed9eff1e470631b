"""A one-page PNG report of a sensor noise fit (`camgen.fit.noise_result.NoiseFit`).

Panels: the photon transfer curve of each channel (EMVA 1288 4.0: σ²_y − σ²_y.dark against
μ_y − μ_y.dark, the fitted line through the origin, the fit range and the saturation point, when the
flats reach it); the histogram of each channel's averaged dark image (pixels per DN on a log scale, hot
pixels in the logarithmic tail) with the Gaussian the fit predicts; the map of hot and dead pixels; the
table of combined figures with where DSNU and PRNU come from, whether illumination shading was corrected,
and the fit's warnings; and the horizontal and vertical spectrograms of DSNU and PRNU (EMVA 1288 4.0
§8.6) with the DSNU1288 / PRNU1288 level and one frame's temporal noise.

Drawn with matplotlib's object API (`matplotlib.figure.Figure`, no pyplot state) and written through
`camgen.io.files.atomic_path`, so a partial PNG never appears under the final name.
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import FixedLocator, FormatStrFormatter, NullLocator

from camgen.fit.noise_flat import GAIN_FIT_LIMIT
from camgen.fit.noise_result import DarkHistogram, NoiseFit, PhotonTransferCurve
from camgen.fit.noise_spatial import Spectrogram
from camgen.io.files import atomic_path

PANEL_SIZE_IN = (4.0, 3.2)
"""Width and height of one panel, inches."""
DPI = 100
SUMMARY_WRAP_CHARS = 64
"""Notes and warnings in the summary panel are wrapped at this many characters (a 4-inch panel at 6.5 pt)."""


def _photon_transfer_panel(ax: Axes, curve: PhotonTransferCurve) -> None:
    """Variance against mean (both above dark), the gain fit and the saturation point of one channel
    (when the flats do not reach saturation: every point fitted, and a note instead of the point)."""
    x, y, used = curve.mean_above_dark_dn, curve.variance_above_dark_dn2, curve.used_in_gain_fit
    sat = curve.saturation_index
    if sat is not None:
        top = x[sat]
        ax.axvspan(0.0, GAIN_FIT_LIMIT * top, color="0.92", label=f"fit range (≤ {GAIN_FIT_LIMIT:.0%} of sat.)")
    else:
        top = float(np.max(x))
        ax.axvspan(0.0, top, color="0.92", label="fit range (all points: saturation not reached)")
    ax.plot(x[used], y[used], "o", ms=4, color="C0", label="fitted points")
    ax.plot(x[~used], y[~used], "o", ms=4, mfc="none", color="C0", label="other points")
    if sat is not None:
        ax.plot(x[sat], y[sat], "*", ms=12, color="C3", label=f"saturation (variance peak), {x[sat]:.0f} DN")
    if curve.gain_dn_per_e is not None:
        line = np.array([0.0, top])
        ax.plot(line, curve.gain_dn_per_e * line, "-", color="C1", lw=1.2, label=f"K = {curve.gain_dn_per_e:.4g} DN/e⁻")
    ax.set_xlim(left=0.0)
    ax.set_xlabel("μ_y − μ_y.dark (DN)")
    ax.set_ylabel("σ²_y − σ²_y.dark (DN²)")
    ax.set_title(f"photon transfer, {curve.channel}")
    ax.legend(fontsize="x-small", loc="upper left")


def _histogram_panel(ax: Axes, histogram: DarkHistogram) -> None:
    """Pixels per DN of the averaged dark image against DN − mean (linear within ±8σ, logarithmic
    beyond), and the fitted Gaussian N·φ((y − μ)/σ)/σ."""
    edges = histogram.bin_edges_dn - histogram.mean_dn
    widths = np.diff(edges)
    density = histogram.counts / widths
    pixels = int(histogram.counts.sum())
    sigma = histogram.sigma_dn
    ax.stairs(np.where(density > 0, density, np.nan), edges, color="C0", label="averaged dark image")
    grid = np.linspace(-8 * sigma, 8 * sigma, 401)
    model = pixels * np.exp(-0.5 * (grid / sigma) ** 2) / (sigma * math.sqrt(2 * math.pi))
    ax.plot(grid, model, "-", color="C3", lw=1.0, label=f"Gaussian, σ = {sigma:.3g} DN")
    ax.set_xscale("symlog", linthresh=8 * sigma)
    # Linear ticks within ±8σ, decades in the logarithmic tails (hot pixels above, none usually below).
    ticks = [k * sigma for k in (-8, 0, 8)]
    decades = 10.0 ** np.arange(math.ceil(math.log10(16 * sigma)), 10)
    ticks += list(decades[decades <= 1.5 * edges[-1]]) + list(-decades[-decades >= 1.5 * edges[0]])
    ax.xaxis.set_major_locator(FixedLocator(sorted(ticks)))
    ax.xaxis.set_major_formatter(FormatStrFormatter("%.3g"))
    ax.xaxis.set_minor_locator(NullLocator())
    ax.set_yscale("log")
    positive = density[density > 0]
    if positive.size:
        ax.set_ylim(bottom=0.3 * positive.min(), top=3 * max(positive.max(), model.max()))
    ax.set_xlabel(f"y − {histogram.mean_dn:.2f} DN")
    ax.set_ylabel("pixels per DN")
    ax.set_title(f"dark histogram, {histogram.channel}", fontsize="medium")
    ax.legend(fontsize="x-small", loc="upper right", title=histogram.label, title_fontsize="x-small")


def _defect_panel(ax: Axes, fit: NoiseFit) -> None:
    """Positions of the hot and dead pixels on the sensor (one marker each, so single pixels show)."""
    height, width = fit.shape_px
    hot_y, hot_x = np.nonzero(fit.hot_pixel_map)
    dead_y, dead_x = np.nonzero(fit.dead_pixel_map)
    ax.plot(hot_x, hot_y, "s", ms=2.5, color="C3", label=f"hot ({hot_x.size})")
    dead = "dead (not measured: no flats)" if fit.dead_pixel_fraction is None else f"dead ({dead_x.size})"
    ax.plot(dead_x, dead_y, "x", ms=3.0, color="C0", label=dead)
    ax.set_xlim(-0.5, width - 0.5)
    ax.set_ylim(height - 0.5, -0.5)
    ax.set_aspect("equal")
    ax.set_xlabel("x (px)")
    ax.set_ylabel("y (px)")
    ax.set_title("hot and dead pixels")
    ax.legend(fontsize="x-small", loc="upper right", framealpha=0.8)


def _summary_panel(ax: Axes, fit: NoiseFit) -> None:
    """The combined figures and the warnings, as text."""
    ax.axis("off")
    lines = [f"{fit.cfa}, {fit.shape_px[1]}×{fit.shape_px[0]} px, {fit.bit_depth} bit"]
    for name, value, uncertainty, unit in fit.summary_rows():
        spread = f" ± {uncertainty:.2g}" if math.isfinite(uncertainty) and uncertainty > 0 else ""
        lines.append(f"{name[:38]:38s} {value:>11.5g}{spread} {unit}")
    for note in fit.notes:
        lines += textwrap.wrap(f"· {note}", width=SUMMARY_WRAP_CHARS, subsequent_indent="  ")
    for warning in fit.warnings:
        lines += textwrap.wrap(f"! {warning}", width=SUMMARY_WRAP_CHARS, subsequent_indent="  ")
    ax.text(0.0, 1.0, "\n".join(lines), va="top", ha="left", family="monospace", fontsize=6.5, transform=ax.transAxes)


def _spectrogram_panel(ax: Axes, spectrograms: list[Spectrogram]) -> None:
    """Horizontal (solid) and vertical (dashed) spectrograms of one kind, a colour per channel, with the
    non-uniformity (DSNU1288 or PRNU1288) and one frame's temporal noise σ_y.stack as levels."""
    kind, unit = spectrograms[0].kind, spectrograms[0].unit
    for i, s in enumerate(spectrograms):
        colour = f"C{i}"
        ax.plot(s.horizontal_frequency_per_px[1:], s.horizontal[1:], "-", lw=0.8, color=colour, label=s.channel)
        ax.plot(s.vertical_frequency_per_px[1:], s.vertical[1:], "--", lw=0.8, color=colour)
        ax.axhline(s.nonuniformity, color=colour, lw=1.2, alpha=0.6)
        ax.axhline(s.temporal, color=colour, lw=1.0, ls=":", alpha=0.6)
    ax.plot([], [], "k-", lw=0.8, label="horizontal")
    ax.plot([], [], "k--", lw=0.8, label="vertical")
    ax.plot([], [], "k-", lw=1.2, alpha=0.6, label=f"{kind}1288")
    ax.plot([], [], "k:", lw=1.0, alpha=0.6, label="σ_y.stack (one frame)")
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(FormatStrFormatter("%.3g"))
    ax.yaxis.set_minor_formatter(FormatStrFormatter("%.3g"))
    ax.set_xlim(0.0, 0.5)
    ax.set_xlabel("cycles per pixel")
    ax.set_ylabel(f"σ per frequency ({unit})")
    ax.set_title(f"{kind} spectrogram (EMVA 1288 §8.6)")
    ax.legend(fontsize="x-small", loc="upper right", ncol=2)


def noise_report_figure(fit: NoiseFit) -> Figure:
    """The report as a matplotlib `Figure` (not drawn to any screen).

    Parameters
    ----------
    fit : NoiseFit

    Returns
    -------
    matplotlib.figure.Figure
        Four rows of panels: photon transfer per channel (a note when there were no flats), dark
        histogram per channel, the defect map and the summary table, then the DSNU and PRNU spectrograms.
    """
    channels = len(fit.dark_histograms)
    columns = max(channels, 2)
    figure = Figure(figsize=(PANEL_SIZE_IN[0] * columns, PANEL_SIZE_IN[1] * 4.4), layout="constrained")
    grid = figure.add_gridspec(4, columns, height_ratios=(1.0, 1.0, 1.4, 1.0))
    span = 1 if channels > 1 else columns
    if fit.photon_transfer:
        for i, curve in enumerate(fit.photon_transfer):
            _photon_transfer_panel(figure.add_subplot(grid[0, i * span : (i + 1) * span]), curve)
    else:
        ax = figure.add_subplot(grid[0, :])
        ax.axis("off")
        ax.text(0.5, 0.5, "no flats: no photon transfer curve", ha="center", va="center")
    for i, histogram in enumerate(fit.dark_histograms):
        _histogram_panel(figure.add_subplot(grid[1, i * span : (i + 1) * span]), histogram)
    half = columns // 2
    _defect_panel(figure.add_subplot(grid[2, :half]), fit)
    _summary_panel(figure.add_subplot(grid[2, half:]), fit)
    for k, kind in enumerate(("DSNU", "PRNU")):
        spectrograms = [s for s in fit.spectrograms if s.kind == kind]
        ax = figure.add_subplot(grid[3, k * half : (k + 1) * half])
        if spectrograms:
            _spectrogram_panel(ax, spectrograms)
        else:
            ax.axis("off")
            ax.text(0.5, 0.5, f"no flats: no {kind} spectrogram", ha="center", va="center")
    figure.suptitle("sensor noise after EMVA 1288 (release 4.0)")
    return figure


def write_noise_report(fit: NoiseFit, path: Path) -> None:
    """Write the report of `fit` as one PNG at `path` (via a temporary file renamed into place).

    Parameters
    ----------
    fit : NoiseFit
    path : Path
        Output file; its folder is created. Nothing is left under this name if drawing fails.
    """
    figure = noise_report_figure(fit)
    with atomic_path(path) as tmp:
        figure.savefig(tmp, format="png", dpi=DPI)
