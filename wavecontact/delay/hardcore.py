"""The hard-core limit of the delay equation (Eq. 26), solved exactly.

For ``kappa -> inf`` the scaled velocity increase ``w = W / kappa`` obeys the
max-plus recursion

    w(tau) = max(0, max_{s <= tau} [ s - tau_free - sum_i beta_i sum_n w(s - n Gamma_i) ])

(echo weights ``beta_i = 1`` for one material, ``2 Z_s / Z_i`` for two).

For a cold bath ``w`` is continuous and piecewise linear, so it is built
exactly, window by window (a window shorter than ``Gamma_1`` only needs the
past): the bracket is piecewise linear with kinks at shifted kinks of ``w``,
and its running maximum is found between consecutive kinks.  Only round-off
separates the result from the exact one.

When does it end?  Once ``w`` has stopped rising at ``t_e``, every rod's memory ``F_i(s) = sum_n w(s - n Gamma_i)``
is ``w_inf s / Gamma_i`` plus a function of period ``Gamma_i``, and since
``sum_i beta_i / Gamma_i = 1`` the bracket is ``-epsilon s`` plus a bounded
quasi-periodic part.  The ends may meet again (a second contact) only while
``-epsilon s`` plus the largest value of that part can still reach ``w_inf``;
The compiled kernel (:mod:`wavecontact.delay.hardcore_kernels`) checks every
kink up to that time from one period of each memory and resumes the
recursion where the bracket comes back.  The NumPy helpers here serve the
diagnostics :func:`contact_intervals` and :func:`closest_return`.
"""

from __future__ import annotations

import itertools

import numpy as np

from .._jit import prefer_interpreted
from ..errors import InvalidParameterError, SolverFailure
from .hardcore_kernels import STATUS_OK, max_plus_history

__all__ = ["hard_core_history"]

_MERGE = 1e-12  # relative distance below which two kinks are one
_ROUNDOFF = 1e-14  # relative rise of w below which it is round-off of the memory sums
INTERPRETED_WINDOWS = 400.0
"""For a command's first answer, recursions of at most this many windows run interpreted while numba has no
compiled kernel for them (:func:`wavecontact._jit.prefer_interpreted`): one material down to gamma = 0.005,
about 200 windows, takes a few milliseconds of plain Python, against seconds to compile the kernel."""


def _rod_memory(points, knots_t, knots_w, gamma_i):
    """``F_i(s) = sum_{n>=1} w(s - n Gamma_i)`` at ``points``.

    Copies that fall after the last kink count ``w_inf`` each; the few that
    fall among the kinks are interpolated together.
    """
    points = np.asarray(points, dtype=float)
    settled = np.maximum(np.floor((points - knots_t[-1]) / gamma_i), 0.0)
    span = int(np.ceil((knots_t[-1] - knots_t[0]) / gamma_i)) + 1
    shifted = points[:, None] - gamma_i * (settled[:, None] + np.arange(1, span + 1)[None, :])
    partial = np.interp(shifted, knots_t, knots_w, left=0.0, right=knots_w[-1]).sum(axis=1)
    return settled * knots_w[-1] + partial


def _memory(points, knots_t, knots_w, delays, weights):
    return sum(beta_i * _rod_memory(points, knots_t, knots_w, gamma_i) for gamma_i, beta_i in zip(delays, weights))


def _future_bracket(knots_t, knots_w, delays, weights, tau_free, start):
    """The bracket at its kinks from ``start`` on, if ``w`` stays at ``w_inf``.

    Beyond the last kink of ``w`` the bracket is
    ``-epsilon s - tau_free - sum_i beta_i P_i(s)`` with ``P_i(s) = F_i(s) - w_inf s / Gamma_i``
    of period ``Gamma_i``; it is bounded above by ``-epsilon s`` plus the
    periodic parts' largest value, so it stays below ``w_inf`` after a time
    ``s_last``.  Returns the kinks in ``[start, s_last]`` and the bracket there
    (empty if ``start >= s_last``), or ``None`` if ``epsilon <= 0`` (the ends
    must meet again).
    """
    end = knots_t[-1]
    w_inf = knots_w[-1]
    epsilon = w_inf - 1.0
    if epsilon <= 0.0:
        return None
    tables = []
    periodic_min = 0.0
    for gamma_i, beta_i in zip(delays, weights):
        # P_i on one period [end, end + Gamma_i]; its kinks are the kinks of w shifted by round trips
        offsets = np.mod(knots_t - end, gamma_i)
        points = np.unique(np.concatenate([[end, end + gamma_i], end + offsets]))
        periodic = _rod_memory(points, knots_t, knots_w, gamma_i) - w_inf * points / gamma_i
        tables.append((points, periodic))
        periodic_min += beta_i * periodic.min()
    last = (-tau_free - periodic_min - w_inf) / epsilon
    if start >= last:
        return np.zeros(0), np.zeros(0)
    kinks = [[start, last]]
    for gamma_i, (points, _p) in zip(delays, tables):
        first = np.floor((start - end) / gamma_i)
        shifts = end + gamma_i * np.arange(first, np.ceil((last - end) / gamma_i) + 1.0)
        kinks.append((shifts[:, None] + (points - end)[None, :]).ravel())
    kinks = np.unique(np.concatenate(kinks))
    kinks = kinks[(kinks >= start) & (kinks <= last)]
    bracket = -epsilon * kinks - tau_free
    for gamma_i, beta_i, (points, periodic) in zip(delays, weights, tables):
        bracket -= beta_i * np.interp(end + np.mod(kinks - end, gamma_i), points, periodic)
    return kinks, bracket


