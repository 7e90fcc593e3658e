"""Regenerate the measured numbers of docs/bath.md (sections 5-7) and of docs/markov.md's Eq. 32 section.

    python docs/bath_studies.py                 # every study (about 20 minutes on 2 shared cores)
    python docs/bath_studies.py grid modes      # only some: grid, modes, kappa, boltzmann, uptake
    python docs/bath_studies.py boltzmann uptake --update-docs   # also write their tables into the pages

The tables are printed as markdown (kept in docs/figures/bath/studies.txt); with ``--update-docs``
each study writes its table into its marked block (``BLOCKS``: docs/bath.md sections 5-7,
docs/markov.md's Eq. 32 section), headed by the command and the load average of the run:

grid       convergence of the hard-core grid against its resolution (docs/bath.md section 5);
modes      nu_max dependence of the statistics in the hard-core mode, at two grid resolutions
           on the same samples (section 6);
kappa      kappa-independence: paired ensembles (the same seeds, hence the same realisations) at
           kappa = 25, 50, 100, 250 against the hard-core mode (section 7);
boltzmann  Eq. 32 with E drawn from Boltzmann: the mean of E' - E against nu_max and the grid
           (docs/markov.md, "A small Boltzmann defect");
uptake     the energy that the cold modes above nu_max take up in the same transitions (same section).
"""

from __future__ import annotations

import math
import re
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(1, str(Path(__file__).resolve().parent.parent / "benchmarks"))

from docs_block import captured_stdout, run_header, write_block

from wavecontact.bath import ThermalBath
from wavecontact.bath.scene import start_gap
from wavecontact.contact import Hard
from wavecontact.delay.stochastic_hardcore import hard_core_noise
from wavecontact.studies.ensemble import ensemble, sample_seed

GAMMA = 0.6173


def kappa_independence(pool, samples=300, temperature=1.0, seed=50):
    hard = ensemble(GAMMA, math.inf, temperature, samples, seed, executor=pool, batch_size=50)
    print(f"\n### kappa-independence (gamma {GAMMA}, T_B/E_tr {temperature}, nu_max 250, {samples} paired samples)\n")
    print("| kappa | mean eps (SE) | std eps | mean of eps(kappa) - eps(inf) (SE) | median abs difference |")
    print("|---|---|---|---|---|")
    for kappa in (25.0, 50.0, 100.0, 250.0):
        soft = ensemble(GAMMA, kappa, temperature, samples, seed, executor=pool, batch_size=20, rtol=1e-6)
        diff = soft.restitution - hard.restitution
        print(f"| {kappa:g} | {soft.mean:.4f} ({soft.standard_error:.4f}) | {soft.std:.4f} | "
              f"{diff.mean():+.4f} ({diff.std(ddof=1) / math.sqrt(diff.size):.4f}) | {np.median(np.abs(diff)):.4f} |")
    print(f"| inf (hard-core mode) | {hard.mean:.4f} ({hard.standard_error:.4f}) | {hard.std:.4f} | 0 | 0 |")


MODES = (50, 100, 250, 500, 1000, 2000)
# the paper's cases (Fig. 9): gamma, T_B/E_tr, samples (standard error of the mean below 0.002)
# (the long rod of gamma = 0.2173 makes a sample about three times as costly: three values of nu_max there)
CASES = ((0.6173, 0.1, 5_000, MODES), (0.6173, 1.0, 25_000, MODES), (0.2173, 1.0, 46_000, (50, 250, 1000)))
GRID_SUBSET = 10_000  # samples rerun at 4 points per period (the paired difference has a small spread)


