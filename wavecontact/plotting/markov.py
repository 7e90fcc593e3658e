"""Figures of a Markov run (the paper's Fig. 10 and the cooling), drawn with matplotlib's Agg backend.

Nothing numerical imports this module; it only reads
:class:`wavecontact.studies.markov.MarkovResult` objects.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

__all__ = ["plot_cooling", "plot_stationary_distribution"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def plot_stationary_distribution(result, path, burn_in: int | None = None, dpi: int = 150) -> Path:
    """Fig. 10: the distribution function of ``E_tr / T_B^0`` in the stationary part, and Eq. 30's.

    Left: ``D(E) = P(E_tr / T_B^0 <= E)`` of the pooled stationary states against
    ``1 - exp(-E)``; right: the histogram density on a log scale against ``exp(-E)``.
    """
    plt = _pyplot()
    states = np.sort(result.stationary(burn_in).ravel())
    summary = result.summary(burn_in)
    fig, (left, right) = plt.subplots(1, 2, figsize=(9.0, 3.6))
    x = np.linspace(0.0, max(6.0, float(states[-1])), 400)
    left.plot(states, np.arange(1, states.size + 1) / states.size, lw=1.5, label="Markov chain")
    left.plot(x, 1.0 - np.exp(-x), "k--", lw=1.0, label="Boltzmann, Eq. 30")
    left.set_xlim(0.0, 6.0)
    left.set_xlabel("$E_{tr} / T_B^0$")
    left.set_ylabel("distribution function")
    left.legend(loc="lower right", fontsize=8)
    counts, edges = np.histogram(states, bins=np.linspace(0.0, 8.0, 33))
    centres = 0.5 * (edges[1:] + edges[:-1])
    density = counts / (states.size * np.diff(edges))
    band = np.sqrt(np.maximum(counts, 1)) / (states.size * np.diff(edges))
    right.errorbar(centres, density, yerr=band, fmt="o", ms=3, label="Markov chain (counting error)")
    right.plot(x, np.exp(-x), "k--", lw=1.0, label="$\\exp(-E_{tr}/T_B^0)$")
    right.set_yscale("log")
    right.set_xlim(0.0, 8.0)
    right.set_xlabel("$E_{tr} / T_B^0$")
    right.set_ylabel("density")
    right.legend(loc="upper right", fontsize=8)
    spec = result.spec
    kappa = "inf" if math.isinf(spec.kappa) else f"{spec.kappa:g}"
    fig.suptitle(
        f"rule {spec.rule}, $\\gamma$ = {spec.gamma:g}, $\\kappa$ = {kappa}, {spec.chains} x {spec.steps} steps: "
        f"mean {summary['mean_energy']:.3f}, KS p = {summary['ks_pvalue']:.2g}",
        fontsize=9,
    )
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def plot_cooling(results: dict, path, dpi: int = 150) -> Path:
    """Mean ``E_tr / T_B^0`` over chains against the collision number, one curve per labelled run."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    for label, result in results.items():
        mean = result.energy.mean(axis=0)
        error = result.energy.std(axis=0, ddof=1) / math.sqrt(result.spec.chains)
        steps = np.arange(mean.size)
        ax.plot(steps, mean, lw=1.5, label=label)
        ax.fill_between(steps, mean - 2 * error, mean + 2 * error, alpha=0.25)
    ax.axhline(1.0, color="k", ls="--", lw=0.8, label="stationary mean $T_B^0$")
    ax.set_yscale("log")
    ax.set_xlabel("collision $j$")
    ax.set_ylabel("$\\langle E_{tr}(j) \\rangle / T_B^0$")
    ax.legend(fontsize=8)
    specs = [result.spec for result in results.values()]
    gammas = ", ".join(sorted({f"{s.gamma:g}" for s in specs}))
    ax.set_title(f"cooling from $E_{{tr}}(0)$: $\\gamma$ = {gammas}, {specs[0].chains} chains per run; bands: 2 SE",
                 fontsize=9)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path
