"""Figures of the thermal bath: noise covariance (Fig. 4), stochastic W (Fig. 7), spread (Fig. 8), law (Fig. 9)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["covariance_figure", "histories_figure", "law_figure", "plot_law", "save", "spread_figure"]


def _figure(size=(6.4, 4.2), cols=1):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    return fig, fig.subplots(1, cols) if cols > 1 else fig.add_subplot()


def save(fig, path) -> Path:
    path = Path(path)
    fig.savefig(path, dpi=120)
    return path


def covariance_figure(data):
    fig, ax = _figure()
    ax.fill_between(data["lag"], data["sampled"] - data["band"], data["sampled"] + data["band"], color="C0", alpha=0.3,
                    label=f"sampled ({data['realisations']} realisations, 2 SE)")
    ax.plot(data["lag"], data["sampled"], color="C0", lw=1)
    ax.plot(data["lag"], data["eq19"], "k--", lw=1, label="Eq. 19")
    ax.set_xlabel(r"$\tau$")
    ax.set_ylabel(r"$C_Q(\tau) / \sigma^2$")
    ax.set_title(rf"noise covariance, $\gamma$ = {data['gamma']:g}, $\nu_{{max}}$ = {data['modes']}")
    ax.legend()
    return fig


def histories_figure(histories, gamma, temperature):
    fig, ax = _figure()
    for h in histories:
        ax.plot(h["tau"], h["W"] / h["kappa"], label=rf"$\kappa$ = {h['kappa']:g} ($\epsilon$ = {h['restitution']:.3f})")
    ax.set_xlabel(r"$\tau$ ($\tau_{free}$ = 1)")
    ax.set_ylabel(r"$W(\tau) / \kappa$")
    ax.set_xlim(0.0, 6.0)
    ax.set_title(rf"one realisation, $\gamma$ = {gamma}, $T_B/E_{{tr}}$ = {temperature}")
    ax.legend()
    return fig


def spread_figure(data):
    fig, ax = _figure()
    for a, gamma in enumerate(data["gamma"]):
        t = data["temperature"]
        ax.errorbar(t, data["mean"][a], yerr=data["mean_error"][a], fmt="^", color=f"C{a}",
                    label=rf"$\langle\epsilon\rangle$, $\gamma$ = {gamma}")
        ax.errorbar(t, data["std"][a], yerr=data["std_error"][a], fmt="o", mfc="none", color=f"C{a}",
                    label=rf"$\Delta\epsilon$, $\gamma$ = {gamma}")
    ax.set_xlabel(r"$T_B / E_{tr}$")
    ax.set_ylabel(r"$\langle\epsilon\rangle$, $\Delta\epsilon$")
    ax.set_title(rf"$\kappa$ = {data['kappa']:g}, {data['samples']} samples per point")
    ax.legend(fontsize=8)
    return fig


def _draw_law(ax, result, bins=40):
    """The density ``p(eps^2)`` on ``ax`` (left axis) and the distribution function ``D(eps^2)`` on a twin
    axis from 0 to 1 (right), each with its 95 % band and one legend for both; returns the twin axis."""
    edges, density, low, high = result.density(bins)
    centres = 0.5 * (edges[1:] + edges[:-1])
    ax.fill_between(centres, low, high, color="C1", alpha=0.25, step="mid")
    lines = ax.step(centres, density, where="mid", color="C1", ls=":", label=r"density $p(\epsilon^2)$ (left)")
    ax.set_ylabel(r"probability density $p(\epsilon^2)$", color="C1")
    ax.set_ylim(bottom=0.0)
    twin = ax.twinx()
    x, d, dl, dh = result.distribution()
    twin.fill_between(x, dl, dh, color="C0", alpha=0.2, step="post")
    lines += twin.step(x, d, where="post", color="C0", label=r"distribution $D(\epsilon^2)$ (right)")
    twin.set_ylim(0.0, 1.02)
    twin.set_ylabel(r"distribution function $D(\epsilon^2)$", color="C0")
    spec = result.spec
    ax.set_title(rf"$\gamma$ = {spec.gamma:g}, $E_{{tr}}/T_B$ = {1.0 / spec.temperature[0]:.3g}, "
                 f"{spec.samples} samples; bands: 95 %", fontsize=9)
    ax.set_xlabel(r"$\epsilon^2$")
    twin.legend(lines, [line.get_label() for line in lines], fontsize=7, loc="upper left")
    return twin


def law_figure(results, gamma_step=0.6173):
    fig, axes = _figure((4.0 * (len(results) + 1), 3.6), cols=len(results) + 1)
    for ax, result in zip(axes, results):
        _draw_law(ax, result)
    ax = axes[-1]
    x = np.linspace(0.0, 1.0, 401)
    ax.plot(x, (x >= gamma_step**2).astype(float), color="C0", label=r"$D(\epsilon^2)$, cold collision")
    ax.set_title(rf"deterministic: $D = \Theta(\epsilon^2 - \gamma^2)$, $\gamma$ = {gamma_step:g}", fontsize=9)
    ax.set_xlabel(r"$\epsilon^2$")
    ax.set_ylabel(r"distribution function $D(\epsilon^2)$")
    ax.set_ylim(0.0, 1.02)
    ax.legend(fontsize=7, loc="upper left")
    return fig


def plot_law(result, path) -> Path:
    """``p(eps^2)`` and ``D(eps^2)`` of one ensemble, with 95 % bands, to ``path``."""
    fig, ax = _figure()
    _draw_law(ax, result)
    return save(fig, path)
