"""Regenerates docs/gas_results.md, docs/gas_vibration_results.md and the figures docs/figures/gas_*.png.

Run from the repository root: ``python docs/gas_study.py [fixed|vibration|collapse|follow_up|all]`` (default all; a few
minutes on two shared cores).  ``fixed`` writes sections 1-3 to docs/gas_results.md, ``vibration``
sections 4-8 to docs/gas_vibration_results.md, ``collapse`` sections C1-C3 (the collapse detector) to
docs/gas_collapse_results.md.

Every number in those two files is printed by this script; docs/gas.md
quotes them.  The vibration rule uses the restitution table computed from rod
collisions that ships with the package (:func:`wavecontact.gas.default_law`, hard core).
Sections:

1. three rods (McNamara & Young): collapse or not against r around 7 - 4 sqrt(3);
2. N rods on a ring with a fixed restitution: collapse against N / N_c, N_c = -ln(1-r)/(1-r);
3. Haff's law: fitted exponent and t0 against kinetic theory;
4. the collision law: its rows, the effect of the two bath temperatures, direct solves below its last row,
   and the soft (finite-kappa) law against the hard core;
5. the law (tabulated) against one solve per collision on small gases (hard core and finite kappa);
6. the vibration rule against the fixed rule with the same mean restitution (and the one-temperature law's
   bath-limited draws, and a run with a contact stiffness);
7. bath damping: the late-time decay exponent of the translational energy;
8. a space-time picture of a damped vibration gas;
C1. the collapse detector on fixed-restitution cells either side of McNamara and Young's threshold;
C2. what happens after a collapse; C3. the damped gas with the one-temperature law;
F1-F2 (``follow_up``, docs/gas_follow_up_results.md): the damped gas in the set-up of the 1998 follow-up paper
(rods of two lengths in turn, gamma = 4/5), with controlled variations on the same realisations.
"""

from __future__ import annotations

import itertools
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import curve_fit

from wavecontact.errors import SolverFailure
from wavecontact.gas import (
    AlternatingLengths,
    EqualLengths,
    FixedRestitution,
    GasSimulation,
    RodGas,
    UniformLengths,
    VibrationLaw,
    VibrationSolve,
    contact_draw,
    default_law,
    default_soft_law,
    hard_core_draw,
    random_gas,
)
from wavecontact.gas.collision_law import blend_draw, point_samples
from wavecontact.gas.hardcore_collision import hard_core_collision
from wavecontact.plotting.gas import plot_gas
from wavecontact.plotting.ring import _pyplot, _save
from wavecontact.studies.gas import gas_ensemble

DOCS = Path(__file__).resolve().parent
FIGURES = DOCS / "figures"
LAW = default_law()
SOFT = default_soft_law()
STIFFNESS = 100.0  # alpha of the section 6 run with soft contacts
lines = []


def resolution_at(gamma, log_x):
    """Grid points per period the law uses at ``(gamma, log_x)`` (nearest gamma row; below its last row, the last
    row's): the resolution of the direct solves compared with it."""
    a = int(np.argmin(np.abs(LAW.gamma - gamma)))
    b = list(LAW.log_x).index(log_x) if log_x in LAW.log_x else 0
    return LAW.point_resolution(a, b)


def grid_note():
    rows = [LAW.point_resolution(LAW.gamma.size - 1, b) for b in range(LAW.log_x.size)]
    return (f"The gamma = 1 rows are solved on finer grids (resolution {', '.join(map(str, rows))} from x = "
            f"1e{LAW.log_x[0]:g} to 1) and lie below the exact eps^2 = 1 by the grid's error only; `python "
            'docs/law_grid_study.py` measures it (docs/gas.md, "Grid error of the law").')


def trapezoid(probability):
    """Weights of the trapezoid rule over the levels: the mean of a tabulated quantile function."""
    weights = np.zeros(probability.size)
    weights[1:] += 0.5 * np.diff(probability)
    weights[:-1] += 0.5 * np.diff(probability)
    return weights


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


HAFF_ROOT = 2026  # realisation i of the Haff study: SeedSequence(HAFF_ROOT).spawn(HAFF_REALISATIONS)[i]
HAFF_REALISATIONS = 12


def _haff_run(seed, restitution, rods, length, collisions):
    """Fixed-restitution gas of equal rods: (t / t0_kinetic, T / T0) at every half-N collisions."""
    gas = random_gas(rods, seed=seed, lengths=EqualLengths(length), packing_fraction=0.01)
    temperature = 2 * gas.kinetic_energy() / rods
    density = rods / gas.free_length
    t0 = math.sqrt(math.pi * length) / ((1 - restitution**2) * density * math.sqrt(temperature))
    result = GasSimulation(gas, FixedRestitution(restitution), seed=seed, record_every=rods // 2,
                           max_frames=0).run(collisions)
    return result.history["time"] / t0, 2 * result.history["kinetic_energy"] / rods / temperature


def haff():
    say("## 3. Haff's law")
    say()
    restitution, rods, length = 0.98, 50, 0.01
    seeds = np.random.SeedSequence(HAFF_ROOT).spawn(HAFF_REALISATIONS)
    grid = np.geomspace(0.01, 300, 60)
    sem = lambda x: np.std(x, ddof=1) / math.sqrt(len(x))
    runs = [_haff_run(seed, restitution, rods, length, 200 * rods) for seed in seeds]
    say(f"r = {restitution}, N = {rods} equal rods (N_c = {-math.log(0.02) / 0.02:.0f}), packing 0.01, "
        f"{HAFF_REALISATIONS} realisations (SeedSequence({HAFF_ROOT}).spawn({HAFF_REALISATIONS})), 200 N collisions "
        "each; t in units of the kinetic-theory t0 = sqrt(pi m) / ((1 - r^2) n sqrt(T0)). Fits per realisation "
        "over the first K N collisions: T(t) = T0 / (1 + t/t0)^a (a and t0 free), and the same with a = 2 (Haff); "
        "mean +- standard error over the realisations.")
    say()
    say("| collisions fitted | exponent a (2 free) | t0 / kinetic theory (2 free) | t0 / kinetic theory (a = 2) |")
    say("|---|---|---|---|")
    for per_rod in (50, 100, 200):
        exponents, times, fixed = [], [], []
        for t, ratio in runs:
            keep = (t > 0) & (np.arange(t.size) * (rods // 2) <= per_rod * rods)
            (a, c), _ = curve_fit(lambda s, a, c: -a * np.log1p(s / c), t[keep], np.log(ratio[keep]), p0=(2, 1))
            (c2,), _ = curve_fit(lambda s, c: -2 * np.log1p(s / c), t[keep], np.log(ratio[keep]), p0=(1,))
            exponents.append(a)
            times.append(c)
            fixed.append(c2)
        say(f"| {per_rod} N | {np.mean(exponents):.3f} +- {sem(exponents):.3f} | {np.mean(times):.3f} +- "
            f"{sem(times):.3f} | {np.mean(fixed):.3f} +- {sem(fixed):.3f} |")
    say()
    curves = [np.interp(grid, t, ratio) for t, ratio in runs]
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 4.2), constrained_layout=True)
    for curve in curves:
        ax.loglog(grid, curve, "-", color="0.6", lw=0.8)
    ax.loglog(grid, np.mean(curves, axis=0), "C0-", lw=1.8, label=f"mean of {HAFF_REALISATIONS} realisations")
    ax.loglog(grid, (1 + grid) ** -2.0, "k--", lw=1.0, label=r"Haff: $(1 + t/t_0)^{-2}$, kinetic-theory $t_0$")
    ax.set_xlabel(r"$t / t_0$")
    ax.set_ylabel(r"$T / T_0$")
    ax.legend(fontsize=8)
    _save(fig, FIGURES / "gas_haff.png", 130)


