"""The report's figures (matplotlib, PNG): run time against error, stage shares, cost growth.

Each function draws one figure from measured numbers and writes it atomically; none measures.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from camgen.io.files import atomic_path

DPI = 110


@dataclass(frozen=True)
class TradeoffPoint:
    label: str
    time_ms: float
    error: float
    default: bool = False


def _figure(width_in: float = 6.4, height_in: float = 4.0):
    from matplotlib.figure import Figure  # no pyplot: no global state, no display backend

    figure = Figure(figsize=(width_in, height_in), dpi=DPI, layout="constrained")
    return figure, figure.add_subplot()


def _save(figure, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        figure.savefig(tmp, format="png", metadata={"Software": None})
    return path


def tradeoff_plot(
    path: Path,
    title: str,
    points: Sequence[TradeoffPoint],
    *,
    error_label: str,
    time_label: str = "median time, ms",
    log_time: bool = False,
    log_error: bool = False,
) -> Path:
    """Error against run time, one labelled point per setting, the default ringed."""
    figure, axes = _figure()
    times = [p.time_ms for p in points]
    errors = [p.error for p in points]
    axes.plot(times, errors, "o", color="tab:blue")
    for p in points:
        axes.annotate(p.label, (p.time_ms, p.error), textcoords="offset points", xytext=(5, 4), fontsize=8)
        if p.default:
            axes.plot(p.time_ms, p.error, "o", markersize=14, fillstyle="none", color="tab:red")
    if any(p.default for p in points):
        axes.plot([], [], "o", markersize=10, fillstyle="none", color="tab:red", label="default")
        axes.legend(loc="best", fontsize=8)
    if log_time:
        axes.set_xscale("log")
    if log_error:
        axes.set_yscale("log")
    axes.set_xlabel(time_label)
    axes.set_ylabel(error_label)
    axes.set_title(title, fontsize=10)
    axes.grid(True, alpha=0.3)
    return _save(figure, path)


def stage_bars(
    path: Path,
    title: str,
    rows: Sequence[tuple[str, dict[str, float]]],
    *,
    unit: str = "ms",
    wall: Sequence[float] | None = None,
) -> Path:
    """Horizontal stacked bars: one row per label, one segment per stage (time per frame); `wall`, one per row,
    marks each row's wall time per frame where stages ran in several threads at once (the bar then reaches past
    it)."""
    stages: list[str] = []
    for _, parts in rows:
        stages += [s for s in parts if s not in stages]
    figure, axes = _figure(8.5, 1.2 + 0.3 * len(rows))
    colours = [_colour(i) for i in range(len(stages))]
    left = np.zeros(len(rows))
    y = np.arange(len(rows))[::-1]
    for stage, colour in zip(stages, colours, strict=True):
        widths = np.array([parts.get(stage, 0.0) for _, parts in rows])
        axes.barh(y, widths, left=left, color=colour, label=stage, height=0.7)
        left += widths
    if wall is not None:
        axes.scatter(wall, y, marker="|", s=260, color="black", linewidths=2, label="wall time", zorder=3)
    axes.set_yticks(y, [label for label, _ in rows], fontsize=7)
    axes.set_xlabel(f"{unit} per frame")
    axes.set_title(title, fontsize=10)
    axes.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    axes.grid(True, axis="x", alpha=0.3)
    return _save(figure, path)


def growth_plot(
    path: Path, title: str, series: Sequence[tuple[str, np.ndarray, np.ndarray, float, float]], *, x_label: str
) -> Path:
    """Log-log: time against size for each series (label, x, time ms, exponent, prefactor), with the
    fitted power law t = prefactor · x^exponent drawn through it."""
    figure, axes = _figure()
    for i, (label, x, t, exponent, prefactor) in enumerate(series):
        colour = _colour(i)
        axes.loglog(x, t, "o", color=colour, label=f"{label}: exponent {exponent:.2f}")
        grid = np.geomspace(min(x), max(x), 50)
        axes.loglog(grid, prefactor * grid**exponent, "-", color=colour, alpha=0.6)
    axes.set_xlabel(x_label)
    axes.set_ylabel("ms")
    axes.set_title(title, fontsize=10)
    axes.legend(fontsize=8)
    axes.grid(True, which="both", alpha=0.3)
    return _save(figure, path)


def memory_plot(path: Path, title: str, resident_mb: Sequence[float], warmup: int, slope_kb: float) -> Path:
    """Resident memory after each frame, with the least-squares line over the frames after `warmup`."""
    figure, axes = _figure(6.4, 3.2)
    frames = np.arange(1, len(resident_mb) + 1)
    axes.plot(frames, resident_mb, "-", color=_colour(0), label="resident memory")
    after = frames[warmup:]
    if len(after) > 1:
        intercept = float(np.mean(np.asarray(resident_mb)[warmup:]) - slope_kb / 1e3 * np.mean(after))
        axes.plot(after, intercept + slope_kb / 1e3 * after, "--", color=_colour(1), label=f"{slope_kb:+.1f} kB/frame")
    axes.set_xlabel("frame")
    axes.set_ylabel("MB")
    axes.set_title(title, fontsize=10)
    axes.legend(fontsize=8)
    axes.grid(True, alpha=0.3)
    return _save(figure, path)


def _colour(i: int):
    """Distinct colours for up to 20 series (matplotlib's tab20, dark shades first)."""
    from matplotlib import colormaps

    return colormaps["tab20"]((2 * i) % 20 + (i // 10) % 2)


def threshold_plot(
    path: Path, title: str, levels: np.ndarray, errors: np.ndarray, time_ratios: np.ndarray, *, threshold: float
) -> Path:
    """An approximation's error (left axis) and its time as a fraction of the exact method's (right
    axis) against the level, with the switch-over threshold drawn."""
    figure, axes = _figure()
    axes.semilogx(levels, errors, "o-", color="tab:blue", label="TV distance (left)")
    axes.set_xlabel("expected electrons λ")
    axes.set_ylabel("total-variation distance", color="tab:blue")
    axes.axvline(threshold, color="tab:red", linestyle="--", label=f"default threshold {threshold:g} e⁻")
    right = axes.twinx()
    right.semilogx(levels, time_ratios, "s--", color="tab:green", label="time / exact (right)")
    right.set_ylabel("Gaussian time / Poisson time", color="tab:green")
    right.set_ylim(0, max(float(np.max(time_ratios)) * 1.3, 0.1))
    handles = axes.get_legend_handles_labels()[0] + right.get_legend_handles_labels()[0]
    axes.legend(handles, [h.get_label() for h in handles], fontsize=8, loc="upper right")
    axes.set_title(title, fontsize=10)
    axes.grid(True, alpha=0.3)
    return _save(figure, path)
