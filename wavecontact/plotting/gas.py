"""Figures of a rod-gas run: energy, collision rate, velocity distribution, and the clusters in space-time."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..gas.simulation import GasResult
from .ring import _pyplot, _save

__all__ = ["plot_gas"]


def plot_gas(result: GasResult, path, *, system_length=None, title="", dpi=130) -> Path:
    """Four panels: kinetic (and bath) energy against time and against collisions, the collision rate,
    the distribution of ``v / v_rms`` against a Gaussian, and the space-time picture of the rods.

    Parameters
    ----------
    result : GasResult
        A run with its history (and frames for the space-time panel).
    path : path-like
        Output image.
    system_length : float, optional
        Ring circumference (the horizontal range of the space-time panel).
    title : str
        Figure title.
    """
    plt = _pyplot()
    h = result.history
    fig, axes = plt.subplots(2, 2, figsize=(11.5, 8.5), constrained_layout=True)
    ax_t, ax_c, ax_v, ax_x = axes.ravel()
    t, kinetic, bath = h["time"], h["kinetic_energy"], h["bath_energy"]
    late = t > 0
    ax_t.loglog(t[late], kinetic[late], "-", lw=1.3, label="translational (centre-of-mass frame)")
    if np.any(bath > 0):
        ax_t.loglog(t[late], bath[late], "-", lw=1.0, label="vibrations (baths)")
    if late.sum() > 2:
        anchor_t, anchor_e = t[late][-1], kinetic[late][-1]
        guide = t[late][t[late] > anchor_t / 30]
        ax_t.loglog(guide, anchor_e * (guide / anchor_t) ** -2.0, "k:", lw=1.0, label=r"$\propto t^{-2}$")
    ax_t.set_xlabel("time")
    ax_t.set_ylabel("energy")
    ax_t.legend(fontsize=8)
    ax_c.semilogy(h["collisions"], kinetic, "-", lw=1.3, label="translational energy")
    ax_c.set_xlabel("collisions")
    ax_c.set_ylabel("energy")
    _, rate = result.collision_rate()
    if rate.size:
        twin = ax_c.twinx()
        finite = np.isfinite(rate)
        twin.plot(0.5 * (h["collisions"][1:] + h["collisions"][:-1])[finite], rate[finite], "C1-", lw=0.8)
        twin.set_ylabel("collisions per unit time", color="C1")
        twin.set_yscale("log")
    v = result.velocities - np.mean(result.velocities)
    rms = np.sqrt(np.mean(v**2))
    if rms > 0:
        ax_v.hist(v / rms, bins=max(10, min(60, int(np.sqrt(v.size)))), density=True, histtype="step", lw=1.3, label="rods at the end")
        grid = np.linspace(-4, 4, 200)
        ax_v.plot(grid, np.exp(-grid**2 / 2) / np.sqrt(2 * np.pi), "k--", lw=1.0, label="Gaussian")
        ax_v.set_yscale("log")
        ax_v.set_ylim(1e-4, 1)
    ax_v.set_xlabel(r"$v / v_\mathrm{rms}$")
    ax_v.set_ylabel("density")
    ax_v.legend(fontsize=8)
    if result.frames.size:
        frames, times = result.frames, result.frame_times
        rows = np.repeat(np.arange(times.size), frames.shape[1])
        ax_x.scatter(frames.ravel(), rows, s=0.15, c="k", marker=".", linewidths=0)
        ticks = np.linspace(0, times.size - 1, min(6, times.size)).astype(int)
        ax_x.set_yticks(ticks)
        ax_x.set_yticklabels([f"{times[i]:.3g}" for i in ticks])
        if system_length:
            ax_x.set_xlim(0, system_length)
    ax_x.set_xlabel("position (centre-of-mass frame)")
    ax_x.set_ylabel("time (one row per frame)")
    fig.suptitle(title or result.message, fontsize=10)
    return _save(fig, path, dpi)
