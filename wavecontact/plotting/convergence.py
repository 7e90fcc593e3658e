"""Figure of a mesh-convergence study: error against elements and against wall time."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError

__all__ = ["convergence_figure", "plot_convergence"]


def convergence_figure(table):
    """Two log-log panels of a :class:`~wavecontact.studies.convergence.ConvergenceTable`.

    Left: error of epsilon against elements on the shorter rod, one line per
    discretization, with guide lines of slope -1 and -2 (orders 1 and 2).
    Runs exact to round-off (error below ``ERROR_FLOOR``) are drawn as hollow
    markers on a dotted floor line, so an exact discretization stays visible.
    Right: error against wall time; guide lines of slope -1/2 and -1, which
    is what orders 1 and 2 give when the cost grows like ``N**2`` (an explicit
    scheme in 1D: N elements times a number of steps proportional to N).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ..studies.convergence import ERROR_FLOOR

    series = []
    for fit in table.fits:
        done = [r for r in table.rows_for(fit.order, fit.mass) if r.error is not None]
        if done:
            # exact results (round-off) have no place on a log scale: drawn on a floor line instead
            series.append((fit, [r for r in done if r.error > ERROR_FLOOR], [r for r in done if r.error <= ERROR_FLOOR]))
    if not series:
        raise InvalidParameterError("nothing to plot: no run of the study finished")

    fig = Figure(figsize=(10, 4.4), dpi=150, layout="constrained")
    FigureCanvasAgg(fig)
    ax_n, ax_t = fig.subplots(1, 2)
    markers = "osD^v<>p"
    floor = ERROR_FLOOR
    for k, (fit, rows, exact) in enumerate(series):
        notes = [f"p = {fit.observed_order:.2f}"] if fit.observed_order is not None else []
        if exact:
            notes.append(f"exact on {len(exact)} mesh{'es' if len(exact) > 1 else ''}")
        label = fit.label + (f" ({'; '.join(notes)})" if notes else "")
        style = {"marker": markers[k % len(markers)], "ms": 4, "lw": 1.2}
        color = f"C{k % 10}"
        for ax, x_of in ((ax_n, lambda r: r.elements), (ax_t, lambda r: r.wall_time_s)):
            shown = [r for r in rows if x_of(r) and x_of(r) > 0]
            if shown:
                ax.loglog([x_of(r) for r in shown], [r.error for r in shown], color=color, **style,
                          label=label if ax is ax_n else None)
            on_floor = [r for r in exact if x_of(r) and x_of(r) > 0]
            if on_floor:
                ax.loglog([x_of(r) for r in on_floor], [floor] * len(on_floor), ls="none", color=color,
                          mfc="none", mew=1.2, marker=style["marker"], ms=6,
                          label=label if (ax is ax_n and not shown) else None)
    exact_any = any(exact for _, _, exact in series)
    if exact_any:
        for ax in (ax_n, ax_t):
            ax.axhline(floor, color="0.5", lw=0.8, ls=":")
        ax_n.annotate(f"exact (error below {floor:.0e}, round-off): hollow markers on this line",
                      xy=(0.01, floor), xycoords=("axes fraction", "data"), xytext=(0, 3),
                      textcoords="offset points", fontsize=7, color="0.35", va="bottom")

    all_rows = [r for _, rows, _ in series for r in rows]
    if all_rows:
        _guides(ax_n, [r.elements for r in all_rows], [r.error for r in all_rows], (1, 2), "N")
        timed = [r for r in all_rows if r.wall_time_s and r.wall_time_s > 0]
        if timed:
            _guides(ax_t, [r.wall_time_s for r in timed], [r.error for r in timed], (0.5, 1), "t")
    all_rows += [r for _, _, exact in series for r in exact]

    from matplotlib.ticker import NullFormatter

    meshes = sorted({r.elements for r in all_rows})
    ax_n.set_xticks(meshes, [str(n) for n in meshes])
    ax_n.xaxis.set_minor_formatter(NullFormatter())
    ax_n.set_xlabel("elements on the shorter rod N")
    ax_n.set_ylabel(r"error $|\epsilon - \epsilon_\mathrm{ref}|$")
    ax_t.set_xlabel("wall time per collision [s]")
    ax_t.set_ylabel(r"error $|\epsilon - \epsilon_\mathrm{ref}|$")
    for ax in (ax_n, ax_t):
        ax.grid(True, which="major", alpha=0.3)
        ax.grid(True, which="minor", alpha=0.1)
    ax_n.legend(fontsize=8, loc="best")
    kappa = r"$\infty$" if math.isinf(table.kappa) else f"{table.kappa:g}"
    fig.suptitle(
        rf"mesh convergence of $\epsilon$: $\gamma$ = {table.gamma:g}, $\kappa$ = {kappa}, "
        f"{table.contact} contact, reference {table.reference:.10g}",
        fontsize=9,
    )
    return fig


def plot_convergence(table, path) -> Path:
    """Write :func:`convergence_figure` to ``path`` (format from the suffix) and return it."""
    path = Path(path)
    if not path.parent.exists():
        raise InvalidParameterError(f"directory of the plot does not exist: {path.parent}")
    convergence_figure(table).savefig(path)
    return path


def _guides(ax, xs, ys, slopes, symbol):
    """Dashed reference lines of the given (negative) slopes through the data's upper left."""
    xs, ys = np.asarray(xs, float), np.asarray(ys, float)
    x0, x1 = xs.min(), xs.max()
    if x1 <= x0:
        return
    anchor = ys.max() * 1.6  # from the upper left corner of the data, above every line
    for index, slope in enumerate(slopes):
        x = np.array([x0, x1])
        y = anchor * (x / x0) ** (-slope)
        exponent = f"{slope:g}" if slope != 0.5 else "1/2"
        ax.loglog(x, y, ls="--", lw=0.8, color="0.45")
        ax.annotate(
            f"${symbol}^{{-{exponent}}}$",
            xy=(x[1], y[1]),
            # the shallower guide's label above its end, the steeper one's below: on a short range
            # of x both ends are close and labels on the same side overlap
            xytext=(-2, 4 if index == 0 else -4),
            textcoords="offset points",
            fontsize=8,
            color="0.35",
            ha="right",
            va="bottom" if index == 0 else "top",
        )
