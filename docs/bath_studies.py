"""Regenerate the measured numbers of docs/bath.md (sections 4-6).

    python docs/bath_studies.py            # prints the markdown tables; about 10 minutes on 2 shared cores

1. kappa-independence: paired ensembles (the same seeds, hence the same realisations) at
   kappa = 25, 50, 100, 250 against the hard-core mode;
2. nu_max dependence of the statistics (hard-core mode);
3. convergence of the hard-core grid against its resolution.
"""

from __future__ import annotations

import math
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

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


def modes_dependence(pool, samples=3000, temperature=1.0, seed=60):
    print(f"\n### nu_max dependence (hard-core mode, gamma {GAMMA}, T_B/E_tr {temperature}, {samples} samples each)\n")
    print("| nu_max | mean eps (SE) | std eps (SE) | mean eps^2 |")
    print("|---|---|---|---|")
    for modes in (25, 50, 100, 250, 500, 1000):
        r = ensemble(GAMMA, math.inf, temperature, samples, seed, bath_modes=modes, executor=pool, batch_size=200)
        print(f"| {modes} | {r.mean:.4f} ({r.standard_error:.4f}) | {r.std:.4f} ({r.std_standard_error:.4f}) | "
              f"{np.mean(r.restitution ** 2):.4f} |")


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


def main():
    with ProcessPoolExecutor(2) as pool:
        grid_convergence(pool)
        modes_dependence(pool)
        kappa_independence(pool)


if __name__ == "__main__":
    main()
