"""The stochastic hard-core mode for many samples at once (Eq. 26 on a grid, batched).

The same recursion as :mod:`wavecontact.delay.stochastic_hardcore`,

    w_k = max(w_{k-1}, f(t_k), 0),   f(t) = t - tau_free - C_1(t) - C_2(t) + q_1(t) + q_2(t),

organised for blocks of samples, with no Python work per grid node or per table entry:

* the bath of sample ``j`` is ``standard_normal((2, 2, nu_max))`` from
  ``numpy.random.default_rng(seed_j)``, the same numbers as
  :meth:`wavecontact.bath.ThermalBath.draw`, so a sample here is the same
  realisation that drives the other solvers; :mod:`wavecontact.bath.streams`
  draws them without a ``SeedSequence`` and ``Generator`` object per sample;
* the noise tables of the whole block come from one 2-D inverse real FFT per
  table; the time origin is the nominal contact time (node ``k`` sits at
  ``(k - m) h``), so no phase factors are needed, and every operation on the
  block is elementwise or a per-row maximum: a row's numbers do not depend on
  the other rows (tested bit for bit against batch size 1);
* one compiled kernel runs the recursion of every sample.  ``A_i = w + C_i``
  is kept instead of ``w`` and ``C_i``: rod 1's memory is ``A_1[k - n_1]``,
  rod 2's a fixed linear interpolation between ``A_2[k - j_2 - 1]`` and
  ``A_2[k - j_2]`` (``Gamma_2 / h = j_2 + f_2``);
* rod 2's noise (a cubic Hermite table) is read only at nodes where
  ``t - C_1 - C_2 + q_1`` plus an upper bound of the table on the node's cell
  can reach ``w`` (and at the node after such a node, for the parabola);
  stretches where a bound over blocks of cells rules out any rise are stepped
  as chunks in a vectorised loop that only stores ``A_i = w + C_i``.

The run stops on a certificate, not on a waiting time.  Once ``w = W`` has
stayed constant since node ``L``, the comb sums obey ``C_1[k + n_1] = C_1[k] + W``
exactly and ``C_2`` is a convex combination of its values one rod-2 period
earlier plus ``W``.  So ``u_i = C_i - W (k - L) h / Gamma_i`` is periodic
(rod 1) or stays within its range over the first rod-2 period (rod 2), and
because ``1/Gamma_1 + 1/Gamma_2 = 1``, for every later node

    f_k <= (L - m) h - (W - 1)(k - L) h + max(q_1 - u_1) - min(u_2) + max q_2.

The kernel steps on until this bound is at most ``W`` for all later nodes
(the bound falls like ``(W - 1)`` per unit time), so no later contact of the
grid recursion is cut off.  The parabolic peak correction between nodes is
not part of the bound (it changes ``w`` by the grid's own error).

Error: first order in ``h``.  ``benchmarks/bench_bath.py`` states the mean error
against a four times finer grid; ``docs/bath_studies.py`` reruns its ensembles at
twice the step and extrapolates.
"""

from __future__ import annotations

import math
import threading
from typing import NamedTuple

import numpy as np

from .._jit import kernel
from ..errors import InvalidParameterError, SolverFailure, require_integer
from .stochastic_hardcore import parabola_peak

__all__ = ["DEFAULT_POINTS_PER_PERIOD", "GridSteps", "HardCoreGrid", "SampleTables", "cached_grid", "hard_core_restitution",
           "hard_core_restitutions", "max_plus_batch"]

DEFAULT_POINTS_PER_PERIOD = 8
_TRANSLATIONAL_ENERGY = 0.25  # E_tr in the paper's units (mu = 1/2, V = 1)
CELLS_PER_BLOCK = 32  # rod 2's table cells per block bound (a power of two)
CHUNK = 64  # grid nodes stepped at once where the noise cannot lift f above w
BLOCK = 32  # samples whose tables are made together (about 1.5 MB at nu_max = 250)
STATUS_OK = 0
STATUS_FULL = 1


class GridSteps(NamedTuple):
    """The constants of one grid that the recursion kernels read (:class:`HardCoreGrid` makes them)."""

    h: float  # grid step (time, in l / c)
    n1: int  # grid points per Gamma_1: rod 1's memory lies n1 nodes back
    j2: int  # whole grid steps in Gamma_2
    f2: float  # Gamma_2 / h - j2, in [0, 1)
    r2: float  # rod 2's table index per grid step


