"""The x-t diagram of stress in both rods: the classic picture of the wave theory of impact.

Position along the line runs horizontally, time upwards; the colour is the
stress, on a diverging scale centred at zero (compression blue, tension red).
Fronts of the stress waves are straight lines of slope ``1/c``; in the
paper's setting the compression pulse fills the short rod for one round trip
``2 l1 / c`` and then leaves it stress-free while it keeps running in the
long rod.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError
from ..io.files import check_figure_path

__all__ = ["plot_xt_diagram", "xt_figure"]

COORDINATES = ("reference", "deformed")
_LABEL_BOX = {
    "boxstyle": "round,pad=0.15",
    "fc": "white",
    "ec": "none",
    "alpha": 0.75,
}  # readable on any colour
# colour-bar units of a scene's fields: SI (``units="SI"``) or the scene's own, unnamed
_SI = {"stress": "Pa", "velocity": "m/s", "displacement": "m"}
_SCENE = {"stress": "stress unit (E's)", "velocity": "length/time", "displacement": "length"}


def xt_figure(
    result,
    *,
    field: str = "stress",
    coordinates: str = "reference",
    cmap: str = "RdBu_r",
    max_nodes: int = 800,
    max_times: int = 800,
    names=None,
    title: str | None = None,
    units: str | None = None,
):
    """Draw the x-t diagram of ``result`` and return the matplotlib Figure.

    Parameters
    ----------
    result : CollisionResult
        A fem result run with ``record_fields=True`` (``--fields`` or ``--xt-plot``).
    field : {'stress', 'velocity', 'displacement'}
        Which sampled field to colour (stress in units of ``rho c V`` in the
        paper's setting, where the impact plateau is ``-1/2``).
    coordinates : {'reference', 'deformed'}
        ``'reference'``: each node at its coordinate in the undeformed rods,
        the rods drawn end to end with the facing ends at ``x = 0``
        (Lagrangian, the textbook picture; the initial gap is left out);
        ``'deformed'``: at ``x + u(t)`` on the line, so the approach, the
        contact and the separation are visible too.
    cmap : str
        A diverging matplotlib colour map; the scale is symmetric about 0.
    max_nodes, max_times : int
        At most this many nodes per rod and samples in time are drawn
        (evenly thinned; the files keep everything).
    names : sequence of str or None
        Scene results (:class:`~wavecontact.ImpactResult`): a name per body for the labels.
    title : str or None
        Scene results: a first title line (the scene's summary); the bodies and contacts follow.
    units : str or None
        Scene results and two-rod scenes of materials: ``'SI'`` puts m, s and Pa on the axes; None
        leaves the scene's own units unnamed (the paper's two rods are always dimensionless).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colors import Normalize
    from matplotlib.figure import Figure

    from ..io.fields import FIELD_NAMES, sampled_fields

    if field not in FIELD_NAMES:
        raise InvalidParameterError(f"field must be one of {', '.join(FIELD_NAMES)}, got {field!r}")
    if coordinates not in COORDINATES:
        raise InvalidParameterError(
            f"coordinates must be one of {', '.join(COORDINATES)}, got {coordinates!r}"
        )
    fields = sampled_fields(result)
    if "points" in fields:  # a scene on a line (ImpactResult): every body at its place, contacts and walls marked
        from .xt_scene import scene_xt_figure

        return scene_xt_figure(result, fields, field=field, coordinates=coordinates, cmap=cmap, rows=_thin(
            fields["time"].size, max_times), max_nodes=max_nodes, names=names, title=title, units=units)
    time = fields["time"]
    rows = _thin(time.size, max_times)

    limit = max(float(np.max(np.abs(rod[field]))) for rod in fields["rods"]) or 1.0
    norm = Normalize(vmin=-limit, vmax=limit)

    fig = Figure(figsize=(7.5, 5.6), dpi=150, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_facecolor("0.82")  # outside the rods: grey, so a stress-free rod (near white) stands out
    mesh = None
    shifts = _abutting_shifts(fields["rods"]) if coordinates == "reference" else [0.0] * len(fields["rods"])
    for number, (rod, shift) in enumerate(zip(fields["rods"], shifts), start=1):
        order = np.argsort(rod["x"], kind="stable")
        cols = order[_thin(order.size, max_nodes)]
        x = rod["x"][cols][None, :] + shift
        if coordinates == "deformed":
            x = x + rod["displacement"][np.ix_(rows, cols)]
        else:
            x = np.broadcast_to(x, (rows.size, cols.size))
        t = np.broadcast_to(time[rows][:, None], x.shape)
        mesh = ax.pcolormesh(
            x, t, rod[field][np.ix_(rows, cols)], cmap=cmap, norm=norm, shading="gouraud", rasterized=True
        )
        for end in (0, -1):  # outline of the rod's ends
            ax.plot(x[:, end], t[:, end], color="0.25", lw=0.6)
        ax.annotate(
            f"rod {number}",
            xy=(float(np.mean(x[-1])), time[rows][-1]),
            xytext=(0, -3),
            textcoords="offset points",
            ha="center",
            va="top",
            fontsize=8,
            color="0.2",
            bbox=_LABEL_BOX,
        )

    start, duration = getattr(result, "contact_start", None), getattr(result, "contact_duration", None)
    if start is not None and duration is not None and np.isfinite(start) and np.isfinite(duration):
        for when, label in ((start, "contact begins"), (start + duration, "contact ends")):
            ax.axhline(when, color="0.35", lw=0.7, ls="--")
            ax.annotate(
                label,
                xy=(1.0, when),
                xycoords=("axes fraction", "data"),
                xytext=(-3, 2),
                textcoords="offset points",
                ha="right",
                va="bottom",
                fontsize=7,
                color="0.25",
                bbox=_LABEL_BOX,
            )

    # the paper's two rods (gamma given) are dimensionless; a two-rod scene of materials (gamma nan) is in the
    # scene's units: SI when the caller says so, else named as the scene's own
    dimensionless = _finite(getattr(result, "gamma", None))
    length, duration = ((" (units of l)", r" $\tau = t\,c/l$") if dimensionless else
                        (" [m]", " t [s]") if units == "SI" else (" (scene length unit)", " t (scene time unit)"))
    ax.set_xlabel(
        "position x" + length
        + ("  [undeformed rods, contact faces at 0]" if coordinates == "reference" else "  [deformed: x + u]")
    )
    ax.set_ylabel("time" + duration)
    ax.set_ylim(time[rows][0], time[rows][-1])
    unit = ({"stress": r"$\rho c V$", "velocity": "V", "displacement": "l"} if dimensionless
            else _SI if units == "SI" else _SCENE)[field]
    label = {"stress": "stress (compression < 0)", "velocity": "velocity", "displacement": "displacement"}[
        field
    ]
    fig.colorbar(mesh, ax=ax, label=f"{label} [{unit}]", shrink=0.9)
    ax.set_title(_title(result, field))
    return fig


def plot_xt_diagram(result, path, **options) -> Path:
    """Write the x-t diagram of stress in both rods to an image file.

    Parameters
    ----------
    result : CollisionResult
        A fem result run with ``record_fields=True``.
    path : str or Path
        Output file; the suffix picks the format (``.png``, ``.pdf``, ``.svg``).
    **options
        Passed to :func:`xt_figure` (``field``, ``coordinates``, ``cmap`` ...).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    MissingFieldsError
        If the result carries no sampled fields.
    """
    path = check_figure_path("path", path)
    fig = xt_figure(result, **options)
    fig.savefig(path)
    return path


def _abutting_shifts(rods) -> list:
    """Shifts that close the gaps: each rod starts where the previous one ends, the first contact at 0."""
    shifts, end = [], None
    for rod in rods:
        left, right = float(np.min(rod["x"])), float(np.max(rod["x"]))
        shift = 0.0 if end is None else end - left
        shifts.append(shift)
        end = right + shift
    first_contact = float(np.max(rods[0]["x"]))
    return [shift - first_contact for shift in shifts]


def _thin(size: int, at_most: int) -> np.ndarray:
    """Indices of at most ``at_most`` evenly spread items, first and last kept."""
    if at_most < 2:
        raise InvalidParameterError(f"max_nodes and max_times must be >= 2, got {at_most}")
    if size <= at_most:
        return np.arange(size)
    return np.unique(np.linspace(0, size - 1, at_most).round().astype(int))


def _title(result, field: str) -> str:
    parts = []
    gamma = getattr(result, "gamma", None)
    kappa = getattr(result, "kappa", None)
    if _finite(gamma):  # nan for a scene of materials: no gamma and kappa of the paper's rods to show
        parts.append(rf"$\gamma$ = {gamma:g}")
    if kappa is not None and not math.isnan(kappa):
        parts.append(r"$\kappa$ = " + (r"$\infty$" if math.isinf(kappa) else f"{kappa:g}"))
    restitution = getattr(result, "restitution", None)
    if restitution is not None and math.isfinite(restitution):
        parts.append(rf"$\epsilon$ = {restitution:.6g}")
    solver = getattr(result, "solver", None)
    head = f"x-t diagram of {field}" + (f" ({solver})" if solver else "")
    return head + ("\n" + ", ".join(parts) if parts else "")


def _finite(value) -> bool:
    return value is not None and math.isfinite(value)
