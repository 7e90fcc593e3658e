"""Figure of an equipartition study: the paper's Fig. 2 for several mode counts, and how the
settling collision grows with the number of modes."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..studies.equipartition import EquipartitionStudy
from .ring import _pyplot, _save

__all__ = ["PAPER_SETTLING_COLLISIONS", "plot_equipartition"]

PAPER_SETTLING_COLLISIONS = 5.0  # "about five collisions", independent of N (paper, Sec. III)


def plot_equipartition(study: EquipartitionStudy, path, dpi: int = 150) -> Path:
    """Two panels: ``eta`` against collision number per ``N``, and settling collision against ``N``.

    Left: the mean of ``eta`` over the realisations (line) and their range
    (band), with the finite-``N`` equipartition mean (dashed, same colour)
    and the settling level (dotted).  Right: each realisation's settling
    collision (dots), their median (line, with the fitted power of ``N``)
    and the paper's "about five collisions".
    """
    plt = _pyplot()
    if not study.entropy:
        raise ValueError("plot_equipartition needs a study with at least one mode count")
    fig, (ax, ax_n) = plt.subplots(1, 2, figsize=(12.0, 4.6), gridspec_kw={"width_ratios": [1.4, 1.0]},
                                   constrained_layout=True)
    for index, n in enumerate(study.modes):
        colour = f"C{index}"
        series = study.entropy[n]
        collisions = np.arange(1, series.shape[1] + 1)
        ax.fill_between(collisions, series.min(axis=0), series.max(axis=0), color=colour, alpha=0.18, lw=0)
        ax.plot(collisions, series.mean(axis=0), "-", color=colour, lw=1.3, label=f"N = {n}")
        level = study.equilibrium(n)
        ax.axhline(level, ls="--", color=colour, lw=1.0)
        ax.axhline(study.threshold * level, ls=":", color=colour, lw=0.8)
    ax.axvline(PAPER_SETTLING_COLLISIONS, color="0.3", lw=0.8, ls="-.", label="paper: about 5 collisions")
    ax.set_xscale("log")
    _plain_log_ticks(ax.xaxis)
    ax.set_xlim(1, max(s.shape[1] for s in study.entropy.values()))
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("collision number")
    ax.set_ylabel(r"spectral entropy $\eta = 1 - h/\ln(2N)$")
    kappa = "inf" if math.isinf(study.kappa) else f"{study.kappa:g}"
    realisations = next(iter(study.entropy.values())).shape[0]
    ax.set_title(f"$\\gamma$ = {study.gamma:g}, $\\kappa$ = {kappa}; mean and range of {realisations} "
                 f"realisations\ndashed: equipartition mean, dotted: {study.threshold:g} x that (settled)",
                 fontsize=9)
    # outside the axes: inside, any corner covers the curves or the dashed equipartition levels
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)
    ax.grid(alpha=0.3, which="both")

    medians = []
    for index, row in enumerate(study.table()):
        settled = [s for s in row["settling"] if s is not None]
        ax_n.plot([row["modes"]] * len(settled), settled, "o", color=f"C{index}", ms=4, alpha=0.6)
        if row["median_settling"] is not None:
            medians.append((row["modes"], row["median_settling"]))
    if medians:
        n_values, s_values = np.array(medians, dtype=float).T
        slope = study.scaling_exponent()
        label = "median" + (f" (slope {slope:.2f} in log-log)" if slope is not None else "")
        ax_n.plot(n_values, s_values, "k-", lw=1.2, label=label)
    ax_n.axhline(PAPER_SETTLING_COLLISIONS, color="0.3", lw=0.8, ls="-.", label="paper: about 5, any N")
    ax_n.set_xscale("log")
    ax_n.set_yscale("log")
    ax_n.set_xticks(study.modes)  # one labelled tick per mode count: log minor labels would overlap
    _plain_log_ticks(ax_n.xaxis, with_locator=False)
    _plain_log_ticks(ax_n.yaxis)
    ax_n.set_xlabel("modes per rod N")
    ax_n.set_ylabel("settling collision")
    ax_n.set_title("collisions until equipartition", fontsize=9)
    ax_n.legend(loc="upper left", fontsize=8, framealpha=0.9)
    ax_n.grid(alpha=0.3, which="both")
    return _save(fig, path, dpi)


def _plain_log_ticks(axis, with_locator=True) -> None:
    """Label a log axis at 1, 2, 5 x 10^k as plain numbers ("20", not "2 x 10^1"), minor ticks unlabelled."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    if with_locator:
        axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    axis.set_minor_formatter(NullFormatter())