class SampleTables(NamedTuple):
    """Per sample (one row each): the noise tables, their bounds and the start node (:meth:`HardCoreGrid.tables`)."""

    q1: np.ndarray  # rod 1's noise on the grid, (samples, n1)
    q2v: np.ndarray  # rod 2's Hermite table: values ...
    q2s: np.ndarray  # ... and slopes per table index, (samples, n2)
    cell2: np.ndarray  # rod 2's upper bound on each table cell, (samples, n2)
    block2: np.ndarray  # ... and on each block of CELLS_PER_BLOCK cells
    reach2: np.ndarray  # the largest of rod 2's cell bounds, (samples,)
    starts: np.ndarray  # the node that stands for the nominal contact time, (samples,)


@kernel(inline="always")
def _rod2(x, values, slopes, mask):
    """Rod 2's noise at table position ``x`` (cubic Hermite on the periodic table; ``mask = size - 1``)."""
    j = int(x)
    f = x - j
    j0 = j & mask
    j1 = (j + 1) & mask
    f2_ = f * f
    f3 = f2_ * f
    return ((2.0 * f3 - 3.0 * f2_ + 1.0) * values[j0] + (f3 - 2.0 * f2_ + f) * slopes[j0]
            + (3.0 * f2_ - 2.0 * f3) * values[j1] + (f3 - f2_) * slopes[j1])


@kernel(inline="always")
def _quiet_chunk(grid, a1, a2, q1, k, end, m, offset, running, top2, zeros):
    """Nodes ``k .. end - 1`` at once if none can rise (``f <= w`` by rod 2's bound ``top2``): then store
    ``A_i = w + C_i`` and return False; else store nothing and return True.

    A chunk lies wholly before node ``n_1`` (rod 1's memory is empty) or wholly after it, and
    likewise for node ``j_2 + 1``; ``zeros`` (at least ``end - k`` zeros) stands for an empty memory.
    ``grid``: the :class:`GridSteps`.
    """
    h, n1, j2, f2, _r2 = grid
    g2 = 1.0 - f2
    length = end - k
    old1 = a1[k - n1:end - n1] if k >= n1 else zeros[:length]
    before2 = a2[k - j2 - 1:end - j2 - 1] if k > j2 else zeros[:length]
    after2 = a2[k - j2:end - j2] if k > j2 else zeros[:length]
    noise = q1[k + offset:end + offset]
    hit = False
    for j in range(length):
        hit |= (k + j - m) * h - old1[j] - (f2 * before2[j] + g2 * after2[j]) + noise[j] + top2 > running
    if hit:
        return True
    new1 = a1[k:end]
    new2 = a2[k:end]
    for j in range(length):
        new1[j] = running + old1[j]
        new2[j] = running + (f2 * before2[j] + g2 * after2[j])
    return False