def law():
    say("## 4. The collision law of the vibration rule")
    say()
    say(f"Hard-core collisions (kappa = inf), {LAW.bath_modes} modes per bath, {LAW.samples_per_point} solves per "
        f"point, grid resolution {LAW.resolution} (gamma = 1: finer, below); x = E_tr / (E_tr + T_pair), T_pair the mean of the two rods' "
        "temperatures, s = T_short / (T_short + T_long). Mean of eps^2 = E'_tr/E_tr at s = 1/2 (both rods equally "
        "warm), and in brackets the mean gain of the short rod's bath in units of E_tr + T_pair (the long rod's is "
        "(1 - eps^2) x minus it), from the shipped law (`wavecontact/data/collision_law_hardcore.npz`).")
    say()
    say("| gamma | " + " | ".join(f"x = 1e{lx:g}" for lx in LAW.log_x) + " |")
    say("|---|" + "---|" * LAW.log_x.size)
    weights = trapezoid(LAW.probability)
    middle = list(LAW.short_share).index(0.5)
    for a, gamma in enumerate(LAW.gamma):
        cells = [f"{np.sum(LAW.eps2_quantiles[0, a, b, middle] * weights):.3g} "
                 f"({np.sum(LAW.gain_short[0, a, b, middle] * weights):+.2g})" for b in range(LAW.log_x.size)]
        say(f"| {gamma:g} | " + " | ".join(cells) + " |")
    say()
    say(grid_note())
    say()
    say("How the split of the bath temperature between the rods changes the law: mean eps^2 and (in brackets) "
        "the short rod's mean gain in units of E_tr + T_pair, against s, at x = 1e-0.5 and x = 1e-2.")
    say()
    say("| gamma | x | " + " | ".join(f"s = {v:g}" for v in LAW.short_share) + " |")
    say("|---|---|" + "---|" * LAW.short_share.size)
    for a, gamma in enumerate(LAW.gamma):
        for lx in (-0.5, -2.0):
            b = list(LAW.log_x).index(lx)
            cells = [f"{np.sum(LAW.eps2_quantiles[0, a, b, c] * weights):.3g} "
                     f"({np.sum(LAW.gain_short[0, a, b, c] * weights):+.2g})" for c in range(LAW.short_share.size)]
            say(f"| {gamma:g} | 1e{lx:g} | " + " | ".join(cells) + " |")
    say()
    below = LAW.log_x[0] - 1.0
    say(f"Below the last row (x < 1e{LAW.log_x[0]:g}) the rule uses that row's law. Direct solves one decade "
        f"further down (x = 1e{below:g}, s = 1/2, 40 solves per gamma at the resolution of the law's last row, mean "
        "eps^2 +- standard error) against the last row:")
    say()
    say(f"| gamma | direct, x = 1e{below:g} | law's last row | direct mean E'_tr/(E_tr + T_pair) |")
    say("|---|---|---|---|")
    for gamma in (0.6, 0.8, 1.0):
        a = int(np.searchsorted(LAW.gamma, gamma))
        mean_last = np.sum(LAW.eps2_quantiles[0, a, 0, middle] * weights)
        try:
            eps2, _gain = point_samples(gamma, below, 40, 7, bath_modes=LAW.bath_modes,
                                        resolution=resolution_at(gamma, below))
        except SolverFailure as exc:  # a solve too long for the grid bound: say so
            say(f"| {gamma:g} | refused ({str(exc)[:60]}...) | {mean_last:.3g} | - |")
            continue
        say(f"| {gamma:g} | {eps2.mean():.3g} +- {eps2.std(ddof=1) / math.sqrt(eps2.size):.2g} | {mean_last:.3g} | "
            f"{eps2.mean() * 10.0**below:.2g} |")
    say()


