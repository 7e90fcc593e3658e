"""The data behind the paper's thermal-bath figures (Fig. 4, 7, 8, 9), solver-independent.

Each function returns plain arrays (and the ensembles it ran); drawing is in
:mod:`wavecontact.plotting.bath`, the commands in ``wavecontact bath-figure``.
"""

from __future__ import annotations

import concurrent.futures
import math

import numpy as np

from ..bath.model import ThermalBath
from ..bath.noise import covariance_eq19, covariance_series, noise_tables
from .ensemble import ensemble, sample_seed

__all__ = ["FIG8_TEMPERATURES", "FIG9_CASES", "noise_covariance", "restitution_law", "spread_against_temperature",
           "stochastic_histories"]

FIG8_TEMPERATURES = tuple(np.round(np.linspace(0.1, 1.0, 10), 10))
FIG9_CASES = ((0.6173, 0.1), (0.6173, 1.0), (0.2173, 1.0))  # (gamma, T_B/E_tr): E_tr/T_B = 10, 1, 1


def noise_covariance(gamma=0.6173, realisations=400, modes=250, seed=0, max_lag=6.0, lags=241, points=4096):
    """Fig. 4: ``C_Q(tau) / sigma^2`` of sampled noise against Eq. 19.

    Each realisation's ``Q`` is tabulated (FFT) on ``points`` nodes per rod
    period and ``<Q(t') Q(t' + tau)>`` is averaged over ``t'`` (a period of rod 1)
    and over realisations; the band is two standard errors over realisations.

    Returns
    -------
    dict
        ``lag``, ``sampled``, ``band`` (2 SE), ``eq19`` (infinitely many modes),
        ``series`` (the same ``modes`` as the samples), all divided by ``sigma^2 = kappa^2 T / (2 E_tr)``.
    """
    kappa, ratio = 1.0, 1.0
    sigma2 = kappa**2 * ratio / 2.0
    lengths = (0.5 * (1 + gamma), 0.5 * (1 + gamma) / gamma)
    periods = (1 + gamma, 1 + 1 / gamma)
    lag = np.linspace(0.0, max_lag, lags)
    starts = np.linspace(0.0, periods[0], 64, endpoint=False)
    bath = ThermalBath(ratio, modes)
    per_realisation = []
    for j in range(realisations):
        v = bath.draw(lengths, sample_seed(seed, j))
        tables = noise_tables(v.noise_coefficients(kappa), periods, 0.0, 0.0, 8)
        def q(t, tables=tables):
            total = np.zeros_like(t)
            for i in range(2):
                n = tables.values.shape[1]
                x = np.mod(t, tables.periods[i]) / tables.periods[i] * n
                total += np.interp(x, np.arange(n + 1), np.append(tables.values[i], tables.values[i][0]))
            return total
        q0 = q(starts)
        per_realisation.append([np.mean(q0 * q(starts + tau)) for tau in lag])
    per_realisation = np.array(per_realisation) / sigma2
    sampled = per_realisation.mean(axis=0)
    band = 2.0 * per_realisation.std(axis=0, ddof=1) / math.sqrt(realisations)
    return {
        "lag": lag, "sampled": sampled, "band": band,
        "eq19": covariance_eq19(lag, gamma, kappa, (ratio, ratio)) / sigma2,
        "series": covariance_series(lag, gamma, kappa, (ratio, ratio), modes) / sigma2,
        "gamma": gamma, "modes": modes, "realisations": realisations,
    }


def stochastic_histories(gamma=0.6, temperature=1.0, kappas=(5.0, 100.0), seed=1, modes=250, tau_free=1.0):
    """Fig. 7: ``W(tau)`` of one realisation at each ``kappa``, time shifted so that ``tau_free = 1``.

    The same realisation (seed) drives every kappa.
    """
    from ..api import collide

    out = []
    for kappa in kappas:
        result = collide(gamma, kappa, "delay", bath_temperature=temperature, bath_modes=modes, seed=seed)
        shift = result.extra["free_flight_time"] - tau_free
        out.append({"kappa": kappa, "tau": result.time - shift, "W": result.velocity_increase,
                    "restitution": result.restitution})
    return out


def spread_against_temperature(gammas=(0.6173, 0.2173), temperatures=FIG8_TEMPERATURES, kappa=250.0, samples=2500,
                               seed=8, modes=250, executor=None, progress=False, **options):
    """Fig. 8: mean and standard deviation of epsilon (with standard errors) against ``T_B / E_tr``.

    Point ``(g, r)`` uses root seed ``seed + 1000 g_index + r_index``.  With an ``executor`` the
    points run at once (one thread each hands its batches to the executor), so the workers stay
    busy from the first batch to the last; the numbers are those of the serial run.

    Returns
    -------
    dict
        ``gamma`` (G,), ``temperature`` (R,), ``mean``, ``mean_error``, ``std``, ``std_error`` (G, R).
    """
    keys = ("mean", "mean_error", "std", "std_error")
    table = {k: np.zeros((len(gammas), len(temperatures))) for k in keys}
    points = [(a, b, gamma, temperature) for a, gamma in enumerate(gammas) for b, temperature in enumerate(temperatures)]

    def run(point):
        a, b, gamma, temperature = point
        return ensemble(gamma, kappa, temperature, samples, seed + 1000 * a + b, bath_modes=modes,
                        executor=executor, progress=progress, **options)

    if executor is None:
        results = [run(point) for point in points]
    else:
        # every point's batches are queued at once: no worker waits while a point's last batch finishes
        with concurrent.futures.ThreadPoolExecutor(len(points)) as threads:
            results = list(threads.map(run, points))
    for (a, b, _gamma, _temperature), result in zip(points, results):
        for key, value in zip(keys, (result.mean, result.standard_error, result.std, result.std_standard_error)):
            table[key][a, b] = value
    return {"gamma": np.array(gammas), "temperature": np.array(temperatures), "kappa": kappa, "samples": samples,
            "bath_modes": modes, **table}


def restitution_law(cases=FIG9_CASES, kappa=100.0, samples=8000, seed=9, modes=250, executor=None, progress=False,
                    **options):
    """Fig. 9: the ensembles behind ``p(eps^2)`` and ``D(eps^2)`` for each ``(gamma, T_B/E_tr)`` case."""
    return [ensemble(gamma, kappa, temperature, samples, seed + j, bath_modes=modes, executor=executor,
                     progress=progress, **options) for j, (gamma, temperature) in enumerate(cases)]
