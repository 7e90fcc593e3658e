"""Where the general explicit step spends its time, one command:

    python benchmarks/profile_explicit_step.py [--repeats 7] [--update-docs]

Prints a Markdown table: CPU time of the calling thread (``time.thread_time``, so
that other jobs on a shared machine do not count) per element of one rod's step
(``step_rod``) and of two of its parts, for each discretization of the general path
at 800 and 12800 elements (the long rod of the gamma = 0.6 pair, 1333 and 21333
elements): the stiffness stencil alone (``_stiffness_forces``; the P1 consistent
step runs it with the solve's scaling folded in, the P2 consistent step not at all:
it forms the condensed right-hand sides from the displacements) and the
tridiagonal solve alone (``_scaled_solve``: all unknowns for P1, the vertices for P2;
on a zero right-hand side, which costs the same instructions and cannot overflow
when repeated).  Each figure includes Python's call overhead, printed last (per
element of the 1333-element rod).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(1, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the checkout this script lives in

from docs_block import run_and_write

import wavecontact
from wavecontact.fem import explicit_step
from wavecontact.fem.simulation import _Run, build_setup

DISCRETIZATIONS = (("P1 consistent", 1, "consistent"), ("P2 lumped", 2, "lumped"), ("P2 consistent", 2, "consistent"))


def cpu_per_call(function, repeats, calls=300):
    """Median over ``repeats`` of the CPU seconds per call of ``function()``."""
    samples = []
    for _ in range(repeats):
        started = time.thread_time()
        for _ in range(calls):
            function()
        samples.append((time.thread_time() - started) / calls)
    return float(np.median(samples))


def profile_row(name, order, mass, elements, repeats):
    """One table row: CPU ns per element of the long rod's step and of its parts."""
    setup = build_setup(wavecontact.two_rods(0.6, 100), elements=elements, order=order, mass=mass)
    run = _Run(setup, 0.05)
    disc = setup.rods[1]
    u, v, a = run.u[1].copy(), run.v[1].copy(), np.zeros(disc.n_nodes)
    kind, table = run.mass_solves[1]
    bands, dt, per = disc.stiffness_bands, setup.dt, 1e9 / disc.n_elements
    explicit_step.step_rod(u, v, a, bands, kind, table, dt)  # compile / load
    step = cpu_per_call(lambda: explicit_step.step_rod(u, v, a, bands, kind, table, dt), repeats)
    stiffness = cpu_per_call(lambda: explicit_step._stiffness_forces(u, bands, a), repeats)
    if mass == "lumped":
        return f"| {name} | {disc.n_elements} | {step * per:.2f} | {stiffness * per:.2f} | - |"
    unknowns = disc.n_elements + 1
    zeros = np.zeros(disc.n_nodes)
    explicit_step._scaled_solve(table, zeros, unknowns)
    solve = cpu_per_call(lambda: explicit_step._scaled_solve(table, zeros, unknowns), repeats)
    return f"| {name} | {disc.n_elements} | {step * per:.2f} | {stiffness * per:.2f} | {solve * per:.2f} |"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--update-docs", action="store_true",
                        help="also write the table into docs/fem.md (between its profile-explicit-step markers)")
    args = parser.parse_args(argv)
    argv_used = None if argv is None else ["benchmarks/profile_explicit_step.py", *argv]
    run_and_write(lambda: measure(args), "fem.md", "profile-explicit-step", args.update_docs, argv_used)


def measure(args):
    """Print the table."""
    print("| discretization | elements (long rod) | step: ns/element | stiffness stencil alone | "
          "tridiagonal solve alone |")
    print("|---|---:|---:|---:|---:|")
    for name, order, mass in DISCRETIZATIONS:
        for elements in (800, 12800):
            print(profile_row(name, order, mass, elements, args.repeats))
    empty = np.zeros(1)
    explicit_step._stiffness_forces(empty, np.zeros((2, 1)), empty)
    overhead = cpu_per_call(lambda: explicit_step._stiffness_forces(empty, np.zeros((2, 1)), empty), args.repeats)
    print(f"\nPython's overhead of one kernel call: {overhead * 1e9:.0f} ns, {overhead * 1e9 / 1333:.2f} ns per element "
          "of the 1333-element rod.")


if __name__ == "__main__":
    main()
