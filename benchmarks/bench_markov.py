"""Benchmark of the Markov chain of the translational energy (issue 12), one command:

    python benchmarks/bench_markov.py [--repeats 3] [--steps 10000] [--update-docs]

Prints a Markdown table: wall time of one chain of STEPS collisions (the
paper's Fig. 10 has 10,000) with each rule, median of repeats, against the
target of 20 s for the solve rule; the solve rule once more with two worker
processes running two chains of STEPS/2 each (the same number of collisions).
The solve rule is the delay solver's stochastic hard-core mode (kappa = inf,
nu_max = 250 bath modes, 8 grid points per period of the fastest mode).  The
kernels are compiled (or loaded from numba's cache) before timing.

A second table (issue 24 item 5) compares the chains' cost per collision with
``ensemble``'s cost per sample, in the same run, alternating the two, at
kappa = inf and kappa = 100 (the ensemble's default options at finite kappa, which
the chains share): the chains of a batch advance one step together through the
same batched samplers, so the target is a cost per collision within 2x of the
ensemble's per sample.  CPU time of this process, median of the repeats.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import math
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
sys.path.insert(1, str(Path(__file__).resolve().parents[1]))  # the checkout this script lives in

from docs_block import run_and_write
from timing import median_time

from wavecontact.restitution_table import RestitutionTable
from wavecontact.studies.ensemble import ensemble
from wavecontact.studies.markov import markov_chains

GAMMA = 0.6
TARGET_S = 20.0
LOCKSTEP_TARGET = 2.0  # per collision at most this many times the ensemble's cost per sample
# (kappa, chains, steps) of the lockstep comparison; the ensemble draws chains x steps samples
LOCKSTEP_RUNS = ((math.inf, 4, 1000), (math.inf, 64, 60), (100.0, 4, 40), (100.0, 16, 10))


def glauber_table(path):
    """Glauber's law as a restitution table (200 levels, 32 temperature ratios): a table of realistic size."""
    u = np.concatenate([[0.0], 1.0 - np.geomspace(1.0, 1e-12, 199)[1:], [1.0]])
    x = np.append(-np.log1p(-u[:-1]), 40.0)
    ratio = np.concatenate([[0.0], np.geomspace(1e-6, 1e9, 31)])
    quantiles = np.repeat(ratio[None, :, None] * x[None, None, :], 2, axis=0)
    RestitutionTable(np.array([0.5, 0.7]), ratio, u, quantiles, np.zeros((2, ratio.size))).save(path)
    return str(path)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--steps", type=int, default=10_000)
    parser.add_argument("--update-docs", action="store_true",
                        help="also write the table into docs/markov.md (between its bench_markov markers)")
    args = parser.parse_args()
    run_and_write(lambda: measure(args), "markov.md", "bench_markov", args.update_docs)


def measure(args):
    """Time the chains and print the table."""
    steps = args.steps
    markov_chains(GAMMA, rule="solve", steps=5, seed=0)  # compile or load the kernels
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        table = glauber_table(Path(tmp) / "glauber.npz")
        for rule, extra in (("solve", {}), ("table", {"table": table}), ("glauber", {})):
            seconds = median_time(lambda rule=rule, extra=extra: markov_chains(
                GAMMA, rule=rule, steps=steps, seed=1, **extra), args.repeats)
            rows.append((f"{rule}, 1 chain x {steps}", seconds))
    lockstep = lockstep_rows(args.repeats)
    with concurrent.futures.ProcessPoolExecutor(2) as pool:
        markov_chains(GAMMA, rule="solve", chains=2, steps=5, seed=0, executor=pool, batch_size=1)  # warm workers
        seconds = median_time(lambda: markov_chains(GAMMA, rule="solve", chains=2, steps=steps // 2, seed=1,
                                                    executor=pool, batch_size=1), args.repeats)
        rows.append((f"solve, 2 workers, 2 chains x {steps // 2}", seconds))
    print(f"Markov chain, gamma = {GAMMA}, hard core, nu_max = 250; {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores (shared with other jobs); median of {args.repeats} repeats\n")
    print("| run | wall time (s) | per collision (ms) | solve target |")
    print("|---|---|---|---|")
    for name, seconds in rows:
        target = f"<= {TARGET_S:g} s: {'met' if seconds <= TARGET_S else 'MISSED'}" if name.startswith("solve") else ""
        print(f"| {name} | {seconds:.2f} | {1e3 * seconds / steps:.3f} | {target} |")
    print(f"\nChains in lockstep against `ensemble` (T_B/E_tr = 1), CPU time, median of {args.repeats} repeats "
          f"alternating the two:\n")
    print("| kappa | chains x steps | Markov per collision (ms) | ensemble per sample (ms) | ratio | "
          f"target <= {LOCKSTEP_TARGET:g}x |")
    print("|---|---|---|---|---|---|")
    for kappa, chains, steps_, chain_cost, sample_cost in lockstep:
        ratio = chain_cost / sample_cost
        print(f"| {'inf' if math.isinf(kappa) else f'{kappa:g}'} | {chains} x {steps_} | {1e3 * chain_cost:.3f} | "
              f"{1e3 * sample_cost:.3f} | {ratio:.2f} | {'met' if ratio <= LOCKSTEP_TARGET else 'MISSED'} |")


def lockstep_rows(repeats):
    """``(kappa, chains, steps, CPU s per collision, CPU s per ensemble sample)`` per LOCKSTEP_RUNS row."""
    rows = []
    for kappa, chains, steps in LOCKSTEP_RUNS:
        markov_chains(GAMMA, kappa=kappa, chains=2, steps=2, seed=0)  # compile or load the kernels
        ensemble(GAMMA, kappa, 1.0, 4, 0)
        chain_times, sample_times = [], []
        for _ in range(repeats):  # alternate: both see the same load
            started = time.process_time()
            markov_chains(GAMMA, kappa=kappa, chains=chains, steps=steps, seed=1)
            chain_times.append(time.process_time() - started)
            started = time.process_time()
            ensemble(GAMMA, kappa, 1.0, chains * steps, 1)
            sample_times.append(time.process_time() - started)
        n = chains * steps
        rows.append((kappa, chains, steps, float(np.median(chain_times)) / n, float(np.median(sample_times)) / n))
    return rows


if __name__ == "__main__":
    main()
