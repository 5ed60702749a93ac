"""The benchmarks' cycle counter (benchmarks/cycle_counter.py) counts: inside compiled code it never
goes back, and a thousand times the work reads many times the cycles."""

from __future__ import annotations

import importlib.util
import pathlib

import pytest
from numba import njit

_PATH = pathlib.Path(__file__).resolve().parents[1] / "benchmarks" / "cycle_counter.py"


def _cycles():
    spec = importlib.util.spec_from_file_location("cycle_counter_under_test", _PATH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.cycles


def test_the_cycle_counter_grows_with_the_work():
    cycles = _cycles()

    @njit
    def timed(n):
        t0 = cycles()
        s = 0.0
        for k in range(n):
            s += (k % 7) * 0.5
        t1 = cycles()
        return t0, t1, s

    t0, t1, _ = timed(10)
    if t0 == 0 and t1 == 0:
        pytest.skip("this CPU has no cycle counter for LLVM to read")
    small = min(b - a for a, b, _ in (timed(1_000) for _ in range(5)))
    large = min(b - a for a, b, _ in (timed(1_000_000) for _ in range(5)))
    assert 0 <= small and t1 >= t0
    assert large > 50 * max(small, 1), (small, large)
