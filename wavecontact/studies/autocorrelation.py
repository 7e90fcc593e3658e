"""The integrated autocorrelation time of stationary chains, and the standard error of their mean.

For a stationary series with autocorrelation ``rho(t)`` the variance of the mean of ``N``
values is ``sigma^2 tau / N`` (for ``N >> tau``), with the integrated autocorrelation time

    tau = 1 + 2 sum_{t >= 1} rho(t).

The sum is estimated up to a window ``M`` chosen automatically as the smallest ``M`` with
``M >= c tau(M)`` (Sokal's rule, ``c = 5``; the choice of ``emcee.autocorr``): beyond it the
estimated ``rho(t)`` is mostly noise, whose sum would add variance, while a shorter window
cuts off correlation.  The estimate is reliable when each chain is many ``tau`` long (``emcee``
asks for 50).  Several chains of one process pool their autocovariances (each chain centred on
its own mean); the standard error of the pooled mean is ``sqrt(C(0) tau / N)`` over all ``N``
values.  For an AR(1) process ``x_t = rho x_{t-1} + noise``, ``tau = (1 + rho) / (1 - rho)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError

__all__ = ["AutocorrelationTime", "autocorrelation", "autocovariance", "integrated_autocorrelation_time"]

SOKAL_C = 5.0  # window factor of the automatic window (Sokal; emcee's default)


def _chains(series) -> np.ndarray:
    values = np.asarray(series, dtype=float)
    if values.ndim == 1:
        values = values[None, :]
    if values.ndim != 2 or values.shape[1] < 2:
        raise InvalidParameterError("series must be a chain (n,) or chains (chains, n) with n >= 2 values")
    if not np.all(np.isfinite(values)):
        raise InvalidParameterError("series must be finite")
    return values


def autocovariance(series) -> np.ndarray:
    """Autocovariance ``C(t)``, ``t`` from 0 to ``n - 1``, pooled over chains (each centred on its own mean).

    ``C(t) = mean over chains of sum_s (x_s - m)(x_{s+t} - m) / n`` (the biased estimator, which
    keeps the estimated spectrum non-negative), by FFT with zero padding.
    """
    values = _chains(series)
    n = values.shape[1]
    size = 1 << (2 * n - 1).bit_length()  # >= 2n: no wrap-around
    centred = values - values.mean(axis=1, keepdims=True)
    spectrum = np.fft.rfft(centred, size, axis=1)
    return np.fft.irfft(spectrum * spectrum.conj(), size, axis=1)[:, :n].mean(axis=0) / n


def autocorrelation(series) -> np.ndarray:
    """Normalised autocorrelation ``rho(t) = C(t) / C(0)`` pooled over chains (all zeros but ``rho(0) = 1``
    for a constant series)."""
    covariance = autocovariance(series)
    if covariance[0] == 0.0:
        out = np.zeros_like(covariance)
        out[0] = 1.0
        return out
    return covariance / covariance[0]


@dataclass(frozen=True)
class AutocorrelationTime:
    """The integrated autocorrelation time of chains and the standard error of their pooled mean.

    Attributes
    ----------
    tau : float
        Integrated autocorrelation time (in steps; 1 for independent values).
    window : int
        The summation window ``M`` (steps).
    mean : float
        Mean over all values.
    variance : float
        ``C(0)``, the pooled variance about each chain's mean.
    values : int
        Number of values ``N`` (all chains).
    chain_length : int
        Values per chain.
    standard_error : float
        ``sqrt(variance tau / N)``: the standard error of :attr:`mean`.
    """

    tau: float
    window: int
    mean: float
    variance: float
    values: int
    chain_length: int
    standard_error: float

    @property
    def effective_samples(self) -> float:
        """``N / tau``: independent values worth as much as the chains for the mean."""
        return self.values / self.tau

    @property
    def reliable(self) -> bool:
        """Each chain is at least 50 ``tau`` long (``emcee``'s rule for a trustworthy estimate)."""
        return self.chain_length >= 50.0 * self.tau


def integrated_autocorrelation_time(series, c: float = SOKAL_C) -> AutocorrelationTime:
    """Integrated autocorrelation time with Sokal's automatic window, and the mean's standard error.

    Parameters
    ----------
    series : array_like (n,) or (chains, n)
        One stationary chain, or several chains of the same process (equal lengths, n >= 2).
    c : float
        Window factor: the window is the smallest ``M`` with ``M >= c tau(M)`` (default 5).

    Returns
    -------
    AutocorrelationTime
    """
    if isinstance(c, bool) or not isinstance(c, (int, float)) or not 0.0 < c < math.inf:
        raise InvalidParameterError(f"c must be a positive number, got {c!r}")
    values = _chains(series)
    covariance = autocovariance(values)
    count = values.size
    if covariance[0] == 0.0:
        return AutocorrelationTime(1.0, 0, float(values.mean()), 0.0, count, values.shape[1], 0.0)
    rho = covariance / covariance[0]
    taus = 2.0 * np.cumsum(rho) - 1.0  # tau(M) = 1 + 2 sum_{t=1}^{M} rho(t)
    short = np.arange(taus.size) < c * taus
    window = int(np.argmin(short)) if not np.all(short) else taus.size - 1
    tau = max(float(taus[window]), 1.0 / count)  # a strongly anticorrelated estimate stays positive
    return AutocorrelationTime(tau, window, float(values.mean()), float(covariance[0]), count, values.shape[1],
                               math.sqrt(float(covariance[0]) * tau / count))