@kernel
def _max_plus_one(grid, row, reach2, m, capacity, a1, a2):
    """One sample; returns ``(w_final, nodes, status)`` (see the module docstring for the names).

    ``grid``: the :class:`GridSteps`; ``row``: this sample's ``(q1, q2v, q2s, cell2, block2)`` of the
    :class:`SampleTables`; ``m``: its start node; ``a1, a2``: work arrays of ``capacity`` nodes.
    """
    h, n1, j2, f2, r2 = grid
    q1, q2v, q2s, cell2, block2 = row
    n2 = q2v.shape[0]
    mask = n2 - 1
    shift = n2 * (m // n2 + 2)  # whole table periods that make rod 2's read position positive
    # quiet nodes before a stop certificate is tried (each try costs about n_1 + j_2 light steps)
    patience = max(2, n1 // 2)
    running = 0.0
    last = -1  # node of the last rise of w
    stop = -1  # first node from which the certificate holds (-1: not tried since the last rise)
    f_older = -math.inf
    f_old = -math.inf
    c1_old = 0.0
    c2_old = 0.0
    i1 = (-m) % n1  # index of node 0 in rod 1's table
    # before the first node at which the noise could lift f above 0, w = 0 and both memories
    # vanish (A_1 = A_2 = 0): scan for that node without the memory terms
    first = 0
    while first < capacity and ((first - m) * h + q1[i1] + reach2 <= 0.0
                                or (first - m) * h + q1[i1] + cell2[int((first - m) * r2 + shift) & mask] <= 0.0):
        a1[first] = 0.0
        a2[first] = 0.0
        first += 1
        i1 += 1
        if i1 == n1:
            i1 = 0
    candidate = False  # whether node k - 1 was read because the noise could lift f above w there
    # whether the bound over rod 2's whole table allowed a rise at nodes k - 1 and k - 2
    back = i1 - 1 if i1 >= 1 else i1 - 1 + n1
    within_old = (first - 1 - m) * h + q1[back] + reach2 > 0.0
    back = i1 - 2 if i1 >= 2 else i1 - 2 + n1
    within_older = (first - 2 - m) * h + q1[back] + reach2 > 0.0
    c1_older = 0.0
    c2_older = 0.0
    zeros = np.zeros(CHUNK)  # an empty memory, for chunks before node n_1 or j_2 + 1
    blocks = block2.shape[0]
    width = n2 // blocks
    g2 = 1.0 - f2
    span = min(CHUNK, int(0.5 * n2 / r2))  # a chunk covers less than half of rod 2's table
    scalar_until = 0
    k = first
    while k < capacity:
        if k >= scalar_until and not candidate:
            # a chunk of nodes at once (a loop the compiler vectorises): where no node of the chunk can
            # rise above w, each only stores A_i = w + C_i, as the node-by-node loop below would
            end = min(k + span, k + n1 - i1, capacity)
            if k < n1:
                end = min(end, n1)
            if k <= j2:
                end = min(end, j2 + 1)
            if last >= 0:
                end = min(end, last + patience if stop < 0 else stop)  # that node goes node by node
            if end - k >= 2:
                b0 = (int((k - m) * r2 + shift) & mask) // width
                b1 = (int((end - 1 - m) * r2 + shift) & mask) // width
                top2 = block2[b0]
                while b0 != b1:
                    b0 = b0 + 1 if b0 + 1 < blocks else 0
                    top2 = max(top2, block2[b0])
                hit = _quiet_chunk(grid, a1, a2, q1, k, end, m, i1 - k, running, top2, zeros)
                if not hit:
                    i1 += end - k
                    if i1 == n1:
                        i1 = 0
                    f_older = -math.inf
                    f_old = -math.inf
                    c1_older = a1[end - 2 - n1] if end - 2 >= n1 else 0.0
                    c2_older = f2 * a2[end - 3 - j2] + g2 * a2[end - 2 - j2] if end - 2 > j2 else 0.0
                    c1_old = a1[end - 1 - n1] if end - 1 >= n1 else 0.0
                    c2_old = f2 * a2[end - 2 - j2] + g2 * a2[end - 1 - j2] if end - 1 > j2 else 0.0
                    back = i1 - 2 if i1 >= 2 else i1 - 2 + n1
                    within_older = (end - 2 - m) * h - c1_older - c2_older + q1[back] + reach2 > running
                    back = i1 - 1 if i1 >= 1 else i1 - 1 + n1
                    within_old = (end - 1 - m) * h - c1_old - c2_old + q1[back] + reach2 > running
                    k = end
                    continue
                scalar_until = end
        c1 = a1[k - n1] if k >= n1 else 0.0
        c2 = f2 * a2[k - j2 - 1] + g2 * a2[k - j2] if k > j2 else 0.0
        rough = (k - m) * h - c1 - c2 + q1[i1]
        x = (k - m) * r2 + shift
        value = -math.inf
        within = rough + reach2 > running  # the bound over the whole table allows a rise
        read = within and rough + cell2[int(x) & mask] > running
        if read or (candidate and within):
            # only near such nodes can the noise lift f above the running maximum: read rod 2's share
            # (also right after a read node, to complete the parabola around it)
            value = rough + _rod2(x, q2v, q2s, mask)
            if candidate and f_older == -math.inf and value <= f_old and within_older and k >= 2:
                # the parabola around node k - 1 also needs node k - 2
                back = i1 - 2 if i1 >= 2 else i1 - 2 + n1
                f_older = ((k - 2 - m) * h - c1_older - c2_older + q1[back]
                           + _rod2((k - 2 - m) * r2 + shift, q2v, q2s, mask))
            peak = parabola_peak(f_older, f_old, value)  # f peaked between nodes k-2 and k
            if peak > running:
                running = peak
                a1[k - 1] = peak + c1_old
                a2[k - 1] = peak + c2_old
                last = k - 1
                stop = -1
            if value > running:
                running = value
                last = k
                stop = -1
        candidate = read
        within_older = within_old
        within_old = within
        a1[k] = running + c1
        a2[k] = running + c2
        i1 += 1
        if i1 == n1:
            i1 = 0
        f_older = f_old
        f_old = value
        c1_older = c1_old
        c2_older = c2_old
        c1_old = c1
        c2_old = c2
        if last >= 0:
            if stop < 0 and k == last + patience:
                stop = _certified_stop(h, n1, j2, f2, q1, reach2, m, last, running, a1, a2)
            if 0 <= stop <= k:
                return running, k + 1, STATUS_OK
        k += 1
    return running, capacity, STATUS_FULL


@kernel(inline="always")
def _top_of_rod1(q1, a1, begin, end, offset, n1, last, rise1):
    """``max_j q_1 - u_1`` over nodes ``begin .. end - 1`` (four running maxima of the same numbers, one loop)."""
    if end <= begin:
        return -math.inf
    noise = q1[begin + offset:end + offset]
    memory = a1[begin - n1:end - n1]
    start = begin - last
    t0 = t1 = t2 = t3 = -math.inf
    count = end - begin
    i = 0
    while i + 4 <= count:
        t0 = max(t0, noise[i] - memory[i] + (start + i) * rise1)
        t1 = max(t1, noise[i + 1] - memory[i + 1] + (start + i + 1) * rise1)
        t2 = max(t2, noise[i + 2] - memory[i + 2] + (start + i + 2) * rise1)
        t3 = max(t3, noise[i + 3] - memory[i + 3] + (start + i + 3) * rise1)
        i += 4
    for k in range(i, count):
        t0 = max(t0, noise[k] - memory[k] + (start + k) * rise1)
    return max(max(t0, t1), max(t2, t3))


@kernel(inline="always")
def _low_of_rod2(a2, begin, end, j2, f2, last, rise2):
    """``min_j u_2`` over nodes ``begin .. end - 1`` (like :func:`_top_of_rod1`)."""
    if end <= begin:
        return math.inf
    g2 = 1.0 - f2
    before = a2[begin - j2 - 1:end - j2 - 1]
    after = a2[begin - j2:end - j2]
    start = begin - last
    t0 = t1 = t2 = t3 = math.inf
    count = end - begin
    i = 0
    while i + 4 <= count:
        t0 = min(t0, f2 * before[i] + g2 * after[i] - (start + i) * rise2)
        t1 = min(t1, f2 * before[i + 1] + g2 * after[i + 1] - (start + i + 1) * rise2)
        t2 = min(t2, f2 * before[i + 2] + g2 * after[i + 2] - (start + i + 2) * rise2)
        t3 = min(t3, f2 * before[i + 3] + g2 * after[i + 3] - (start + i + 3) * rise2)
        i += 4
    for k in range(i, count):
        t0 = min(t0, f2 * before[k] + g2 * after[k] - (start + k) * rise2)
    return min(min(t0, t1), min(t2, t3))


@kernel
def _certified_stop(h, n1, j2, f2, q1, reach2, m, last, w, a1, a2):
    """First node from which ``f <= w`` holds for every later node if ``w`` stays constant (or a far node).

    Uses only ``A_1`` before ``last`` and ``A_2`` up to ``last + 1``: the comb sums over the
    next rod-1 and rod-2 periods follow from them without stepping.
    """
    if w <= 1.0:
        return 2**62  # still approaching: no certificate, step on
    # rod 1: the maximum of q_1 - u_1 over the next period, in two runs that do not wrap rod 1's table
    top1 = -math.inf
    rise1 = w / n1
    i0 = (last - m) % n1
    for part in range(2):
        begin, end = (last, last + n1 - i0) if part == 0 else (last + n1 - i0, last + n1)
        offset = i0 - last if part == 0 else i0 - last - n1
        top1 = max(top1, _top_of_rod1(q1, a1, max(begin, n1), end, offset, n1, last, rise1))
        for j in range(begin, min(end, n1)):  # before node n1 rod 1's memory is empty
            top1 = max(top1, q1[j + offset] + (j - last) * rise1)
    # rod 2: the least u_2 over the next period
    rise2 = w / (j2 + f2)
    low2 = _low_of_rod2(a2, max(last, j2 + 1), last + j2 + 2, j2, f2, last, rise2)
    if last <= j2:
        low2 = min(low2, -(j2 - last) * rise2)  # nodes before j2 + 1: no memory yet (u_2 <= 0 there)
    excess = (last - m) * h + top1 + reach2 - low2 - w
    if excess <= 0.0:
        return last
    steps = excess / (h * (w - 1.0))
    if steps > 2.0**60:
        return 2**62
    return last + int(math.ceil(steps)) + 1  # noqa: RUF046 (an int in numba and in Python alike)


@kernel
def max_plus_batch(grid, tables, capacity, work, out):
    """Run :func:`_max_plus_one` for every row (sample) of the tables.

    Parameters
    ----------
    grid : GridSteps
        The grid's constants.
    tables : SampleTables
        One row per sample.
    capacity : int
        Nodes of each work array.
    work : tuple of ndarray
        ``(a1, a2)``, the work arrays ``A_i = w + C_i`` (at least ``capacity`` nodes each).
    out : tuple of ndarray
        ``(w_final, nodes, status)``, one entry per sample, filled here.
    """
    q1, q2v, q2s, cell2, block2, reach2, starts = tables
    a1, a2 = work
    w_final, nodes, status = out
    for s in range(q1.shape[0]):
        w, count, flag = _max_plus_one(grid, (q1[s], q2v[s], q2s[s], cell2[s], block2[s]), reach2[s], starts[s],
                                       capacity, a1, a2)
        w_final[s] = w
        nodes[s] = count
        status[s] = flag


@kernel
def _noise_coefficients(normals, temperatures, energy, rod1, rod2, out):
    """The noise coefficients of every sample, in the arithmetic of ``ThermalBath.draw`` and
    ``BathRealisation.noise_coefficients(1.0)`` (so the same numbers).

    ``rod_i = (length, omega, sign)``: the rod's length, its modes' angular frequencies and the signs of
    their shapes at the contact end; ``out = (a1, b1, a2, b2)``, filled here.
    """
    length1, omega1, sign1 = rod1
    length2, omega2, sign2 = rod2
    a1, b1, a2, b2 = out
    for s in range(normals.shape[0]):
        root1 = math.sqrt(temperatures[s, 0] * energy / length1)
        root2 = math.sqrt(temperatures[s, 1] * energy / length2)
        for nu in range(normals.shape[3]):
            spread, factor = root1 / omega1[nu], 1.0 * math.sqrt(2.0) * sign1[nu]
            a1[s, nu] = factor * (normals[s, 0, 0, nu] * spread)
            b1[s, nu] = factor * (normals[s, 0, 1, nu] * spread)
            spread, factor = root2 / omega2[nu], 1.0 * math.sqrt(2.0) * sign2[nu]
            a2[s, nu] = factor * (normals[s, 1, 0, nu] * spread)
            b2[s, nu] = factor * (normals[s, 1, 1, nu] * spread)


@kernel
def _spectra(a1, b1, a2, b2, scale1, scale2, slope_factor, spectrum1, spectrum2):
    """Fill the half spectra of rod 1's table and of rod 2's values and slopes (bins 1..nu_max).

    ``q(t) = sum a cos + b sin`` has the bins ``scale (a - i b)``; the slope per table index
    multiplies them by ``i slope_factor``.
    """
    for s in range(a1.shape[0]):
        for nu in range(a1.shape[1]):
            spectrum1[s, nu + 1] = complex(scale1 * a1[s, nu], -(scale1 * b1[s, nu]))
            real, imag = scale2 * a2[s, nu], -(scale2 * b2[s, nu])
            spectrum2[0, s, nu + 1] = complex(real, imag)
            spectrum2[1, s, nu + 1] = complex(-(imag * slope_factor[nu]), real * slope_factor[nu])


@kernel
def _table_bounds(q1, values, slopes, h, cell2, block2, reach2, reach, starts):
    """Per sample: rod 2's upper bound on each table cell, its maximum ``reach2``, ``reach`` and the start node.

    A cubic Hermite piece exceeds its larger end value by at most 4/27 of the sum of its
    end slopes (per index).  Node 0 lies before the earliest possible contact:
    ``f <= t + reach < 0`` there.
    """
    size = values.shape[1]
    for s in range(values.shape[0]):
        top2 = 0.0
        for j in range(size):
            k = j + 1 if j + 1 < size else 0
            bound = max(values[s, j], values[s, k]) + (4.0 / 27.0) * (abs(slopes[s, j]) + abs(slopes[s, k]))
            cell2[s, j] = bound
            top2 = max(top2, bound)
        width = size // block2.shape[1]
        for b in range(block2.shape[1]):
            top = -math.inf
            for j in range(b * width, (b + 1) * width):
                top = max(top, cell2[s, j])
            block2[s, b] = top
        top1 = 0.0
        for j in range(q1.shape[1]):
            top1 = max(top1, q1[s, j])
        reach2[s] = top2
        reach[s] = top1 + top2
        starts[s] = int(math.ceil(reach[s] / h)) + 1  # noqa: RUF046 (an int in numba and in Python alike)


class HardCoreGrid:
    """The grid of the hard-core recursion for one ``(gamma, nu_max, points per period)``.

    Parameters
    ----------
    gamma : float
        Length ratio ``l_1 / l_2`` in (0, 1].
    modes : int
        Bath modes per rod ``nu_max`` (>= 1).
    points_per_period : int
        Grid points per period of rod 1's fastest bath mode, in [2, 8192]
        (``n_1 = max(points_per_period nu_max, min_points)`` points per ``Gamma_1``).
    min_points : int
        Least grid points per ``Gamma_1``.
    max_points : int
        Refuse a sample longer than this many grid points.
    rod2_points : int, optional
        Nodes of rod 2's Hermite table per period of its fastest mode (rounded up to a power of two
        per table); default half of ``points_per_period``.
    """

    def __init__(self, gamma: float, modes: int, points_per_period: int = DEFAULT_POINTS_PER_PERIOD,
                 min_points: int = 256, max_points: int = 50_000_000, rod2_points: int | None = None):
        from ..bath.model import MAX_BATH_MODES
        from ..bath.noise import table_points

        if not (isinstance(gamma, (int, float, np.floating)) and 0.0 < float(gamma) <= 1.0):
            raise InvalidParameterError(f"gamma must be in (0, 1], got {gamma!r}")
        modes = require_integer("bath modes (nu_max)", modes, 1, MAX_BATH_MODES)
        points_per_period = require_integer("hard_core_resolution (points per period)", points_per_period, 2, 8192)
        self.gamma = float(gamma)
        self.modes = int(modes)
        self.lengths = (0.5 * (1.0 + self.gamma), 0.5 * (1.0 + self.gamma) / self.gamma)
        self.periods = (1.0 + self.gamma, 1.0 + 1.0 / self.gamma)
        self.n1 = max(int(points_per_period) * self.modes, int(min_points), 2 * self.modes + 2)
        self.h = self.periods[0] / self.n1
        d2 = self.periods[1] / self.h
        self.j2 = int(d2)
        self.f2 = d2 - self.j2
        # rod 2's Hermite table: half as many nodes per period of its fastest mode as the grid has for
        # rod 1's (a power of two).  The noise is read there only near candidate maxima, and the
        # interpolation error it adds is unbiased and below the grid's own (test_rod2_table_*)
        self.n2 = table_points(self.modes, max(2, int(points_per_period) // 2) if rod2_points is None
                               else int(rod2_points))
        self.r2 = self.h * self.n2 / self.periods[1]  # rod 2's table index per grid step
        self.steps = GridSteps(self.h, self.n1, self.j2, self.f2, self.r2)
        self.max_points = int(max_points)
        nu = np.arange(1, self.modes + 1)
        self._omega = tuple(math.pi * nu / length for length in self.lengths)  # m_i = l_i, c = 1
        self._signs = ((-1.0) ** nu, -np.ones(self.modes))  # BathRealisation.contact_end_signs
        self._slope_factor = 2.0 * math.pi * nu / self.periods[1] * (self.periods[1] / self.n2)  # d/d(index) / i

    def coefficients(self, normals, temperatures):
        """Noise coefficients ``(a_1, b_1, a_2, b_2)`` of ``q = Q / kappa``, each ``(samples, nu_max)``.

        The arithmetic of :meth:`ThermalBath.draw` followed by
        ``BathRealisation.noise_coefficients(1.0)``, elementwise.
        """
        count = normals.shape[0]
        out = [_work(f"coefficients {name}", (max(count, BLOCK), self.modes))[:count] for name in ("a1", "b1", "a2", "b2")]
        _noise_coefficients(np.ascontiguousarray(normals), np.ascontiguousarray(temperatures, dtype=float),
                            _TRANSLATIONAL_ENERGY, (self.lengths[0], self._omega[0], self._signs[0]),
                            (self.lengths[1], self._omega[1], self._signs[1]), tuple(out))
        return out

    def tables(self, a1, b1, a2, b2):
        """Rod 1's table on the grid, rod 2's Hermite table (values, slopes per index), its cell bounds, reaches, start nodes.

        ``a_i, b_i``: noise coefficients ``(samples, nu_max)`` (:meth:`coefficients`).  The
        arrays returned are this thread's work arrays, overwritten by its next call.
        """
        count = a1.shape[0]
        rows = max(count, BLOCK)
        # half spectra: only the bins 1..nu_max are ever written, the others stay zero
        spectrum1 = _work(f"spectrum1 {self.modes}", (rows, self.n1 // 2 + 1), complex)[:count]
        spectrum2 = _work(f"spectrum2 {self.modes}", (2, rows, self.n2 // 2 + 1), complex)[:, :count]
        _spectra(a1, b1, a2, b2, 0.5 * self.n1, 0.5 * self.n2, self._slope_factor, spectrum1, spectrum2)
        q1 = _irfft(spectrum1, self.n1, _work("q1", (rows, self.n1))[:count])
        q2 = _irfft(spectrum2, self.n2, _work("q2", (2, rows, self.n2))[:, :count])
        cell2 = _work("cell2", (rows, self.n2))[:count]
        block2 = _work("block2", (rows, self.n2 // min(self.n2, CELLS_PER_BLOCK)))[:count]
        reach2, reach, starts = np.empty(count), np.empty(count), np.empty(count, dtype=np.int64)
        _table_bounds(q1, q2[0], q2[1], self.h, cell2, block2, reach2, reach, starts)
        return q1, q2[0], q2[1], cell2, block2, reach2, reach, starts

    def restitutions(self, normals, temperatures) -> np.ndarray:
        """epsilon of each sample from its normals ``(samples, 2, 2, nu_max)`` and ``T_i / E_tr`` ``(samples, 2)``.

        The samples go through in blocks of :data:`BLOCK` (tables that stay in cache); a
        sample's result does not depend on the block it is in.
        """
        count = normals.shape[0]
        out = np.empty(count)
        nodes = np.empty(count, dtype=np.int64)
        for start in range(0, count, BLOCK):
            stop = min(start + BLOCK, count)
            coefficients = self.coefficients(normals[start:stop], temperatures[start:stop])
            out[start:stop] = self._block(coefficients, nodes[start:stop])
        return out

    def restitution_of(self, vibrations) -> float:
        """epsilon of one :class:`~wavecontact.bath.BathRealisation` of this grid's rods (at nominal contact).

        Its noise coefficients are the numbers :meth:`coefficients` makes from the same draw,
        so the result equals the batch's for that seed, bit for bit.
        """
        if vibrations.modes != self.modes:
            raise InvalidParameterError(f"the realisation has {vibrations.modes} modes per rod, the grid {self.modes}")
        (_o1, a1, b1), (_o2, a2, b2) = vibrations.noise_coefficients(1.0)
        return float(self._block([a1[None], b1[None], a2[None], b2[None]], np.empty(1, dtype=np.int64))[0])

    def _block(self, coefficients, nodes):
        q1, q2v, q2s, cell2, block2, reach2, _reach, starts = self.tables(*coefficients)
        tables = SampleTables(q1, q2v, q2s, cell2, block2, reach2, starts)
        count = q1.shape[0]
        w = np.empty(count)
        status = np.empty(count, dtype=np.int64)
        capacity = int(min(self.max_points, int(starts.max()) + 6 * self.n1 + 4 * self.j2))
        # this thread's work arrays (a grid is shared by every thread that samples it, and the kernel
        # runs without the GIL); the capacity only decides which samples are rerun alone below
        a1, a2 = _work("a1", (capacity,), grow=True), _work("a2", (capacity,), grow=True)
        max_plus_batch(self.steps, tables, a1.size, (a1, a2), (w, nodes, status))
        for s in np.flatnonzero(status != STATUS_OK):
            # a long sample: run it alone with larger work arrays (same arithmetic, same result)
            size = a1.size
            while status[s] != STATUS_OK:
                if size >= self.max_points:
                    raise SolverFailure(f"hard-core recursion did not settle within {self.max_points} grid points")
                size = min(self.max_points, 4 * size)
                big = (np.empty(size), np.empty(size))
                one = slice(s, s + 1)
                max_plus_batch(self.steps, SampleTables(*(table[one] for table in tables)), size, big,
                               (w[one], nodes[one], status[one]))
        return w - 1.0


_LOCAL = threading.local()  # per thread: work arrays reused between calls (fresh large arrays cost page faults)


def _work(name: str, shape: tuple, dtype=float, grow: bool = False) -> np.ndarray:
    """This thread's work array ``name`` of ``shape`` (zeros when first made); ``grow``: at least that size."""
    arrays = getattr(_LOCAL, "arrays", None)
    if arrays is None:
        arrays = _LOCAL.arrays = {}
    key = (name, np.dtype(dtype).str) if grow else (name, np.dtype(dtype).str, shape)
    array = arrays.get(key)
    if array is None or (grow and array.shape[0] < shape[0]):
        if len(arrays) > 64:
            arrays.clear()
        array = arrays[key] = np.zeros(shape, dtype)
    return array


def _irfft(spectrum, size, out):
    """``numpy.fft.irfft`` along the last axis into ``out`` (where NumPy takes ``out``: 2.0 and later)."""
    try:
        return np.fft.irfft(spectrum, size, axis=-1, out=out)
    except TypeError:  # NumPy < 2.0
        out[...] = np.fft.irfft(spectrum, size, axis=-1)
        return out


def _temperature_rows(temperature, count):
    values = np.asarray(temperature, dtype=float)
    if values.ndim == 0:
        values = np.full((count, 2), float(values))
    elif values.shape == (2,):
        values = np.broadcast_to(values, (count, 2)).copy()
    elif values.shape == (count,):
        values = np.repeat(values[:, None], 2, axis=1)
    elif values.shape != (count, 2):
        raise InvalidParameterError(f"bath temperature must be a number, a pair, or one (pair) per sample; got shape "
                                    f"{values.shape} for {count} samples")
    if not np.all(np.isfinite(values) & (values >= 0.0)):
        raise InvalidParameterError("bath temperature T_B/E_tr must be finite and >= 0")
    return values


def hard_core_restitutions(gamma, temperature, seeds, *, modes: int = 250,
                           points_per_period: int = DEFAULT_POINTS_PER_PERIOD, grid: HardCoreGrid | None = None):
    """epsilon of hard-core thermal collisions, one per seed (the fast ensemble path).

    Parameters
    ----------
    gamma : float
        Length ratio in (0, 1].
    temperature : float, pair, or array (samples,) or (samples, 2)
        ``T_i / E_tr`` of each rod (dimensionless), >= 0; per sample if an array.
    seeds : sequence of int or numpy.random.SeedSequence, or SpawnedSeeds
        Sample ``j``'s bath is ``default_rng(seeds[j]).standard_normal((2, 2, modes))``,
        the realisation :meth:`wavecontact.bath.ThermalBath.draw` gives for that seed
        (drawn by :mod:`wavecontact.bath.streams`, the same numbers; a
        :class:`~wavecontact.bath.streams.SpawnedSeeds` range is hashed at once).
    modes : int
        Bath modes per rod ``nu_max``.
    points_per_period : int
        Grid points per period of the short rod's fastest bath mode (the error is first order
        in ``1 / points_per_period``).
    grid : HardCoreGrid, optional
        A prepared grid (reused across calls); overrides ``modes`` and ``points_per_period``.

    Returns
    -------
    ndarray (samples,)
        The coefficients of restitution (dimensionless); row ``j`` is the same number
        whatever the other seeds in the call.
    """
    from ..bath.streams import SpawnedSeeds, seed_states, standard_normals

    grid = grid or HardCoreGrid(gamma, modes, points_per_period)
    if not isinstance(seeds, SpawnedSeeds):
        seeds = list(seeds)
    if not len(seeds):
        return np.empty(0)
    temperatures = _temperature_rows(temperature, len(seeds))
    # numpy's own streams, without a SeedSequence and a Generator per sample (bath/streams.py)
    normals = standard_normals(seed_states(seeds), 4 * grid.modes).reshape(len(seeds), 2, 2, grid.modes)
    return grid.restitutions(normals, temperatures)


def hard_core_restitution(gamma: float, temperatures, modes: int, rng: np.random.Generator,
                          points_per_period: int = DEFAULT_POINTS_PER_PERIOD) -> float:
    """epsilon of one hard-core thermal collision, its bath drawn from ``rng`` (a single-call fast path).

    Parameters
    ----------
    gamma : float
        Length ratio in (0, 1].
    temperatures : float or pair of float
        ``T_1 / E_tr`` and ``T_2 / E_tr`` (short rod first), >= 0.
    modes : int
        ``nu_max``.
    rng : numpy.random.Generator
        Supplies ``standard_normal((2, 2, modes))`` (the same numbers as
        ``ThermalBath.draw`` with the generator's seed when it is fresh).
    points_per_period : int
        See :func:`hard_core_restitutions`.

    Returns
    -------
    float
    """
    grid = cached_grid(float(gamma), int(modes), int(points_per_period))
    normals = rng.standard_normal((1, 2, 2, grid.modes))
    return float(grid.restitutions(normals, _temperature_rows(temperatures, 1))[0])


_GRIDS: dict = {}


def cached_grid(gamma: float, modes: int, points_per_period: int = DEFAULT_POINTS_PER_PERIOD) -> HardCoreGrid:
    """A :class:`HardCoreGrid` kept for reuse (per process; at most 64 kept)."""
    key = (gamma, modes, points_per_period)
    grid = _GRIDS.get(key)
    if grid is None:
        if len(_GRIDS) > 64:
            _GRIDS.clear()
        grid = _GRIDS[key] = HardCoreGrid(gamma, modes, points_per_period)
    return grid
