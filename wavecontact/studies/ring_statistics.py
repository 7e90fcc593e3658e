"""Statistics of a run of many collisions on a ring: what the paper reads off Fig. 1-3.

Pure functions of arrays (no solver, no files):

* ``E_tr`` before each collision against its equilibrium mean (Eq. 8,
  :func:`wavecontact.analytic.equilibrium_translational_energy`) and the
  Boltzmann law of its fluctuations (Eq. 9, Kolmogorov-Smirnov test);
* relative modal energies ``w_i^nu = E_i^nu / E_bath`` and the normalised
  spectral entropy ``eta = 1 - h / ln(2N)`` (Eq. 10) against its equilibrium
  mean (Eq. 11, :func:`wavecontact.analytic.equilibrium_spectral_entropy`);
* the correlation ``C_eps(k)`` of successive restitution coefficients (Eq. 13).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..analytic import (
    equilibrium_spectral_entropy,
    equilibrium_spectral_entropy_finite,
    equilibrium_translational_energy,
)
from ..errors import InvalidParameterError, require_integer, require_positive

__all__ = [
    "RingStatistics",
    "decorrelation_stride",
    "default_transient",
    "ks_exponential",
    "relative_modal_energies",
    "relaxation_collisions",
    "restitution_correlation",
    "ring_statistics",
    "settling_index",
    "spectral_entropy",
]


@dataclass
class RingStatistics:
    """What the paper reads off a ring run (Sec. III, Fig. 1-3).

    Energies in the units of ``two_rods`` (initial ``E_tr = mu V^2/2 = 1/4``).
    ``transient`` collisions are discarded before every stationary average.
    Successive values of ``E_tr`` are correlated (``E_tr`` after one
    collision is ``E_tr`` before the next), so the Kolmogorov-Smirnov test of
    Eq. 9 uses every ``ks_stride``-th stationary value
    (:func:`decorrelation_stride`); ``ks_pvalue_all_samples`` is the same
    test on all of them, valid only if they were independent.  The standard
    error of the mean ``E_tr`` is likewise that of the thinned samples.
    Collision counts: ``relaxation_collisions`` from
    :func:`relaxation_collisions`; ``entropy_settling_collisions`` is the
    first collision after which ``eta`` lies within two stationary standard
    deviations of its stationary mean.
    """

    modes: int
    collisions: int
    transient: int
    equilibrium_translational_energy: float
    mean_translational_energy: float
    translational_energy_standard_error: float
    relaxation_collisions: int | None
    translational_energy_autocorrelation_lag1: float
    ks_stride: int
    ks_samples: int
    ks_statistic: float
    ks_pvalue: float
    ks_pvalue_all_samples: float
    equilibrium_spectral_entropy: float
    equilibrium_spectral_entropy_finite: float
    mean_spectral_entropy: float
    spectral_entropy_standard_error: float
    entropy_settling_collisions: int | None
    mean_restitution: float
    restitution_correlation: np.ndarray
    restitution_correlation_coefficient_lag1: float
    mean_relative_spectrum: np.ndarray
    energy_drift: float

    def as_dict(self) -> dict:
        """Plain JSON-ready dictionary."""
        out = {}
        for name, value in self.__dict__.items():
            out[name] = value.tolist() if isinstance(value, np.ndarray) else value
        return out



def ring_statistics(run, transient: int | None = None, max_lag: int = 20, window: int = 20) -> RingStatistics:
    """The paper's numbers for a ring run.

    Parameters
    ----------
    run : RingRun
        The per-collision record (:class:`wavecontact.studies.ring.RingRun`).
    transient : int, optional
        Collisions discarded before the stationary averages; default
        :func:`default_transient`.
    max_lag : int
        Largest lag of ``C_eps(k)`` (reduced if the run is short).
    window : int
        Window of :func:`relaxation_collisions`.
    """
    m = run.n_collisions
    if m < 4:
        raise InvalidParameterError(f"statistics need at least 4 collisions, got {m}")
    e_eq = equilibrium_translational_energy(run.modes, run.reduced_mass, 1.0)
    relax = relaxation_collisions(run.translational_energy, e_eq, window=min(window, m))
    if transient is None:
        transient = default_transient(m, relax)
    transient = require_integer("transient", transient, 0, m - 3)
    stationary_energy = run.translational_energy[transient:]
    stride = decorrelation_stride(stationary_energy)
    ks = ks_exponential(stationary_energy[::stride], e_eq)
    ks_all = ks_exponential(stationary_energy, e_eq)
    energy_dev = stationary_energy - stationary_energy.mean()
    energy_rho1 = float(np.dot(energy_dev[:-1], energy_dev[1:]) / np.dot(energy_dev, energy_dev))
    eta = run.spectral_entropy()
    eta_stationary = eta[transient:]
    eta_tolerance = 2.0 * float(np.std(eta_stationary)) + 1e-15
    eta_settle = settling_index(eta, float(np.mean(eta_stationary)), eta_tolerance, 1)
    if eta_settle is not None:
        eta_settle += 1  # eta[j] is measured after collision j + 1
    lag = int(min(max_lag, m - transient - 2))
    corr = restitution_correlation(run.restitution, lag, transient)
    rho1 = float(corr[1] / corr[0]) if lag >= 1 and corr[0] > 0 else float("nan")
    spectrum = run.relative_modal_energies()[transient:].mean(axis=0)
    drift = float(np.max(np.abs(run.total_energy - run.initial_energy)) / run.initial_energy)
    return RingStatistics(
        modes=run.modes,
        collisions=m,
        transient=transient,
        equilibrium_translational_energy=e_eq,
        mean_translational_energy=float(np.mean(stationary_energy)),
        translational_energy_standard_error=float(
            np.std(stationary_energy, ddof=1) * math.sqrt(stride / stationary_energy.size)
        ),
        relaxation_collisions=relax,
        translational_energy_autocorrelation_lag1=energy_rho1,
        ks_stride=stride,
        ks_samples=int(stationary_energy[::stride].size),
        ks_statistic=float(ks.statistic),
        ks_pvalue=float(ks.pvalue),
        ks_pvalue_all_samples=float(ks_all.pvalue),
        equilibrium_spectral_entropy=equilibrium_spectral_entropy(run.modes),
        equilibrium_spectral_entropy_finite=equilibrium_spectral_entropy_finite(run.modes),
        mean_spectral_entropy=float(np.mean(eta_stationary)),
        spectral_entropy_standard_error=float(
            np.std(eta_stationary, ddof=1)
            * math.sqrt(decorrelation_stride(eta_stationary) / eta_stationary.size)
        ),
        entropy_settling_collisions=eta_settle,
        mean_restitution=float(np.mean(run.restitution[transient:])),
        restitution_correlation=corr,
        restitution_correlation_coefficient_lag1=rho1,
        mean_relative_spectrum=spectrum,
        energy_drift=drift,
    )


# ----------------------------------------------------------------------------
# Statistics of one run (pure functions of arrays)
# ----------------------------------------------------------------------------


def relative_modal_energies(modal_energies) -> np.ndarray:
    """Relative modal energies ``w_i^nu = E_i^nu / E_bath``.

    Parameters
    ----------
    modal_energies : array_like, shape (..., 2, N)
        Energy of mode ``nu`` of rod ``i`` (energy units); the last two axes
        are (rod, mode).  ``E_bath`` is their sum over both rods and all modes.

    Returns
    -------
    ndarray, same shape
        ``w`` summing to 1 over the last two axes; all zeros where the bath
        holds no energy at all (cold bath), where ``w`` is undefined.
    """
    energies = np.asarray(modal_energies, dtype=float)
    if energies.ndim < 2:
        raise InvalidParameterError(
            f"modal_energies must have shape (..., rods, modes), got shape {energies.shape}"
        )
    if not np.all(np.isfinite(energies)) or np.any(energies < 0.0):
        raise InvalidParameterError("modal_energies must be finite and >= 0")
    total = energies.sum(axis=(-2, -1), keepdims=True)
    safe = np.where(total > 0.0, total, 1.0)
    return np.where(total > 0.0, energies / safe, 0.0)


def spectral_entropy(relative_energies) -> np.ndarray:
    """Normalised spectral entropy ``eta = 1 - h / ln(M)``, Eq. 10.

    ``h = -sum w ln w`` over the last two axes (rod, mode), ``M`` the number
    of entries there (``2 N``), with ``0 ln 0 = 0``.  ``eta = 0`` for exact
    equipartition, ``eta = 1`` when one mode holds everything or the bath
    is empty (``h = 0`` at the cold start, as in the paper).

    Parameters
    ----------
    relative_energies : array_like, shape (..., 2, N)
        ``w`` from :func:`relative_modal_energies` (each spectrum sums to 1
        or is all zeros).

    Returns
    -------
    ndarray of shape (...) or float
    """
    w = np.asarray(relative_energies, dtype=float)
    if w.ndim < 2:
        raise InvalidParameterError(f"relative_energies must have shape (..., rods, modes), got {w.shape}")
    count = w.shape[-1] * w.shape[-2]
    if count < 2:
        raise InvalidParameterError("the spectral entropy needs at least two modes in all")
    if np.any(w < 0.0) or not np.all(np.isfinite(w)):
        raise InvalidParameterError("relative modal energies must be finite and >= 0")
    positive = w > 0.0
    terms = np.where(positive, w * np.log(np.where(positive, w, 1.0)), 0.0)
    h = -terms.sum(axis=(-2, -1))
    eta = 1.0 - h / math.log(count)
    return eta if np.ndim(eta) else float(eta)


def restitution_correlation(restitution, max_lag: int = 20, start: int = 0) -> np.ndarray:
    """Correlation function of successive restitution coefficients, Eq. 13.

    ``C(k) = mean_j (eps_j - <eps>) (eps_{j+k} - <eps>)`` over the collisions
    ``j >= start`` for which ``j + k`` is recorded, ``<eps>`` being the mean
    over the same stationary window.  ``C(0)`` is the variance; divide by it
    for the correlation coefficient.

    Parameters
    ----------
    restitution : array_like, shape (M,)
        ``eps_j`` of the collisions ``j = 0 .. M-1`` (dimensionless).
    max_lag : int
        Largest ``k``; needs at least two pairs at that lag.
    start : int
        First collision of the stationary state (``j_0``).

    Returns
    -------
    ndarray, shape (max_lag + 1,)
    """
    eps = np.asarray(restitution, dtype=float)
    if eps.ndim != 1:
        raise InvalidParameterError(f"restitution must be one-dimensional, got shape {eps.shape}")
    if not np.all(np.isfinite(eps)):
        raise InvalidParameterError("restitution must be finite")
    require_integer("max_lag", max_lag, 0)
    require_integer("start", start, 0)
    window = eps[int(start):]
    if window.size < int(max_lag) + 2:
        raise InvalidParameterError(
            f"max_lag must be at most {window.size - 2} for {window.size} stationary collisions, got {max_lag}"
        )
    dev = window - window.mean()
    n = window.size
    return np.array([np.dot(dev[: n - k], dev[k:]) / (n - k) for k in range(int(max_lag) + 1)])


def settling_index(series, level: float, tolerance: float, window: int) -> int | None:
    """First index from which the mean of the next ``window`` values is within ``tolerance`` of ``level``.

    Returns ``None`` if that never happens (the series has not settled).
    """
    values = np.asarray(series, dtype=float)
    window = require_integer("window", window, 1)
    if values.size < window:
        return None
    cumulative = np.concatenate(([0.0], np.cumsum(values)))
    forward_mean = (cumulative[window:] - cumulative[:-window]) / window
    inside = np.nonzero(np.abs(forward_mean - level) <= tolerance)[0]
    return int(inside[0]) if inside.size else None


def relaxation_collisions(translational_energy, equilibrium: float, window: int = 20, z: float = 2.0):
    """Collisions until ``E_tr`` has relaxed to its stationary band.

    ``E_tr`` fluctuates with a standard deviation equal to its mean (Eq. 9),
    so the mean of ``window`` stationary values scatters by about
    ``equilibrium / sqrt(window)``.  The run counts as relaxed from the first
    collision ``j`` (0-based, i.e. the number of collisions that came before)
    whose forward window mean ``E_tr[j : j + window]`` lies within ``z``
    such standard errors of ``equilibrium``.

    Returns
    -------
    int or None
        ``None`` when the run never gets there.
    """
    level = require_positive("equilibrium", equilibrium)
    return settling_index(translational_energy, level, z * level / math.sqrt(window), window)


def ks_exponential(samples, mean: float):
    """Kolmogorov-Smirnov test of samples against the exponential law Eq. 9.

    The hypothesis is fully specified (the mean is Eq. 8's, not fitted), so
    the standard KS p-value applies to independent samples.

    Returns
    -------
    scipy.stats result with ``.statistic`` and ``.pvalue``
    """
    from scipy import stats

    values = np.asarray(samples, dtype=float)
    if values.ndim != 1 or values.size < 2:
        raise InvalidParameterError(f"samples must be one-dimensional with >= 2 values, got shape {values.shape}")
    scale = require_positive("mean", mean)
    return stats.kstest(values, "expon", args=(0.0, scale))


def decorrelation_stride(series, threshold: float = 0.1, max_stride: int = 50) -> int:
    """Smallest lag ``k >= 1`` at which the autocorrelation of ``series`` has fallen below ``threshold``.

    The KS p-value assumes independent samples; taking every ``k``-th value
    of a correlated series brings it closer to that.  The threshold is
    raised to ``3 / sqrt(n)`` when the series is too short to resolve it.
    Returns ``max_stride`` if the correlation never drops that far.
    """
    values = np.asarray(series, dtype=float)
    n = values.size
    if n < 4:
        return 1
    level = max(float(threshold), 3.0 / math.sqrt(n))
    dev = values - values.mean()
    variance = float(np.dot(dev, dev)) / n
    if variance == 0.0:
        return 1
    for k in range(1, min(int(max_stride), n - 2) + 1):
        if abs(float(np.dot(dev[: n - k], dev[k:])) / (n - k) / variance) < level:
            return k
    return int(max_stride)


def default_transient(collisions: int, relaxation: int | None) -> int:
    """Collisions to discard before the stationary averages.

    The paper discards 500 of 4500 collisions.  Here: the larger of that
    fraction (1/9 of the run) and three relaxation times, at most half the
    run (half the run too when ``E_tr`` never relaxed).
    """
    half = collisions // 2
    if relaxation is None:
        return half
    return int(min(half, max(collisions // 9, 3 * relaxation)))
