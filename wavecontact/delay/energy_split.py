"""Which rod's vibrations took the energy: the per-rod split of the delay solution.

In the paper's units (docs/theory.md; ``Z = 1``, ``alpha = kappa``) a contact
force ``F`` moves rod ``i``'s facing end, away from the contact, by

    kappa y_i(tau) = W(tau) / 2 + S_i(tau) - Q_i(tau),
    S_i(tau) = sum_{n >= 1} W(tau - n Gamma_i)

(the wave theory of a free-free rod: the end takes ``F / Z`` at once and
``2 F / Z`` again after every round trip ``Gamma_i``; ``Q_i`` is rod ``i``'s
own vibration, its share of Eq. 17).  Both rods' terms add up to the memory
and noise of Eq. 16.  Rod ``i``'s centre of mass moves by
``int_0^tau W ds / Gamma_i`` of that (momentum over mass), so its vibrations
gain

    Delta E_i = 1 / (2 kappa^2) int W'(tau) [W'/2 + S_i' - W / Gamma_i - Q_i'] dtau

(energy units with ``E_tr = mu V^2 / 2 = 1/4``; ``F = W' / (2 kappa)``).  Their
sum is the translational energy lost, ``(1 - epsilon^2) / 4``; the test suite
checks that identity and compares each term with the modal solver.
"""

from __future__ import annotations

import numpy as np

from .._jit import kernel, prefer_interpreted
from .kernels import INTERPRETED_KAPPA_MIN, hermite5_on, locate_from, table_value

__all__ = ["vibration_energy_gain"]

# Gauss-Legendre on [0, 1], 8 nodes
_X, _W = np.polynomial.legendre.leggauss(8)
NODES = 0.5 * (_X + 1.0)
WEIGHTS = 0.5 * _W


def vibration_energy_gain(kappa, t, w, d1, d2, delays, periods, tables, table_slopes, nodes, weights, subdivide):
    """``Delta E_i`` per rod (see module docstring), Gauss-Legendre on each stored step.

    Parameters
    ----------
    kappa : float
        Softness.
    t, w, d1, d2 : ndarray
        The delay solver's grid and ``W, W', W''`` on it.
    delays : ndarray (2,)
        ``Gamma_1, Gamma_2``.
    periods, tables, table_slopes : ndarray
        Each rod's noise table (``R = 0`` rows for a cold bath).
    nodes, weights : ndarray
        Quadrature rule on [0, 1].
    subdivide : int
        Sub-intervals per stored step.

    Returns
    -------
    ndarray (2,)
        ``Delta E_1, Delta E_2`` (``E_tr = 1/4``).
    """
    noise = None if periods.shape[0] != 2 else (periods, tables, table_slopes)  # None: a cold bath
    # the nodes advance through the history, so each delayed copy's step is found by walking on from
    # where it was last (locate_from: the same step as hermite5's binary search, without the search)
    copies = int((t[-1] - t[0]) / min(delays[0], delays[1])) + 2
    hints = np.zeros((2, copies), dtype=np.int64)
    gain = np.zeros(2)
    arguments = (kappa, (t, w, d1, d2), delays, noise, (nodes, weights), subdivide, gain, hints)
    # interpreted for a first answer, as the history it walks (kernels.integrate_delay_equation), up to a
    # thousand steps of that history (about a second of plain Python)
    small = noise is None and kappa >= INTERPRETED_KAPPA_MIN and t.shape[0] <= 1000
    prefer_interpreted(_energy_gain, arguments, small, compile_later=True)(*arguments)
    return gain


@kernel
def _energy_gain(kappa, history, delays, noise, rule, subdivide, gain, hints):
    """:func:`vibration_energy_gain` into ``gain`` (zeros), with ``noise`` None for a cold bath (numba then
    compiles the kernel without the tables' code); ``hints`` (zeros) are the steps last found for each rod's
    delayed copies.  The arrays come from the caller: numba's ``np.empty`` is a compilation of its own."""
    t, w, d1, d2 = history
    nodes, weights = rule
    last = t.shape[0] - 1
    for j in range(last):
        for part in range(subdivide):
            a = t[j] + (t[j + 1] - t[j]) * part / subdivide
            b = t[j] + (t[j + 1] - t[j]) * (part + 1) / subdivide
            for m in range(nodes.shape[0]):
                s = a + (b - a) * nodes[m]
                # the points u = s - n Gamma_i in turn, through one inlined interpolation (each inlined copy
                # compiles on its own): n = 0, s itself (its step hint in the unused slot (0, 0)), then each
                # rod's delayed copies n >= 1, after which that rod's term is added
                value = 0.0
                slope = 0.0
                memory_slope = 0.0
                i = 0
                n = 0
                while i < 2:
                    u = s - n * delays[i]
                    if u > t[0]:
                        hints[i, n] = locate_from(t, last, u, hints[i, n])
                        v, ds, _c = hermite5_on(t, w, d1, d2, hints[i, n], u)
                        if n > 0:
                            memory_slope += ds
                        elif ds == 0.0:
                            break  # no force at s
                        else:
                            value = v
                            slope = ds
                        n += 1
                        continue
                    if n == 0:
                        break  # s at or before the start: no force
                    noise_slope = 0.0
                    if noise is not None:
                        periods, tables, table_slopes = noise
                        _q, noise_slope = table_value(s, periods[i], tables[i], table_slopes[i])
                    end_slope = 0.5 * slope + memory_slope - value / delays[i] - noise_slope
                    gain[i] += weights[m] * (b - a) * slope * end_slope
                    i += 1
                    n = 1
                    memory_slope = 0.0
    scale = 2.0 * kappa * kappa
    for i in range(2):  # not gain / scale: an array expression compiles a ufunc loop, a second of compilation
        gain[i] /= scale