def modes_dependence(pool, cases=CASES, seed=60):
    """Mean and std of epsilon against nu_max; the grid's share by a second run at half the resolution."""
    print(f"\n### nu_max dependence (hard-core mode; 8 points per period, and 4 on the first {GRID_SUBSET} "
          "samples)\n")
    print("| gamma | T_B/E_tr | nu_max | samples | mean eps (SE) | std eps (SE) | grid: mean(eps_8 - eps_4) (SE) "
          "| mean extrapolated to h = 0 |")
    print("|---|---|---|---|---|---|---|---|")
    found = {}
    for gamma, temperature, samples, modes in cases:
        for m in modes:
            fine = ensemble(gamma, math.inf, temperature, samples, seed, bath_modes=m, executor=pool,
                            batch_size=1000)
            subset = min(samples, GRID_SUBSET)
            coarse = ensemble(gamma, math.inf, temperature, subset, seed, bath_modes=m, executor=pool,
                              batch_size=1000, hard_core_resolution=4)
            grid = fine.restitution[:subset] - coarse.restitution
            extrapolated = fine.mean + grid.mean()
            print(f"| {gamma} | {temperature:g} | {m} | {samples} | {fine.mean:.4f} ({fine.standard_error:.4f}) | "
                  f"{fine.std:.4f} ({fine.std_standard_error:.4f}) | {grid.mean():+.5f} "
                  f"({grid.std(ddof=1) / math.sqrt(subset):.5f}) | {extrapolated:.4f} |", flush=True)
            found[gamma, temperature, m] = (fine.mean, fine.standard_error, fine.std, grid.mean())
    _modes_summary(found)


def _modes_summary(found):
    """The changes of the mean between mode counts, in standard errors, and the grid's share against them."""
    print()
    for gamma, temperature in sorted({(g, t) for g, t, _ in found}, reverse=True):
        rows = {m: v for (g, t, m), v in found.items() if (g, t) == (gamma, temperature)}
        for low, high in ((50, 250), (250, 1000)):
            if low in rows and high in rows:
                change = rows[high][0] - rows[low][0]
                error = math.hypot(rows[high][1], rows[low][1])
                print(f"* gamma {gamma}, T_B/E_tr {temperature:g}: mean from {low} to {high} modes "
                      f"{change:+.4f} +- {error:.4f} ({change / error:+.1f} standard errors).")
        means = [rows[m][0] for m in rows if m >= 250]
        stds = [rows[m][2] for m in rows]
        print(f"* gamma {gamma}, T_B/E_tr {temperature:g}: means from 250 modes on within {max(means) - min(means):.4f} "
              f"of each other; standard deviations within {max(stds) - min(stds):.4f} over all mode counts.")
    grids = [abs(v[3]) for v in found.values()]
    ratio = min(v[1] / abs(v[3]) for v in found.values() if v[3])
    print(f"* Grid corrections |mean(eps_8 - eps_4)| from {min(grids):.0e} to {max(grids):.0e}; the standard error "
          f"of each mean is at least {ratio:.0f} times its grid correction.")


def _grid_errors(args):
    seed, resolutions = args
    lengths = (0.5 * (1 + GAMMA), 0.5 * (1 + GAMMA) / GAMMA)
    v = ThermalBath(1.0, 250).draw(lengths, sample_seed(70, seed))
    tau = start_gap(v, Hard())
    reference = hard_core_noise(GAMMA, v, tau, 256)[1][-1]
    return [abs(hard_core_noise(GAMMA, v, tau, r)[1][-1] - reference) for r in resolutions]


def grid_convergence(pool, realisations=40):
    resolutions = (2, 4, 8, 16, 32, 64)
    errors = np.array(list(pool.map(_grid_errors, [(s, resolutions) for s in range(realisations)])))
    print(f"\n### hard-core grid against resolution (nu_max 250, T_B/E_tr 1, {realisations} realisations, "
          "reference 256 points per period)\n")
    print("| points per period of the fastest mode | median error | 90th percentile | largest |")
    print("|---|---|---|---|")
    for j, r in enumerate(resolutions):
        e = errors[:, j]
        print(f"| {r} | {np.median(e):.1e} | {np.quantile(e, 0.9):.1e} | {e.max():.1e} |")


# nu_max and transitions (the cost of one grows like nu_max)
DEFECT_RUNS = ((8, 400_000), (16, 400_000), (32, 400_000), (64, 400_000), (128, 400_000), (250, 200_000),
               (500, 200_000))


def _transitions(args):
    """Independent transitions of docs/markov.md: chain c's E from the first uniform of its generator
    (Eq. 30), its bath from its step-0 seed, one hard-core collision at T_B/E_tr = 1/E; returns (E, E')."""
    from wavecontact.delay.stochastic_hardcore_batch import HardCoreGrid, hard_core_restitutions
    from wavecontact.studies.markov import chain_seed, step_seed

    gamma, modes, seed, start, stop, resolution = args
    chains = [chain_seed(seed, c) for c in range(start, stop)]
    energy = -np.log1p(-np.array([np.random.default_rng(c).random() for c in chains]))
    # min_points=0: the step is Gamma_1 / (resolution nu_max) for every nu_max, so halving it is a real halving
    grid = HardCoreGrid(gamma, modes, resolution, min_points=0)
    eps = hard_core_restitutions(gamma, 1.0 / energy, [step_seed(c, 0) for c in chains], grid=grid)
    return energy, eps**2 * energy


