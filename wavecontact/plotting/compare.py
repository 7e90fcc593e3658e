"""Error against wall time for one comparison (a Pareto picture)."""

from __future__ import annotations

import math
from pathlib import Path

__all__ = ["comparison_figure", "method_family", "plot_comparison"]

MARKERS = "os^Dv<>ph*"  # one per registered solver, in registry order


def method_family(row) -> str:
    """The series a comparison row belongs to: one per solver and discretization (its solver's
    ``comparison_family``, recorded with the row)."""
    return row.family or row.solver


def resolution_label(row) -> str:
    """The short resolution written next to a point: elements, modes or the tolerance."""
    return row.point or row.resolution


def _marker(solver: str) -> str:
    from ..solvers import solver_names

    names = solver_names()
    return MARKERS[names.index(solver) % len(MARKERS)] if solver in names else "x"


def comparison_figure(table, ax=None, legend: bool = True):
    """Error against wall time for the rows of a
    :class:`~wavecontact.studies.compare.ComparisonTable`: one line per solver
    and discretization, in the order of increasing resolution, each point
    labelled with its resolution (elements, modes, tolerance).  Runs the
    solver refused (it raised an error instead of returning an untrustworthy
    number) have no point; their number is stated under the axes.  Exact
    results are drawn at 1e-16."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = None
    if ax is None:
        fig = Figure(figsize=(7.0, 4.8), layout="constrained")
        FigureCanvasAgg(fig)
        ax = fig.add_subplot()
    series = {}
    failures = 0
    for row in table.rows:
        if not row.ok:
            failures += 1
            continue
        series.setdefault(method_family(row), []).append(row)
    floor = 1e-16
    for family, rows in series.items():
        (line,) = ax.loglog([r.wall_time_s for r in rows], [max(r.error, floor) for r in rows],
                            marker=_marker(rows[0].solver), ms=4, label=family)
        for row in rows:
            ax.annotate(resolution_label(row), (row.wall_time_s, max(row.error, floor)), xytext=(3, 2),
                        textcoords="offset points", fontsize=5.5, color=line.get_color())
    kappa = r"$\infty$" if math.isinf(table.kappa) else f"{table.kappa:g}"
    title = rf"$\gamma$ = {table.gamma:g}, $\kappa$ = {kappa}"
    if failures:
        title += f"\n{failures} run{'s' if failures > 1 else ''} refused by the solver, not drawn"
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("wall time per collision (s)")
    ax.set_ylabel(r"$|\epsilon - \epsilon_{ref}|$")
    ax.grid(alpha=0.3, which="both")
    if legend:
        ax.legend(fontsize=7, loc="best")
    return fig if fig is not None else ax.figure


def plot_comparison(table, path) -> Path:
    """Write :func:`comparison_figure` to ``path``."""
    path = Path(path)
    comparison_figure(table).savefig(path, dpi=130)
    return path