def closest_return(knots_t, knots_w, delays, weights=(1.0, 1.0), tau_free: float = 0.0):
    """Smallest gap at which the ends come back towards each other after the contact.

    The gap ``w_inf - bracket`` (units ``V mu / Z_s``) after the last kink of a
    finished history, wherever it has shrunk (by more than round-off) since it
    was last largest; ``inf`` if it never shrinks.  A second contact would make
    it zero.
    """
    _kinks, bracket = _future_bracket(np.asarray(knots_t), np.asarray(knots_w), np.asarray(delays, dtype=float),
                                     np.asarray(weights, dtype=float), tau_free, float(knots_t[-1]))
    gap = knots_w[-1] - bracket
    # where the gap has shrunk (beyond round-off) from its largest value so far
    shrunk = np.maximum.accumulate(gap) - gap > _MERGE * max(1.0, abs(knots_w[-1]))
    return float(gap[shrunk].min()) if np.any(shrunk) else np.inf


def _window_kinks(knots_t, delays, start, stop):
    """Kinks of the bracket in ``[start, stop]``: the kinks of ``w`` shifted by whole round trips.

    Kinks closer than round-off (two rods' echoes arriving together) are merged,
    so that ``w`` has no pieces of zero length.
    """
    candidates = [np.array([start, stop])]
    for gamma_i in delays:
        n = np.arange(max(1.0, np.ceil((start - knots_t[-1]) / gamma_i)), np.floor((stop - knots_t[0]) / gamma_i) + 1.0)
        shifted = (knots_t[None, :] + gamma_i * n[:, None]).ravel()
        candidates.append(shifted[(shifted > start) & (shifted < stop)])
    points = np.unique(np.concatenate(candidates))
    distinct = np.diff(points) > _MERGE * max(1.0, abs(stop))
    points = np.concatenate([points[:1], points[1:-1][distinct[:-1]], points[-1:]])
    return points


def hard_core_history(delays, weights=(1.0, 1.0), tau_free: float = 0.0, max_windows: int = 20_000):
    """Exact ``w(tau) = W(tau) / kappa`` of the cold hard-core collision.

    Parameters
    ----------
    delays : sequence of float
        ``(Gamma_1, Gamma_2)``, dimensionless round-trip times.
    weights : sequence of float
        ``(beta_1, beta_2)``, echo weights (1 for one material).
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
    delays = np.ascontiguousarray(delays, dtype=float)
    weights = np.ascontiguousarray(weights, dtype=float)
    window = float(delays.min())
    # the contact lasts until the other rod's echo, or until the force steps R^k (1 - R is the short
    # rod's weight) fall below round-off: that many windows, at most
    short = int(np.argmin(delays))
    needed = min(delays.max() / window, 40.0 / max(weights[short], 1e-300)) + 2.0
    if needed > max_windows:
        raise InvalidParameterError(
            f"the hard-core recursion would need about {needed:.3g} windows (limit max_windows = {max_windows}); "
            "the impedance and transit-time ratios are too extreme: use solver='fem'"
        )
    arguments = (delays, weights, float(tau_free), int(max_windows), _MERGE, _ROUNDOFF)
    # a few windows take milliseconds of plain Python, less than numba's compilation (seconds) or cache load
    run = prefer_interpreted(max_plus_history, arguments, small=needed <= INTERPRETED_WINDOWS)
    knots_t, knots_w, count, status = run(*arguments)
    if status != STATUS_OK:
        raise SolverFailure("hard-core recursion did not settle; raise max_windows")
    return knots_t[:count].copy(), knots_w[:count].copy()


def contact_intervals(knots_t, knots_w, delays, weights=(1.0, 1.0), tau_free: float = 0.0, gap_tolerance=1e-9):
    """The separate contacts of a hard-core history: ``[(start, end), ...]``.

    Between two stretches where ``w`` rises the ends either stay touching
    without force (the bracket stays at ``w``) or separate (the bracket drops
    below ``w``: a gap ``w - bracket`` opens).  Only a gap larger than
    ``gap_tolerance`` (in units of ``V mu / Z_s``, about ``1e-9``: round-off
    makes tiny ones) splits the history into two contacts.
    """
    knots_t = np.asarray(knots_t, dtype=float)
    knots_w = np.asarray(knots_w, dtype=float)
    delays = np.asarray(delays, dtype=float)
    weights = np.asarray(weights, dtype=float)
    rising = np.flatnonzero(np.diff(knots_w) > 0.0)
    if rising.size == 0:
        return []
    intervals = [[knots_t[rising[0]], knots_t[rising[0] + 1]]]
    for previous, current in itertools.pairwise(rising):
        flat_start, flat_end = knots_t[previous + 1], knots_t[current]
        if current > previous + 1 and flat_end > flat_start:
            points = _window_kinks(knots_t, delays, flat_start, flat_end)
            bracket = points - tau_free - _memory(points, knots_t, knots_w, delays, weights)
            if np.max(knots_w[previous + 1] - bracket) > gap_tolerance:
                intervals.append([knots_t[current], knots_t[current + 1]])
                continue
        intervals[-1][1] = knots_t[current + 1]
    return [tuple(map(float, pair)) for pair in intervals]
