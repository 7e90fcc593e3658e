"""The x-t diagram of a scene on a line: every body at its place, contacts and walls marked.

Called by :func:`wavecontact.plotting.xt.xt_figure` for an
:class:`~wavecontact.ImpactResult` run with ``record_fields=True``.  Position
along the line runs horizontally (each body at its reference position, gaps
left grey), time upwards; rods are coloured by the field on a diverging scale
centred at zero (compression blue), rigid bodies drawn as thick lines (their
path ``x + u(t)`` in deformed coordinates), walls as thick vertical lines, and
each contact as a black bar at its place from its first to its last time in
contact.
"""

from __future__ import annotations

import numpy as np

from .xt import _LABEL_BOX, _SCENE, _SI, _thin

__all__ = ["scene_xt_figure"]

_SYMBOLS = {"stress": r"stress $\sigma = E\,\partial u/\partial x$ (compression < 0)",
            "velocity": r"velocity $v$", "displacement": r"displacement $u$"}


def scene_xt_figure(result, fields: dict, *, field: str, coordinates: str, cmap: str, rows: np.ndarray,
                    max_nodes: int, names=None, title=None, units=None):
    """Draw the x-t diagram of a scene result's sampled ``fields`` (see :func:`~wavecontact.plotting.xt.xt_figure`).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colors import Normalize
    from matplotlib.figure import Figure

    time = fields["time"][rows]
    count = len(fields["rods"]) + len(fields["points"])
    names = list(names) if names is not None else [f"body {i}" for i in range(count)]
    limit = max(float(np.max(np.abs(rod[field]))) for rod in fields["rods"]) if fields["rods"] else 0.0
    norm = Normalize(vmin=-(limit or 1.0), vmax=limit or 1.0)

    fig = Figure(figsize=(8.5, 5.6), dpi=150, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_facecolor("0.82")  # gaps: grey
    mesh = None
    places = {}  # body -> (left, right) reference ends
    for rod in fields["rods"]:
        order = np.argsort(rod["x"], kind="stable")
        cols = order[_thin(order.size, max_nodes)]
        x = np.broadcast_to(rod["x"][cols][None, :], (rows.size, cols.size))
        if coordinates == "deformed":
            x = x + rod["displacement"][np.ix_(rows, cols)]
        t = np.broadcast_to(time[:, None], x.shape)
        mesh = ax.pcolormesh(x, t, rod[field][np.ix_(rows, cols)], cmap=cmap, norm=norm, shading="gouraud",
                             rasterized=True)
        for end in (0, -1):
            ax.plot(x[:, end], t[:, end], color="0.25", lw=0.6)
        places[rod["body"]] = (float(rod["x"].min()), float(rod["x"].max()))
        _label(ax, float(np.mean(x[-1])), time[-1], names[rod["body"]])
    for point in fields["points"]:
        x = point["x"] + (point["displacement"][rows] if coordinates == "deformed" else 0.0 * time)
        ax.plot(x, time, color="black", lw=2.5, solid_capstyle="butt")
        places[point["body"]] = (point["x"], point["x"])
        _label(ax, float(x[-1]), time[-1], names[point["body"]] + " (rigid)")
    walls = [w for w in fields.get("walls", ()) if w is not None]
    for w in walls:
        ax.axvline(w, color="black", lw=3.0)
        _label(ax, w, time[-1], "wall")
    marked = False
    for record in getattr(result, "contacts", ()):
        if record.intervals == 0:
            continue
        where = _contact_place(record.name, places, fields.get("walls", (None, None)))
        if where is None:
            continue
        ax.plot([where, where], [record.first_contact, record.last_contact], color="black", lw=1.6,
                marker="_", markersize=8, label=None if marked else "contact: first to last time in contact")
        marked = True
    if marked:
        ax.legend(loc="lower right", fontsize=7, framealpha=0.8)
    unit = {"SI": _SI}.get(units, None)
    ax.set_xlabel("position x" + (" [m]" if units == "SI" else " (scene length unit)")
                  + ("  [bodies at their reference places]" if coordinates == "reference" else "  [deformed: x + u]"))
    ax.set_ylabel("time t" + (" [s]" if units == "SI" else " (scene time unit)"))
    ax.set_ylim(time[0], time[-1])
    if mesh is not None:
        fig.colorbar(mesh, ax=ax, shrink=0.9, label=_SYMBOLS[field] + f" [{(unit or _SCENE)[field]}]")
    solver = getattr(result, "solver", "fem")
    summary = f"x-t diagram of {field} ({solver}): {count} bodies, " \
              f"{len(getattr(result, 'contacts', ()))} contacts" + (f", {len(walls)} wall(s)" if walls else "")
    ax.set_title(summary if not title else f"{title}\n{summary}", fontsize=10)
    return fig


def _label(ax, x: float, t: float, text: str) -> None:
    ax.annotate(text, xy=(x, t), xytext=(0, -3), textcoords="offset points", ha="center", va="top", fontsize=7,
                color="0.2", bbox=_LABEL_BOX)


def _contact_place(name: str, places: dict, walls) -> float | None:
    """Reference position of a contact ``"i-j"`` (body i's right end), ``"left wall"`` or ``"right wall"``."""
    if name == "left wall":
        return walls[0]
    if name == "right wall":
        return walls[1]
    left, _, _right = name.partition("-")
    try:
        return places[int(left)][1]
    except (ValueError, KeyError):
        return None
