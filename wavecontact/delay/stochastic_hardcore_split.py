"""One hard-core thermal collision with each rod's share of the energy (the gas's solve rule).

Reached from studies through the registry: ``solver_for(HARD_CORE_THERMAL).hard_core_thermal_split``
(the capability the delay solver declares, :mod:`wavecontact.solvers.base`).

The stochastic hard-core limit (``kappa -> inf``) of the paper's two rods is
the max-plus recursion of :mod:`wavecontact.delay.stochastic_hardcore`; this
module runs it and also returns what each rod's vibrations gained, which the
recursion alone does not give.

The split.  With ``W = kappa w`` the per-rod energy of
:mod:`wavecontact.delay.energy_split` becomes, in units with ``E_tr = 1/4``,

    Delta E_i = 1/2 int w' (y_i' - w / Gamma_i) dtau,   y_i = w/2 + s_i - q_i,

``s_i`` rod ``i``'s memory comb sum and ``q_i = Q_i / kappa`` its noise.
While the rods touch, ``y_1 + y_2 = tau - tau_free`` (the ends move together),
so ``y_1' = (1 + d') / 2`` with ``d = y_1 - y_2 = s_1 - s_2 - q_1 + q_2``, and
off contact ``w' = 0``.  Hence, with ``w_e = 1 + epsilon`` the final value and
``J = int d' dw`` (a Stieltjes integral against the non-decreasing ``w``),

    Delta E_1 = w_e/4 + J/4 - w_e^2 / (4 Gamma_1),
    Delta E_2 = w_e/4 - J/4 - w_e^2 / (4 Gamma_2),

whose sum is ``(1 - epsilon^2)/4`` exactly (``1/Gamma_1 + 1/Gamma_2 = 1``).
``J`` is the sum over grid steps of ``(w_k - w_{k-1}) (d_k - d_{k-1}) / h``,
first order in the grid step ``h`` like the recursion itself; the tests
compare it with the delay solver's split at large finite ``kappa``.
"""

from __future__ import annotations

from .._jit import kernel
from ..bath.model import ThermalBath
from ..errors import InvalidParameterError, require_integer
from .kernels import table_value
from .stochastic_hardcore import run_grid

__all__ = ["MAX_GRID_POINTS", "hard_core_collision"]

MAX_GRID_POINTS = 50_000_000  # bounds memory (3 arrays of float64) and time of one collision


@kernel
def stieltjes_split(count, h, n1, t0, w, c1, c2, q1_table, q2_period, q2_values, q2_slopes):
    """``J = sum_k (w_k - w_{k-1}) (d_k - d_{k-1}) / h`` with ``d = s_1 - s_2 - q_1 + q_2`` on the nodes."""
    total = 0.0
    q2_old, _s = table_value(0.0, q2_period, q2_values, q2_slopes)
    d_old = c1[0] - c2[0] - q1_table[0] + q2_old
    for k in range(1, count):
        q2, _s = table_value(k * h, q2_period, q2_values, q2_slopes)
        d = c1[k] - c2[k] - q1_table[k % n1] + q2
        dw = w[k] - w[k - 1]
        if dw != 0.0:
            total += dw * (d - d_old)
        d_old = d
    return total / h


def hard_core_collision(gamma, temperature_ratio, seed, *, bath_modes=250, resolution=8, temperatures=None):
    """``(epsilon^2, gain_1, gain_2)`` of one hard-core collision in a thermal bath.

    Parameters
    ----------
    gamma : float
        Length ratio ``l_1 / l_2`` in (0, 1] (rod 1 the short one).
    temperature_ratio : float
        ``T_B / E_tr`` of both rods (dimensionless, finite, >= 0).
    seed : int or numpy.random.SeedSequence
        Source of the bath realisation (as :class:`wavecontact.bath.ThermalBath`).
    bath_modes : int
        ``nu_max`` per rod.
    resolution : int
        Grid points per period of the short rod's fastest bath mode (the
        grid step ``h`` is ``Gamma_1 / max(resolution nu_max, 256)``).
    temperatures : pair of float, optional
        ``(T_1, T_2) / E_tr`` per rod instead of ``temperature_ratio`` for both.

    Returns
    -------
    eps2 : float
        Outgoing over incoming translational energy.
    gain_1, gain_2 : float
        Energy each rod's vibrations gained, in units of the incoming
        ``E_tr`` (negative: the rod gave energy); ``gain_1 + gain_2 = 1 - eps2``.
    """
    gamma = float(gamma)
    if not 0.0 < gamma <= 1.0:
        raise InvalidParameterError(f"gamma must lie in (0, 1], got {gamma!r}")
    pair = (temperature_ratio, temperature_ratio) if temperatures is None else tuple(temperatures)
    bath = ThermalBath(tuple(float(t) for t in pair), bath_modes)
    resolution = require_integer("resolution", resolution, 2, 4096)
    lengths = (0.5 * (1.0 + gamma), 0.5 * (1.0 + gamma) / gamma)  # mu = 1/2, V = 1: E_tr = 1/4
    vibrations = None if bath.is_cold else bath.draw(lengths, seed)
    grid = run_grid(gamma, vibrations, bath.modes, 0.0, int(resolution), 256, MAX_GRID_POINTS,
                    what=f"hard-core collision (gamma {gamma:g}, T_B/E_tr {pair})")
    count, w = grid.count, grid.w
    g1 = 1.0 + gamma
    w_end = float(w[count - 1])
    split = stieltjes_split(count, grid.h, grid.n1, grid.t0, w, grid.c1, grid.c2, grid.q1, *grid.rod2_table)
    eps2 = (w_end - 1.0) ** 2
    gain_1 = w_end + split - w_end**2 / g1
    gain_2 = (1.0 - eps2) - gain_1
    return eps2, gain_1, gain_2