def boltzmann_defect(pool, gamma=0.6, runs=DEFECT_RUNS, seed=77, block=5000):
    """Eq. 32: with E from Boltzmann (units of T_B) the mean of E' - E must vanish; measured against
    nu_max, with the grid's share from the same transitions at half the resolution."""
    print(f"\n### Eq. 32 defect (gamma {gamma}, hard-core mode, E from Boltzmann; 8 points per period, and 4 on "
          "the same transitions)\n")
    print("| nu_max | transitions | mean E' - E (SE) | grid: mean of (E'_8 - E'_4) (SE) | extrapolated to h = 0 | "
          "from E < 0.1 | 0.1 <= E < 1 | 1 <= E < 3 | E >= 3 |")
    print("|---|---|---|---|---|---|---|---|---|")
    rows = {}
    for m, transitions in runs:
        found = {}
        for resolution in (8, 4):
            tasks = [(gamma, m, seed, a, min(a + block, transitions), resolution)
                     for a in range(0, transitions, block)]
            parts = list(pool.map(_transitions, tasks))
            found[resolution] = (np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]))
        energy, after = found[8]
        gain = after - energy
        grid = after - found[4][1]
        share = [float(np.sum(gain[(energy >= lo) & (energy < hi)])) / transitions
                 for lo, hi in ((0.0, 0.1), (0.1, 1.0), (1.0, 3.0), (3.0, np.inf))]
        se = gain.std(ddof=1) / math.sqrt(transitions)
        print(f"| {m} | {transitions} | {gain.mean():+.4f} ({se:.4f}) | {grid.mean():+.5f} ({grid.std(ddof=1) / math.sqrt(transitions):.5f})"
              f" | {gain.mean() + grid.mean():+.4f} | {share[0]:+.4f} | {share[1]:+.4f} | {share[2]:+.4f} | {share[3]:+.4f} |",
              flush=True)
        rows[m] = (gain.mean(), se, grid.mean(), np.abs(grid).max())
    _defect_trend(rows)


def _defect_trend(rows):
    """The extrapolated defect against nu_max: its decay per doubling up to 128 modes, continued beyond."""
    fitted = sorted(m for m in rows if m <= 128)
    if len(fitted) < 2:
        return
    defect = {m: rows[m][0] + rows[m][2] for m in rows}  # the mean, its grid part removed
    slope = np.polyfit(np.log(fitted), np.log([-defect[m] for m in fitted]), 1)[0]
    print(f"\nThe extrapolated defect falls by a factor {2.0**slope:.2f} per doubling of nu_max from {fitted[0]} to "
          f"{fitted[-1]} modes (nu_max^{slope:.2f}); the grid moves E' by {abs(rows[fitted[0]][2]):.4f} on average at "
          f"{fitted[0]} modes and by {abs(rows[fitted[-1]][2]):.4f} at {fitted[-1]}.")
    for m in sorted(m for m in rows if m > fitted[-1]):
        trend = defect[fitted[-1]] * (m / fitted[-1]) ** slope
        mean, se = defect[m], rows[m][1]
        print(f"At {m} modes the trend gives {trend:+.4f}; measured (extrapolated to h = 0) {mean:+.4f} +- {se:.4f}, "
              f"{(mean - trend) / se:+.1f} standard errors from the trend and {mean / se:+.1f} from zero.")


