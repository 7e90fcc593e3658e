"""The velocity increase ``W(tau)`` of one collision next to its asymptotic form (Fig. 6)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..analytic import asymptotic_velocity_increase, hard_core_relative_velocity, round_trip_times
from ..io.files import check_figure_path

__all__ = ["plot_velocity_history", "velocity_history_figure"]


def _free_flight_time(result) -> float:
    """``tau_free`` of the result: exact for the delay solver, else matched at
    the mid-contact crossing of the large-kappa solution."""
    if "free_flight_time" in result.extra:
        return float(result.extra["free_flight_time"])
    g1, _ = round_trip_times(result.gamma)
    half = -1.0 + 0.5 * g1
    v = np.asarray(result.relative_velocity)
    crossing = int(np.argmax(v >= half))
    kappa = result.kappa
    return float(result.time[crossing]) - 0.5 * g1 - math.log(kappa) / kappa


def velocity_history_figure(result):
    """Figure with ``W(tau) / kappa`` (or, for ``kappa = inf``, ``v_rel(tau)``) and the
    asymptotic curve: Eq. 21/22 for finite kappa, Eq. 24 in the hard limit.

    ``W`` is shown over ``kappa``, as in the paper's Fig. 6 and 7 (and ``wavecontact paper-figures``),
    so that curves of different kappa share one scale: ``W / kappa`` is the change of the relative
    velocity in units of the approach speed ``V``, from 0 to ``1 + epsilon`` (Eq. 16)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 4.2), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    tau = np.asarray(result.time, dtype=float)
    kappa = result.kappa
    label = f"{result.solver} solver"
    if kappa is not None and math.isfinite(kappa):
        tau_free = _free_flight_time(result)
        ax.plot(tau - tau_free, np.asarray(result.velocity_increase) / kappa, lw=2, label=label)
        fine = np.linspace(tau.min(), tau.max(), 2000)
        ax.plot(
            fine - tau_free,
            asymptotic_velocity_increase(fine, result.gamma, kappa, tau_free) / kappa,
            "k--", lw=1, label="asymptotic, Eq. 21-22",
        )
        ax.set_ylabel(r"velocity increase $W(\tau) / \kappa$  (units of $V$)")
        ax.set_xlabel(r"$\tau - \tau_{free}$  (units of $l/c$)")
        kappa_text = f"{kappa:g}"
    else:
        ax.plot(tau, result.relative_velocity, lw=2, label=label)
        fine = np.linspace(tau.min() - 0.5, tau.max() + 0.5, 2000)
        ax.plot(fine, hard_core_relative_velocity(fine, result.gamma, result.contact_start or 0.0),
                "k--", lw=1, label="wave theory, Eq. 24")
        ax.set_ylabel(r"relative velocity $v_2 - v_1$  (units of $V$)")
        ax.set_xlabel(r"$\tau$  (units of $l/c$)")
        kappa_text = r"$\infty$"
    ax.set_xlim(-1.0, round_trip_times(result.gamma)[1] + 2.0)
    ax.set_title(
        rf"$\gamma$ = {result.gamma:g}, $\kappa$ = {kappa_text}: $\epsilon$ = {result.restitution:.8f}"
    )
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right")
    return fig


def plot_velocity_history(result, path) -> Path:
    """Write :func:`velocity_history_figure` to ``path`` (format from the suffix)."""
    path = check_figure_path("path", path)
    velocity_history_figure(result).savefig(path, dpi=130)
    return path
