"""Collision-rule tables from thermal ensembles: p(eps^2) as quantile functions on a (gamma, T_B/E_tr) grid.

The table (:class:`wavecontact.restitution_table.RestitutionTable`) serves two
kinds of many-particle codes: those that take one restitution per material
pair (LIGGGHTS, LAMMPS, MercuryDPM, Kratos: use
:meth:`~wavecontact.restitution_table.RestitutionTable.mean_restitution`) and
those that call back into user code per collision (Chrono, DEM-Engine,
REBOUND: draw with
:meth:`~wavecontact.restitution_table.RestitutionTable.sample`).  See
``docs/bath.md`` and ``examples/restitution_table_dem.py``.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InvalidParameterError, require_integer
from ..restitution_table import RestitutionTable
from .ensemble import ensemble

__all__ = ["MAX_TABLE_SAMPLES", "restitution_table"]

MAX_TABLE_SAMPLES = 50_000_000  # all points together


def restitution_table(gammas, temperatures, samples, seed, *, kappa=100.0, bath_modes=250, levels=101, executor=None,
                      progress=False, **options) -> RestitutionTable:
    """Tabulate the law of ``epsilon^2`` from one thermal ensemble per grid point.

    Parameters
    ----------
    gammas : sequence of float
        Length ratios, strictly ascending in (0, 1].
    temperatures : sequence of float
        ``T_B / E_tr``, strictly ascending, >= 0.
    samples : int
        Collisions per grid point.
    seed : int
        Root seed; point ``(a, b)`` uses ``seed + a * len(temperatures) + b``.
    kappa : float
        Finite softness (the per-rod split needs it); the statistics hardly
        change above about 50 (docs/bath.md).
    bath_modes : int
        ``nu_max``.
    levels : int
        Probability levels ``0, 1/(levels-1), ..., 1`` of the quantile functions, >= 2.
    executor, progress, **options
        As for :func:`wavecontact.ensemble` (e.g. ``rtol``).

    Returns
    -------
    RestitutionTable
        ``eps2_quantiles`` are the empirical quantiles (linear between order
        statistics); ``rod1_share`` is ``sum Delta E_1 / sum (Delta E_1 + Delta E_2)``;
        ``rod_gain`` and ``rod_gain_standard_error`` are each rod's mean gain per collision and
        its standard error (sample standard deviation over ``sqrt(samples)``), in units of
        ``E_tr``.
    """
    gammas = np.asarray(gammas, dtype=float)
    temperatures = np.asarray(temperatures, dtype=float)
    if not math.isfinite(float(kappa)):
        raise InvalidParameterError("restitution tables need a finite kappa (the hard-core grid gives no per-rod split)")
    levels = require_integer("levels", levels, 2, 100_001)
    if gammas.ndim != 1 or temperatures.ndim != 1 or gammas.size * temperatures.size * int(samples) > MAX_TABLE_SAMPLES:
        raise InvalidParameterError(f"a table may hold at most {MAX_TABLE_SAMPLES} collisions in all")
    probability = np.linspace(0.0, 1.0, int(levels))
    quantiles = np.zeros((gammas.size, temperatures.size, probability.size))
    share = np.zeros((gammas.size, temperatures.size))
    gain, gain_error = np.zeros(share.shape + (2,)), np.zeros(share.shape + (2,))
    for a, gamma in enumerate(gammas):
        for b, temperature in enumerate(temperatures):
            result = ensemble(gamma, kappa, temperature, samples, seed + a * temperatures.size + b,
                              bath_modes=bath_modes, executor=executor, progress=progress, energy_split=True, **options)
            quantiles[a, b] = np.quantile(result.restitution**2, probability)
            share[a, b] = result.rod1_share
            gain[a, b], gain_error[a, b] = _mean_and_standard_error(result.vibration_energy_gain / ENSEMBLE_E_TR)
    return RestitutionTable(gammas, temperatures, probability, quantiles, share, kappa=float(kappa),
                            bath_modes=bath_modes, samples_per_point=int(samples), solver="delay", seed=int(seed),
                            rod_gain=gain, rod_gain_standard_error=gain_error)


ENSEMBLE_E_TR = 0.25  # the translational energy of the ensembles' collisions (mu V^2 / 2 with mu = 1/2, V = 1)


def _mean_and_standard_error(values: np.ndarray) -> tuple:
    """Column means of ``values`` (samples along axis 0) and their standard errors (0 for one sample)."""
    n = values.shape[0]
    spread = np.std(values, axis=0, ddof=1) if n > 1 else np.zeros(values.shape[1:])
    return np.mean(values, axis=0), spread / np.sqrt(n)