def _cold_mode_uptake(args):
    """Energy that the modes above nu_max (at rest before the collision) take up, per transition.

    A mode at rest driven by the end force F = w'/2 gains |F^(omega)|^2 / m_i exactly (units with
    E_tr = 1/4), whatever drives F; F is piecewise constant on the hard-core grid, so its transform is
    a sum over the grid steps.  Modes up to ``top`` nu_max are summed and the 1/nu^2 tail beyond is
    added as ``top nu_max`` times the last mode's share.  Returns (E, E', uptake in units of T_B)."""
    from wavecontact.bath import ThermalBath
    from wavecontact.delay.stochastic_hardcore import hard_core_noise
    from wavecontact.studies.markov import chain_seed, step_seed

    gamma, modes, seed, start, stop, resolution, top = args
    lengths = (0.5 * (1 + gamma), 0.5 * (1 + gamma) / gamma)
    rows = []
    for c in range(start, stop):
        chain = chain_seed(seed, c)
        energy = float(-np.log1p(-np.random.default_rng(chain).random()))
        vibrations = ThermalBath(1.0 / energy, modes).draw(lengths, step_seed(chain, 0))
        t, w = hard_core_noise(gamma, vibrations, 0.0, resolution)
        h = t[1] - t[0]
        slope = np.diff(w) / h
        moving = np.flatnonzero(slope)
        uptake = 0.0
        for length in lengths:
            nu = np.arange(modes + 1, top * modes + 1)
            omega = math.pi * nu / length
            spectrum = np.zeros(nu.size, dtype=complex)
            for part in np.array_split(moving, max(1, moving.size // 256)):
                spectrum += np.exp(1j * np.outer(omega, t[part])) @ slope[part]
            gain = np.abs(spectrum) ** 2 * np.abs(np.expm1(1j * omega * h)) ** 2 / (4 * omega**2) / length
            uptake += float(gain.sum() + gain[-1] * nu[-1])
        rows.append((energy, (1.0 + w[-1] - 2.0) ** 2 * energy, 4.0 * energy * uptake))
    return np.array(rows)


def cold_mode_uptake(pool, gamma=0.6, transitions=1000, modes=(8, 16), seed=77, resolution=16, top=4):
    """The energy the cold modes above nu_max take up, against the Eq. 32 defect of the same transitions."""
    print(f"\n### Where the Eq. 32 defect goes (gamma {gamma}, {transitions} Boltzmann transitions per nu_max, "
          f"{resolution} points per period; modes nu_max+1 .. {top} nu_max summed, 1/nu^2 tail added)\n")
    print("| nu_max | mean E' - E (SE) | energy taken up by the modes above nu_max (SE) | lost by the thermal modes "
          "(SE) |")
    print("|---|---|---|---|")
    for m in modes:
        tasks = [(gamma, m, seed, a, min(a + 100, transitions), resolution, top) for a in range(0, transitions, 100)]
        rows = np.concatenate(list(pool.map(_cold_mode_uptake, tasks)))
        gain, uptake = rows[:, 1] - rows[:, 0], rows[:, 2]
        total = gain + uptake
        se = [x.std(ddof=1) / math.sqrt(len(x)) for x in (gain, uptake, total)]
        print(f"| {m} | {gain.mean():+.4f} ({se[0]:.4f}) | {uptake.mean():.4f} ({se[1]:.4f}) | "
              f"{total.mean():+.4f} ({se[2]:.4f}) |", flush=True)


STUDIES = {"grid": grid_convergence, "modes": modes_dependence, "kappa": kappa_independence,
           "boltzmann": boltzmann_defect, "uptake": cold_mode_uptake}


# the page and marked block each study's table goes to with --update-docs
BLOCKS = {"grid": ("bath.md", "bath-studies-grid"), "modes": ("bath.md", "bath-studies-modes"),
          "kappa": ("bath.md", "bath-studies-kappa"), "boltzmann": ("markov.md", "bath-studies-boltzmann"),
          "uptake": ("markov.md", "bath-studies-uptake")}


def main(argv=None):
    argv = list(argv if argv is not None else sys.argv[1:])
    update = "--update-docs" in argv
    names = [a for a in argv if a != "--update-docs"] or list(STUDIES)
    unknown = [n for n in names if n not in STUDIES]
    if unknown:
        raise SystemExit(f"unknown study {unknown[0]!r}; choose from {', '.join(STUDIES)}")
    with ProcessPoolExecutor(2) as pool:
        for name in names:
            header = run_header(["docs/bath_studies.py", name])
            with captured_stdout() as tee:
                STUDIES[name](pool)
            if update:
                table = re.sub(r"^### (.*)$", r"\1:", tee.copy.getvalue(), flags=re.MULTILINE)  # no headings
                write_block(*BLOCKS[name], header + "\n" + table)


if __name__ == "__main__":
    main()
