"""Time a named case over repeats; report the median and spread, and its error where it has one."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Case:
    """A benchmark case. `run` does the work once and returns its error against a reference, or None."""

    name: str
    run: Callable[[], float | None]
    setup: Callable[[], None] | None = None
    error_unit: str = ""
    repeats: int | None = None
    """Timed runs for this case (slow cases use fewer); None uses the harness's number."""
    baseline: str | None = None
    """Name of the case this one is compared with: the table gives the ratio of medians (same run)."""
    warmup: int | None = None
    """Untimed runs first; None uses the harness's number."""


@dataclass(frozen=True)
class Result:
    name: str
    repeats: int
    median_ms: float
    q1_ms: float
    q3_ms: float
    min_ms: float
    error: float | None
    error_unit: str
    baseline: str | None = None


def relative_rms_pct(image: np.ndarray, reference: np.ndarray) -> float:
    """RMS of image − reference as a percentage of the reference's mean (the cases' image error)."""
    return float(100 * np.sqrt(np.mean((image - reference) ** 2)) / np.mean(reference))


def run_case(case: Case, repeats: int = 7, warmup: int = 1, clock=time.perf_counter) -> Result:
    """Run `warmup` untimed and `repeats` timed calls; the error is the largest one seen."""
    repeats = case.repeats or repeats
    warmup = warmup if case.warmup is None else case.warmup
    if repeats < 1:
        raise ValueError(f"repeats must be ≥ 1, got {repeats}")
    if case.setup:
        case.setup()
    for _ in range(warmup):
        case.run()
    times_ms, errors = [], []
    for _ in range(repeats):
        start = clock()
        error = case.run()
        times_ms.append((clock() - start) * 1e3)
        if error is not None:
            errors.append(error)
    quartiles = statistics.quantiles(times_ms, n=4, method="inclusive") if repeats > 1 else times_ms * 3
    return Result(
        name=case.name,
        repeats=repeats,
        median_ms=statistics.median(times_ms),
        q1_ms=quartiles[0],
        q3_ms=quartiles[2],
        min_ms=min(times_ms),
        error=max(errors) if errors else None,
        error_unit=case.error_unit,
        baseline=case.baseline,
    )


def markdown_table(results: list[Result]) -> str:
    """One row per result; `× baseline` is its median over its baseline's median from the same run."""
    medians = {r.name: r.median_ms for r in results}
    lines = [
        "| case | median ms | IQR ms | min ms | repeats | max error | × baseline |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in results:
        error = f"{r.error:.3g} {r.error_unit}" if r.error is not None else "—"
        ratio = f"{r.median_ms / medians[r.baseline]:.3g}" if r.baseline in medians else "—"
        lines.append(
            f"| {r.name} | {r.median_ms:.2f} | {r.q1_ms:.2f}–{r.q3_ms:.2f} | {r.min_ms:.2f} | {r.repeats} | {error} "
            f"| {ratio} |"
        )
    return "\n".join(lines)


@dataclass(frozen=True)
class PowerLaw:
    """t = prefactor · x^exponent, fitted in log-log by least squares."""

    exponent: float
    prefactor: float
    exponent_stderr: float
    """Standard error of the exponent from the fit's residuals (nan with two points)."""


def power_law_fit(x, t) -> PowerLaw:
    """Fit t = a·x^b through (x, t) > 0 by linear least squares on (ln x, ln t)."""
    x, t = np.asarray(x, np.float64), np.asarray(t, np.float64)
    if x.size < 2 or np.any(x <= 0) or np.any(t <= 0):
        raise ValueError(f"a power law needs ≥ 2 positive points, got x={x.tolist()}, t={t.tolist()}")
    lx, lt = np.log(x), np.log(t)
    (b, ln_a), residuals, *_ = np.polyfit(lx, lt, 1, full=True)
    n = x.size
    if n > 2:
        sigma2 = float(residuals[0]) / (n - 2) if residuals.size else 0.0
        stderr = float(np.sqrt(sigma2 / np.sum((lx - lx.mean()) ** 2)))
    else:
        stderr = float("nan")
    return PowerLaw(exponent=float(b), prefactor=float(np.exp(ln_a)), exponent_stderr=stderr)
