"""Figures of the cold collision for ``wavecontact paper-figures``: epsilon against kappa (Fig. 5), W(tau) (Fig. 6)."""

from __future__ import annotations

import math

import numpy as np

from .bath import _figure, save

__all__ = ["restitution_figure", "save", "velocity_increase_figure"]


def restitution_figure(kappas, restitution, asymptotic, gamma):
    """Fig. 5: the delay equation's epsilon(kappa) (markers) against Eq. 23 (dashed) and the hard core.

    ``asymptotic`` is a pair ``(kappa, epsilon)`` of Eq. 23 on its own (finer) grid.
    """
    fig, ax = _figure((6.0, 4.0))
    ax.semilogx(kappas, restitution, "^", ms=5, label="delay equation (Eq. 16)")
    ax.semilogx(*asymptotic, "k--", lw=1, label="asymptotic (Eq. 23)")
    ax.axhline(gamma, color="gray", lw=0.8, label=rf"hard core: $\gamma$ = {gamma:g}")
    ax.set_ylim(0.5, 1.1)
    ax.set_xlabel(r"$\kappa = \alpha V l / c$")
    ax.set_ylabel(r"coefficient of restitution $\epsilon$")
    ax.set_title(rf"cold collision, $\gamma$ = {gamma:g}")
    ax.grid(alpha=0.3)
    ax.legend()
    return fig


def velocity_increase_figure(curves, gamma):
    """Fig. 6: ``W(tau) / kappa`` per curve (``tau_free = 1``), with Eq. 22 where given and Eq. 24 at kappa = inf."""
    fig, ax = _figure((6.4, 4.2))
    for j, c in enumerate(curves):
        hard = math.isinf(c["kappa"])
        label = r"$\kappa = \infty$ (hard core, Eq. 24)" if hard else rf"$\kappa$ = {c['kappa']:g}, delay equation"
        ax.plot(c["tau"], np.asarray(c["W"]) / (1.0 if hard else c["kappa"]), color=f"C{j}", lw=2 if hard else 2.5,
                alpha=0.8, label=label)
        if c.get("eq22") is not None:
            ax.plot(c["tau"], np.asarray(c["eq22"]) / c["kappa"], "k--", lw=1,
                    label="Eq. 22" if j == 0 else None)
    ax.set_xlim(0.0, 5.0)
    ax.set_xlabel(r"$\tau$ ($\tau_{free}$ = 1)")
    ax.set_ylabel(r"$W(\tau) / \kappa$")
    ax.set_title(rf"velocity increase, cold bath, $\gamma$ = {gamma:g}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    return fig
