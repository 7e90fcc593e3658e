"""Numerical kernel for the delay equation (Eq. 16), method of steps.

The equation ``W' = exp(g(tau) - W)`` with

    g(tau) = kappa tau - a0 - S(tau) + Q(tau),
    S(tau) = sum_{i=1,2} beta_i sum_{n>=1} W(tau - n Gamma_i)

has the property ``(e^W)' = e^g``, and ``g`` only involves *delayed* values
of ``W``.  As long as a step is shorter than the smallest delay ``Gamma_1``,
``g`` is a known function on the step and

    e^{W(t + h)} = e^{W(t)} + integral_t^{t+h} e^{g(s)} ds

is a plain quadrature: there is nothing implicit and nothing stiff.  The echo
weights ``beta_i`` are 1 for rods of one material (Eq. 16) and ``2 Z_s / Z_i``
for two materials (:mod:`wavecontact.delay.parameters`).  The
integrand grows like ``e^{kappa s}`` during contact, so the quadrature is done
on ``e^{g(s)} = e^{g(t) + a s + r(s)}`` with the secant slope ``a`` taken out
exactly (a change of variable that makes ``e^{a s}`` uniform) and only the
smooth remainder ``e^{r}`` integrated by a Gauss-Kronrod (3, 7) pair.  All of
it is done with logarithms, so nothing overflows although ``g`` and ``W``
reach ``kappa`` times a few (millions for ``kappa = 1e6``).

The history of ``W`` is stored at the step ends together with ``W'`` and
``W''`` (both known in closed form from ``g``), which defines a quintic
Hermite interpolant used for the delayed values.  The step size is
controlled by the Kronrod error estimate and by the distance between the
quintic and the quartic Hermite interpolant of the same step (an estimate of
the interpolation error that later delayed evaluations will see), and a step
is never longer than two stored steps around any delayed time it depends on,
so the sharp features of ``W`` are resolved again wherever they come back
through the memory terms.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel, prefer_interpreted

# Gauss-Kronrod (3, 7) on [0, 1]: Kronrod nodes; the Gauss nodes are 1, 3, 5.
_KRONROD_X = np.array(
    [
        0.960491268708020283423507092629,
        0.774596669241483377035853079956,
        0.434243749346802558002071502844,
        0.0,
        -0.434243749346802558002071502844,
        -0.774596669241483377035853079956,
        -0.960491268708020283423507092629,
    ]
)
KRONROD_NODES = 0.5 * (1.0 + _KRONROD_X)
KRONROD_WEIGHTS = 0.5 * np.array(
    [
        0.104656226026467265193823857192,
        0.268488089868333440728569280667,
        0.401397414775962222905051818618,
        0.450916538658474142345110087045,
        0.401397414775962222905051818618,
        0.268488089868333440728569280667,
        0.104656226026467265193823857192,
    ]
)
GAUSS_WEIGHTS = 0.5 * np.array([0.0, 5.0 / 9.0, 0.0, 8.0 / 9.0, 0.0, 5.0 / 9.0, 0.0])
# Gauss-Lobatto 4 points with its Kronrod extension to 7 (Gander and Gautschi 2000), on [0, 1]; the end
# nodes are the step's ends, where g is known, so a step costs 5 evaluations of g plus its end point
# instead of 7 plus its end point (degree 9 instead of 11; the embedded rule has degree 5 in both)
_LOBATTO_X = np.array([1.0, math.sqrt(2.0 / 3.0), 1.0 / math.sqrt(5.0), 0.0, -1.0 / math.sqrt(5.0),
                       -math.sqrt(2.0 / 3.0), -1.0])
LOBATTO_NODES = 0.5 * (1.0 + _LOBATTO_X)
LOBATTO_KRONROD_WEIGHTS = 0.5 * np.array([11.0 / 210.0, 72.0 / 245.0, 125.0 / 294.0, 16.0 / 35.0, 125.0 / 294.0,
                                          72.0 / 245.0, 11.0 / 210.0])
LOBATTO_WEIGHTS = 0.5 * np.array([1.0 / 6.0, 0.0, 5.0 / 6.0, 0.0, 5.0 / 6.0, 0.0, 1.0 / 6.0])
QUADRATURE_RULES = {
    "gauss-kronrod": (KRONROD_NODES, KRONROD_WEIGHTS, GAUSS_WEIGHTS),
    "lobatto-kronrod": (LOBATTO_NODES, LOBATTO_KRONROD_WEIGHTS, LOBATTO_WEIGHTS),
}

STATUS_OK = 0
STATUS_MAX_STEPS = 1
STATUS_NONFINITE = 2
STATUS_STEP_UNDERFLOW = 3
STATUS_TIME_LIMIT = 4
# internal: the history's buffers are full (integrate_delay_equation doubles them and resumes)
_STATUS_FULL = -1
_FIRST_CAPACITY = 1024  # the history's first buffers (steps)
INTERPRETED_KAPPA_MIN = 5.0
"""A cold collision of one material with ``gamma >= 0.1``, ``kappa`` at least this and ``rtol`` at least
:data:`INTERPRETED_RTOL_MIN` takes at most about a second of plain Python (the slowest corner, gamma = 0.1 and
kappa = 5; the README's ``kappa = 100`` tens of milliseconds): a command's first answer runs it interpreted
while numba has no compiled kernel for it, and compiles it afterwards
(:func:`wavecontact._jit.prefer_interpreted`, ``compile_later``)."""
INTERPRETED_RTOL_MIN = 1e-7
# the integrator's state between two calls (an index into its ``state`` array each); a negative
# last index means a fresh start
_LAST, _STEP, _G_NOW, _T_SIGNIFICANT, _T_ACTIVE, _ERROR_SUM, _REJECTED, _EVALUATIONS = range(8)

# max |H5 - H4| / (h^2 |c1_pred - c1|) on [0, 1]: the quintic basis x^3 (1-x)^2 / 2 at x = 3/5.
_QUARTIC_GAP = 0.01728
# below this |a h| the exponential change of variable is the identity to round-off
_LINEAR_THRESHOLD = 1e-9
# no_later_contact certifies only separations faster than this share of the approach speed
SLOW_SEPARATION = 1e-3


@kernel(internal=True)
def locate(t, last, s):
    """Index ``j`` of the stored step ``[t[j], t[j + 1]]`` that holds ``s`` (binary search)."""
    lo = 0
    hi = last
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if t[mid] <= s:
            lo = mid
        else:
            hi = mid
    return lo


@kernel(inline="always")
def locate_from(t, last, s, lo):
    """:func:`locate` (the same index for ``s >= t[0]``) found by walking from the index ``lo``:
    cheaper when ``s`` moved by a step or two since ``lo`` was found."""
    while lo > 0 and t[lo] > s:
        lo -= 1
    while lo + 1 < last and t[lo + 1] <= s:
        lo += 1
    return lo


@kernel(inline="always")
def hermite5(t, w, d1, d2, last, s):
    """Value, first and second derivative at ``s`` of the quintic Hermite
    interpolant of the history ``(t, w, d1, d2)[:last + 1]``; zero for ``s <= t[0]``."""
    if s <= t[0]:
        return 0.0, 0.0, 0.0
    return hermite5_on(t, w, d1, d2, locate(t, last, s), s)


@kernel(inline="always")
def hermite5_on(t, w, d1, d2, lo, s):
    """:func:`hermite5` on the stored step ``[t[lo], t[lo + 1]]`` (found by the caller).

    Inlined: each copy costs numba about half a second of compilation, but called instead, it made
    cold solves at the default tolerance 15-85 % slower and the energy split 50 % (CPU time, the
    memory sums call it for every delayed copy).
    """
    h = t[lo + 1] - t[lo]
    x = (s - t[lo]) / h
    x = min(x, 1.0)
    x2 = x * x
    x3 = x2 * x
    x4 = x3 * x
    x5 = x4 * x
    y0 = w[lo]
    dy = w[lo + 1] - y0
    a0 = h * d1[lo]
    a1 = h * d1[lo + 1]
    b0 = h * h * d2[lo]
    b1 = h * h * d2[lo + 1]
    h3 = 10.0 * x3 - 15.0 * x4 + 6.0 * x5
    h1 = x - 6.0 * x3 + 8.0 * x4 - 3.0 * x5
    h2 = 0.5 * x2 - 1.5 * x3 + 1.5 * x4 - 0.5 * x5
    h4 = -4.0 * x3 + 7.0 * x4 - 3.0 * x5
    h5 = 0.5 * x3 - x4 + 0.5 * x5
    value = y0 + dy * h3 + a0 * h1 + b0 * h2 + a1 * h4 + b1 * h5
    dh3 = 30.0 * x2 - 60.0 * x3 + 30.0 * x4
    dh1 = 1.0 - 18.0 * x2 + 32.0 * x3 - 15.0 * x4
    dh2 = x - 4.5 * x2 + 6.0 * x3 - 2.5 * x4
    dh4 = -12.0 * x2 + 28.0 * x3 - 15.0 * x4
    dh5 = 1.5 * x2 - 4.0 * x3 + 2.5 * x4
    slope = (dy * dh3 + a0 * dh1 + b0 * dh2 + a1 * dh4 + b1 * dh5) / h
    ch3 = 60.0 * x - 180.0 * x2 + 120.0 * x3
    ch1 = -36.0 * x + 96.0 * x2 - 60.0 * x3
    ch2 = 1.0 - 9.0 * x + 18.0 * x2 - 10.0 * x3
    ch4 = -24.0 * x + 84.0 * x2 - 60.0 * x3
    ch5 = 3.0 * x - 12.0 * x2 + 10.0 * x3
    curvature = (dy * ch3 + a0 * ch1 + b0 * ch2 + a1 * ch4 + b1 * ch5) / (h * h)
    return value, slope, curvature


@kernel(internal=True)
def table_value(s, period, values, slopes):
    """Value and slope at ``s`` of a periodic table (cubic Hermite between its nodes).

    ``values[j]`` and ``slopes[j]`` sample one period ``[0, period)`` at
    ``j period / n``; the table repeats with that period.
    """
    n = values.shape[0]
    x = s / period
    x = (x - math.floor(x)) * n
    j = int(x)
    if j >= n:
        j = n - 1
    f = x - j
    j1 = j + 1
    if j1 == n:
        j1 = 0
    h = period / n
    y0 = values[j]
    y1 = values[j1]
    m0 = h * slopes[j]
    m1 = h * slopes[j1]
    f2 = f * f
    f3 = f2 * f
    value = (2.0 * f3 - 3.0 * f2 + 1.0) * y0 + (f3 - 2.0 * f2 + f) * m0 + (3.0 * f2 - 2.0 * f3) * y1 + (f3 - f2) * m1
    slope = ((6.0 * f2 - 6.0 * f) * (y0 - y1) + (3.0 * f2 - 4.0 * f + 1.0) * m0 + (3.0 * f2 - 2.0 * f) * m1) / h
    return value, slope


@kernel(internal=True)
def _cell_upper(values, slopes, j, h):
    """Upper bound of the cubic Hermite interpolant on cell ``j`` (``|H10|, |H11| <= 4/27``)."""
    j1 = j + 1
    if j1 == values.shape[0]:
        j1 = 0
    return max(values[j], values[j1]) + (4.0 / 27.0) * h * (abs(slopes[j]) + abs(slopes[j1]))


@kernel(internal=True)
def noise_upper_bound(t0, t1, periods, tables, table_slopes, block_max):
    """An upper bound of the tabulated noise (the sum of the rows) on ``[t0, t1]``.

    Each row is bounded on the cells that the interval touches (one more on
    each side against round-off in the cell index), whole blocks at once
    from ``block_max`` (:func:`wavecontact.bath.noise.block_maxima`).
    """
    total = 0.0
    for i in range(periods.shape[0]):
        values = tables[i]
        slopes = table_slopes[i]
        n = values.shape[0]
        blocks = block_max.shape[1]
        size = n // blocks
        h = periods[i] / n
        first = int(t0 / h) - 1  # t0 >= 0
        stop = int(t1 / h) + 2
        if stop - first >= n:
            best = block_max[i, 0]
            for k in range(1, blocks):
                best = max(best, block_max[i, k])
            total += best
            continue
        best = -math.inf
        k = first
        while k < stop:
            j = k % n
            if j % size == 0 and k + size <= stop:
                best = max(best, block_max[i, j // size])
                k += size
            else:
                best = max(best, _cell_upper(values, slopes, j, h))
                k += 1
        total += best
    return total


@kernel(internal=True)
def noise_curvature_bound(t0, t1, periods, tables, curvature_blocks):
    """An upper bound of ``|Q''|`` of the tabulated noise (the sum of the rows) on ``[t0, t1]``.

    Each row's bound is the largest of its per-block curvature bounds
    (:class:`wavecontact.bath.noise.NoiseTables`) over the blocks that the
    interval touches, one cell more on each side against round-off.
    """
    total = 0.0
    blocks = curvature_blocks.shape[1]
    n = tables.shape[1]
    size = n // blocks
    for i in range(periods.shape[0]):
        h = periods[i] / n
        first = int(t0 / h) - 1  # t0 >= 0
        stop = int(t1 / h) + 2
        best = 0.0
        if stop - first >= n:
            for k in range(blocks):
                best = max(best, curvature_blocks[i, k])
        else:
            c = first
            while c < stop:
                j = c % n
                if j < 0:
                    j += n
                best = max(best, curvature_blocks[i, j // size])
                c += size - j % size  # the first cell of the next block
        total += best
    return total


@kernel(internal=True)
def no_later_contact(t0, w_final, kappa, a0, history, last, delays, weights, noise_tables, negligible):
    """True if, with ``W`` held at ``w_final`` from ``t0`` on, ``W'`` stays below ``e^negligible`` for good.

    A certificate for stopping with tabulated noise, where a contact may come back long after the
    last one.  With ``W`` constant, ``S_i(s + Gamma_i) = S_i(s) + W``, so ``u_i = S_i - W s / Gamma_i``
    is ``Gamma_i``-periodic after ``t0``, like rod ``i``'s noise row, and
    ``g - W = drift s - a0 - W + sum_i (Q_i - beta_i u_i)`` with ``drift = kappa - W sum_i beta_i / Gamma_i``.
    Each row's ``Q_i - beta_i u_i`` is bounded over one period block by block (``block_max`` for
    ``Q_i``; ``S_i`` never decreases), which bounds ``g - W`` for every later time once
    ``drift < 0``.  Rows whose period is not their rod's round trip get no certificate, nor do
    rods that separate at less than ``SLOW_SEPARATION`` of the approach speed (``-drift / kappa``
    is epsilon for one material): True, the caller's own rule decides.  ``history`` is ``(t, w, d1, d2)``
    and ``noise_tables`` the tuple of :func:`integrate_delay_equation`.
    """
    t, w, d1, d2 = history
    periods, tables, _slopes, block_max, _curvature, _excursion = noise_tables
    if periods.shape[0] != delays.shape[0]:
        return True
    drift = kappa
    for i in range(delays.shape[0]):
        if abs(periods[i] - delays[i]) > 1e-12 * delays[i]:
            return True
        drift -= w_final * weights[i] / delays[i]
    if drift >= 0.0:
        return False  # the ends still approach on average: the force must come back
    if drift > -SLOW_SEPARATION * kappa:
        return True  # too slow a separation to certify within the time limit: one memory period decides
    bound = drift * t0 - a0 - w_final
    n = tables.shape[1]
    size = n // block_max.shape[1]
    for i in range(delays.shape[0]):
        gamma_i = delays[i]
        beta = weights[i]
        h = periods[i] / n
        best = -math.inf
        c = int(t0 / h)  # t0 >= 0: the cell that holds t0
        while c * h <= t0 + gamma_i + h:
            j = c % n
            stop = c + size - j % size  # first cell of the next block
            start = max(c * h, t0)
            memory = 0.0  # S_i at the block's start (it only grows within the block)
            m = 1
            while start - m * gamma_i > t[0]:
                memory += hermite5(t, w, d1, d2, last, start - m * gamma_i)[0]
                m += 1
            best = max(best, block_max[i, j // size] - beta * memory + beta * w_final * (stop * h) / gamma_i)
            c = stop
        bound += best
    return bound < negligible


@kernel(internal=True)
def span_is_free(t0, span, distance, rate, periods, tables, table_slopes, block_max, q0):
    """True if the force stays negligible on ``[t0, t0 + span]`` (tabulated noise).

    The exponent ``g - W`` of ``W'`` is ``distance`` below the negligible level
    at ``t0``; it rises no faster than ``rate`` (``kappa`` plus the bound of an
    untabulated noise's slope) plus the tabulated noise's rise above its value
    ``q0`` at ``t0`` (bounded by :func:`noise_upper_bound`), because the
    memory terms and ``W`` never decrease.
    """
    if distance <= 0.0 or rate * span >= distance:
        return False
    rise = noise_upper_bound(t0, t0 + span, periods, tables, table_slopes, block_max) - q0
    return rate * span + rise <= distance


@kernel(inline="always")
def noise_value(s, series, noise_tables):
    """``Q(s)`` and ``Q'(s)``: a Fourier series (Eq. 17) plus periodic tables (one row per rod).

    ``series`` (``freq, cos_amp, sin_amp``) or ``noise_tables`` (see :func:`integrate_delay_equation`) None:
    no such term, and numba compiles none of its code.
    """
    q = 0.0
    dq = 0.0
    if series is not None:
        freq, cos_amp, sin_amp = series
        for j in range(freq.shape[0]):
            c = math.cos(freq[j] * s)
            sn = math.sin(freq[j] * s)
            q += cos_amp[j] * c + sin_amp[j] * sn
            dq += freq[j] * (sin_amp[j] * c - cos_amp[j] * sn)
    if noise_tables is not None:
        periods, tables, table_slopes = noise_tables[0], noise_tables[1], noise_tables[2]
        for i in range(periods.shape[0]):
            value, slope = table_value(s, periods[i], tables[i], table_slopes[i])
            q += value
            dq += slope
    return q, dq


@kernel(inline="always")
def memory_sum(t, w, d1, d2, last, s, delays, weights, t_significant, comb, direct_copies):
    """``S(s) = sum_i beta_i sum_n W(s - n Gamma_i)``, ``S'(s)`` and ``S''(s)``.

    Delayed times before ``t_significant`` (where ``W`` is still below
    round-off) are skipped.  With ``direct_copies = K`` (an int; None: every copy on its own) the copies older
    than ``K`` round trips are taken at once from the stored comb sums
    ``C_i(v) = sum_{m>=1} W(v - m Gamma_i)`` (rows ``3i, 3i+1, 3i+2`` of
    ``comb``: value, slope, curvature) as ``C_i(s - K Gamma_i)``.
    """
    total = 0.0
    slope = 0.0
    curvature = 0.0
    for i in range(delays.shape[0]):
        gamma_i = delays[i]
        rod_total = 0.0
        rod_slope = 0.0
        rod_curvature = 0.0
        n = 1
        while True:
            u = s - n * gamma_i
            if u <= t_significant:
                break
            if direct_copies is not None and n > direct_copies:
                value, derivative, second = _comb_sum(t, comb, 3 * i, last, u + gamma_i)
                rod_total += value
                rod_slope += derivative
                rod_curvature += second
                break
            value, derivative, second = hermite5(t, w, d1, d2, last, u)
            rod_total += value
            rod_slope += derivative
            rod_curvature += second
            n += 1
        total += weights[i] * rod_total
        slope += weights[i] * rod_slope
        curvature += weights[i] * rod_curvature
    return total, slope, curvature


@kernel(internal=True)
def _comb_sum(t, comb, row, last, s):
    """``C_i(s)`` and its two derivatives from the comb sums' rows ``row, row + 1, row + 2`` (:func:`hermite5`).

    Called, not inlined, by :func:`memory_sum`: numba inlines before it drops the comb code of a
    specialisation without comb sums, so an inlined copy here cost every cold solve's compilation.
    """
    return hermite5(t, comb[row], comb[row + 1], comb[row + 2], last, s)


@kernel(internal=True)
def comb_values(t, w, d1, d2, last, s, gamma_i, comb, row):
    """``C_i(s) = W(s - Gamma_i) + C_i(s - Gamma_i)`` with its two derivatives."""
    u = s - gamma_i
    wv, ws, wc = hermite5(t, w, d1, d2, last, u)
    cv, cs, cc = hermite5(t, comb[row], comb[row + 1], comb[row + 2], last, u)
    return wv + cv, ws + cs, wc + cc


@kernel(inline="always")
def _series_curvature(s, series):
    """``Q''(s)`` of the Fourier series (Eq. 17)."""
    ddq = 0.0
    if series is not None:
        freq, cos_amp, sin_amp = series
        for j in range(freq.shape[0]):
            ddq -= freq[j] * freq[j] * (cos_amp[j] * math.cos(freq[j] * s) + sin_amp[j] * math.sin(freq[j] * s))
    return ddq


@kernel(internal=True)
def _exponent(point, t, w, d1, d2, last, delays, weights, series, noise_tables, comb, direct_copies):
    """``g(s)``, ``g'(s)`` and (without tables, else NaN) ``g''(s)``; ``point`` is ``(s, kappa, a0,
    t_significant)``, the other arguments those of :func:`integrate_delay_equation`.

    Only scalars are grouped: a tuple holding arrays would count their references at every call
    (measured: cold solves 8 % slower).

    Not inlined: the integrator calls it from two places, and one compiled copy takes seconds less to
    compile than two inlined ones (the derivatives, which only the step's end needs, cost a few additions:
    :func:`hermite5_on` computes them anyway).
    """
    s, kappa, a0, t_significant = point
    memory, memory_slope, memory_curvature = memory_sum(t, w, d1, d2, last, s, delays, weights, t_significant,
                                                        comb, direct_copies)
    q, dq = noise_value(s, series, noise_tables)
    gpp = math.nan
    if noise_tables is None:
        gpp = _series_curvature(s, series) - memory_curvature
    return kappa * s - a0 - memory + q, kappa - memory_slope + dq, gpp


@kernel(inline="always")
def _sturdy_curvature(slope1, g1, gp1, gpp1, w1, drift):
    """``W''`` at the end of a step, from ``W'' = W' (g' - W')`` unless round-off hides it.

    ``W' = e^{g - W}`` carries the round-off of ``g - W`` (numbers up to
    ``kappa`` times a few), so ``g' - W'`` is a difference of two large
    numbers, each uncertain by ``W'`` times that round-off: the exact
    formula is uncertain by ``floor`` below.  Where the contact force is
    quasi-static (a force plateau, ``W'`` following ``g'`` at a relaxation
    rate ``W'``), ``W''`` is ``g''`` to within the much smaller ``(W''/W')'``,
    and ``g''`` (delayed curvatures only) carries no such round-off.  That
    value is taken only where it agrees with the exact formula to within the
    latter's round-off, so ``W''`` never moves by more than its own
    uncertainty; without a ``g''`` (tabulated noise: NaN) the exact formula is kept.
    """
    curvature = slope1 * (gp1 - slope1)
    if not math.isfinite(gpp1):
        return curvature
    unit = 2.220446049250313e-16
    floor = slope1 * (slope1 * 8.0 * unit * (abs(g1) + abs(w1) + abs(drift)) + 8.0 * unit * (abs(gp1) + abs(drift)))
    if abs(gpp1 - curvature) <= floor:
        return gpp1
    return curvature


@kernel(inline="always")
def _logaddexp(x, y):
    if x == -math.inf:
        return y
    if y == -math.inf:
        return x
    if x > y:
        return x + math.log1p(math.exp(y - x))
    return y + math.log1p(math.exp(x - y))


@kernel
def _method_of_steps(kappa, a0, delays, weights, rtol, series, noise_tables, stop, rule, direct_copies, history,
                     state):
    """:func:`integrate_delay_equation` with None for each absent part of the noise and for
    ``direct_copies = 0`` (each combination of present parts compiles on its own, without the others' code).

    ``rule`` ends with a scratch array as long as its nodes (no array is allocated here: numba's
    ``np.empty`` is a compilation of its own), ``history`` is the buffers ``(t, w, d1, d2, comb)`` and
    ``state`` the step's state (indices ``_LAST``...):
    a fresh start if ``state[_LAST] < 0``, else where a call returned ``_STATUS_FULL``, the buffers full, which
    the caller doubles (in Python: the growth compiled here was a third of a second of compilation).
    Returns ``status, error_estimate, rejected, evaluations, last``.
    """
    t_end_min, t_limit, settle_time, max_steps = stop
    nodes, weights_k, weights_g, gx = rule  # gx: scratch, g at the nodes
    if noise_tables is not None:
        periods, tables, table_slopes, block_max, curvature_blocks, noise_excursion = noise_tables
    t, w, d1, d2, comb = history  # comb: column k <= last is read once written; 0 is zero
    capacity = t.shape[0]
    scale = max(kappa, 1e-300)
    tol = rtol * scale * 0.05
    negligible = math.log(max(rtol * 1e-4 * min(scale, 1.0) * scale, 1e-300))
    significant = math.log(1e-18 * scale) if scale > 0 else -700.0
    gamma_min = delays[0]
    for i in range(delays.shape[0]):
        gamma_min = min(gamma_min, delays[i])
    h_max = 0.95 * gamma_min

    if state[_LAST] < 0.0:
        t[0] = 0.0
        w[0] = 0.0
        for row in range(comb.shape[0]):  # a loop, not a slice: each of numba's array helpers compiles apart
            comb[row, 0] = 0.0
        # int64 from the start: a literal 0 would be typed as the value 0 until the loop's increments widen
        # it, and numba compiles every kernel called with it for both types
        last = np.int64(0)
        # g and g' at tau = 0 as _exponent gives them: no delayed copy is back yet, so its memory terms are
        # exactly 0 (written out here rather than a third inlined copy of _exponent, seconds of compilation)
        q_start, dq_start = noise_value(0.0, series, noise_tables)
        g_now = kappa * 0.0 - a0 - 0.0 + q_start
        gp_now = kappa - 0.0 + dq_start
        d1[0] = math.exp(g_now)
        d2[0] = d1[0] * (gp_now - d1[0])
        h = min(h_max, 1.0 / scale)
        t_significant = math.inf
        t_active = -math.inf
        error_sum = 0.0
        rejected = np.int64(0)
        evaluations = np.int64(1)
    else:  # resumed in larger buffers: the state as it was
        last = np.int64(state[_LAST])
        h = state[_STEP]
        g_now = state[_G_NOW]
        t_significant = state[_T_SIGNIFICANT]
        t_active = state[_T_ACTIVE]
        error_sum = state[_ERROR_SUM]
        rejected = np.int64(state[_REJECTED])
        evaluations = np.int64(state[_EVALUATIONS])
    status = STATUS_OK
    series_rate = kappa
    if series is not None:
        freq, cos_amp, sin_amp = series
        for j in range(freq.shape[0]):
            series_rate += abs(freq[j]) * (abs(cos_amp[j]) + abs(sin_amp[j]))
    tabulated = noise_tables is not None

    while True:
        if last + 1 >= capacity:
            status = _STATUS_FULL
            break
        t0 = t[last]
        if last + 1 >= max_steps:
            status = STATUS_MAX_STEPS
            break
        if t0 > t_limit:
            status = STATUS_TIME_LIMIT
            break
        # W' stays below `negligible` for at least h_free: E = g - W rises no faster than kappa + max|Q'|
        h_wanted = h
        if noise_tables is not None:
            # with tables: no faster than kappa plus the local rise of the tabulated noise; the proposed
            # step is free or it is not (a free step is the proposed one in either branch below)
            distance = negligible - (g_now - w[last])
            free = False
            if distance > 0.0 and series_rate * h < distance:  # else span_is_free is False at once
                q0 = 0.0
                for i in range(periods.shape[0]):
                    q0 += table_value(t0, periods[i], tables[i], table_slopes[i])[0]
                free = span_is_free(t0, h, distance, series_rate, periods, tables, table_slopes, block_max, q0)
            h_free = h if free else 0.0
        else:
            h_free = (negligible - (g_now - w[last])) / series_rate
            free = not h_free < h
        # do not stride over more than two stored steps around any delayed time
        if t_significant < math.inf and not free:
            for i in range(delays.shape[0]):
                n = 1
                while True:
                    u = t0 - n * delays[i]
                    if u <= t_significant - h_max or (direct_copies is not None and direct_copies < n - 1):
                        break
                    if u >= 0.0:
                        lo = locate(t, last, u)
                        j = min(lo + 2, last)
                        reach = t[j] - u
                        if reach > 0.0 and j > lo:
                            h = min(h, reach)
                    n += 1
        if not tabulated:
            free = h_free > h
        if free:
            h = min(h_wanted, h_free)
        elif noise_tables is not None and noise_excursion > 0.0:
            curvature = noise_curvature_bound(t0, t0 + h, periods, tables, curvature_blocks)
            if curvature > 0.0:
                h = min(h, math.sqrt(8.0 * noise_excursion / curvature))
        h = min(h, h_max)
        if h < 1e-14 * max(1.0, abs(t0)):
            status = STATUS_STEP_UNDERFLOW
            break

        t1 = t0 + h
        g1, gp1, gpp1 = _exponent((t1, kappa, a0, t_significant), t, w, d1, d2, last, delays, weights, series,
                                  noise_tables, comb, direct_copies)
        a = (g1 - g_now) / h
        # nodes of the transformed rule: e^{a s} ds becomes uniform
        z = a * h
        if z > _LINEAR_THRESHOLD:
            em = math.expm1(-z)
            log_base = g1 + math.log(-em / a)
        elif z < -_LINEAR_THRESHOLD:
            em = math.expm1(z)
            log_base = g_now + math.log(-em / (-a))
        else:
            em = 0.0
            log_base = g_now + math.log(h)
        r_max = -math.inf
        # a free step of tabulated noise: the bounds show W' below e^negligible all along it, so its whole
        # increment (at most h e^negligible) is taken as its error and g only at the ends (the secant)
        for j in range(0 if free and tabulated else nodes.shape[0]):
            x = nodes[j]
            if x == 0.0:  # a node at a step end (Lobatto rules): g is known there
                s = 0.0
                gs = g_now
            elif x == 1.0:
                s = h
                gs = g1
            else:
                if z > _LINEAR_THRESHOLD:
                    s = h + math.log1p((1.0 - x) * em) / a
                elif z < -_LINEAR_THRESHOLD:
                    s = math.log1p(x * em) / a
                else:
                    s = h * x
                gs = _exponent((t0 + s, kappa, a0, t_significant), t, w, d1, d2, last, delays, weights, series,
                               noise_tables, comb, direct_copies)[0]
                evaluations += 1
            if z > _LINEAR_THRESHOLD:
                gx[j] = gs - g1 - a * (s - h)
            elif z < -_LINEAR_THRESHOLD:
                gx[j] = gs - g_now - a * s
            else:
                gx[j] = gs - g_now
            r_max = max(r_max, gx[j])
        evaluations += 1
        secant_only = free and tabulated
        sum_k = 1.0
        sum_g = 1.0
        log_integral = log_base
        if not secant_only:
            sum_k = 0.0
            sum_g = 0.0
            for j in range(nodes.shape[0]):
                e = math.exp(gx[j] - r_max)
                sum_k += weights_k[j] * e
                sum_g += weights_g[j] * e
            log_integral = log_base + r_max + math.log(sum_k)
        w1 = _logaddexp(w[last], log_integral)
        if not math.isfinite(w1) or not math.isfinite(g1):
            status = STATUS_NONFINITE
            break
        if secant_only:
            error_quadrature = h * math.exp(negligible)
        else:
            error_quadrature = math.exp(log_integral - w1) * abs(1.0 - sum_g / sum_k)
        slope1 = math.exp(g1 - w1)
        curvature1 = _sturdy_curvature(slope1, g1, gp1, gpp1, w1, kappa * t1)
        top = 12.0 * (w[last] - w1) + 6.0 * h * (d1[last] + slope1) + h * h * (d2[last] - curvature1)
        error_interpolation = _QUARTIC_GAP * abs(top)
        error = error_quadrature + error_interpolation
        if error > tol and h > 1e-14 * max(1.0, abs(t0)):
            rejected += 1
            h *= max(0.1, 0.8 * (tol / error) ** 0.2)
            continue

        # accept
        if direct_copies is not None:
            for i in range(delays.shape[0]):
                value, slope, curvature = comb_values(t, w, d1, d2, last, t1, delays[i], comb, 3 * i)
                comb[3 * i, last + 1] = value
                comb[3 * i + 1, last + 1] = slope
                comb[3 * i + 2, last + 1] = curvature
        last += 1
        t[last] = t1
        w[last] = w1
        d1[last] = slope1
        d2[last] = curvature1
        g_now = g1
        error_sum += error
        if t_significant == math.inf and (g1 - w1) > significant:
            t_significant = t0
        if (g1 - w1) > negligible:
            t_active = t1
        factor = 4.0 if error == 0.0 else min(4.0, 0.8 * (tol / error) ** 0.2)
        h *= max(0.2, factor)
        # with tabulated noise a contact may come back later than one memory period: stop on a certificate
        settled = t1 >= t_end_min and t_active > -math.inf and t1 - t_active >= settle_time
        if settled and (noise_tables is None or no_later_contact(t1, w1, kappa, a0, (t, w, d1, d2), last, delays,
                                                                weights, noise_tables, negligible)):
            break

    state[_LAST] = last
    state[_STEP] = h
    state[_G_NOW] = g_now
    state[_T_SIGNIFICANT] = t_significant
    state[_T_ACTIVE] = t_active
    state[_ERROR_SUM] = error_sum
    state[_REJECTED] = rejected
    state[_EVALUATIONS] = evaluations
    tail = d1[last] * settle_time
    return status, (error_sum + tail) / scale, rejected, evaluations, last


def integrate_delay_equation(kappa, a0, delays, weights, rtol, series, noise_tables, stop, rule, direct_copies):
    """Integrate Eq. 16 from ``tau = 0`` until ``W`` has settled.

    Parameters
    ----------
    kappa, a0 : float
        ``alpha V l / c`` and the scaled initial gap ``alpha R0``.
    delays : ndarray
        ``(Gamma_1, Gamma_2)``, the round-trip times of the two rods.
    weights : ndarray
        ``(beta_1, beta_2)``, the echo weights ``2 Z_s / Z_i`` (1 for one material).
    rtol : float
        Target absolute accuracy of ``W / kappa`` (hence of epsilon).
    series : tuple of ndarray
        ``(freq, cos_amp, sin_amp)``: Fourier series of the noise ``Q`` (empty arrays for a cold bath).
    noise_tables : tuple
        ``(periods, tables, table_slopes, block_max, curvature_blocks, noise_excursion)``: further noise
        terms as periodic tables, shapes ``(R,)``, ``(R, n)``, ``(R, n)`` (``R = 0``: none; see
        :func:`table_value`); upper bounds of the tables over blocks of cells, ``(R, n / B)``
        (:func:`wavecontact.bath.noise.block_maxima`): with tables, a step is taken as force-free only
        where these bounds show the force negligible all along it (:func:`span_is_free`).  Wherever the
        force may become appreciable, a step is short enough that the tabulated ``Q`` departs from its
        secant by at most ``noise_excursion`` (float) units of the exponent (``max|Q''| h^2 / 8``,
        ``|Q''|`` bounded on the step by the per-block bounds ``curvature_blocks``, shape ``(R, n / C)``;
        :func:`noise_curvature_bound`), so that no narrow rise of the noise slips between the
        quadrature nodes of a step that looked force-free (0: no limit).
    stop : tuple
        ``(t_end_min, t_limit, settle_time, max_steps)``: never stop before ``t_end_min``; give up
        (status 4) past ``t_limit``; stop once ``W'`` has stayed negligible for ``settle_time``; give up
        (status 1) after ``max_steps`` (int) accepted steps.
    rule : tuple of ndarray
        ``(nodes, weights_k, weights_g)``: quadrature rule on [0, 1] (Kronrod nodes, Kronrod and
        embedded weights; one of :data:`QUADRATURE_RULES`).  Nodes at 0 and 1 take ``g`` from the
        step's ends.
    direct_copies : int
        0: every delayed copy of ``W`` is interpolated on its own.  ``K > 0``:
        copies older than ``K`` round trips come from running comb sums, one
        interpolation per rod whatever the number of copies.  Only for smooth
        ``W`` (soft contact), where the comb sums interpolate as well as ``W``.

    Returns
    -------
    t, w, d1, d2 : ndarray
        The accepted grid and ``W, W', W''`` on it.
    status : int
        0 on success.
    error_estimate : float
        Sum of the local error estimates of ``W / kappa`` plus the neglected tail.
    rejected, evaluations : int
        Rejected steps and evaluations of the exponent ``g``.

    Notes
    -----
    The compiled kernel (:func:`_method_of_steps`) takes each absent part (no Fourier series, no
    tables, ``direct_copies = 0``) as None, and numba compiles a separate, smaller specialisation
    for each combination without the code of the absent parts: a cold collision compiles neither
    the noise tables' bounds nor the comb sums.  The arithmetic of what remains is the same.
    Without tables a step is force-free while ``g - W`` stays below the negligible level at the rate
    ``kappa + sum_j |freq_j| (|cos_j| + |sin_j|)``.
    """
    if series[0].shape[0] == 0:
        series = None
    if noise_tables[0].shape[0] == 0:
        noise_tables = None
    direct_copies = direct_copies if direct_copies > 0 else None
    capacity = _FIRST_CAPACITY
    history = (np.empty(capacity), np.empty(capacity), np.empty(capacity), np.empty(capacity),
               np.empty((3 * delays.shape[0], capacity)))
    state = np.full(_EVALUATIONS + 1, -1.0)
    rule = (*rule, np.empty(rule[0].shape[0]))
    small = (series is None and noise_tables is None and kappa >= INTERPRETED_KAPPA_MIN
             and rtol >= INTERPRETED_RTOL_MIN and delays.shape[0] == 2 and min(delays) >= 0.1 * max(delays))
    arguments = (kappa, a0, delays, weights, rtol, series, noise_tables, stop, rule, direct_copies, history, state)
    method_of_steps = prefer_interpreted(_method_of_steps, arguments, small, compile_later=True)
    while True:
        status, error, rejected, evaluations, last = method_of_steps(
            kappa, a0, delays, weights, rtol, series, noise_tables, stop, rule, direct_copies, history, state)
        if status != _STATUS_FULL:
            break
        history = tuple(_doubled(buffer, last + 1) for buffer in history)
    size = last + 1  # views of the buffers, at most twice as long as the history
    return history[0][:size], history[1][:size], history[2][:size], history[3][:size], status, error, rejected, \
        evaluations


def _doubled(buffer, size):
    """A buffer twice as long (last axis) holding the first ``size`` entries of ``buffer``."""
    grown = np.empty(buffer.shape[:-1] + (2 * buffer.shape[-1],))
    grown[..., :size] = buffer[..., :size]
    return grown