def soft_law():
    say("### 4c. Soft contacts: the finite-kappa law")
    say()
    say(f"Finite-kappa delay solves with each rod's energy split, kappa = {', '.join(f'{k:g}' for k in SOFT.kappa)}, "
        f"{SOFT.samples_per_point} solves per point (`wavecontact/data/collision_law_soft.npz`). A gas collision "
        "has kappa = alpha V l; the rule adds to the hard-core draw the soft law's change against the hard core, "
        "interpolated linearly in z = ln(kappa)/kappa between these rows and, above the stiffest, between it and "
        "zero (the hard core, z = 0).")
    say()
    say("Cold collisions at gamma = 0.6: the rule's eps against the independent reference values of "
        "tests/test_delay_solver.py (rows marked * are the law's own rows).")
    say()
    say("| kappa | rule's eps | reference | difference |")
    say("|---|---|---|---|")
    references = {20: 0.7530132413, 100: 0.646697087, 250: 0.622343998, 1000: 0.606972294, 10000: 0.600927488}
    for kappa, reference in references.items():
        eps = math.sqrt(blend_draw(LAW, SOFT, 0.6, 1.0, 0.5, 0.5, kappa)[0])
        mark = "*" if kappa in SOFT.kappa else ""
        say(f"| {kappa}{mark} | {eps:.5f} | {reference:.5f} | {eps - reference:+.1e} |")
    say()
    g = list(SOFT.gamma).index(0.6)
    say("The soft law's own cold rows at gamma = 0.6 (eps, deterministic): " + ", ".join(
        f"kappa = {k:g}: {math.sqrt(SOFT.eps2_quantiles[r, g, -1, 0, 0]):.4f}" for r, k in enumerate(SOFT.kappa))
        + f"; hard core: {math.sqrt(LAW.eps2_quantiles[0, 0, -1, 0, 0]):.4f}. Softer than kappa = "
        f"{SOFT.kappa[0]:g} the rule keeps the kappa = {SOFT.kappa[0]:g} correction.")
    say()
    weights = trapezoid(SOFT.probability)
    hard_weights = trapezoid(LAW.probability)
    say("Warm baths (s = 1/2): mean eps^2 of the soft rows and of the hard-core law, and the standard error of "
        f"a mean over {SOFT.samples_per_point} samples (the soft law's own sampling error) in brackets.")
    say()
    columns = [lx for lx in SOFT.log_x if lx < 0]
    say("| gamma | kappa | " + " | ".join(f"x = 1e{lx:g}" for lx in columns) + " |")
    say("|---|---|" + "---|" * len(columns))
    middle = list(SOFT.short_share).index(0.5)
    hard_middle = list(LAW.short_share).index(0.5)
    for a, gamma in enumerate(SOFT.gamma):
        for r, kappa in enumerate(SOFT.kappa):
            cells = []
            for lx in columns:
                b = list(SOFT.log_x).index(lx)
                q = SOFT.eps2_quantiles[r, a, b, middle]
                mean = np.sum(q * weights)
                spread = math.sqrt(max(np.sum(q**2 * weights) - mean**2, 0.0))
                cells.append(f"{mean:.3g} ({spread / math.sqrt(SOFT.samples_per_point):.2g})")
            say(f"| {gamma:g} | {kappa:g} | " + " | ".join(cells) + " |")
        g = int(np.searchsorted(LAW.gamma, gamma))
        cells = [f"{np.sum(LAW.eps2_quantiles[0, g, list(LAW.log_x).index(lx), hard_middle] * hard_weights):.3g}"
                 for lx in columns]
        say(f"| {gamma:g} | inf | " + " | ".join(cells) + " |")
    say()
def limit_exploration():
    say("### 4b. eps^2 as x -> 0, direct solves")
    say()
    say(f"40 hard-core solves per point (resolution {LAW.resolution}, {LAW.bath_modes} modes; gamma = 1 at the "
        "resolution of the law's row, at x = 1e-5 its last row's), mean eps^2 +- standard error; in brackets the "
        "mean of E'_tr / (E_tr + T_B) = eps^2 x.")
    say()
    exponents = (-1, -2, -3, -4, -5)
    say("| gamma | " + " | ".join(f"x = 1e{e}" for e in exponents) + " |")
    say("|---|" + "---|" * len(exponents))
    for gamma in (0.6, 0.85, 1.0):
        cells = []
        for e in exponents:
            try:
                eps2, _gain = point_samples(gamma, e, 40, 11, bath_modes=LAW.bath_modes,
                                            resolution=resolution_at(gamma, float(e)) if gamma == 1.0 else
                                            LAW.resolution)
            except SolverFailure as exc:  # a solve too long for the grid bound: say so
                cells.append(f"refused ({str(exc)[:40]}...)")
                continue
            sem = eps2.std(ddof=1) / math.sqrt(eps2.size)
            cells.append(f"{eps2.mean():.3g} +- {sem:.2g} ({eps2.mean() * 10.0**e:.2g})")
        say(f"| {gamma:g} | " + " | ".join(cells) + " |")
    say()
    say(grid_note())
    say()
    gains = [hard_core_collision(0.8, 3.0, 1, resolution=r)[1] for r in (8, 16, 32, 64)]
    say("Grid convergence of one rod's gain (gamma 0.8, T_B/E_tr = 3, seed 1; short rod's gain in units of E_tr) at "
        "resolution 8, 16, 32, 64: " + ", ".join(f"{g:.3f}" for g in gains) + ".")
    say()


