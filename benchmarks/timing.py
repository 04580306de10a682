"""Timing shared by the benchmarks."""

from __future__ import annotations

import time


def best_of(repeats: int, job):
    """(result, fastest wall ms) of `repeats` runs of ``job()``: a shared VM's timings
    wander by 15 %, and the fastest run is the one least disturbed."""
    best, result = float("inf"), None
    for _ in range(repeats):
        start = time.perf_counter()
        result = job()
        best = min(best, (time.perf_counter() - start) * 1e3)
    return result, best
