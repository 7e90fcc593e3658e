"""The hard-core limit of the delay equation (Eq. 26), solved exactly.

For ``kappa -> inf`` the scaled velocity increase ``w = W / kappa`` obeys the
max-plus recursion

    w(tau) = max(0, max_{s <= tau} [ s - tau_free - sum_{i,n} w(s - n Gamma_i) ]).

For a cold bath ``w`` is continuous and piecewise linear, so it is built
exactly, window by window (a window shorter than ``Gamma_1`` only needs the
past): the bracket is piecewise linear with kinks at shifted kinks of ``w``,
and its running maximum is found between consecutive kinks.  Only round-off
separates the result from the exact one.
"""

from __future__ import annotations

import numpy as np

from ..errors import SolverFailure

__all__ = ["hard_core_history"]


def _memory(points, knots_t, knots_w, delays):
    total = np.zeros_like(points)
    for gamma_i in delays:
        n = 1
        while True:
            shifted = points - n * gamma_i
            if np.all(shifted <= 0.0):
                break
            total += np.interp(shifted, knots_t, knots_w, left=0.0, right=knots_w[-1])
            n += 1
    return total


def hard_core_history(delays, tau_free: float = 0.0, max_windows: int = 10_000):
    """Exact ``w(tau) = W(tau) / kappa`` of the cold hard-core collision.

    Parameters
    ----------
    delays : sequence of float
        ``(Gamma_1, Gamma_2)``, dimensionless round-trip times.
    tau_free : float
        Time at which the ends would meet without interaction.
    max_windows : int
        Safety limit on the number of windows of length ``min(delays)``.

    Returns
    -------
    knots_t, knots_w : ndarray
        Kinks of the piecewise-linear ``w`` (``w = 0`` before the first one,
        constant after the last).  ``epsilon = w(inf) - 1``.
    """
    delays = np.asarray(delays, dtype=float)
    window = float(delays.min())
    settle = float(delays.sum())
    knots_t = [tau_free]
    knots_w = [0.0]
    running_max = 0.0
    last_rise = tau_free
    start = tau_free
    for _ in range(max_windows):
        stop = start + window
        kt = np.asarray(knots_t)
        kw = np.asarray(knots_w)
        candidates = [start, stop]
        for gamma_i in delays:
            for n in range(1, int((stop - tau_free) // gamma_i) + 2):
                shifted = kt + n * gamma_i
                candidates.extend(shifted[(shifted > start) & (shifted < stop)])
        points = np.unique(np.asarray(candidates))
        bracket = points - tau_free - _memory(points, kt, kw, delays)
        for p_a, p_b, h_a, h_b in zip(points[:-1], points[1:], bracket[:-1], bracket[1:]):
            if h_b <= running_max:
                continue
            if h_a < running_max:
                p_a = p_a + (running_max - h_a) * (p_b - p_a) / (h_b - h_a)
            if p_a > knots_t[-1]:
                knots_t.append(p_a)
                knots_w.append(running_max)
            knots_t.append(p_b)
            knots_w.append(h_b)
            running_max = h_b
            last_rise = p_b
        start = stop
        if start - last_rise > settle:
            return np.asarray(knots_t), np.asarray(knots_w)
    raise SolverFailure("hard-core recursion did not settle; raise max_windows")