def _small_gases(rule, seeds, rods, collisions, stiffness=None):
    values, limited, started = [], 0, time.time()
    for seed in range(seeds):
        gas = random_gas(rods, seed=seed, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
        rng = np.random.default_rng(np.random.SeedSequence([seed, 1]))
        gas = RodGas(gas.lengths, gas.positions, gas.velocities,
                     rng.exponential(1.0, rods) * gas.kinetic_energy() / rods, gas.system_length, gas.boundary)
        result = GasSimulation(gas, rule, seed=seed, record_every=collisions, max_frames=0,
                               contact_stiffness=stiffness).run(collisions)
        values.append(math.log(result.final_energy / gas.kinetic_energy()))
        limited += result.bath_limited
    sem = np.std(values, ddof=1) / math.sqrt(len(values))
    return f"{np.mean(values):.3f} +- {sem:.3f} | {limited} | {time.time() - started:.0f}"


def solve_vs_law():
    say("## 5. Law (tabulated) against one solve per collision")
    say()
    rods, collisions, seeds = 16, 80, 12
    say(f"{seeds} gases of {rods} rods (lengths in [0.6, 1], packing 0.2, each bath at its own temperature, "
        "exponentially distributed with mean E_kin/N per mode), the same initial states for each rule; statistic: "
        "log of the final over the initial kinetic energy (mean +- standard error over the gases). 'solve, own "
        "temperatures': each collision one solve with each rod at its own temperature and this collision's own "
        "per-rod split; 'solve, mean temperature': both rods at the pair's mean; 'law, one temperature': the "
        "law's s = 1/2 slice (the earlier law).")
    say()
    say("| contact | rule | log(E_end/E_start) | bath-limited draws (all gases) | wall time (s) |")
    say("|---|---|---|---|---|")
    rules = {"law (kernel)": VibrationLaw(LAW),
             "law, one temperature": VibrationLaw(LAW.equal_temperature_slice()),
             "solve, own temperatures": VibrationSolve(hard_core_draw(resolution=LAW.resolution), per_rod=True),
             "solve, mean temperature": VibrationSolve(hard_core_draw(resolution=LAW.resolution))}
    for name, rule in rules.items():
        say(f"| hard core, {collisions} collisions | {name} | {_small_gases(rule, seeds, rods, collisions)} |")
    soft_rods, soft_collisions, alpha = 10, 40, 30.0
    for name, rule in {"law (kernel), blended at each kappa": VibrationLaw(LAW, SOFT),
                       "finite-kappa solve, own temperatures": VibrationSolve(contact_draw(), per_rod=True)}.items():
        say(f"| alpha = {alpha:g} ({soft_rods} rods, {soft_collisions} collisions) | {name} | "
            f"{_small_gases(rule, seeds, soft_rods, soft_collisions, alpha)} |")
    say()


def vibration_vs_fixed():
    say("## 6. Vibration rule against the fixed rule")
    say()
    rods, seeds = 400, 5
    say(f"N = {rods} rods, lengths uniform in [0.6, 1] (gamma in [0.6, 1]), packing 0.2, cold baths at the start, "
        f"{1000 * rods} collisions at most, the same initial state for every rule. The fixed rule uses the "
        "vibration rule's cold-bath mean restitution for these pairs (hard core: eps = gamma). N_c = "
        "-ln(1-r)/(1-r) is McNamara and Young's critical number. Bath-limited: fraction of the draws that asked a "
        "bath for more than it held, with the law (two temperatures) and with its s = 1/2 slice (one temperature, "
        f"the earlier law). Last column: the law with a contact stiffness alpha = {STIFFNESS:g} (each collision at "
        "its own kappa = alpha V l): status, final / initial kinetic energy, fraction of the draws softer than "
        "the soft law's softest row.")
    say()
    say("| seed | fixed r (N_c) | fixed rule | vibration rule | vibration: final / initial kinetic energy | "
        "draws below the law's last row | bath-limited (two temperatures) | bath-limited (one temperature) | "
        f"alpha = {STIFFNESS:g} |")
    say("|---|---|---|---|---|---|---|---|---|")
    single = VibrationLaw(LAW.equal_temperature_slice())
    for seed in range(seeds):
        gas = random_gas(rods, seed=seed, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
        vibrating = GasSimulation(gas, VibrationLaw(LAW), seed=seed, record_every=rods, max_frames=0)
        r = float(np.mean(vibrating.pair_gamma))
        fixed = GasSimulation(gas, FixedRestitution(r), seed=seed, record_every=rods, max_frames=0).run(1000 * rods)
        result = vibrating.run(1000 * rods)
        old = GasSimulation(gas, single, seed=seed, record_every=rods, max_frames=0).run(1000 * rods)
        soft = GasSimulation(gas, VibrationLaw(LAW, SOFT), seed=seed, record_every=rods, max_frames=0,
                             contact_stiffness=STIFFNESS).run(1000 * rods)
        fixed_text = f"collapsed after {fixed.collisions}" if fixed.collapsed else f"{fixed.status} ({fixed.collisions})"
        ratio = result.final_energy / result.history["kinetic_energy"][0]
        critical = -math.log(1 - r) / (1 - r)
        soft_text = (f"{soft.status} ({soft.collisions}), {soft.final_energy / soft.history['kinetic_energy'][0]:.3g}, "
                     f"{soft.softer_than_law / max(soft.collisions, 1):.2f}")
        say(f"| {seed} | {r:.4f} ({critical:.1f}) | {fixed_text} | {result.status} ({result.collisions}) | "
            f"{ratio:.3g} | {result.beyond_law} | {result.bath_limited / result.collisions:.3f} | "
            f"{old.bath_limited / old.collisions:.3f} | {soft_text} |")
    say()
    modes = LAW.bath_modes
    say(f"Energy is conserved in the vibration runs, so they can end in equipartition: each rod's translation "
        f"holding T/2 and its bath {modes} T would leave a fraction 0.5 / ({modes} + 0.5) = {0.5 / (modes + 0.5):.5f} "
        "of the energy (all kinetic at the start) in the translation.")
    say()


def damping():
    say("## 7. Bath damping: late-time energy decay")
    say()
    rods, collisions, realisations = 200, 4_000_000, 6
    say(f"N = {rods}, lengths in [0.6, 1], packing 0.2, cold baths at the start, vibration rule (hard-core law), "
        f"{collisions:,} collisions at most per run, {realisations} realisations per tau_diss (ensemble on the "
        "serial executor, seeds spawned from 40). Slope: least-squares fit of log E_tr against log t over the last "
        "decade of time reached, per realisation that ran all its collisions (a collapsed run has no late time); "
        "mean +- standard error over those realisations, and the fit's own standard error (median) in brackets.")
    say()
    say("| tau_diss | collapsed / runs | collisions at the collapse (median) | t reached by the others (median) | "
        "E_tr end / start (others, median) | slope of E_tr(t) (others: mean +- sem [fit error], runs) | "
        "bath energy / E_tr at the end (others, median) |")
    say("|---|---|---|---|---|---|---|")
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.2, 4.3), constrained_layout=True)
    for index, tau in enumerate((1.0, 10.0, 100.0, 1000.0)):
        ensemble = gas_ensemble(realisations, rods=rods, collisions=collisions, rule=VibrationLaw(LAW), seed=40,
                                lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2, damping=tau,
                                record_every=collisions // 400)
        slopes, errors, reached, left, baths, collapses = [], [], [], [], [], []
        for k, result in enumerate(ensemble.results):
            t, energy = result.history["time"], result.history["kinetic_energy"]
            ax.loglog(t[t > 0], energy[t > 0], "-", color=f"C{index}", lw=0.9,
                      label=rf"$\tau_\mathrm{{diss}}$ = {tau:g}" if k == 0 else None)
            if result.collapsed:
                collapses.append(result.collisions)
                continue
            late = t > t[-1] / 10
            coefficients, covariance = np.polyfit(np.log(t[late]), np.log(energy[late]), 1, cov=True)
            slopes.append(coefficients[0])
            errors.append(math.sqrt(covariance[0, 0]))
            reached.append(t[-1])
            left.append(energy[-1] / energy[0])
            baths.append(result.history["bath_energy"][-1] / energy[-1])
        collapse_text = f"{np.median(collapses):,.0f}" if collapses else "-"
        if len(slopes) >= 2:
            sem = np.std(slopes, ddof=1) / math.sqrt(len(slopes))
            slope_text = f"{np.mean(slopes):.2f} +- {sem:.2f} [{np.median(errors):.2f}], {len(slopes)}"
        elif slopes:
            slope_text = f"{slopes[0]:.2f} [{errors[0]:.2f}], 1"
        else:
            slope_text = "none"
        others = (f"{np.median(reached):.3g} | {np.median(left):.3g}" if slopes else "- | -")
        bath_text = f"{np.median(baths):.3g}" if slopes else "-"
        say(f"| {tau:g} | {len(collapses)}/{realisations} | {collapse_text} | {others} | {slope_text} | {bath_text} |")
    t_guide = np.geomspace(1e2, 1e5, 10)
    ax.loglog(t_guide, 1e4 * t_guide**-2.0, "k--", lw=1.0, label=r"$\propto t^{-2}$")
    ax.set_xlabel("time")
    ax.set_ylabel("translational energy (centre-of-mass frame)")
    ax.legend(fontsize=8)
    _save(fig, FIGURES / "gas_damping.png", 130)
    say()


def picture():
    gas = random_gas(500, seed=3, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
    sim = GasSimulation(gas, VibrationLaw(LAW), seed=4, record_every=500, max_frames=400)
    result = sim.run(200_000)
    plot_gas(result, FIGURES / "gas_run.png", system_length=gas.system_length,
             title=f"500 rods, vibration rule (hard-core law), no bath damping: {result.status}, "
             f"{result.collisions} collisions")
    say("## 8. Example run (figure gas_run.png)")
    say()
    say(f"500 rods, cold baths at the start, no damping, 200,000 collisions: {result.message}; energy drift "
        f"{result.energy_drift:.1e}; bath-limited draws: {result.bath_limited} "
        f"({result.bath_limited / result.collisions:.3f} of all); draws below the law's last row: "
        f"{result.beyond_law}; kinetic energy at the end / start: "
        f"{result.final_energy / result.history['kinetic_energy'][0]:.3g}.")
    say()
    order = np.argsort(gas.lengths)
    thirds = np.array_split(order, 3)
    single = GasSimulation(gas, VibrationLaw(LAW.equal_temperature_slice()), seed=4, record_every=500, max_frames=0).run(200_000)
    for name, run in (("law (two temperatures)", result), ("one-temperature law (s = 1/2 slice), same start", single)):
        temperature = run.bath_temperatures
        say(f"{name}: bath temperature at the end (per mode, mean over the rods) of the shortest, middle and "
            "longest third of the rods: " + ", ".join(f"{temperature[part].mean():.3g}" for part in thirds) +
            f"; rods with an empty bath (T < 1e-12 of the mean): "
            f"{int(np.sum(temperature < 1e-12 * temperature.mean()))} of {gas.rods}; bath-limited draws "
            f"{run.bath_limited / run.collisions:.3f} of all; mean kinetic energy per rod over the mean bath "
            f"temperature: {run.final_energy / gas.rods / temperature.mean():.3g} (equipartition: 0.5).")
        say()


COLLAPSE_ROOT = 20261206  # realisation i of cell (r, N): SeedSequence([COLLAPSE_ROOT, N, 100 r]).spawn(12)[i]
COLLAPSE_CELLS = ((0.8, 24), (0.8, 32), (0.9, 46), (0.9, 69), (0.95, 60), (0.95, 120))


def _cell_runs(restitution, rods, floor, equal=True, **options):
    """The 12 realisations of a fixed-restitution cell run until a stop (at most 4 million collisions)."""
    seeds = np.random.SeedSequence([COLLAPSE_ROOT, rods, round(100 * restitution)]).spawn(12)
    results = []
    for seed in seeds:
        gas = (random_gas(rods, seed=seed, lengths=EqualLengths(0.01), packing_fraction=0.01) if equal else
               random_gas(rods, seed=seed, lengths=UniformLengths(0.5, 1.0), packing_fraction=0.2))
        sim = GasSimulation(gas, FixedRestitution(restitution), seed=seed, record_every=10**7, max_frames=0,
                            energy_floor=floor, **options)
        results.append(sim.run(4_000_000))
    return results


def collapse_cells():
    say("## C1. The collapse detector on fixed-restitution cells either side of McNamara and Young's threshold")
    say()
    say(f"12 realisations per cell, realisation i from SeedSequence([{COLLAPSE_ROOT}, N, 100 r]).spawn(12)[i]; "
        "each run goes until it stops (at most 4,000,000 collisions). 'equal rods': lengths 0.01, packing 0.01 "
        "(the set-up of gas_results.md section 2); 'unequal rods': lengths uniform in [0.5, 1], packing 0.2 "
        "(random_gas's default lengths). energy floor: the run stops as 'cooled' below that fraction of the initial "
        "kinetic energy (0: no floor, the run goes on until it collapses or freezes numerically). Cell: collapsed / "
        "frozen / cooled (completed), then for the collapses the median collision count, the range of the cluster "
        "sizes (rods) and the median log10 of the kinetic energy left.")
    say()
    say("| rods | energy floor | r | N | N / N_c | collapsed | frozen | cooled (completed) | collisions at the "
        "collapse (median) | cluster rods (range) | log10 E/E0 at the collapse (median) |")
    say("|---|---|---|---|---|---|---|---|---|---|---|")
    for equal, floor in ((True, 1e-20), (True, 0.0), (False, 0.0)):
        for restitution, rods in COLLAPSE_CELLS:
            results = _cell_runs(restitution, rods, floor, equal)
            collapsed = [r for r in results if r.collapsed]
            statuses = [r.status for r in results]
            critical = -math.log(1 - restitution) / (1 - restitution)
            if collapsed:
                sizes = [r.collapse["cluster_rods"] for r in collapsed]
                left = [math.log10(max(r.final_energy, 1e-300) / r.history["kinetic_energy"][0]) for r in collapsed]
                details = (f"{np.median([r.collisions for r in collapsed]):,.0f} | {min(sizes)}-{max(sizes)} | "
                           f"{np.median(left):.0f}")
            else:
                details = "- | - | -"
            say(f"| {'equal' if equal else 'unequal'} | {floor:g} | {restitution} | {rods} | {rods / critical:.1f} | "
                f"{len(collapsed)}/12 | {statuses.count('frozen')} | {statuses.count('cooled')} "
                f"({statuses.count('completed')}) | {details} |")
    say()


def after_collapse():
    say("## C2. What happens after a collapse (continue_after_collapse)")
    say()
    say("The 12 realisations of the cell r = 0.8, N = 32 (equal rods, no energy floor), each run once until the "
        "detector stops it and once with continue_after_collapse for 100,000 collisions more: the collisions after "
        "the detection that fall at the time of the collapse (within 4 ulps of the clock), the time reached, and "
        "the kinetic energy then over the energy at the collapse.")
    say()
    say("| realisation | collapse at collision | cluster rods | collisions at the collapse's time afterwards | "
        "t at the end / t at the collapse | E at the end / E at the collapse |")
    say("|---|---|---|---|---|---|")
    stopped = _cell_runs(0.8, 32, 0.0)
    seeds = np.random.SeedSequence([COLLAPSE_ROOT, 32, 80]).spawn(12)
    for index, (seed, first) in enumerate(zip(seeds, stopped)):
        gas = random_gas(32, seed=seed, lengths=EqualLengths(0.01), packing_fraction=0.01)
        sim = GasSimulation(gas, FixedRestitution(0.8), seed=seed, record_every=1, max_frames=0, energy_floor=0.0,
                            continue_after_collapse=True)
        going = sim.run(first.collisions + 100_000)
        times = going.history["time"][first.collisions + 1:]
        stuck = int(np.sum(times <= first.simulated_time * (1 + 2.0**-50)))
        say(f"| {index} | {first.collisions:,} | {first.collapse['cluster_rods']} | {stuck:,} | "
            f"{going.simulated_time / first.simulated_time:.3g} | {going.final_energy / first.final_energy:.3g} |")
    say()


def damped_one_temperature():
    say("## C3. Damped gas with the one-temperature law (the s = 1/2 slice of the law)")
    say()
    say("The runs of gas_vibration_results.md section 7 (200 rods, lengths in [0.6, 1], packing 0.2, cold baths, "
        "6 realisations per tau_diss from seed 40, at most 4,000,000 collisions) with the law's s = 1/2 slice, "
        "which splits each collision's loss as if both baths had the pair's mean temperature: does the temperature "
        "split decide the collapse?")
    say()
    say("| tau_diss | law | collapsed / runs | collisions at the collapses | completed runs: E_tr end / start (median) |")
    say("|---|---|---|---|---|")
    for tau in (1.0, 10.0, 100.0):
        ensemble = gas_ensemble(6, rods=200, collisions=4_000_000, rule=VibrationLaw(LAW.equal_temperature_slice()),
                                seed=40, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2, damping=tau,
                                record_every=10_000)
        collapses = [r.collisions for r in ensemble.results if r.collapsed]
        others = [r.final_energy / r.history["kinetic_energy"][0] for r in ensemble.results if not r.collapsed]
        say(f"| {tau:g} | one temperature (s = 1/2) | {len(collapses)}/6 | "
            f"{', '.join(f'{c:,}' for c in sorted(collapses)) or '-'} | "
            f"{np.median(others) if others else float('nan'):.3g} |")
    say()


FOLLOW_UP_ROOT = 1998  # realisation i of the follow-up study: SeedSequence(FOLLOW_UP_ROOT).spawn(FOLLOW_UP_RUNS)[i]
FOLLOW_UP_RUNS = 8
FOLLOW_UP_RODS = 200
FOLLOW_UP_COLLISIONS = 4_000_000
FOLLOW_UP_TAUS = (1.0, 10.0, 100.0, 1000.0)
FOLLOW_UP_FIT_FLOOR = 1e-20  # the slope is fitted over the last decade of time before E_tr falls below this
FOLLOW_UP_EARLY = 200_000  # 1,000 collisions per rod: how many runs collapse this early
FOLLOW_UP_LENGTHS = AlternatingLengths(0.8, 1.0)  # gamma = 4/5 at every collision, as in the 1998 paper


def _follow_up_simulation(seed, rule, damping, **options):
    """Realisation ``seed`` of the 1998 paper's set-up (the same split of the stream as ``gas_ensemble``).

    The two children are built from the sequence's key rather than by ``seed.spawn(2)``, which would give new
    children on every call: each variant and tau_diss must get the same realisation."""
    initial, dynamics = (np.random.SeedSequence(seed.entropy, spawn_key=seed.spawn_key + (j,)) for j in (0, 1))
    gas = random_gas(FOLLOW_UP_RODS, seed=initial, lengths=FOLLOW_UP_LENGTHS, packing_fraction=0.2)
    return GasSimulation(gas, rule, damping=damping, seed=dynamics, record_every=FOLLOW_UP_COLLISIONS // 400,
                         max_frames=0, energy_floor=0.0, **options)


def _cluster_state(sim, collapse):
    """The pairs of a detected cluster: log10 of x = E_tr / (E_tr + T_pair) and the short rod's share s."""
    n = sim.gas.rods
    first, last = collapse["first_rod"], collapse["last_rod"]
    rods = [(first + k) % n for k in range((last - first) % n + 1)]
    log_x, shares = [], []
    for a, b in itertools.pairwise(rods):
        mu = sim.mass[a] * sim.mass[b] / (sim.mass[a] + sim.mass[b])
        energy = 0.5 * mu * (sim.v[a] - sim.v[b]) ** 2
        short = a if sim.mass[a] < sim.mass[b] else b
        pair = 0.5 * (sim.temperature[a] + sim.temperature[b])
        log_x.append(math.log10(energy / (energy + pair)) if energy + pair > 0 else 0.0)
        shares.append(sim.temperature[short] / (2 * pair) if pair > 0 else 0.5)
    return np.array(log_x), np.array(shares)


def _law_with_modes(law, modes):
    """The same law with another bath heat capacity (``modes`` per bath in the energy bookkeeping only)."""
    from dataclasses import replace
    return replace(law, bath_modes=modes)


FOLLOW_UP_VARIANTS = (  # name, rule, simulation options
    ("law (two temperatures), 250 modes", lambda: VibrationLaw(LAW), {}),
    ("one-temperature law (s = 1/2 slice)", lambda: VibrationLaw(LAW.equal_temperature_slice()), {}),
    ("law, bath heat capacity of 25 modes", lambda: VibrationLaw(_law_with_modes(LAW, 25)), {}),
    (f"law with soft contacts, alpha = {STIFFNESS:g}", lambda: VibrationLaw(LAW, SOFT),
     {"contact_stiffness": STIFFNESS}),
)


def follow_up_law():
    say("## F0. The law at gamma = 4/5: mean eps^2 and mean ln eps^2 against x")
    say()
    say("From the shipped hard-core law's quantiles at gamma = 0.8 (a row of its grid: no interpolation in gamma), "
        "for the short rod's share s = 0, 1/2, 1. A pair whose E_tr is multiplied by eps^2 at every collision "
        "shrinks geometrically when the mean of ln eps^2 is negative, however large the mean of eps^2: that sign "
        "decides whether kicks can stop a cluster from collapsing. Each cell: mean eps^2 / mean ln eps^2 "
        "(the quantile function integrated over its levels, linear between them).")
    say()
    g = list(LAW.gamma).index(0.8)
    say("| s | " + " | ".join(f"log10 x = {v:g}" for v in LAW.log_x) + " |")
    say("|---|" + "---|" * LAW.log_x.size)
    for si, share in enumerate(LAW.short_share):
        if share not in (0.0, 0.5, 1.0):
            continue
        cells = []
        for xi in range(LAW.log_x.size):
            q = LAW.eps2_quantiles[0, g, xi, si]
            cells.append(f"{trapezoid_levels(q):.3g} / {trapezoid_levels(np.log(np.maximum(q, 1e-300))):+.2f}")
        say(f"| {share:g} | " + " | ".join(cells) + " |")
    say()


def trapezoid_levels(values):
    """Mean of a quantity given at the law's levels (trapezoid over the probability levels)."""
    p = LAW.probability
    return float(np.sum(0.5 * (values[1:] + values[:-1]) * np.diff(p)))


def follow_up():
    follow_up_law()
    say("## F1. The damped gas in the set-up of the 1998 follow-up paper")
    say()
    say(f"Aspelmeier, Giese and Zippelius, PRE 57, 857 (1998): rods of two lengths in turn, so that every collision has "
        f"gamma = 4/5; one bath temperature per rod; collisions drawn as a Markov process from the two-rod "
        f"calculation; damping of the vibrations with one time tau_diss. Here: N = {FOLLOW_UP_RODS} rods of lengths "
        f"0.8 and 1 in turn on a ring (packing 0.2; in one dimension the packing only rescales the free length, i.e. "
        f"the time unit), Maxwellian velocities, cold baths at the start, at most {FOLLOW_UP_COLLISIONS:,} "
        f"collisions per run ({FOLLOW_UP_COLLISIONS // FOLLOW_UP_RODS:,} per rod), {FOLLOW_UP_RUNS} realisations: "
        f"realisation i from SeedSequence({FOLLOW_UP_ROOT}).spawn({FOLLOW_UP_RUNS})[i] (the same realisations for "
        "every tau_diss and every variant below). No energy floor: a run ends when it collapses, freezes numerically (its relative motion lost in the rounding) or reaches the collision limit. Collapse: the package's detector (a cluster of >= 3 rods with gaps "
        "below 1e-6 of the mean free spacing whose collisions accelerate until 16 fall within 4 ulps of the clock).")
    say()
    say(f"Criterion, fixed before the runs: the paper's 'inelastic collapse is avoided also with damping' is "
        f"*reproduced* at a tau_diss if 0 of the {FOLLOW_UP_RUNS} runs collapse within {FOLLOW_UP_COLLISIONS:,} "
        f"collisions, *not reproduced* if any does. Its 't^-2 at long times' is *reproduced* if the mean slope of "
        "log E_tr against log t over the last decade of time of the runs that did not collapse (before E_tr "
        f"fell below {FOLLOW_UP_FIT_FLOOR:g} of its start, for a run that cooled that far) lies within 3 "
        "standard errors of -2 (at least 3 such runs).")
    say()
    say(f"| variant | tau_diss | collapsed / runs | collapsed within the first {FOLLOW_UP_EARLY:,} collisions | "
        "runs ended (status; collisions reached) | collisions at the collapses (median, range) | slope of E_tr(t), "
        "last decade (mean +- sem, runs) | E_tr end / start (not collapsed, median) | verdict: collapse avoided; "
        "t^-2 |")
    say("|---|---|---|---|---|---|---|---|---|")
    plt = _pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.3), constrained_layout=True)
    seeds = np.random.SeedSequence(FOLLOW_UP_ROOT).spawn(FOLLOW_UP_RUNS)
    collapsed_runs = {}
    counts = {}
    softer = []
    for variant, (name, make_rule, options) in enumerate(FOLLOW_UP_VARIANTS):
        for index, tau in enumerate((math.inf,) + FOLLOW_UP_TAUS if variant == 0 else FOLLOW_UP_TAUS):
            collapses, slopes, left_over, statuses, reached = [], [], [], [], []
            for k, seed in enumerate(seeds):
                sim = _follow_up_simulation(seed, make_rule(), None if math.isinf(tau) else tau, **options)
                result = sim.run(FOLLOW_UP_COLLISIONS)
                statuses.append(result.status)
                reached.append(result.collisions)
                if options:
                    softer.append(result.softer_than_law / result.collisions)
                t, energy = result.history["time"], result.history["kinetic_energy"]
                if variant == 0 and not math.isinf(tau):
                    left.loglog(t[t > 0], energy[t > 0], "-", color=f"C{index - 1}", lw=0.8,
                                label=rf"$\tau_\mathrm{{diss}}$ = {tau:g}" if k == 0 else None)
                    if result.collapsed:
                        left.plot(t[-1], energy[-1], "kx", ms=6)
                if result.collapsed:
                    collapses.append(result.collisions)
                    if variant == 0:
                        collapsed_runs[(tau, k)] = (result.collapse, result.final_energy, *_cluster_state(sim, result.collapse))
                    continue
                warm = (t > 0) & (energy > FOLLOW_UP_FIT_FLOOR * energy[0])  # a frozen gas ends at E = 0
                late = warm & (t > t[warm][-1] / 10)
                slopes.append(np.polyfit(np.log(t[late]), np.log(energy[late]), 1)[0])
                left_over.append(energy[-1] / energy[0])
            counts[(variant, tau)] = len(collapses)
            where = (f"{np.median(collapses):,.0f} ({min(collapses):,}-{max(collapses):,})" if collapses else "-")
            sem = np.std(slopes, ddof=1) / math.sqrt(len(slopes)) if len(slopes) >= 2 else math.nan
            slope = f"{np.mean(slopes):.2f} +- {sem:.2f}, {len(slopes)}" if len(slopes) >= 2 else "-"
            if math.isinf(tau):
                verdict = ("reproduced" if not collapses else "not reproduced") + " (no damping: the paper's first claim)"
            else:
                decay = ("not judged (fewer than 3 runs)" if len(slopes) < 3 else
                         "reproduced" if abs(np.mean(slopes) + 2.0) <= 3 * sem else "not reproduced")
                verdict = f"{'reproduced' if not collapses else 'not reproduced'}; {decay}"
            early = sum(c <= FOLLOW_UP_EARLY for c in collapses)
            ended = ", ".join(f"{statuses.count(k)} {k}" for k in dict.fromkeys(statuses))
            say(f"| {name} | {'none' if math.isinf(tau) else f'{tau:g}'} | {len(collapses)}/{FOLLOW_UP_RUNS} | "
                f"{early}/{FOLLOW_UP_RUNS} | {ended}; {min(reached):,}-{max(reached):,} collisions | {where} | "
                f"{slope} | {np.median(left_over) if left_over else float('nan'):.3g} | {verdict} |")
    say(f"Soft contacts: each collision at its own kappa = alpha V l (docs/gas.md); {min(softer):.0%} to "
        f"{max(softer):.0%} of a run's draws fall below the soft law's softest row (kappa = 5) and take its "
        "correction, which dissipates more than their softer contacts would (eps -> 1 as kappa -> 0).")
    say()
    t_guide = np.geomspace(1e2, 1e5, 10)
    left.loglog(t_guide, 3e3 * t_guide**-2.0, "k--", lw=1.0, label=r"$\propto t^{-2}$")
    left.set_xlabel("time")
    left.set_ylabel("translational energy (centre-of-mass frame)")
    left.set_title(r"$\gamma$ = 4/5 in turn, law with damping (x: collapse detected)", fontsize=9)
    left.legend(fontsize=8)
    width = 0.2
    for variant, (name, _make, _options) in enumerate(FOLLOW_UP_VARIANTS):
        right.bar(np.arange(len(FOLLOW_UP_TAUS)) + (variant - 1.5) * width,
                  [counts[(variant, tau)] for tau in FOLLOW_UP_TAUS], width, label=name)
    right.set_xticks(range(len(FOLLOW_UP_TAUS)), [rf"$\tau_\mathrm{{diss}}$ = {tau:g}" for tau in FOLLOW_UP_TAUS])
    right.set_ylim(0, FOLLOW_UP_RUNS)
    right.set_ylabel(f"runs collapsed (of {FOLLOW_UP_RUNS})")
    right.legend(fontsize=8)
    _save(fig, FIGURES / "gas_follow_up.png", 130)
    follow_up_clusters(collapsed_runs, seeds)


