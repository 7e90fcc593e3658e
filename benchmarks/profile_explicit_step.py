"""Where the general explicit step spends its time, one command:

    python benchmarks/profile_explicit_step.py [--repeats 7] [--update-docs]

Prints two Markdown tables, CPU time of the calling thread (``time.thread_time``, so
that other jobs on a shared machine do not count), medians of ``--repeats`` runs:

1. per element of one rod's step, for each discretization of the general path at 800
   and 12800 elements (the long rod of the gamma = 0.6 pair, 1333 and 21333
   elements): the step as the time loop runs it (consistent masses of at least 1200
   unknowns or vertices in the interleaved layout, ``interleaved_step.py``, on the
   packed state), the same step in the flat layout (``prepare_mass(...,
   interleaved=False)``; measured alternately with the first), and two parts of the
   flat step: the stiffness stencil alone (``_stiffness_forces``) and the flat
   tridiagonal solve alone (``_scaled_solve``: all unknowns for P1, the vertices for
   P2; on a zero right-hand side, which costs the same instructions and cannot
   overflow when repeated).  Each figure includes Python's call overhead, printed
   under the table (per element of the 1333-element rod);
2. per element-step of both rods, 800 and 12800 elements (short rod): the time loop
   (``_Run.advance`` from the start, divided by the steps it ran) against the two
   rods' elastic steps alone in a compiled loop, so that the difference is what the
   loop does besides the steps (contact, histories, energy checks).
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
from wavecontact._jit import kernel
from wavecontact.fem import explicit_step, interleaved_step, kernels
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


def alternated(functions, repeats, calls=300):
    """``cpu_per_call`` of each function, their runs alternated so that all see the same load."""
    samples = [[] for _ in functions]
    for _ in range(repeats):
        for function, times in zip(functions, samples):
            started = time.thread_time()
            for _ in range(calls):
                function()
            times.append((time.thread_time() - started) / calls)
    return [float(np.median(times)) for times in samples]


def loop_step(rod, u, v, kind, table):
    """The step of one rod as the time loop runs it (``kernels._step``; the interleaved layout packed first)."""
    rows = int(table[interleaved_step.L_SHAPE, 0])
    if rows:
        interleaved_step.pack_nodes(u, table[interleaved_step.L_U], rows, rod.order)
        interleaved_step.pack_nodes(v, table[interleaved_step.L_V], rows, rod.order)
    a = np.zeros(rod.n_nodes)
    return lambda dt: kernels._step(u, v, a, rod.stiffness_bands, kind, table, rows, dt)


def profile_row(name, order, mass, elements, repeats):
    """One row of table 1: CPU ns per element of the long rod's step and of its parts."""
    setup = build_setup(wavecontact.two_rods(0.6, 100), elements=elements, order=order, mass=mass)
    run = _Run(setup, 0.05)
    disc = setup.rods[1]
    dt, per = setup.dt, 1e9 / disc.n_elements
    kind, table = run.mass_solves[1]
    flat_kind, flat_table = explicit_step.prepare_mass(disc, interleaved=False)
    step = loop_step(disc, run.u[1].copy(), run.v[1].copy(), kind, table)
    u, v, a = run.u[1].copy(), run.v[1].copy(), np.zeros(disc.n_nodes)
    bands = disc.stiffness_bands
    step(dt)
    explicit_step.step_rod(u, v, a, bands, flat_kind, flat_table, dt)  # compile / load
    ours, flat = alternated((lambda: step(dt), lambda: explicit_step.step_rod(u, v, a, bands, flat_kind, flat_table,
                                                                              dt)), repeats)
    layout = "interleaved" if table[interleaved_step.L_SHAPE, 0] > 0 else "flat"
    stiffness = cpu_per_call(lambda: explicit_step._stiffness_forces(u, bands, a), repeats)
    if mass == "lumped":
        return (f"| {name} | {disc.n_elements} | {ours * per:.2f} ({layout}) | {flat * per:.2f} | "
                f"{stiffness * per:.2f} | - |")
    unknowns = disc.n_elements + 1
    zeros = np.zeros(disc.n_nodes)
    explicit_step._scaled_solve(flat_table, zeros, unknowns)
    solve = cpu_per_call(lambda: explicit_step._scaled_solve(flat_table, zeros, unknowns), repeats)
    return (f"| {name} | {disc.n_elements} | {ours * per:.2f} ({layout}) | {flat * per:.2f} | {stiffness * per:.2f} | "
            f"{solve * per:.2f} |")


