"""The stochastic hard-core mode for many samples at once (Eq. 26 on a grid, batched).

The same recursion as :mod:`wavecontact.delay.stochastic_hardcore`,

    w_k = max(w_{k-1}, f(t_k), 0),   f(t) = t - tau_free - C_1(t) - C_2(t) + q_1(t) + q_2(t),

organised for blocks of samples, with no Python work per grid node or per table entry:

* the bath of sample ``j`` is ``standard_normal((2, 2, nu_max))`` from
  ``numpy.random.default_rng(seed_j)``, the same numbers as
  :meth:`wavecontact.bath.ThermalBath.draw`, so a sample here is the same
  realisation that drives the other solvers;
* the noise tables of the whole block come from one 2-D inverse real FFT per
  table; the time origin is the nominal contact time (node ``k`` sits at
  ``(k - m) h``), so no phase factors are needed, and every operation on the
  block is elementwise or a per-row maximum: a row's numbers do not depend on
  the other rows (tested bit for bit against batch size 1);
* one compiled kernel runs the recursion of every sample.  ``A_i = w + C_i``
  is kept instead of ``w`` and ``C_i``: rod 1's memory is ``A_1[k - n_1]``,
  rod 2's a fixed linear interpolation between ``A_2[k - j_2 - 1]`` and
  ``A_2[k - j_2]`` (``Gamma_2 / h = j_2 + f_2``).

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

import numpy as np

from .._jit import kernel
from ..errors import InvalidParameterError, SolverFailure
from .stochastic_hardcore import parabola_peak

__all__ = ["DEFAULT_POINTS_PER_PERIOD", "HardCoreGrid", "cached_grid", "hard_core_restitution", "hard_core_restitutions",
           "max_plus_batch"]

DEFAULT_POINTS_PER_PERIOD = 8
_TRANSLATIONAL_ENERGY = 0.25  # E_tr in the paper's units (mu = 1/2, V = 1)
BLOCK = 32  # samples whose tables are made together (about 1.5 MB at nu_max = 250)
STATUS_OK = 0
STATUS_FULL = 1


@kernel
def _max_plus_one(h, n1, j2, f2, q1, q2v, q2s, r2, reach2, m, capacity, a1, a2):
    """One sample; returns ``(w_final, nodes, status)`` (see the module docstring for the names)."""
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
    for k in range(capacity):
        c1 = a1[k - n1] if k >= n1 else 0.0
        c2 = f2 * a2[k - j2 - 1] + (1.0 - f2) * a2[k - j2] if k > j2 else 0.0
        bracket = (k - m) * h - c1 - c2
        value = -math.inf
        rough = bracket + q1[i1]
        if rough + reach2 > running:
            # only here can the noise lift f above the running maximum: read rod 2's share
            x = (k - m) * r2 + shift
            j = int(x)
            f = x - j
            j0 = j & mask
            j1 = (j + 1) & mask
            f2_ = f * f
            f3 = f2_ * f
            value = rough + ((2.0 * f3 - 3.0 * f2_ + 1.0) * q2v[j0] + (f3 - 2.0 * f2_ + f) * q2s[j0]
                             + (3.0 * f2_ - 2.0 * f3) * q2v[j1] + (f3 - f2_) * q2s[j1])
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
        a1[k] = running + c1
        a2[k] = running + c2
        i1 += 1
        if i1 == n1:
            i1 = 0
        f_older = f_old
        f_old = value
        c1_old = c1
        c2_old = c2
        if last >= 0:
            if stop < 0 and k == last + patience:
                stop = _certified_stop(h, n1, j2, f2, q1, reach2, m, last, running, a1, a2)
            if 0 <= stop <= k:
                return running, k + 1, STATUS_OK
    return running, capacity, STATUS_FULL


@kernel
def _certified_stop(h, n1, j2, f2, q1, reach2, m, last, w, a1, a2):
    """First node from which ``f <= w`` holds for every later node if ``w`` stays constant (or a far node).

    Uses only ``A_1`` before ``last`` and ``A_2`` up to ``last + 1``: the comb sums over the
    next rod-1 and rod-2 periods follow from them without stepping.
    """
    if w <= 1.0:
        return 2**62  # still approaching: no certificate, step on
    top1 = -math.inf
    i1 = (last - m) % n1
    for j in range(last, last + n1):
        c1 = a1[j - n1] if j >= n1 else 0.0
        top = q1[i1] - (c1 - w * (j - last) / n1)
        top1 = max(top1, top)
        i1 += 1
        if i1 == n1:
            i1 = 0
    low2 = math.inf
    d2 = j2 + f2
    for j in range(last, last + j2 + 2):
        c2 = f2 * a2[j - j2 - 1] + (1.0 - f2) * a2[j - j2] if j > j2 else 0.0
        u2 = c2 - w * (j - last) / d2
        low2 = min(low2, u2)
    excess = (last - m) * h + top1 + reach2 - low2 - w
    if excess <= 0.0:
        return last
    steps = excess / (h * (w - 1.0))
    if steps > 2.0**60:
        return 2**62
    return last + int(math.ceil(steps)) + 1  # noqa: RUF046 (an int in numba and in Python alike)


@kernel
def max_plus_batch(h, n1, j2, f2, q1, q2v, q2s, r2, reach2, starts, capacity, a1, a2, w_final, nodes, status):
    """Run :func:`_max_plus_one` for every row (sample) of the tables; fills ``w_final``, ``nodes``, ``status``."""
    for s in range(q1.shape[0]):
        w, count, flag = _max_plus_one(h, n1, j2, f2, q1[s], q2v[s], q2s[s], r2, reach2[s], starts[s], capacity,
                                       a1, a2)
        w_final[s] = w
        nodes[s] = count
        status[s] = flag


class HardCoreGrid:
    """The grid of the hard-core recursion for one ``(gamma, nu_max, points per period)``.

    Parameters
    ----------
    gamma : float
        Length ratio ``l_1 / l_2`` in (0, 1].
    modes : int
        Bath modes per rod ``nu_max`` (>= 1).
    points_per_period : int
        Grid points per period of rod 1's fastest bath mode, in [2, 4096]
        (``n_1 = max(points_per_period nu_max, min_points)`` points per ``Gamma_1``).
    min_points : int
        Least grid points per ``Gamma_1``.
    max_points : int
        Refuse a sample longer than this many grid points.
    """

    def __init__(self, gamma: float, modes: int, points_per_period: int = DEFAULT_POINTS_PER_PERIOD,
                 min_points: int = 256, max_points: int = 50_000_000):
        from ..bath.model import MAX_BATH_MODES
        from ..bath.noise import table_points

        if not (isinstance(gamma, (int, float, np.floating)) and 0.0 < float(gamma) <= 1.0):
            raise InvalidParameterError(f"gamma must be in (0, 1], got {gamma!r}")
        if isinstance(modes, bool) or not isinstance(modes, (int, np.integer)) or not 1 <= modes <= MAX_BATH_MODES:
            raise InvalidParameterError(f"bath modes (nu_max) must be an integer in [1, {MAX_BATH_MODES}], got {modes!r}")
        if isinstance(points_per_period, bool) or not isinstance(points_per_period, (int, np.integer)) \
                or not 2 <= points_per_period <= 4096:
            raise InvalidParameterError(
                f"hard_core_resolution (points per period) must be an integer in [2, 4096], got {points_per_period!r}")
        self.gamma = float(gamma)
        self.modes = int(modes)
        self.lengths = (0.5 * (1.0 + self.gamma), 0.5 * (1.0 + self.gamma) / self.gamma)
        self.periods = (1.0 + self.gamma, 1.0 + 1.0 / self.gamma)
        self.n1 = max(int(points_per_period) * self.modes, int(min_points), 2 * self.modes + 2)
        self.h = self.periods[0] / self.n1
        d2 = self.periods[1] / self.h
        self.j2 = int(d2)
        self.f2 = d2 - self.j2
        # rod 2's Hermite table: as many nodes per period of its fastest mode as the grid has for rod 1's
        # (rod 2's modes are slower by gamma); a power of two
        self.n2 = table_points(self.modes, int(points_per_period))
        self.r2 = self.h * self.n2 / self.periods[1]  # rod 2's table index per grid step
        self.max_points = int(max_points)
        nu = np.arange(1, self.modes + 1)
        self._omega = tuple(math.pi * nu / length for length in self.lengths)  # m_i = l_i, c = 1
        self._signs = ((-1.0) ** nu, -np.ones(self.modes))  # BathRealisation.contact_end_signs
        self._derivative = 2j * math.pi * nu / self.periods[1] * (self.periods[1] / self.n2)  # d/d(index)

    def coefficients(self, normals, temperatures):
        """Noise coefficients ``(a_1, b_1, a_2, b_2)`` of ``q = Q / kappa``, each ``(samples, nu_max)``.

        The arithmetic of :meth:`ThermalBath.draw` followed by
        ``BathRealisation.noise_coefficients(1.0)``, elementwise.
        """
        out = []
        for i in range(2):
            spread = np.sqrt(temperatures[:, i:i + 1] * _TRANSLATIONAL_ENERGY / self.lengths[i]) / self._omega[i]
            factor = 1.0 * math.sqrt(2.0) * self._signs[i]
            out.append(factor * (normals[:, i, 0] * spread))
            out.append(factor * (normals[:, i, 1] * spread))
        return out

    def tables(self, a1, b1, a2, b2):
        """Rod 1's table on the grid, rod 2's Hermite table (values, slopes per index), reaches, start nodes.

        ``a_i, b_i``: noise coefficients ``(samples, nu_max)`` (:meth:`coefficients`).
        """
        count = a1.shape[0]
        top = self.modes + 1
        spectrum = np.zeros((count, self.n1 // 2 + 1), dtype=complex)
        spectrum[:, 1:top] = 0.5 * self.n1 * (a1 - 1j * b1)
        q1 = np.fft.irfft(spectrum, self.n1, axis=-1)
        spectrum = np.zeros((2, count, self.n2 // 2 + 1), dtype=complex)
        spectrum[0, :, 1:top] = 0.5 * self.n2 * (a2 - 1j * b2)
        spectrum[1, :, 1:top] = spectrum[0, :, 1:top] * self._derivative
        q2 = np.fft.irfft(spectrum, self.n2, axis=-1)
        # a cubic Hermite piece exceeds its end values by at most 8/27 of a step's slope: 0.3 max|slope|
        reach2 = np.maximum(q2[0].max(axis=1) + 0.3 * np.abs(q2[1]).max(axis=1), 0.0)
        reach = np.maximum(q1.max(axis=1), 0.0) + reach2
        # node 0 before the earliest possible contact: f = t + q <= t + reach < 0 there
        starts = (np.ceil(reach / self.h) + 1.0).astype(np.int64)
        return q1, q2[0], q2[1], reach2, reach, starts

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
        q1, q2v, q2s, reach2, _reach, starts = self.tables(*coefficients)
        count = q1.shape[0]
        w = np.empty(count)
        status = np.empty(count, dtype=np.int64)
        capacity = int(min(self.max_points, int(starts.max()) + 6 * self.n1 + 4 * self.j2))
        # work arrays of this call: a grid is shared (cached_grid) by every thread that samples it,
        # and the kernel runs without the GIL, so arrays kept on the grid would be overwritten
        a1, a2 = np.empty(capacity), np.empty(capacity)
        max_plus_batch(self.h, self.n1, self.j2, self.f2, q1, q2v, q2s, self.r2, reach2, starts, a1.size, a1, a2,
                       w, nodes, status)
        for s in np.flatnonzero(status != STATUS_OK):
            # a long sample: run it alone with larger work arrays (same arithmetic, same result)
            size = a1.size
            while status[s] != STATUS_OK:
                if size >= self.max_points:
                    raise SolverFailure(f"hard-core recursion did not settle within {self.max_points} grid points")
                size = min(self.max_points, 4 * size)
                big = (np.empty(size), np.empty(size))
                one = slice(s, s + 1)
                max_plus_batch(self.h, self.n1, self.j2, self.f2, q1[one], q2v[one], q2s[one], self.r2, reach2[one],
                               starts[one], size, big[0], big[1], w[one], nodes[one], status[one])
        return w - 1.0


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
    seeds : sequence of int or numpy.random.SeedSequence
        Sample ``j``'s bath is ``default_rng(seeds[j]).standard_normal((2, 2, modes))``,
        the realisation :meth:`wavecontact.bath.ThermalBath.draw` gives for that seed.
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
    grid = grid or HardCoreGrid(gamma, modes, points_per_period)
    seeds = list(seeds)
    if not seeds:
        return np.empty(0)
    normals = np.empty((len(seeds), 2, 2, grid.modes))
    for j, seed in enumerate(seeds):
        np.random.default_rng(seed).standard_normal(out=normals[j])
    return grid.restitutions(normals, _temperature_rows(temperature, len(seeds)))


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
