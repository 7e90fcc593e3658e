"""Error against wall time for one comparison (a Pareto picture)."""

from __future__ import annotations

import math
from pathlib import Path

__all__ = ["comparison_figure", "method_family", "plot_comparison"]

MARKERS = {"delay": "o", "fem": "s", "modal": "^"}


def method_family(row) -> str:
    """The series a comparison row belongs to: one per solver and discretization."""
    if row.solver == "fem":
        return "fem: " + row.resolution.split(",")[0]
    if row.solver == "modal":
        return "modal: " + row.resolution.split(", ")[-1]
    return row.solver


def resolution_label(row) -> str:
    """The short resolution written next to a point: elements, modes or the tolerance."""
    text = row.resolution
    if row.solver == "fem" and ", " in text:
        return text.split(", ")[1].split()[0]  # "P1 lumped, 100 elements" -> "100"
    if row.solver == "modal":
        return text.split()[0]  # "25 modes, static correction" -> "25"
    if "=" in text:
        return text.split("=", 1)[1]  # "rtol=1e-05" -> "1e-05"
    return text


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
                            marker=MARKERS.get(rows[0].solver, "x"), ms=4, label=family)
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
