"""Figures of a rod-gas run: energy, collision rate, velocity distribution, and the clusters in space-time."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..gas.simulation import GasResult
from .ring import _pyplot, _save

__all__ = ["plot_gas"]


def plot_gas(result: GasResult, path, *, system_length=None, title="", dpi=130) -> Path:
    """Four panels: the energies against time and against collisions (with the collision rate), the
    distribution of ``v / v_rms`` against a Gaussian, and the space-time picture of the rods.

    Energies are shown over the initial total energy ``E(0)`` (translational plus baths); times are in
    the gas's unit, the rod-length unit over the wave speed ``c`` (``rho = A = c = 1``). A ``t^-2`` guide
    (Haff's law) is drawn only for a run that cools, i.e. whose total energy fell below half its start.

    Parameters
    ----------
    result : GasResult
        A run with its history (and frames for the space-time panel).
    path : path-like
        Output image.
    system_length : float, optional
        Ring circumference (the horizontal range of the space-time panel, rod-length unit).
    title : str
        The run's parameters (rods, rule, damping, seed), shown above the panels with its outcome.
    """
    plt = _pyplot()
    h = result.history
    fig, axes = plt.subplots(2, 2, figsize=(11.5, 8.5), constrained_layout=True)
    ax_t, ax_c, ax_v, ax_x = axes.ravel()
    t, kinetic, bath = h["time"], h["kinetic_energy"], h["bath_energy"]
    total = kinetic + bath
    scale = total[0] if total.size and total[0] > 0 else 1.0
    has_baths = bool(np.any(bath > 0))
    late = t > 0
    ax_t.loglog(t[late], kinetic[late] / scale, "C0-", lw=1.3, label="translational (centre-of-mass frame)")
    if has_baths:
        ax_t.loglog(t[late], bath[late] / scale, "C1-", lw=1.0, label="vibrations (baths)")
    if late.sum() > 2 and total[-1] < 0.5 * total[0]:
        anchor_t, anchor_e = t[late][-1], kinetic[late][-1] / scale
        guide = t[late][t[late] > anchor_t / 30]
        ax_t.loglog(guide, anchor_e * (guide / anchor_t) ** -2.0, "k:", lw=1.0,
                    label=r"$\propto t^{-2}$ (Haff's law), through the last point")
    ax_t.set_xlabel(r"time $t$ (length unit / $c$)")
    ax_t.set_ylabel(r"energy / $E(0)$")
    ax_t.legend(fontsize=8)
    lines = ax_c.semilogy(h["collisions"], kinetic / scale, "C0-", lw=1.3, label="translational energy / E(0)")
    if has_baths:
        lines += ax_c.semilogy(h["collisions"], bath / scale, "C1-", lw=1.0, label="vibrational energy / E(0)")
    ax_c.set_xlabel("collisions")
    ax_c.set_ylabel(r"energy / $E(0)$")
    _, rate = result.collision_rate()
    legend_axis = ax_c
    if rate.size:
        twin = ax_c.twinx()
        finite = np.isfinite(rate)
        lines += twin.plot(0.5 * (h["collisions"][1:] + h["collisions"][:-1])[finite], rate[finite], "C2-", lw=0.8,
                           label="collision rate (right axis)")
        twin.set_ylabel(r"collisions per unit time ($c$ / length unit)", color="C2")
        twin.set_yscale("log")
        legend_axis = twin  # drawn above both axes' lines
    legend_axis.legend(lines, [line.get_label() for line in lines], fontsize=8, framealpha=0.9)
    v = result.velocities - np.mean(result.velocities)
    rms = np.sqrt(np.mean(v**2))
    if rms > 0:
        ax_v.hist(v / rms, bins=max(10, min(60, int(np.sqrt(v.size)))), density=True, histtype="step", lw=1.3,
                  label=f"the {v.size} rods at the end")
        grid = np.linspace(-4, 4, 200)
        ax_v.plot(grid, np.exp(-grid**2 / 2) / np.sqrt(2 * np.pi), "k--", lw=1.0, label="Gaussian")
        ax_v.set_yscale("log")
        ax_v.set_ylim(1e-4, 1)
    ax_v.set_xlabel(r"$v / v_\mathrm{rms}$")
    ax_v.set_ylabel("probability density")
    ax_v.legend(fontsize=8)
    if result.frames.size:
        frames, times = result.frames, result.frame_times
        # each frame at its own time: frames are taken every few collisions, not at equal times
        ax_x.scatter(frames.ravel(), np.repeat(times, frames.shape[1]), s=0.15, c="k", marker=".", linewidths=0,
                     label="rod centres")
        if system_length:
            ax_x.set_xlim(0, system_length)
    ax_x.set_xlabel("position $x$ (centre-of-mass frame, length unit)")
    ax_x.set_ylabel(r"time $t$ (length unit / $c$)")
    heading = f"{title}: {result.message}" if title else result.message
    fig.suptitle(heading, fontsize=10)
    return _save(fig, path, dpi)
