"""Figure of the two-material restitution map: epsilon over (Z2/Z1, T1/T2)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

__all__ = ["material_map_figure", "plot_material_map"]


def material_map_figure(maps):
    """One panel per :class:`~wavecontact.studies.material_map.MaterialMap`.

    Colour: epsilon on log axes of the impedance ratio ``Z2/Z1`` (x) and the
    transit-time ratio ``T1/T2`` (y), contours every 0.1.  Dashed lines mark
    the known lines of the hard-core limit: equal impedances (``epsilon =
    min(T1/T2, T2/T1)``) and equal transit times (``epsilon = 1``).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    maps = list(maps)
    fig = Figure(figsize=(4.6 * len(maps) + 0.8, 4.2), dpi=150, layout="constrained")
    FigureCanvasAgg(fig)
    axes = np.atleast_1d(fig.subplots(1, len(maps), sharey=True))
    image = None
    for ax, one in zip(axes, maps):
        x, y = np.meshgrid(one.impedance_ratios, one.time_ratios, indexing="ij")
        image = ax.pcolormesh(x, y, one.restitution, shading="nearest", cmap="viridis", vmin=0.0, vmax=1.0)
        if min(one.restitution.shape) > 1:
            lines = ax.contour(x, y, one.restitution, levels=np.arange(0.1, 1.0, 0.1), colors="white",
                               linewidths=0.5)
            ax.clabel(lines, fontsize=6, fmt="%.1f")
        ax.axvline(1.0, color="red", ls="--", lw=1.0, label="equal impedances")
        ax.axhline(1.0, color="orange", ls="--", lw=1.0, label="equal transit times")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(r"impedance ratio $Z_2/Z_1$")
        kappa = r"$\kappa = \infty$ (hard core)" if math.isinf(one.kappa) else rf"$\kappa$ = {one.kappa:g}"
        ax.set_title(kappa, fontsize=9)
    axes[0].set_ylabel(r"transit-time ratio $T_1/T_2$")
    axes[0].legend(fontsize=7, loc="lower left")
    fig.colorbar(image, ax=list(axes), label=r"restitution $\epsilon$")
    return fig


def plot_material_map(maps, path) -> Path:
    """Write :func:`material_map_figure` to ``path`` (format from the suffix)."""
    path = Path(path)
    material_map_figure(maps).savefig(path)
    return path
