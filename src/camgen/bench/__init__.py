"""Benchmarks: run time (and, where a reference exists, error) of named cases, written to BENCHMARKS.md."""

from camgen.bench.harness import Case, Result, run_case

__all__ = ["Case", "Result", "run_case"]
