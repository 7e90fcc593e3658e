"""The hard-core limit with thermal noise: the max-plus recursion of Eq. 26 on a grid.

For ``kappa -> inf`` the scaled velocity increase ``w = W / kappa`` obeys

    w(tau) = max(0, max_{s <= tau} f(s)),
    f(s) = s - tau_free - sum_{i} C_i(s) + q_1(s) + q_2(s),
    C_i(s) = sum_{n >= 1} w(s - n Gamma_i),

with ``q_i = Q_i / kappa`` rod ``i``'s noise (independent of ``kappa``).  On a
uniform grid ``t_k = t_0 + k h`` with ``h = Gamma_1 / n_1`` the recursion is

    w_k = max(w_{k-1}, f(t_k), 0),

where rod 1's copies fall on grid points exactly (``C_1`` is a running comb
sum, ``C_1[k] = w[k - n_1] + C_1[k - n_1]``), rod 2's are linear
interpolations of ``w`` and of its own comb sum ``C_2`` at ``k - Gamma_2 / h``,
``q_1`` is read from its FFT table on the same grid and ``q_2`` from its table
by cubic Hermite interpolation.  Each step is O(1), whatever the number of
bath modes or memory copies.

The grid misses maxima of ``f`` between nodes and interpolates ``w`` across
its kinks: the error falls like ``h`` (measured in the tests and
docs/bath.md); :func:`hard_core_noise` states it by a second run at ``h / 2``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._jit import kernel
from .kernels import table_value

__all__ = ["STATUS_MAX_POINTS", "STATUS_OK", "GridRun", "hard_core_noise", "max_plus_recursion", "parabola_peak",
           "run_grid"]

STATUS_OK = 0
STATUS_MAX_POINTS = 1
# rod 2's table: nodes per period of its fastest mode (cubic Hermite: relative error of that
# mode's amplitude ~ (2 pi / 8)^4 / 384 = 1e-3, and that amplitude is 1/nu_max of the first's)
ROD2_TABLE_POINTS = 8


@kernel(inline="always")
def parabola_peak(f_older, f_old, value):
    """Peak of ``f`` between three equally spaced nodes whose middle value is the largest.

    The parabola through the three values finds the maximum that the nodes miss (error
    ``h^3`` instead of ``h^2`` for smooth ``f``); ``-inf`` where the middle value is not a
    peak or a value was not read.
    """
    if f_old > -math.inf and f_older > -math.inf and f_old >= f_older and f_old >= value:
        curvature = f_older - 2.0 * f_old + value
        if curvature < 0.0:
            return f_old - (value - f_older) ** 2 / (8.0 * curvature)
    return -math.inf


@kernel
def max_plus_recursion(h, n1, gamma2, tau_free, t0, q1_table, rod2_table, reach, max_points, w, c1, c2):
    """Run the recursion; returns ``(points, status)``.

    Parameters
    ----------
    h : float
        Grid step (``Gamma_1 / n1``).
    n1 : int
        Grid points per ``Gamma_1`` (rod 1's copies fall on nodes).
    gamma2 : float
        ``Gamma_2``.
    tau_free : float
        Nominal contact time.
    t0 : float
        Time of node 0 (before the earliest possible contact).
    q1_table : ndarray (n1,)
        ``q_1`` at ``t0 + j h`` (one period).
    rod2_table : tuple (float, ndarray, ndarray)
        Rod 2's periodic table ``(period, values, slopes)`` of ``q_2`` and ``q_2'``, origin ``t0``
        (:attr:`GridRun.rod2_table`).
    reach : float
        Upper bound of ``q_1 + q_2`` on the grid (table maxima plus the
        interpolant's overshoot bound).
    max_points : int
        Capacity of ``w``, ``c1``, ``c2``.
    w, c1, c2 : ndarray
        Work arrays (filled with ``w`` and the comb sums).
    """
    q2_period, q2_values, q2_slopes = rod2_table
    d2 = gamma2 / h
    settle = n1 + int(d2) + 2
    running = 0.0
    quiet = 0
    f_older = -math.inf  # f at the two previous nodes (-inf where the noise was not read)
    f_old = -math.inf
    for k in range(max_points):
        t = t0 + k * h
        memory1 = 0.0
        if k >= n1:
            memory1 = w[k - n1] + c1[k - n1]
        c1[k] = memory1
        x = k - d2
        memory2 = 0.0
        if x > 0.0:
            j = int(x)
            f = x - j
            memory2 = (1.0 - f) * (w[j] + c2[j]) + f * (w[j + 1] + c2[j + 1])
        c2[k] = memory2
        bracket = t - tau_free - memory1 - memory2
        value = -math.inf
        if bracket + reach > running:
            # only here can the noise lift f above the running maximum: read it
            q2, _slope = table_value(t - t0, q2_period, q2_values, q2_slopes)
            value = bracket + q1_table[k % n1] + q2
            peak = parabola_peak(f_older, f_old, value)
            if peak > running:
                running = peak
                w[k - 1] = peak
            running = max(running, value)
            quiet = 0
        elif running > 0.0:
            # finished once, for a full memory period, even the largest noise could not have
            # lifted f to w (the memory of the last rise has arrived by then: only it can
            # push the bracket that far below w)
            quiet += 1
            if quiet > settle:
                w[k] = running
                return k + 1, STATUS_OK
        f_older = f_old
        f_old = value
        w[k] = running
    return max_points, STATUS_MAX_POINTS


def _grid_noise(coefficients, gamma, tau_free, t0, n1, points_per_period):
    from ..bath.noise import _harmonic_series, table_points

    (_o1, a1, b1), (_o2, a2, b2) = coefficients
    g1, g2 = 1.0 + gamma, 1.0 + 1.0 / gamma
    q1 = _harmonic_series(a1, b1, g1, t0 - tau_free, n1, slopes=False)[0]
    n2 = table_points(a2.size, points_per_period)
    q2, s2 = _harmonic_series(a2, b2, g2, t0 - tau_free, n2)
    # a cubic Hermite piece exceeds its end values by at most 8/27 h max|slope| < 0.3 h max|slope|
    reach = float(q1.max()) + float(q2.max()) + 0.3 * (g2 / n2) * float(np.abs(s2).max()) if a1.size else 0.0
    return q1, (g2, q2, s2), max(reach, 0.0)


def hard_core_noise(gamma: float, vibrations, tau_free: float, points_per_period: int = 8, min_points: int = 256,
                    max_points: int = 50_000_000):
    """``w = W / kappa`` of one hard-core collision with thermal vibrations.

    Parameters
    ----------
    gamma : float
        Length ratio in (0, 1].
    vibrations : BathRealisation or None
        The rods' vibrations at the nominal contact time (``None``: cold).
    tau_free : float
        Nominal contact time (only shifts the result).
    points_per_period : int
        Grid points per period of rod 1's fastest bath mode (``h = Gamma_1 / n_1``,
        ``n_1 = max(points_per_period nu_max, min_points)``).
    min_points : int
        Least grid points per ``Gamma_1`` (resolves the cold kinks).
    max_points : int
        Refuse a run longer than this many grid points.

    Returns
    -------
    t, w : ndarray
        Grid and ``w`` on it; ``epsilon = w[-1] - 1``.
    """
    grid = run_grid(gamma, vibrations, 0 if vibrations is None else vibrations.modes, tau_free, points_per_period,
                    min_points, max_points)
    return grid.t0 + grid.h * np.arange(grid.count), grid.w[:grid.count]


@dataclass(frozen=True)
class GridRun:
    """One run of :func:`max_plus_recursion`: the grid, the noise read on it and the filled arrays."""

    h: float
    n1: int
    t0: float
    count: int
    w: np.ndarray
    c1: np.ndarray
    c2: np.ndarray
    q1: np.ndarray
    rod2_table: tuple  # (period, values, slopes) of rod 2's Hermite table


def run_grid(gamma: float, vibrations, modes: int, tau_free: float, points_per_period: int, min_points: int,
             max_points: int, what: str = "hard-core recursion") -> GridRun:
    """Tabulate the noise of ``vibrations`` (None: cold) on the grid and run the recursion until it settles.

    ``n_1 = max(points_per_period modes, min_points)`` grid points per ``Gamma_1``; the work
    arrays grow (by 4) up to ``max_points``, beyond which :class:`SolverFailure` names ``what``.
    """
    from ..errors import SolverFailure

    g1, g2 = 1.0 + gamma, 1.0 + 1.0 / gamma
    n1 = max(points_per_period * modes, min_points)
    h = g1 / n1
    if vibrations is None:
        q1, (p2, q2, s2), reach = np.zeros(n1), (g2, np.zeros(1), np.zeros(1)), 0.0
        t0 = tau_free - h
    else:
        # node 0 before the earliest possible contact (the coefficients bound |q|); whole steps
        # from tau_free, so refining the grid keeps its nodes
        coefficients = vibrations.noise_coefficients(1.0)  # q = Q / kappa
        bound = sum(float(np.sum(np.hypot(a, b))) for _o, a, b in coefficients)
        t0 = tau_free - h * (math.ceil(bound / h) + 1)
        q1, (p2, q2, s2), reach = _grid_noise(coefficients, gamma, tau_free, t0, n1, ROD2_TABLE_POINTS)
    capacity = int(min(max_points, max(4 * n1, (2.0 * reach + 8.0 * (g1 + g2)) / h)))
    while True:
        w = np.empty(capacity)
        c1 = np.empty(capacity)
        c2 = np.empty(capacity)
        count, status = max_plus_recursion(h, n1, g2, tau_free, t0, q1, (p2, q2, s2), reach, capacity, w, c1, c2)
        if status == STATUS_OK:
            return GridRun(h, n1, t0, count, w, c1, c2, q1, (p2, q2, s2))
        if capacity >= max_points:
            raise SolverFailure(f"{what} did not settle within {max_points} grid points")
        capacity = min(max_points, 4 * capacity)