def follow_up_clusters(collapsed_runs, seeds):
    say("## F2. The collapses of F1 (law, 250 modes): the cluster's pairs at the detection, and the runs continued")
    say()
    say("Each collapsed run of the first variant of F1: log10 x = log10(E_tr / (E_tr + T_pair)) of the cluster's "
        "neighbour pairs at the detection (median and range; the law's rows reach -4, its kicks grow below about "
        "-1 when both baths are warm), the pairs whose short-rod share s lies below 0.1 or above 0.9 (noise on one "
        "rod only: the law then gives about the cold eps^2 = gamma^2 = 0.64 at every x), and the same realisation "
        f"run again with continue_after_collapse to {FOLLOW_UP_COLLISIONS:,} collisions: the collisions after the "
        "detection that fall at the collapse's time (within 4 ulps of the clock; the fixed-restitution collapses of "
        "gas_collapse_results.md section C2 show 4 to 24), its status, the time it reached over the time of the "
        "collapse, and the translational energy then over the energy at the collapse.")
    say()
    say("| tau_diss | realisation | collapse at collision | cluster rods | log10 x of its pairs (median, range) | "
        "pairs with s < 0.1 or > 0.9 | continued: collisions at the collapse's time | continued: status, "
        "collisions | t end / t collapse | E end / E collapse |")
    say("|---|---|---|---|---|---|---|---|---|---|")
    for (tau, k), (collapse, energy_then, log_x, shares) in sorted(collapsed_runs.items()):
        sim = _follow_up_simulation(seeds[k], VibrationLaw(LAW), tau, continue_after_collapse=True)
        sim.run(collapse["collision"])  # the same run up to the detection (the detector notes it and goes on)
        stuck = 0
        while stuck < 100_000:  # collisions after the detection that fall at the collapse's time (4 ulps)
            sim.run(1)
            if sim.time > collapse["time"] * (1 + 2.0**-50):
                break
            stuck += 1
        going = sim.run(FOLLOW_UP_COLLISIONS - sim.collisions)
        one_rod = int(np.sum((shares < 0.1) | (shares > 0.9)))
        say(f"| {tau:g} | {k} | {collapse['collision']:,} | {collapse['cluster_rods']} | {np.median(log_x):.1f} "
            f"({log_x.min():.1f} to {log_x.max():.1f}) | {one_rod} of {log_x.size} | {stuck:,} | {going.status}, "
            f"{going.collisions:,} | {going.simulated_time / collapse['time']:.3g} | "
            f"{going.final_energy / energy_then:.3g} |")
    say()


