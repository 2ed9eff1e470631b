"""Numerical stress suite: property-based tests over the schema's valid ranges (hypothesis).

`stress_settings` scales every property's example count: ``n`` examples under ``make test`` (bounded,
derandomized, so the run is the same every time and cannot flake), ``n × STRESS_FACTOR`` random ones
under ``make stress`` (``CAMGEN_STRESS=1``), which explores new inputs on every run.
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

STRESS = os.environ.get("CAMGEN_STRESS", "") not in ("", "0")
"""True under ``make stress`` (the environment variable ``CAMGEN_STRESS=1``)."""
STRESS_FACTOR = 20
"""How many times more examples each property draws under ``make stress``."""


def stress_settings(max_examples: int, **kwargs) -> settings:
    """Hypothesis settings with `max_examples` scaled for the bounded or the long run.

    No deadline (the 2-core machine's timing varies with other load); bounded runs are derandomized
    and keep no example database, so ``make test`` checks the same inputs every time.
    """
    kwargs.setdefault("suppress_health_check", [HealthCheck.too_slow, HealthCheck.filter_too_much])
    return settings(
        max_examples=max_examples * (STRESS_FACTOR if STRESS else 1),
        deadline=None,
        derandomize=not STRESS,
        database=None if not STRESS else settings.default.database,
        **kwargs,
    )
