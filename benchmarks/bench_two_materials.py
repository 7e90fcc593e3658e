"""Benchmark of rods of two materials (issue 14), one command:

    python benchmarks/bench_two_materials.py [--repeats 20]

Prints Markdown tables:
1. the delay solver on two-material collisions against the one-material
   collision with the same transit-time ratio (0.6) and kappa, at the same
   rtol: steps and median time, and their ratio (target: at most 1.5);
2. the hard-core recursion, the same comparison;
3. the restitution map of 10,000 points (101 impedance ratios in [0.01, 100]
   x 99 transit-time ratios in [0.1, 10]) in the hard-core limit and at
   kappa = 100 (target: under 10 s).
The machine is usually shared with other jobs: compare columns of one run only.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
sys.path.insert(1, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the checkout this script lives in

from docs_block import run_and_write
from timing import median_time, wall_times

import wavecontact
from wavecontact.delay.hardcore import hard_core_history
from wavecontact.delay.parameters import echoes_from_ratios
from wavecontact.delay.solver import solve_delay_equation
from wavecontact.studies.material_map import material_map

TIME_RATIO = 0.6
IMPEDANCE_RATIOS = (0.1, 0.4, 2.5, 10.0)
KAPPAS = (5.0, 20.0, 100.0, 1e3, 1e4, 1e6)


def _times(function, repeats):
    """Median and minimum wall time (s) (the minimum is robust to a busy machine)."""
    times = wall_times(function, repeats)
    return float(np.median(times)), float(np.min(times))


def table_delay(repeats, rtol):
    print(f"\n### Delay solver, transit-time ratio {TIME_RATIO}, rtol = {rtol:g}: two materials against one\n")
    print("Cells: steps, median time in ms (ratio of medians / ratio of minima to one material).\n")
    header = " | ".join(f"Z2/Z1 = {z:g}" for z in IMPEDANCE_RATIOS)
    print(f"| kappa | one material: steps, ms | {header} |")
    print("|---|---|" + "---|" * len(IMPEDANCE_RATIOS))
    worst_median = worst_min = 0.0
    for kappa in KAPPAS:
        def run(z, kappa=kappa):
            return solve_delay_equation(TIME_RATIO, kappa, rtol=rtol, impedance_ratio=z)

        base_steps = run(1.0)[4]["steps"]
        base_median, base_min = _times(lambda: run(1.0), repeats)
        cells = []
        for z in IMPEDANCE_RATIOS:
            steps = run(z)[4]["steps"]
            median, least = _times(lambda z=z: run(z), repeats)
            worst_median = max(worst_median, median / base_median)
            worst_min = max(worst_min, least / base_min)
            cells.append(f"{steps}, {1e3 * median:.3f} ({median / base_median:.2f}x / {least / base_min:.2f}x)")
        print(f"| {kappa:g} | {base_steps}, {1e3 * base_median:.3f} | " + " | ".join(cells) + " |")
    print(f"\nlargest ratio two materials / one material: {worst_median:.2f} (medians), {worst_min:.2f} (minima)")


def table_hard(repeats):
    print(f"\n### Hard-core recursion, transit-time ratio {TIME_RATIO}: two materials against one\n")
    print("| Z2/Z1 | kinks | median time (us) | ratio to Z2/Z1 = 1 |")
    print("|---|---|---|---|")
    base = None
    for z in (1.0, *IMPEDANCE_RATIOS):
        delays, weights = echoes_from_ratios(z, TIME_RATIO)
        kinks = hard_core_history(delays, weights)[0].size
        seconds = median_time(lambda delays=delays, weights=weights: hard_core_history(delays, weights), repeats)
        base = base or seconds
        print(f"| {z:g} | {kinks} | {1e6 * seconds:.1f} | {seconds / base:.2f} |")


def table_map():
    impedance = np.geomspace(0.01, 100.0, 101)
    time_ratio = np.geomspace(0.1, 10.0, 99)
    material_map(impedance[:2], time_ratio[:2], progress=False)  # load the kernels
    material_map(impedance[:2], time_ratio[:2], 100.0, progress=False)
    print("\n### Restitution map, 101 x 99 = 9999 points (Z2/Z1 in [0.01, 100], T1/T2 in [0.1, 10])\n")
    print("| kappa | threads | wall time (s) | CPU time, all threads (s) | all finite |")
    print("|---|---|---|---|---|")
    for kappa, workers in ((math.inf, 1), (100.0, os.cpu_count() or 1)):
        cpu = time.process_time()
        result = material_map(impedance, time_ratio, kappa, rtol=1e-8, workers=workers, progress=False)
        cpu = time.process_time() - cpu
        label = "inf (hard core)" if math.isinf(kappa) else f"{kappa:g} (rtol 1e-8)"
        print(f"| {label} | {workers} | {result.wall_time_s:.2f} | {cpu:.2f} | "
              f"{bool(np.isfinite(result.restitution).all())} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--update-docs", action="store_true",
                        help="also write the tables into docs/materials.md (between its bench-two-materials markers)")
    args = parser.parse_args()
    run_and_write(lambda: measure(args), "materials.md", "bench-two-materials", args.update_docs)


def measure(args):
    """Time the solvers and print the tables."""
    wavecontact.collide(0.6, 100.0)  # load the compiled kernels
    wavecontact.collide(0.6, math.inf)
    print(f"Machine: {platform.machine()}, {os.cpu_count()} cores (shared), Python {platform.python_version()}, "
          f"numpy {np.__version__}")
    for rtol in (1e-8, 1e-11):
        table_delay(args.repeats, rtol)
    table_hard(args.repeats)
    table_map()


if __name__ == "__main__":
    main()
