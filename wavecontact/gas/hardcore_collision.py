"""One hard-core thermal collision with each rod's share of the energy (the gas's solve rule).

The computation belongs to the delay solver
(:mod:`wavecontact.delay.stochastic_hardcore_split`); the gas reaches it through
the solver registry, like every study.
"""

from __future__ import annotations

from ..solvers import get_solver

__all__ = ["hard_core_collision"]


def hard_core_collision(gamma, temperature_ratio, seed, *, bath_modes=250, resolution=8, temperatures=None):
    """``(epsilon^2, gain_1, gain_2)`` of one hard-core collision in a thermal bath.

    See :meth:`wavecontact.delay.solver.DelaySolver.hard_core_thermal_split` for the
    parameters (``temperature_ratio`` is ``T_B / E_tr``, dimensionless; the gains are
    in units of the incoming ``E_tr``, ``gain_1 + gain_2 = 1 - eps2``).
    """
    return get_solver("delay").hard_core_thermal_split(gamma, temperature_ratio, seed, bath_modes=bath_modes,
                                                       resolution=resolution, temperatures=temperatures)
