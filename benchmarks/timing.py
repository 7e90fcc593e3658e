"""Timing helper shared by the benchmark scripts."""

import time

import numpy as np


def _times(function, repeats, clock):
    times = []
    for _ in range(repeats):
        started = clock()
        function()
        times.append(clock() - started)
    return np.asarray(times)


def wall_times(function, repeats):
    """Wall times (s) of ``repeats`` calls of ``function()``."""
    return _times(function, repeats, time.perf_counter)


def median_cpu_time(function, repeats):
    """Median CPU time (s) of ``repeats`` calls: the per-core cost, less disturbed by other jobs than wall time."""
    return float(np.median(_times(function, repeats, time.process_time)))


def median_time(function, repeats):
    """Median wall time (s) of ``repeats`` calls of ``function()``."""
    return float(np.median(wall_times(function, repeats)))
