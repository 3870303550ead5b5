"""Timing helper shared by the benchmark scripts (not a benchmark itself)."""

from __future__ import annotations

import time

import numpy as np


def best_of(fn, repeat=1, clock=time.perf_counter):
    """``(least seconds of `repeat` calls of fn, fn's last result)``; ``clock`` the timer
    (``time.process_time`` for CPU seconds on a shared machine)."""
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = clock()
        out = fn()
        best = min(best, clock() - t0)
    return best, out
