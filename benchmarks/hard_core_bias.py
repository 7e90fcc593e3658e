"""Grid bias of the stochastic hard-core mode against resolution (docs/bath.md section 3).

For each gamma and ``T_B/E_tr`` the same samples run at 4, 8, 16 and 32 points per period; the
bias of the mean at ``r`` points is measured against the run at 64 points, first-order
extrapolated (``eps_64 - (eps_32 - eps_64)``), and set against the ensemble's own spread:
``|bias| / std_r`` (``std_r``: the spread of epsilon at ``r`` points, what an ensemble
at ``r`` points states) times ``sqrt(samples)`` is how many of its standard errors the bias
makes (at 2500 samples: 50 times the column).  CPU time per sample at each
resolution is the median over the cases (the machine's load disturbs it).

    python benchmarks/hard_core_bias.py [--samples N] [--update-docs]

``--update-docs`` writes the table into the block ``hard-core-bias`` of docs/bath.md.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from docs_block import run_and_write

from wavecontact.bath.streams import SpawnedSeeds
from wavecontact.delay.stochastic_hardcore_batch import cached_grid, hard_core_restitutions
from wavecontact.studies.ensemble import grid_bias_indices

GAMMAS = (0.2173, 0.6173, 0.9, 1.0)
TEMPERATURES = (0.1, 1.0, 10.0, 100.0)
RESOLUTIONS = (4, 8, 16, 32)
REFERENCE = 64
SEED = 2026


def measure(samples: int) -> None:
    seeds = SpawnedSeeds(SEED, 0, samples)
    cost = {r: [] for r in (*RESOLUTIONS, REFERENCE)}
    hard_core_restitutions(1.0, 1.0, SpawnedSeeds(0, 0, 2), grid=cached_grid(1.0, 250, 8))  # compile
    print(f"nu_max 250, {samples} samples per case (seed {SEED}); bias of the mean at r points per period "
          f"against 64 points extrapolated; 'est.' = 2 mean(eps_r - eps_2r), what ensembles state\n")
    print("| gamma | T_B/E_tr | std of eps (r=8) | bias r=4 | r=8 | r=16 | r=32 | est. r=8 | bias/std r=8 | r=16 | r=32 |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for gamma in GAMMAS:
        for temperature in TEMPERATURES:
            eps = {}
            for r in (*RESOLUTIONS, REFERENCE):
                grid = cached_grid(gamma, 250, r)
                start = time.process_time()
                eps[r] = hard_core_restitutions(gamma, temperature, seeds, grid=grid)
                cost[r].append((time.process_time() - start) / samples)
            exact = eps[REFERENCE] - (eps[32] - eps[REFERENCE])  # first-order extrapolation, per sample
            bias = {r: float(np.mean(eps[r] - exact)) for r in RESOLUTIONS}
            std = {r: float(np.std(eps[r], ddof=1)) for r in RESOLUTIONS}
            estimate = 2.0 * float(np.mean(eps[8] - eps[16]))
            print(f"| {gamma} | {temperature:g} | {std[8]:.3g} | " + " | ".join(f"{bias[r]:.2e}" for r in RESOLUTIONS)
                  + f" | {estimate:.2e} | " + " | ".join(f"{abs(bias[r]) / std[r]:.2g}" for r in (8, 16, 32)) + " |",
                  flush=True)
    print("\nCPU time per sample (median over the cases): "
          + ", ".join(f"{r} points {np.median(cost[r]) * 1e6:.0f} us" for r in (*RESOLUTIONS, REFERENCE)))
    ratio = np.median(cost[16]) / np.median(cost[8])
    print("Cost of stating the bias at the default 8 points (its subset at 16 points, "
          f"{ratio:.2f} times a sample's CPU time): "
          + ", ".join(f"{n} samples {ratio * grid_bias_indices(n).size / n:.1%}" for n in (100, 400, 2500, 8000, 50000)))


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=400, help="samples per case (default 400)")
    parser.add_argument("--update-docs", action="store_true", help="write the table into docs/bath.md")
    args = parser.parse_args(argv)
    run_and_write(lambda: measure(args.samples), "bath.md", "hard-core-bias", args.update_docs)


if __name__ == "__main__":
    main()