def main(argv):
    which = argv[0] if argv else "all"
    if which not in ("fixed", "vibration", "collapse", "follow_up", "all"):
        print("usage: python docs/gas_study.py [fixed|vibration|collapse|follow_up|all]", file=sys.stderr)
        return 2
    parts = {"fixed": ("gas_results.md", "Rod gas", (three_rods, n_rods, haff)),
             "vibration": ("gas_vibration_results.md", "Rod gas, vibration rule",
                           (law, limit_exploration, soft_law, solve_vs_law, vibration_vs_fixed, damping, picture)),
             "collapse": ("gas_collapse_results.md", "Rod gas, the collapse detector",
                          (collapse_cells, after_collapse, damped_one_temperature)),
             "follow_up": ("gas_follow_up_results.md", "Rod gas, the damped gas against the 1998 follow-up paper",
                           (follow_up,))}
    for name, (page, title, sections) in parts.items():
        if which not in (name, "all"):
            continue
        lines.clear()
        started = time.time()
        say(f"# {title}: results regenerated by `python docs/gas_study.py {name}`")
        say()
        say("Generated file; docs/gas.md explains it.  Machine: two cores shared with other jobs.")
        say()
        for section in sections:
            section()
        say(f"(wall time {time.time() - started:.0f} s)")
        (DOCS / page).write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
