"""Error against wall time for one comparison (a Pareto picture)."""

from __future__ import annotations

import math
from pathlib import Path

__all__ = ["comparison_figure", "plot_comparison"]

MARKERS = {"delay": "o", "fem": "s", "modal": "^"}


def comparison_figure(table, ax=None):
    """Scatter of ``error`` against ``wall_time_s`` for the rows of a
    :class:`~wavecontact.studies.compare.ComparisonTable`, one series per
    solver and discretization; failed rows are listed in the title."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = None
    if ax is None:
        fig = Figure(figsize=(7.0, 4.8), layout="constrained")
        FigureCanvasAgg(fig)
        ax = fig.add_subplot()
    series = {}
    failures = []
    for row in table.rows:
        if not row.ok:
            failures.append(f"{row.solver} {row.resolution}")
            continue
        key = (row.solver, row.resolution.split(",")[0] if row.solver != "delay" else "")
        series.setdefault(key, []).append(row)
    floor = 1e-16
    for (solver, family), rows in series.items():
        rows = sorted(rows, key=lambda r: r.wall_time_s)
        label = solver if not family else f"{solver}: {family}"
        if solver == "modal":
            label = f"modal: {rows[0].resolution.split(', ')[-1]}"
        ax.loglog([r.wall_time_s for r in rows], [max(r.error, floor) for r in rows],
                  marker=MARKERS.get(solver, "x"), label=label)
    kappa = r"$\infty$" if math.isinf(table.kappa) else f"{table.kappa:g}"
    title = rf"$\gamma$ = {table.gamma:g}, $\kappa$ = {kappa}"
    if failures:
        title += f"  (failed: {len(failures)})"
    ax.set_title(title)
    ax.set_xlabel("wall time per collision (s)")
    ax.set_ylabel(r"$|\epsilon - \epsilon_{ref}|$")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, loc="best")
    return fig if fig is not None else ax.figure


def plot_comparison(table, path) -> Path:
    """Write :func:`comparison_figure` to ``path``."""
    path = Path(path)
    comparison_figure(table).savefig(path, dpi=130)
    return path
