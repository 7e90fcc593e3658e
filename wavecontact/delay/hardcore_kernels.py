"""Compiled kernel of the hard-core max-plus recursion (see :mod:`wavecontact.delay.hardcore`).

``w`` is stored as its kinks ``(kt, kw)[:n]``: zero before ``kt[0]``, linear
between kinks, constant after ``kt[n - 1]``.  Windows of length
``min(Gamma_i)`` are processed in turn; in a window the bracket

    b(s) = s - tau_free - sum_i beta_i sum_{n>=1} w(s - n Gamma_i)

only needs ``w`` before the window, is linear between the shifted kinks of
``w``, and ``w`` follows its running maximum.  After a window without a rise
the future of the bracket is known in closed form if ``w`` stays constant
(``-epsilon s`` plus periodic parts); :func:`_restart_time` checks it up to
the last time it could reach ``w`` again and tells where to resume, if anywhere.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel
from .kernels import locate

STATUS_OK = 0
STATUS_MAX_WINDOWS = 1


@kernel(inline="always")
def _w_at(kt, kw, n, u):
    """``w(u)`` from the kinks ``(kt, kw)[:n]``."""
    if u <= kt[0]:
        return 0.0
    if u >= kt[n - 1]:
        return kw[n - 1]
    lo = locate(kt, n - 1, u)
    return kw[lo] + (u - kt[lo]) * (kw[lo + 1] - kw[lo]) / (kt[lo + 1] - kt[lo])


@kernel
def _rod_sum(kt, kw, n, s, gamma_i):
    """``F_i(s) = sum_{n>=1} w(s - n Gamma_i)``: copies after the last kink count ``w_inf`` each."""
    settled = max(math.floor((s - kt[n - 1]) / gamma_i), 0.0)
    total = settled * kw[n - 1]
    u = s - (settled + 1.0) * gamma_i
    while u > kt[0]:
        total += _w_at(kt, kw, n, u)
        u -= gamma_i
    return total


@kernel(inline="always")
def _bracket(kt, kw, n, s, delays, weights, tau_free):
    total = s - tau_free
    for i in range(delays.shape[0]):
        total -= weights[i] * _rod_sum(kt, kw, n, s, delays[i])
    return total


@kernel
def _grow(array, size):
    if size < array.shape[0]:
        return array
    bigger = np.empty(2 * array.shape[0])
    for j in range(array.shape[0]):  # not a slice assignment: that compiles numba's shape-check message
        bigger[j] = array[j]
    return bigger


@kernel
def _sorted(values, count):
    """``values[:count]`` in ascending order, as a new array (bottom-up merge sort).

    The same array as ``np.sort(values[:count])`` for values without NaN (equal values are
    interchangeable), in a few lines that numba compiles in a tenth of the time of its ``np.sort``.
    """
    a = np.empty(count)
    for k in range(count):
        a[k] = values[k]
    b = np.empty(count)
    width = 1
    while width < count:
        for lo in range(0, count, 2 * width):
            mid = min(lo + width, count)
            hi = min(lo + 2 * width, count)
            i = lo
            j = mid
            for k in range(lo, hi):
                if i < mid and (j >= hi or a[i] <= a[j]):
                    b[k] = a[i]
                    i += 1
                else:
                    b[k] = a[j]
                    j += 1
        a, b = b, a
        width *= 2
    return a


@kernel(inline="always")
def _smallest(values):
    """``values.min()`` of a non-empty 1-D array, without compiling numba's reduction."""
    best = values[0]
    for k in range(1, values.shape[0]):
        best = min(best, values[k])
    return best


@kernel
def _window_points(kt, n, delays, start, stop, merge, buffer):
    """Sorted kinks of the bracket in ``[start, stop]`` (closer than ``merge`` merged) into ``buffer``."""
    count = np.int64(0)  # not the literal 0 or 2: _grow and _sorted would compile for both types
    buffer = _grow(buffer, count + 2)
    buffer[0] = start
    buffer[1] = stop
    count += 2
    for i in range(delays.shape[0]):
        gamma_i = delays[i]
        for j in range(n):
            first = max(1.0, math.ceil((start - kt[j]) / gamma_i))
            last = math.floor((stop - kt[j]) / gamma_i)
            k = first
            while k <= last:
                p = kt[j] + k * gamma_i
                if start < p < stop:
                    buffer = _grow(buffer, count + 1)
                    buffer[count] = p
                    count += 1
                k += 1.0
    points = _sorted(buffer, count)
    tolerance = merge * max(1.0, abs(stop))
    kept = 1
    for j in range(1, count):
        if points[j] - points[kept - 1] > tolerance:
            points[kept] = points[j]
            kept += 1
    points[kept - 1] = stop
    return points[:kept], buffer


@kernel(inline="always")
def _periodic_table(kt, kw, n, gamma_i):
    """``P_i(s) = F_i(s) - w_inf s / Gamma_i`` on one period ``[end, end + Gamma_i]`` at its kinks."""
    end = kt[n - 1]
    points = np.empty(n + 2)
    points[0] = end
    points[1] = end + gamma_i
    for j in range(n):
        points[j + 2] = end + (kt[j] - end) % gamma_i
    points = _sorted(points, n + 2)
    values = np.empty(n + 2)
    for j in range(n + 2):
        values[j] = _rod_sum(kt, kw, n, points[j], gamma_i) - kw[n - 1] * points[j] / gamma_i
    return points, values


