"""One hard-core thermal collision with each rod's share of the energy (the gas's solve rule).

The computation belongs to the solver that offers the stochastic hard-core mode
(the delay solver, :mod:`wavecontact.delay.stochastic_hardcore_split`); the gas
reaches it through the solver registry, like every study.
"""

from __future__ import annotations

from ..solvers import solver_for
from ..solvers.base import HARD_CORE_THERMAL

__all__ = ["hard_core_collision"]


def hard_core_collision(gamma, temperature_ratio, seed, *, bath_modes=250, resolution=8, temperatures=None):
    """``(epsilon^2, gain_1, gain_2)`` of one hard-core collision in a thermal bath.

    See :meth:`wavecontact.solvers.base.SolverBase.hard_core_thermal_split` (the delay solver's) for the
    parameters (``temperature_ratio`` is ``T_B / E_tr``, dimensionless; the gains are
    in units of the incoming ``E_tr``, ``gain_1 + gain_2 = 1 - eps2``).
    """
    return solver_for(HARD_CORE_THERMAL).hard_core_thermal_split(gamma, temperature_ratio, seed, bath_modes=bath_modes,
                                                                 resolution=resolution, temperatures=temperatures)
