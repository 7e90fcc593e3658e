"""A stand-in restitution table from a simple analytic model (not computed from rods).

Until tables computed from stochastic rod collisions are at hand (the
thermal-bath study exports them), the gas can be exercised with this model:
the relative velocity leaves the collision as

    V' = -(gamma V + sqrt(1 - gamma^2) eta),   eta ~ Normal(0, T_B / mu),

the cold hard-core restitution ``gamma`` plus a thermal kick whose size grows
with the bath temperature.  Hence ``epsilon = |gamma + sqrt((1 - gamma^2) R / 2) zeta|``
with ``zeta`` standard normal and ``R = T_B / E_tr``.  It has the two
features of the vibration rule that matter for the collapse: the cold limit
``epsilon -> gamma`` and energy flowing back from hot baths to slow pairs
(``epsilon^2 > 1`` when ``R`` is large).  The lost energy is split equally
between the two baths.
"""

from __future__ import annotations

import numpy as np
from scipy.special import ndtr

from ..restitution_table import RestitutionTable

__all__ = ["thermal_kick_table"]


def _eps_quantiles(gamma, ratio, levels, points=4001):
    """Quantiles of ``|gamma + a zeta|`` (a folded normal), by inverting its CDF on a fine grid."""
    spread = np.sqrt((1.0 - gamma**2) * ratio / 2.0)
    if spread == 0.0:
        return np.full(levels.size, gamma)
    top = gamma + 9.0 * spread
    e = np.linspace(0.0, top, points)
    cdf = ndtr((e - gamma) / spread) - ndtr((-e - gamma) / spread)
    cdf = (cdf - cdf[0]) / (cdf[-1] - cdf[0])
    cdf = np.maximum.accumulate(cdf)
    keep = np.concatenate([[True], np.diff(cdf) > 0])
    return np.interp(levels, cdf[keep], e[keep])


def thermal_kick_table(gamma=None, temperature_ratio=None, levels=201, bath_modes=250) -> RestitutionTable:
    """The model table (see the module docstring) on a ``(gamma, T_B/E_tr)`` grid.

    Parameters
    ----------
    gamma : array_like, optional
        Length ratios (default 0.3 ... 1 in steps of 0.05).
    temperature_ratio : array_like, optional
        ``T_B/E_tr`` (default 0 and 31 points from 1e-3 to 1e3, geometric).
    levels : int
        Probability levels (equally spaced from 0 to 1; the quantile at level
        1 is the model's value 9 standard deviations out).
    bath_modes : int
        Heat capacity of each rod's bath in modes.
    """
    gamma = np.linspace(0.3, 1.0, 15) if gamma is None else np.asarray(gamma, dtype=float)
    ratio = (np.concatenate([[0.0], np.geomspace(1e-3, 1e3, 31)]) if temperature_ratio is None
             else np.asarray(temperature_ratio, dtype=float))
    probability = np.linspace(0.0, 1.0, int(levels))
    quantiles = np.empty((gamma.size, ratio.size, probability.size))
    for i, g in enumerate(gamma):
        for j, r in enumerate(ratio):
            quantiles[i, j] = _eps_quantiles(g, r, probability) ** 2
    return RestitutionTable(gamma, ratio, probability, quantiles, np.full((gamma.size, ratio.size), 0.5),
                            kappa=np.inf, bath_modes=bath_modes, samples_per_point=0,
                            solver="thermal-kick model (analytic stand-in)", seed=0)