@kernel(inline="always")
def _table_value(points, values, s, end, gamma_i):
    u = end + (s - end) % gamma_i
    lo = locate(points, points.shape[0] - 1, u)
    width = points[lo + 1] - points[lo]
    if width <= 0.0:
        return values[lo]
    return values[lo] + (u - points[lo]) * (values[lo + 1] - values[lo]) / width


@kernel
def _restart_time(kt, kw, n, delays, weights, tau_free, start, window, merge):
    """Where to resume the windows, or ``nan`` if the bracket never reaches ``w_inf`` again.

    Valid when nothing rose since ``kt[n - 1]``.  ``epsilon <= 0`` means the
    ends must meet again: resume at ``start``.
    """
    end = kt[n - 1]
    w_inf = kw[n - 1]
    epsilon = w_inf - 1.0
    if epsilon <= 0.0:
        return start
    rods = delays.shape[0]
    # one row per rod (each table has n + 2 points): arrays, not lists, which take numba seconds to compile
    tables_p = np.empty((rods, n + 2))
    tables_v = np.empty((rods, n + 2))
    periodic_min = 0.0
    for i in range(rods):
        points, values = _periodic_table(kt, kw, n, delays[i])
        for j in range(n + 2):
            tables_p[i, j] = points[j]
            tables_v[i, j] = values[j]
        periodic_min += weights[i] * _smallest(values)
    last = (-tau_free - periodic_min - w_inf) / epsilon
    if start >= last:
        return math.nan
    threshold = w_inf + merge * max(1.0, abs(w_inf))
    earliest = math.inf
    for i in range(rods):
        gamma_i = delays[i]
        points = tables_p[i]
        for j in range(points.shape[0]):
            offset = points[j] - end
            k = math.floor((start - end - offset) / gamma_i)
            s = end + offset + k * gamma_i
            while s <= last and s < earliest:
                if s >= start:
                    bracket = -epsilon * s - tau_free
                    for r in range(rods):
                        bracket -= weights[r] * _table_value(tables_p[r], tables_v[r], s, end, delays[r])
                    if bracket > threshold:
                        earliest = s
                s += gamma_i
    if earliest == math.inf:
        return math.nan
    return max(start, earliest - window)


@kernel
def max_plus_history(delays, weights, tau_free, max_windows, merge, roundoff):
    """Kinks ``(kt, kw)[:n]`` of the cold hard-core ``w``, ``n`` and a status (0: settled).

    The kinks are returned in their buffers (longer than ``n``), for the caller to cut: a copy of a
    slice here compiles numba's array copy.

    Parameters
    ----------
    delays, weights : ndarray
        ``(Gamma_1, Gamma_2)`` and ``(beta_1, beta_2)``.
    tau_free : float
        Time at which the ends would meet without interaction.
    max_windows : int
        Give up (status 1) after this many windows of length ``min(delays)``.
    merge : float
        Relative distance below which two kinks are one.
    roundoff : float
        Relative rise of ``w`` below which it is round-off of the memory sums.
    """
    kt = np.empty(64)
    kw = np.empty(64)
    kt[0] = tau_free
    kw[0] = 0.0
    n = np.int64(1)  # not the literal 1: every kernel called with n would compile for both types
    window = _smallest(delays)
    running = 0.0
    last_rise = tau_free
    start = tau_free
    buffer = np.empty(256)
    for _ in range(max_windows):
        stop = start + window
        known = n  # the bracket in this window only needs w before it
        points, buffer = _window_points(kt, known, delays, start, stop, merge, buffer)
        h_a = _bracket(kt, kw, known, points[0], delays, weights, tau_free)
        for j in range(1, points.shape[0]):
            p_a = points[j - 1]
            p_b = points[j]
            h_b = _bracket(kt, kw, known, p_b, delays, weights, tau_free)
            if h_b > running + roundoff * max(1.0, abs(h_b)):
                if h_a < running:
                    p_a = p_a + (running - h_a) * (p_b - p_a) / (h_b - h_a)
                if p_a > kt[n - 1] + merge * max(1.0, abs(p_a)):
                    kt = _grow(kt, n + 1)
                    kw = _grow(kw, n + 1)
                    kt[n] = p_a
                    kw[n] = running
                    n += 1
                kt = _grow(kt, n + 1)
                kw = _grow(kw, n + 1)
                kt[n] = p_b
                kw[n] = h_b
                n += 1
                running = h_b
                last_rise = p_b
            h_a = h_b
        start = stop
        if last_rise < start - window:  # nothing rose in this window: is the contact over?
            again = _restart_time(kt, kw, n, delays, weights, tau_free, start, window, merge)
            if math.isnan(again):
                return kt, kw, n, STATUS_OK
            start = max(start, again)
    return kt, kw, n, STATUS_MAX_WINDOWS
