"""Integrated autocorrelation time (Sokal's automatic window) against AR(1) processes.

Reference: for x_t = rho x_{t-1} + sqrt(1 - rho^2) e_t (unit stationary variance) the
autocorrelation is rho^t, so tau = (1 + rho) / (1 - rho) and the variance of the mean of N
values is tau / N (to O(1/N^2)).  The processes are generated here with scipy's lfilter,
started from their stationary law; checks pool realisations and take their tolerances from
the realisations' spread or from the chi-square law.
"""

import math

import numpy as np
import pytest
from scipy import signal, stats

from wavecontact.errors import InvalidParameterError
from wavecontact.studies.autocorrelation import autocorrelation, integrated_autocorrelation_time

REALISATIONS = 12


def ar1(rho, chains, n, seed):
    """``chains`` stationary AR(1) chains of ``n`` values, unit variance."""
    rng = np.random.default_rng(seed)
    start = rng.standard_normal(chains)
    noise = rng.standard_normal((chains, n))
    out = np.empty((chains, n))
    for c in range(chains):
        out[c] = signal.lfilter([math.sqrt(1.0 - rho**2)], [1.0, -rho], noise[c], zi=[rho * start[c]])[0]
    return out


def realisations(rho, chains=4, n=20_000):
    return [ar1(rho, chains, n, seed) for seed in np.random.SeedSequence(2024).spawn(REALISATIONS)]


@pytest.mark.parametrize("rho", [0.0, 0.5, 0.77, 0.9])
def test_tau_of_ar1_matches_the_analytic_value(rho):
    exact = (1.0 + rho) / (1.0 - rho)
    taus = np.array([integrated_autocorrelation_time(x).tau for x in realisations(rho)])
    spread = taus.std(ddof=1) / math.sqrt(taus.size)
    assert abs(taus.mean() - exact) < 3.0 * spread + 1e-3 * exact
    assert spread < 0.03 * exact  # the test resolves a few percent


def test_standard_error_of_the_pooled_mean_has_the_ar1_variance():
    """z = mean / SE over independent realisations is standard normal: sum z^2 follows chi2(12).
    Without the autocorrelation (SE = sqrt(var / N)) the sum would be about tau = 7.7 times larger."""
    rho = 0.77
    z = []
    for x in realisations(rho):
        result = integrated_autocorrelation_time(x)
        exact_error = math.sqrt((1.0 + rho) / (1.0 - rho) / x.size)
        assert abs(result.standard_error / exact_error - 1.0) < 0.15
        assert result.reliable and result.window >= 5.0 * result.tau
        z.append(result.mean / result.standard_error)
    total = float(np.sum(np.square(z)))
    low, high = stats.chi2.ppf([1e-4, 1.0 - 1e-4], len(z))
    assert low < total < high


def test_autocorrelation_of_ar1_falls_like_rho_to_the_lag():
    rho = 0.77
    curves = np.array([autocorrelation(x)[:6] for x in realisations(rho)])
    spread = curves.std(axis=0, ddof=1) / math.sqrt(REALISATIONS)
    assert np.all(np.abs(curves.mean(axis=0) - rho ** np.arange(6)) <= 3.0 * spread + 1e-12)


def test_a_constant_series_and_bad_input():
    result = integrated_autocorrelation_time(np.ones((2, 10)))
    assert (result.tau, result.standard_error, result.mean) == (1.0, 0.0, 1.0)
    for bad in (np.ones(1), np.array([1.0, np.nan]), np.ones((2, 2, 2))):
        with pytest.raises(InvalidParameterError):
            integrated_autocorrelation_time(bad)
    with pytest.raises(InvalidParameterError, match="c must"):
        integrated_autocorrelation_time(np.arange(5.0), c=0)
