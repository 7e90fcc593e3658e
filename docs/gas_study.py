"""Regenerates docs/gas_results.md and the figures docs/figures/gas_*.png used by docs/gas.md.

Run from the repository root: ``python docs/gas_study.py`` (a few minutes on two shared cores).

Every number in docs/gas_results.md is printed by this script; docs/gas.md
quotes them.  Sections:

1. three rods (McNamara & Young): collapse or not against r around 7 - 4 sqrt(3);
2. N rods on a ring with a fixed restitution: collapse against N / N_c, N_c = -ln(1-r)/(1-r);
3. Haff's law: fitted exponent and t0 against kinetic theory;
4. the vibration rule (thermal-kick stand-in table) against the fixed rule with the same mean restitution;
5. bath damping: the late-time decay exponent of the translational energy;
6. a space-time picture of a damped vibration gas.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import curve_fit

from wavecontact.gas import (
    EqualLengths,
    FixedRestitution,
    GasSimulation,
    RodGas,
    UniformLengths,
    VibrationTable,
    random_gas,
    thermal_kick_table,
)
from wavecontact.plotting.gas import plot_gas
from wavecontact.plotting.ring import _pyplot, _save
from wavecontact.studies.gas import gas_ensemble

DOCS = Path(__file__).resolve().parent
FIGURES = DOCS / "figures"
TABLE = thermal_kick_table()
lines = []


def say(text=""):
    print(text, flush=True)
    lines.append(text)


def three_rods():
    critical = 7 - 4 * math.sqrt(3)
    say("## 1. Three rods")
    say()
    say(f"Rods of length 0.01 at -3, m, +3 (m uniform in [-0.5, 0.5]), velocities +1, 0, -u (u uniform in "
        f"[0.5, 1.5]); five initial conditions per r; r_c = 7 - 4 sqrt(3) = {critical:.6f}.")
    say()
    say("| r / r_c | r | collapsed | collisions (min-max) |")
    say("|---|---|---|---|")
    for factor in (0.5, 0.9, 0.98, 1.02, 1.1, 2.0):
        r = factor * critical
        counts, collapsed = [], 0
        for seed in range(5):
            rng = np.random.default_rng(np.random.SeedSequence(seed))
            middle, speed = rng.uniform(-0.5, 0.5), rng.uniform(0.5, 1.5)
            gas = RodGas([0.01] * 3, [497.0, 500.0 + middle, 503.0], [1.0, 0.0, -speed], [0, 0, 0], 1000.0)
            result = GasSimulation(gas, FixedRestitution(r), record_every=10**6, energy_floor=0.0).run(
                10**5, max_time=100.0)
            collapsed += result.collapsed
            counts.append(result.collisions)
        say(f"| {factor:g} | {r:.5f} | {collapsed}/5 | {min(counts)}-{max(counts)} |")
    say()


def n_rods():
    say("## 2. N rods, fixed restitution")
    say()
    say("Equal rods (length 0.01, packing 0.01) on a ring, Maxwellian velocities, six seeds per cell; each run "
        "goes until a collapse or until the kinetic energy has fallen to 1e-20 of its start ('cooled'). "
        "Cell: collapsed runs / 6, and the median log10 of the kinetic energy left at the collapse.")
    say()
    factors = (0.5, 1.0, 2.0, 3.0, 4.0, 8.0)
    say("| r | N_c | " + " | ".join(f"N = {f:g} N_c" for f in factors) + " |")
    say("|---|---|" + "---|" * len(factors))
    for r in (0.6, 0.8, 0.9, 0.95):
        critical = -math.log(1 - r) / (1 - r)
        cells = []
        for f in factors:
            n = max(3, round(f * critical))
            collapsed, left = 0, []
            for seed in range(6):
                gas = random_gas(n, seed=seed, lengths=EqualLengths(0.01), packing_fraction=0.01)
                start = gas.kinetic_energy()
                sim = GasSimulation(gas, FixedRestitution(r), seed=seed, record_every=10**7, max_frames=0)
                result = sim.run(10**7)
                if result.collapsed:
                    collapsed += 1
                    left.append(math.log10(max(result.final_energy, 1e-300) / start))
            cell = f"{collapsed}/6 (N={n}" + (f", {np.median(left):.0f})" if left else ")")
            cells.append(cell)
        say(f"| {r} | {critical:.1f} | " + " | ".join(cells) + " |")
    say()


def haff():
    say("## 3. Haff's law")
    say()
    restitution, rods, length = 0.98, 50, 0.01
    exponents, times, curves = [], [], []
    grid = np.geomspace(0.01, 300, 60)
    for seed in range(8):
        gas = random_gas(rods, seed=seed, lengths=EqualLengths(length), packing_fraction=0.01)
        temperature = 2 * gas.kinetic_energy() / rods
        density = rods / gas.free_length
        t0 = math.sqrt(math.pi * length) / ((1 - restitution**2) * density * math.sqrt(temperature))
        result = GasSimulation(gas, FixedRestitution(restitution), seed=seed, record_every=rods // 2,
                               max_frames=0).run(200 * rods)
        t = result.history["time"] / t0
        ratio = 2 * result.history["kinetic_energy"] / rods / temperature
        (a, c), _ = curve_fit(lambda s, a, c: -a * np.log1p(s / c), t[t > 0], np.log(ratio[t > 0]), p0=(2, 1))
        exponents.append(a)
        times.append(c)
        curves.append(np.interp(grid, t, ratio))
    sem = lambda x: np.std(x, ddof=1) / math.sqrt(len(x))
    say(f"r = {restitution}, N = {rods} equal rods (N_c = {-math.log(0.02) / 0.02:.0f}), packing 0.01, 200 N "
        "collisions, 8 realisations; T(t) = T0 / (1 + t/t0)^a fitted per realisation, t in units of the "
        "kinetic-theory t0 = sqrt(pi m) / ((1 - r^2) n sqrt(T0)).")
    say()
    say(f"- exponent a = {np.mean(exponents):.3f} +- {sem(exponents):.3f} (Haff: 2)")
    say(f"- t0 / kinetic theory = {np.mean(times):.3f} +- {sem(times):.3f}")
    say()
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 4.2), constrained_layout=True)
    for curve in curves:
        ax.loglog(grid, curve, "-", color="0.6", lw=0.8)
    ax.loglog(grid, np.mean(curves, axis=0), "C0-", lw=1.8, label="mean of 8 realisations")
    ax.loglog(grid, (1 + grid) ** -2.0, "k--", lw=1.0, label=r"Haff: $(1 + t/t_0)^{-2}$, kinetic-theory $t_0$")
    ax.set_xlabel(r"$t / t_0$")
    ax.set_ylabel(r"$T / T_0$")
    ax.legend(fontsize=8)
    _save(fig, FIGURES / "gas_haff.png", 130)


def vibration_vs_fixed():
    say("## 4. Vibration rule against the fixed rule")
    say()
    rods = 400
    say(f"N = {rods} rods, lengths uniform in [0.6, 1] (gamma in [0.6, 1]), packing 0.2, cold baths at the start, "
        f"{300 * rods} collisions at most; table: the thermal-kick stand-in ({TABLE.bath_modes} modes per bath). "
        "The fixed rule uses the mean restitution the table gives these pairs with cold baths (= mean gamma).")
    say()
    say("| seed | fixed r | fixed rule | vibration rule | vibration: final / initial kinetic energy |")
    say("|---|---|---|---|---|")
    for seed in range(5):
        gas = random_gas(rods, seed=seed, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
        vibrating = GasSimulation(gas, VibrationTable(TABLE), seed=seed, record_every=rods, max_frames=0)
        gamma = vibrating.pair_gamma
        r = float(np.mean(TABLE.mean_restitution(gamma, np.zeros_like(gamma))))
        fixed = GasSimulation(gas, FixedRestitution(r), seed=seed, record_every=rods, max_frames=0).run(300 * rods)
        result = vibrating.run(300 * rods)
        fixed_text = f"collapsed after {fixed.collisions}" if fixed.collapsed else fixed.status
        ratio = result.final_energy / result.history["kinetic_energy"][0]
        say(f"| {seed} | {r:.4f} | {fixed_text} | {result.status} ({result.collisions}) | {ratio:.3g} |")
    say()


def damping():
    say("## 5. Bath damping: late-time energy decay")
    say()
    rods, collisions, realisations = 200, 4_000_000, 4
    say(f"N = {rods}, lengths in [0.6, 1], packing 0.2, vibration rule (stand-in table), {collisions:,} collisions "
        f"per run, {realisations} realisations (ensemble on the serial executor). Slope: least-squares fit of "
        "log E_tr against log t over the last decade of time reached.")
    say()
    say("| tau_diss | statuses | t reached (median) | slope of E_tr(t) (mean +- sem) |")
    say("|---|---|---|---|")
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.2, 4.3), constrained_layout=True)
    for index, tau in enumerate((1.0, 10.0, 100.0, 1000.0)):
        ensemble = gas_ensemble(realisations, rods=rods, collisions=collisions, rule=VibrationTable(TABLE), seed=40,
                                lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2, damping=tau,
                                record_every=collisions // 400)
        slopes, reached = [], []
        for k, result in enumerate(ensemble.results):
            t, energy = result.history["time"], result.history["kinetic_energy"]
            late = t > t[-1] / 10
            slopes.append(np.polyfit(np.log(t[late]), np.log(energy[late]), 1)[0])
            reached.append(t[-1])
            ax.loglog(t[t > 0], energy[t > 0], "-", color=f"C{index}", lw=0.9,
                      label=rf"$\tau_\mathrm{{diss}}$ = {tau:g}" if k == 0 else None)
        sem = np.std(slopes, ddof=1) / math.sqrt(len(slopes))
        statuses = ", ".join(sorted(set(ensemble.summary()["statuses"])))
        say(f"| {tau:g} | {statuses} | {np.median(reached):.3g} | {np.mean(slopes):.2f} +- {sem:.2f} |")
    t_guide = np.geomspace(1e2, 1e5, 10)
    ax.loglog(t_guide, 1e4 * t_guide**-2.0, "k--", lw=1.0, label=r"$\propto t^{-2}$")
    ax.set_xlabel("time")
    ax.set_ylabel("translational energy (centre-of-mass frame)")
    ax.legend(fontsize=8)
    _save(fig, FIGURES / "gas_damping.png", 130)
    say()


def picture():
    gas = random_gas(500, seed=3, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
    sim = GasSimulation(gas, VibrationTable(TABLE), seed=4, damping=50.0, record_every=250, max_frames=400)
    result = sim.run(100_000)
    plot_gas(result, FIGURES / "gas_run.png", system_length=gas.system_length,
             title=f"500 rods, vibration rule (stand-in table), tau_diss = 50: {result.message}")
    say("## 6. Example run (figure gas_run.png)")
    say()
    say(f"500 rods, tau_diss = 50, 100,000 collisions: {result.message}; energy drift {result.energy_drift:.1e}; "
        f"ratio lookups beyond the table: {result.ratio_clamped}; bath-limited draws: {result.bath_limited}.")
    say()


def main():
    started = time.time()
    say("# Rod gas: results regenerated by `python docs/gas_study.py`")
    say()
    say("Generated file; docs/gas.md explains it.  Machine: two cores shared with other jobs.")
    say()
    for section in (three_rods, n_rods, haff, vibration_vs_fixed, damping, picture):
        section()
    say(f"(wall time {time.time() - started:.0f} s)")
    (DOCS / "gas_results.md").write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