@kernel
def _stream(u, v, a, dt):
    """``v += dt a``, ``u += dt v``: the plainest pass, 5 doubles moved per entry (3 read, 2 written)."""
    for i in range(u.size):
        velocity = v[i] + dt * a[i]
        v[i] = velocity
        u[i] += dt * velocity


@kernel
def _steps_only(rod1, rod2, kinds, tables, shape, dt, steps):
    """``steps`` elastic steps of both rods (no contact, no histories, no energy checks)."""
    u1, v1, a1, bands1 = rod1
    u2, v2, a2, bands2 = rod2
    for _ in range(steps):
        kernels._step(u1, v1, a1, bands1, kinds[0], tables[0], shape[0], dt)
        kernels._step(u2, v2, a2, bands2, kinds[1], tables[1], shape[1], dt)


def loop_row(name, order, mass, elements, repeats):
    """One row of table 2: the time loop against the two rods' steps alone, CPU ns per element-step."""
    setup = build_setup(wavecontact.two_rods(0.6, 100), elements=elements, order=order, mass=mass)
    both = sum(d.n_elements for d in setup.rods)
    steps = max(100, int(1e7 / both))
    loop, alone = [], []
    for _ in range(repeats):
        run = _Run(setup, 0.05)
        started = time.thread_time()
        _, history, _ = run.advance(steps)
        loop.append((time.thread_time() - started) / (len(history[0]) * both))
        run = _Run(setup, 0.05)
        shape = np.array([int(table[interleaved_step.L_SHAPE, 0]) for _, table in run.mass_solves])
        rods = [(run.u[k], run.v[k], run.a[k], setup.rods[k].stiffness_bands) for k in range(2)]
        for k, (_, table) in enumerate(run.mass_solves):
            if shape[k]:
                interleaved_step.pack_nodes(run.u[k], table[interleaved_step.L_U], shape[k], order)
                interleaved_step.pack_nodes(run.v[k], table[interleaved_step.L_V], shape[k], order)
        kinds = np.array([kind for kind, _ in run.mass_solves])
        tables = (run.mass_solves[0][1], run.mass_solves[1][1])
        _steps_only(rods[0], rods[1], kinds, tables, shape, setup.dt, 1)
        started = time.thread_time()
        _steps_only(rods[0], rods[1], kinds, tables, shape, setup.dt, steps)
        alone.append((time.thread_time() - started) / (steps * both))
    loop_ns, alone_ns = float(np.median(loop)) * 1e9, float(np.median(alone)) * 1e9
    return f"| {name} | {elements} | {loop_ns:.2f} | {alone_ns:.2f} | {loop_ns - alone_ns:+.2f} |"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--update-docs", action="store_true",
                        help="also write the tables into docs/fem.md (between its profile-explicit-step markers)")
    args = parser.parse_args(argv)
    argv_used = None if argv is None else ["benchmarks/profile_explicit_step.py", *argv]
    run_and_write(lambda: measure(args), "fem.md", "profile-explicit-step", args.update_docs, argv_used)


def measure(args):
    """Print the tables."""
    print("| discretization | elements (long rod) | step as the loop runs it: ns/element (layout) | flat layout | "
          "stiffness stencil alone | flat tridiagonal solve alone |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, order, mass in DISCRETIZATIONS:
        for elements in (800, 12800):
            print(profile_row(name, order, mass, elements, args.repeats))
    empty = np.zeros(1)
    explicit_step._stiffness_forces(empty, np.zeros((2, 1)), empty)
    overhead = cpu_per_call(lambda: explicit_step._stiffness_forces(empty, np.zeros((2, 1)), empty), args.repeats)
    print(f"\nPython's overhead of one kernel call: {overhead * 1e9:.0f} ns, {overhead * 1e9 / 1333:.2f} ns per element "
          "of the 1333-element rod.")
    entries = 2 * 21334 + 1  # the nodes of the 21333-element P2 rod
    u, v, a = np.zeros(entries), np.zeros(entries), np.zeros(entries)
    _stream(u, v, a, 0.0)
    stream = cpu_per_call(lambda: _stream(u, v, a, 0.0), args.repeats)
    print(f"Streaming pass (v += dt a, u += dt v over three arrays of {entries} doubles, 1 MB, the size of the L2 "
          f"cache): {stream * 1e9 / (5 * entries):.3f} ns per double read or written.\n")
    print("| discretization | elements (short rod) | time loop: ns/element-step | the two rods' steps alone | "
          "rest of the loop |")
    print("|---|---:|---:|---:|---:|")
    for name, order, mass in DISCRETIZATIONS:
        for elements in (800, 12800):
            print(loop_row(name, order, mass, elements, args.repeats))


if __name__ == "__main__":
    main()
