"""Timing helper shared by the benchmark scripts."""

import time

import numpy as np


def wall_times(function, repeats):
    """Wall times (s) of ``repeats`` calls of ``function()``."""
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        function()
        times.append(time.perf_counter() - started)
    return np.asarray(times)


def median_time(function, repeats):
    """Median wall time (s) of ``repeats`` calls of ``function()``."""
    return float(np.median(wall_times(function, repeats)))
