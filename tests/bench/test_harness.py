"""The benchmark harness reports medians, quartiles and the worst error correctly."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from camgen.bench.harness import Case, markdown_table, run_case


def fake_clock(durations_s):
    """A clock whose successive start/stop pairs are `durations_s` apart."""
    ticks = itertools.chain.from_iterable((0.0, d) for d in durations_s)
    return lambda: next(ticks)


def test_median_quartiles_and_worst_error():
    errors = iter([0.1, 0.5, 0.2, 0.3, 0.4])
    case = Case(name="c", run=lambda: next(errors), error_unit="px")
    result = run_case(case, repeats=5, warmup=0, clock=fake_clock([0.005, 0.001, 0.003, 0.002, 0.004]))
    assert result.median_ms == pytest.approx(3.0)
    assert (result.q1_ms, result.q3_ms) == (pytest.approx(2.0), pytest.approx(4.0))
    assert result.min_ms == pytest.approx(1.0)
    assert result.error == 0.5
    assert "0.5 px" in markdown_table([result])


def test_warmup_runs_are_not_timed():
    calls = []
    case = Case(name="c", run=lambda: calls.append(1))
    result = run_case(case, repeats=2, warmup=3, clock=fake_clock([0.001, 0.001]))
    assert len(calls) == 5 and result.repeats == 2 and result.error is None


def test_repeats_must_be_positive():
    with pytest.raises(ValueError, match="repeats must be ≥ 1"):
        run_case(Case(name="c", run=lambda: None), repeats=0)


def test_case_repeats_override_and_baseline_ratio():
    calls = []
    slow = Case(name="slow", run=lambda: calls.append(1), repeats=2)
    result = run_case(slow, repeats=7, warmup=0, clock=fake_clock([0.004, 0.004]))
    assert result.repeats == 2 and len(calls) == 2
    fast = run_case(
        Case(name="fast", run=lambda: None, baseline="slow"), repeats=1, warmup=0, clock=fake_clock([0.001])
    )
    table = markdown_table([result, fast])
    assert "| 0.25 |" in table.splitlines()[-1]


def test_power_law_fit_recovers_a_known_exponent_and_its_uncertainty():
    from camgen.bench.harness import power_law_fit

    x = np.array([1.0, 2, 4, 8, 16, 32])
    exact = power_law_fit(x, 3.0 * x**1.5)
    assert exact.exponent == pytest.approx(1.5, abs=1e-12) and exact.prefactor == pytest.approx(3.0)
    assert exact.exponent_stderr == pytest.approx(0.0, abs=1e-12)
    # Scatter of ±10 % about t = 2 x^0.8: the exponent within a few standard errors, which are > 0.
    rng = np.random.default_rng(1)
    noisy = power_law_fit(x, 2.0 * x**0.8 * np.exp(rng.normal(0, 0.1, x.size)))
    assert noisy.exponent_stderr > 0
    assert abs(noisy.exponent - 0.8) < 4 * noisy.exponent_stderr
    with pytest.raises(ValueError, match="≥ 2 positive points"):
        power_law_fit([1.0, 0.0], [1.0, 2.0])
