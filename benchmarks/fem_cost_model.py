"""The cost model of the exact-lattice time loop (docs/fem.md section 4): ``python benchmarks/fem_cost_model.py``.

Loop time = steps x c_step + checks x c_node x (nodes of both rods) + c_call x calls.  For
each contact law and mesh this script runs the collision once to learn its number of steps,
then times that many steps of the lattice kernel twice on fresh runs: with the solver's
energy and separation checks (every ``check_every`` steps) and with the checks switched off.
The second gives ``c_step``; the difference, divided by the number of checks and the nodes
of both rods, gives ``c_node``.  Times are medians of CPU time (``time.process_time``) over
``--repeats`` runs, so other jobs on a shared machine disturb them little.  ``--update-docs``
writes the table into docs/fem.md (block ``fem-cost-model``).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the checkout this script lives in

from docs_block import run_and_write

import wavecontact
from wavecontact.fem import layout
from wavecontact.fem.simulation import _Run, build_setup, run_collision

GAMMA = 0.6
CASES = ((math.inf, 800), (math.inf, 3200), (100.0, 800), (100.0, 3200))


def _cpu_times(setup, steps: int, check_every: int, repeats: int) -> tuple:
    """Median CPU seconds of ``steps`` lattice steps on fresh runs, and the median set-up of a run."""
    loop, start = [], []
    for _ in range(repeats):
        began = time.process_time()
        run = _Run(setup, 0.05)
        start.append(time.process_time() - began)
        run.control[layout.K_CHECK_EVERY] = check_every
        began = time.process_time()
        _status, history, _energies = run.advance(steps)
        loop.append(time.process_time() - began)
        if history[0].size != steps:
            raise SystemExit(f"the run stopped after {history[0].size} of {steps} steps")
    return float(np.median(loop)), float(np.median(start))


def measure(kappa: float, elements: int, repeats: int) -> dict:
    """One row: steps, checks and the model's constants for the collision (GAMMA, kappa) on ``elements``."""
    setup = build_setup(wavecontact.two_rods(GAMMA, kappa), elements=elements)
    steps = run_collision(setup)["steps"]
    check_every = _Run(setup, 0.05).check_every
    # the run above stops at its first check after separation; time exactly its steps (a check at
    # the last step would end the run there, so the timed runs stop one step short of it)
    steps -= 1
    nodes = sum(d.n_nodes for d in setup.rods)
    with_checks, set_up = _cpu_times(setup, steps, check_every, repeats)
    without_checks, _ = _cpu_times(setup, steps, steps + 1, repeats)
    checks = steps // check_every
    return {
        "contact": "hard" if math.isinf(kappa) else f"exponential, kappa = {kappa:g}",
        "elements": elements, "nodes": nodes, "steps": steps, "checks": checks,
        "loop_ms": 1e3 * with_checks, "c_step_us": 1e6 * without_checks / steps,
        "c_node_ns": 1e9 * (with_checks - without_checks) / (checks * nodes),
        "check_share": (with_checks - without_checks) / with_checks, "set_up_ms": 1e3 * set_up,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=21, help="timed runs per median (default: 21)")
    parser.add_argument("--update-docs", action="store_true", help="write the table into docs/fem.md")
    args = parser.parse_args()

    def table():
        wavecontact.collide(GAMMA, 100.0, solver="fem", elements=50)  # numba: compile or load once, untimed
        wavecontact.collide(GAMMA, math.inf, solver="fem", elements=50)
        print(f"gamma = {GAMMA}, P1 lumped on the exact lattice; CPU time, median of {args.repeats} runs\n")
        print("| contact | elements (short rod) | nodes (both rods) | steps | checks | loop (ms) | c_step (us) "
              "| c_node (ns) | checks' share of the loop | run set-up (ms) |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        for kappa, elements in CASES:
            r = measure(kappa, elements, args.repeats)
            print(f"| {r['contact']} | {r['elements']} | {r['nodes']} | {r['steps']} | {r['checks']} | "
                  f"{r['loop_ms']:.2f} | {r['c_step_us']:.3f} | {r['c_node_ns']:.1f} | "
                  f"{100 * r['check_share']:.0f} % | {r['set_up_ms']:.2f} |")

    run_and_write(table, "fem.md", "fem-cost-model", args.update_docs)


if __name__ == "__main__":
    main()
