"""Figures of a ring run (the paper's Fig. 1-3), drawn with matplotlib's Agg backend.

Nothing numerical imports this module; it only reads a
:class:`wavecontact.studies.ring.RingRun` and its statistics.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..analytic import equilibrium_spectral_entropy
from ..io.files import FIGURE_SUFFIXES, check_output_file
from ..studies.ring import RingRun
from ..studies.ring_statistics import RingStatistics

__all__ = [
    "FIGURE_NAMES",
    "plot_restitution_correlation",
    "plot_ring_figures",
    "plot_spectral_entropy",
    "plot_translational_energy",
]

FIGURE_NAMES = {
    "energy": "fig1_translational_energy.png",
    "entropy": "fig2_spectral_entropy.png",
    "correlation": "fig3_restitution_correlation.png",
}


# fixed margins of the one-panel figures (fractions of the figure): the labels fit at the sizes below, and
# matplotlib's constrained layout, which measures every label to find them, took 40 % of the figures' time
_MARGINS = {"left": 0.105, "right": 0.975, "bottom": 0.115, "top": 0.93}


def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _title(run: RingRun) -> str:
    kappa = "inf" if math.isinf(run.kappa) else f"{run.kappa:g}"
    return f"$\\gamma$ = {run.gamma:g}, $\\kappa$ = {kappa}, N = {run.modes} modes per rod"


def _running_mean(values: np.ndarray, window: int) -> np.ndarray:
    """Centred moving average (shorter windows at the ends)."""
    window = max(1, min(window, values.size))
    cumulative = np.concatenate(([0.0], np.cumsum(values)))
    half = window // 2
    lo = np.clip(np.arange(values.size) - half, 0, values.size)
    hi = np.clip(np.arange(values.size) - half + window, 0, values.size)
    return (cumulative[hi] - cumulative[lo]) / (hi - lo)


def plot_translational_energy(run: RingRun, path, statistics: RingStatistics | None = None, dpi: int = 150) -> Path:
    """Fig. 1: ``E_tr`` before each collision, and the stationary modal spectrum.

    Left: ``E_tr`` against collision number (log scale) with a running
    mean and the equipartition value Eq. 8.  Right: the relative modal
    energies ``w_i^nu`` averaged over the stationary collisions, grey for
    the short rod (1), black for the long rod (2), with the equipartition
    level ``1 / (2 N)``.
    """
    plt = _pyplot()
    stats = statistics if statistics is not None else run.statistics()
    collisions = np.arange(run.n_collisions)  # E_tr[j] is measured after j collisions
    energy = run.translational_energy
    fig, (ax, ax_spec) = plt.subplots(1, 2, figsize=(11.5, 4.4), gridspec_kw={"width_ratios": [1.35, 1.0]})
    fig.subplots_adjust(left=0.068, right=0.988, bottom=0.115, top=0.925, wspace=0.2)
    ax.semilogy(collisions, energy, ".", ms=2.5, color="0.55", label="$E_{tr}$ before each collision")
    window = max(5, min(50, run.n_collisions // 40))
    ax.semilogy(collisions, _running_mean(energy, window), "-", lw=1.3, color="C0",
                label=f"running mean ({window} collisions)")
    ax.axhline(stats.equilibrium_translational_energy, ls="--", color="k", lw=1.2,
               label=r"Eq. 8: $\mu V^2 / (2(2N+1))$")
    if stats.relaxation_collisions is not None:
        ax.axvline(stats.relaxation_collisions, ls=":", color="C3", lw=1.2,
                   label=f"relaxed after {stats.relaxation_collisions} collisions")
    ax.axvspan(0, stats.transient, color="0.92", zorder=0, label=f"transient ({stats.transient}), not averaged")
    ax.set_xlim(0, max(1, run.n_collisions - 1))
    low = max(float(np.min(energy[energy > 0])) if np.any(energy > 0) else 1e-6,
              stats.equilibrium_translational_energy * 1e-3)
    ax.set_ylim(low * 0.7, float(np.max(energy)) * 1.6)
    ax.set_xlabel("collision number")
    ax.set_ylabel(r"translational energy $E_{tr}$  (start: $\mu V^2/2 = 1/4$)")
    ax.set_title(_title(run), fontsize=10)
    ax.legend(loc="upper right", fontsize=8, framealpha=0.9)

    spectrum = stats.mean_relative_spectrum
    modes = np.arange(1, run.modes + 1)
    width = 0.42
    ax_spec.bar(modes - width / 2, spectrum[0], width=width, color="0.65", label="rod 1 (short)")
    ax_spec.bar(modes + width / 2, spectrum[1], width=width, color="k", label="rod 2 (long)")
    ax_spec.axhline(1.0 / (2 * run.modes), ls="--", color="C3", lw=1.2, label=r"equipartition $1/(2N)$")
    ax_spec.set_xlim(0.3, run.modes + 0.7)
    ax_spec.set_ylim(0, max(float(spectrum.max()) * 1.25, 1.5 / (2 * run.modes)))
    ax_spec.set_xlabel(r"mode number $\nu$")
    ax_spec.set_ylabel(r"mean relative modal energy $\langle w_i^{(\nu)} \rangle$")
    averaged = run.n_collisions - stats.transient
    ax_spec.set_title(f"modal spectrum averaged over collisions {stats.transient + 1}-{run.n_collisions} "
                      f"({averaged})", fontsize=10)
    ax_spec.legend(loc="upper right", fontsize=8, framealpha=0.9)
    return _save(fig, path, dpi)


def plot_spectral_entropy(runs: RingRun | Sequence[RingRun], path, dpi: int = 150) -> Path:
    """Fig. 2: normalised spectral entropy ``eta`` against collision number.

    Several runs (e.g. different ``N``) share the axes, each with its own
    Eq. 11 level ``0.423 / ln(2N)`` as a dashed line of the same colour.
    """
    plt = _pyplot()
    runs = [runs] if isinstance(runs, RingRun) else list(runs)
    if not runs:
        raise ValueError("plot_spectral_entropy needs at least one run")
    fig, ax = plt.subplots(figsize=(7.5, 4.6))
    fig.subplots_adjust(**_MARGINS)
    for index, run in enumerate(runs):
        colour = f"C{index}"
        eta = run.spectral_entropy()
        collisions = np.arange(1, run.n_collisions + 1)  # eta[j] is measured after collision j + 1
        ax.semilogx(collisions, eta, "-", lw=0.8, color=colour, alpha=0.85, label=f"N = {run.modes}")
        level = equilibrium_spectral_entropy(run.modes)
        if len(runs) == 1:
            label = f"Eq. 11: 0.423 / ln(2N) = {level:.4f}"
        else:
            label = "Eq. 11 (dashed, same colour)" if index == 0 else None
        ax.axhline(level, ls="--", color=colour, lw=1.2, label=label)
    ax.set_xlim(1, max(r.n_collisions for r in runs))
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("collision number")
    ax.set_ylabel(r"spectral entropy $\eta = 1 - h/\ln(2N)$")
    ax.set_title(_title(runs[0]) if len(runs) == 1 else
                 f"$\\gamma$ = {runs[0].gamma:g}, $\\kappa$ = {runs[0].kappa:g}", fontsize=10)
    ax.legend(loc="upper right", fontsize=8, framealpha=0.9)
    ax.grid(alpha=0.3, which="both")
    return _save(fig, path, dpi)


def plot_restitution_correlation(run: RingRun, path, statistics: RingStatistics | None = None,
                                 dpi: int = 150) -> Path:
    """Fig. 3: correlation ``C_eps(k)`` (Eq. 13) of the restitution coefficients in the stationary state.

    The shaded band is ``+-2 C(0) / sqrt(n)``: where the estimate of
    ``C(k)`` for uncorrelated coefficients would fall 95 % of the time.
    """
    plt = _pyplot()
    stats = statistics if statistics is not None else run.statistics()
    corr = stats.restitution_correlation
    lags = np.arange(corr.size)
    n = run.n_collisions - stats.transient
    noise = 2.0 * corr[0] / math.sqrt(n)
    fig, ax = plt.subplots(figsize=(7.0, 4.4))
    fig.subplots_adjust(**{**_MARGINS, "top": 0.87})  # a title of two lines
    ax.axhspan(-noise, noise, color="0.88", label=r"$\pm 2\,C(0)/\sqrt{n}$ (no correlation)")
    ax.axhline(0.0, color="0.4", lw=0.8)
    ax.vlines(lags, 0.0, corr, color="C0", lw=1.5)
    ax.plot(lags, corr, "o", color="C0", ms=4.5, label=r"$C_\epsilon(k)$, Eq. 13")
    ax.set_xlim(-0.5, lags[-1] + 0.5)
    from matplotlib.ticker import MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("lag k (collisions)")
    ax.set_ylabel(r"$C_\epsilon(k)$")
    ax.set_title(f"{_title(run)}\nstationary collisions {stats.transient + 1}-{run.n_collisions}, "
                 f"$C(1)/C(0)$ = {stats.restitution_correlation_coefficient_lag1:+.3f}", fontsize=10)
    ax.legend(loc="upper right", fontsize=8, framealpha=0.9)
    return _save(fig, path, dpi)


def plot_ring_figures(run: RingRun, out_dir, statistics: RingStatistics | None = None) -> list[Path]:
    """Write Fig. 1, 2 and 3 of a run into ``out_dir`` (names in :data:`FIGURE_NAMES`)."""
    stats = statistics if statistics is not None else run.statistics()
    out_dir = Path(out_dir)
    return [
        plot_translational_energy(run, out_dir / FIGURE_NAMES["energy"], stats),
        plot_spectral_entropy(run, out_dir / FIGURE_NAMES["entropy"]),
        plot_restitution_correlation(run, out_dir / FIGURE_NAMES["correlation"], stats),
    ]


def _save(fig, path, dpi) -> Path:
    try:
        path = check_output_file("path", path, FIGURE_SUFFIXES)
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=dpi)
    finally:
        import matplotlib.pyplot as plt

        plt.close(fig)
    return path
