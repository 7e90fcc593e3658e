"""Benchmark of the finite-element solver (issue 3), one command:

    python benchmarks/bench_fem.py [--repeats 7] [--only discretizations] [--update-docs]

Prints Markdown tables:
1. ns per element-step of the time loop (set-up excluded), P1 lumped, kappa = 100;
2. the same mesh with the straightforward scikit-fem + scipy.sparse loop
   (benchmarks/peers/fem_scipy_loop.py), measured in the same run;
3. time to epsilon within 1e-6 of the delay reference at kappa = 100
   (the whole ``collide`` call, set-up included), cheapest mesh that gets there;
4. cost at kappa = 1e6 against kappa = 100 on the same mesh;
5. the general explicit path (P1 consistent, P2 lumped, P2 consistent, P1 lumped off the exact
   lattice) at 800, 3200 and 12800 elements against the scikit-fem + scipy.sparse loop of the
   same discretization (consistent mass: splu factorized once), both timed in the same run;
6. the two gap quadratures of the characteristic scheme (gap_quadrature='substeps' / 'gauss').
All times are medians of repeated runs.

"ns / element-step" is the loop's wall time divided by (steps x elements of both rods), the
usual unit for explicit FE loops.  On the exact lattice (the default P1 lumped scheme) our
loop does not touch every element every step: it carries each rod as d'Alembert's two waves
and costs O(1) per step (end nodes, contact) plus O(N) per energy / separation check (every
~0.1 N steps) and per call; so the figure falls as N grows and is not a per-node cost.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
sys.path.insert(1, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the checkout this script lives in

from docs_block import run_and_write
from peers.fem_scipy_loop import scipy_fem_run
from timing import median_time

import wavecontact
from wavecontact.fem import interleaved_step
from wavecontact.fem.explicit_step import prepare_mass
from wavecontact.fem.simulation import _Run, build_setup, run_collision

GAMMA = 0.6
_LATTICE_NOTE = ("Ours runs the exact lattice at O(1) work per step plus O(N) per energy check (every ~0.1 N "
                 "steps), so its ns per element-step falls with N; the peer's is a true per-element cost.")


def loop_cost(kappa, elements, repeats):
    """(seconds, element_steps, epsilon) of the time loop alone (epsilon from the full solve)."""
    setup = build_setup(wavecontact.two_rods(GAMMA, kappa), elements=elements)
    out = run_collision(setup)
    element_steps = out["steps"] * sum(d.n_elements for d in setup.rods)
    seconds = median_time(lambda: run_collision(setup), repeats)
    epsilon = wavecontact.collide(GAMMA, kappa, solver="fem", elements=elements).restitution
    return seconds, element_steps, epsilon


def table_loop(repeats):
    print("\n#### Time loop, P1 lumped, kappa = 100 (target <= 2 ns per element-step)\n")
    print(_LATTICE_NOTE + "\n")
    print("| elements (short rod) | elements (both) | steps | loop time (ms) | ns / element-step |")
    print("|---:|---:|---:|---:|---:|")
    for elements in (800, 3200, 10000):
        setup = build_setup(wavecontact.two_rods(GAMMA, 100), elements=elements)
        seconds, element_steps, _ = loop_cost(100, elements, repeats if elements < 10000 else 3)
        both = sum(d.n_elements for d in setup.rods)
        print(f"| {elements} | {both} | {element_steps // both} | {seconds * 1e3:.2f} | "
              f"{seconds / element_steps * 1e9:.2f} |")


def table_peer(repeats, reference):
    print("\n#### Against the scikit-fem + scipy.sparse loop on the same mesh (target >= 20x)\n")
    print("Runs of both alternate, so that both see the same load on a shared machine. " + _LATTICE_NOTE + "\n")
    print("| kappa | elements | ours: ns/el-step | peer: ns/el-step | speed-up per el-step | "
          "ours: error | peer: error |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for kappa, elements in ((100, 800), (100, 3200), (1e4, 800)):
        setup = build_setup(wavecontact.two_rods(GAMMA, kappa), elements=elements)
        out = run_collision(setup)
        element_steps = out["steps"] * sum(d.n_elements for d in setup.rods)
        epsilon = wavecontact.collide(GAMMA, kappa, solver="fem", elements=elements).restitution
        ours, theirs = [], []
        peer_eps = peer_steps = None
        for _ in range(repeats):
            started = time.perf_counter()
            run_collision(setup)
            ours.append(time.perf_counter() - started)
            peer_eps, peer_seconds, _, peer_steps = scipy_fem_run(GAMMA, kappa, elements, courant=0.99)
            theirs.append(peer_seconds)
        ours_ns = float(np.median(ours)) / element_steps * 1e9
        theirs_ns = float(np.median(theirs)) / peer_steps * 1e9
        exact = reference[kappa]
        print(f"| {kappa:g} | {elements} | {ours_ns:.2f} | {theirs_ns:.1f} | {theirs_ns / ours_ns:.0f}x | "
              f"{abs(epsilon - exact):.1e} | {abs(peer_eps - exact):.1e} |")
    print("\n(peer at Courant number 0.99: at exactly 1 the contact stiffness makes it blow up even at kappa = 100;"
          " at kappa = 1e4 it returns garbage on every mesh, see docs/fem.md)")


def table_time_to_accuracy(repeats, reference):
    print("\n#### Time to |epsilon - delay| <= 1e-6 at kappa = 100 (target < 20 ms; whole collide call)\n")
    print("| elements | error | wall time (ms), set-up included | of which set-up (ms) |")
    print("|---:|---:|---:|---:|")
    exact = reference[100]
    for elements in (50, 100, 200, 400, 800):
        result = wavecontact.collide(GAMMA, 100, solver="fem", elements=elements)
        error = abs(result.restitution - exact)
        seconds = median_time(lambda e=elements: wavecontact.collide(GAMMA, 100, solver="fem", elements=e), repeats)
        setup = median_time(lambda e=elements: build_setup(wavecontact.two_rods(GAMMA, 100), elements=e), repeats)
        print(f"| {elements} | {error:.1e} | {seconds * 1e3:.1f} | {setup * 1e3:.1f} |")
        if error <= 1e-6:
            break


def table_stiffness(repeats, reference):
    print("\n#### Cost at kappa = 1e6 against kappa = 100, same mesh (target <= 3)\n")
    print("| elements | kappa | steps | loop time (ms) | error | cost ratio vs kappa = 100 |")
    print("|---:|---:|---:|---:|---:|---:|")
    for elements in (800, 3200):
        base = None
        for kappa in (100, 1e4, 1e6, float("inf")):
            seconds, element_steps, epsilon = loop_cost(kappa, elements, repeats)
            base = base or seconds
            exact = reference.get(kappa)
            error = f"{abs(epsilon - exact):.1e}" if exact is not None else "n/a"
            steps = element_steps // sum(d.n_elements for d in build_setup(
                wavecontact.two_rods(GAMMA, kappa), elements=elements).rods)
            print(f"| {elements} | {kappa:g} | {steps} | {seconds * 1e3:.2f} | {error} | {seconds / base:.2f} |")


DISCRETIZATIONS = (("P1 consistent", 1, "consistent", {}), ("P2 lumped", 2, "lumped", {}),
                   ("P2 consistent", 2, "consistent", {}), ("P1 lumped, Courant 0.9", 1, "lumped", {"courant": 0.9}))
OURS_ELEMENT_STEPS = 2e7  # per timed run: about 0.1 s of our loop
PEER_ELEMENT_STEPS = 3e6  # per timed run of the peer (0.02 - 0.6 s)


def _our_loop(setup, steps, both, flat_layout, held_constants=True):
    """(CPU, wall) seconds per element-step of our time loop over up to ``steps`` steps from the start, divided
    by the steps it ran (a short run separates before ``steps``); ``flat_layout``: every mass solve in the
    flat layout (``prepare_mass(..., interleaved=False)``), for comparison with the interleaved one;
    ``held_constants`` False: the interleaved layout's uniform rows read from the table's arrays (the same
    values) instead of constants held in registers, the step before they were."""
    run = _Run(setup, 0.05)
    if flat_layout:
        run.mass_solves = [prepare_mass(d, interleaved=False) for d in setup.rods]
    if not held_constants:
        for _, table in run.mass_solves:
            table[interleaved_step.L_UNIFORM, :2] = 1.0
    started, started_wall = time.thread_time(), time.perf_counter()
    _, history, _ = run.advance(steps)
    done = len(history[0]) * both
    return (time.thread_time() - started) / done, (time.perf_counter() - started_wall) / done


def table_discretizations(repeats, reference):
    print("\n#### General explicit path against the scikit-fem + scipy.sparse loop, kappa = 100 "
          "(target <= 2 ns per element-step, >= 20x)\n")
    print("Both loops take the same step (ours: 'auto', the force scheme here) on the same kind of mesh (both rods "
          "meshed whole); the peer solves a consistent mass with scipy.sparse.linalg.splu factorized once. Timed over "
          "a fixed number of steps from the start (the cost per step does not depend on the phase of the collision), "
          "runs alternated, medians, divided by the steps the run took (it may separate earlier); 'flat layout': our "
          "loop with every mass solve in the flat layout instead of the interleaved one of large consistent masses "
          "(the same otherwise); 'no held constants': the interleaved layout reading the coefficients of its uniform rows "
          "from the table's arrays (the same values) instead of holding them as constants; epsilon error from full runs at 800 elements. 'CPU' is the CPU time of the "
          "calling thread (time.thread_time), 'wall' the elapsed time: on a shared machine the wall time also counts "
          "the time other jobs hold the core, the CPU time does not. Not the process's CPU time: OpenBLAS's worker "
          "threads, woken by the BLAS calls of a set-up on the large meshes (build_setup at 12800 elements), spin "
          "for a while afterwards and add their CPU time to whatever loop runs then (OPENBLAS_NUM_THREADS=1 "
          "removes it).\n")
    print("| discretization | elements | dt / stable step | ours: ns/el-step CPU (wall) | ours, flat layout: CPU | "
          "ours, no held constants: CPU | peer: ns/el-step CPU (wall) | speed-up CPU (wall) | "
          "error at 800 (ours / peer) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---|")
    for name, order, mass, extra in DISCRETIZATIONS:
        for elements in (800, 3200, 12800):
            setup = build_setup(wavecontact.two_rods(GAMMA, 100), elements=elements, order=order, mass=mass, **extra)
            both = sum(d.n_elements for d in setup.rods)
            ours_steps = max(100, int(OURS_ELEMENT_STEPS / both))
            peer_steps = max(20, int(PEER_ELEMENT_STEPS / both))
            ours, ours_wall, flat, arrays, theirs, theirs_wall = [], [], [], [], [], []
            for _ in range(max(3, repeats)):  # each run builds new tables: medians over placements (docs/fem.md)
                seconds, seconds_wall = _our_loop(setup, ours_steps, both, flat_layout=False)
                ours.append(seconds)
                ours_wall.append(seconds_wall)
                flat.append(_our_loop(setup, ours_steps, both, flat_layout=True)[0])
                arrays.append(_our_loop(setup, ours_steps, both, flat_layout=False, held_constants=False)[0])
                _, seconds, _, element_steps = scipy_fem_run(GAMMA, 100, elements, order, mass, dt=setup.dt,
                                                             max_steps=peer_steps, clock=time.thread_time)
                theirs.append(seconds / element_steps)
                _, seconds, _, element_steps = scipy_fem_run(GAMMA, 100, elements, order, mass, dt=setup.dt,
                                                             max_steps=peer_steps)
                theirs_wall.append(seconds / element_steps)
            ours_ns, theirs_ns = float(np.median(ours)) * 1e9, float(np.median(theirs)) * 1e9
            flat_ns, arrays_ns = float(np.median(flat)) * 1e9, float(np.median(arrays)) * 1e9
            ours_wall_ns, theirs_wall_ns = float(np.median(ours_wall)) * 1e9, float(np.median(theirs_wall)) * 1e9
            errors = ""
            if elements == 800:
                mine = wavecontact.collide(GAMMA, 100, solver="fem", elements=elements, order=order, mass=mass, **extra)
                peer_eps = scipy_fem_run(GAMMA, 100, elements, order, mass, dt=setup.dt)[0]
                errors = f"{abs(mine.restitution - reference[100]):.1e} / {abs(peer_eps - reference[100]):.1e}"
            print(f"| {name} | {elements} | {setup.dt / setup.stable_step:.2f} | {ours_ns:.2f} ({ours_wall_ns:.2f}) | "
                  f"{flat_ns:.2f} | {arrays_ns:.2f} | "
                  f"{theirs_ns:.1f} ({theirs_wall_ns:.1f}) | {theirs_ns / ours_ns:.0f}x "
                  f"({theirs_wall_ns / ours_wall_ns:.0f}x) | {errors} |")


def table_gap_quadrature(repeats):
    print("\n#### Gap quadrature of the characteristic scheme, P1 lumped, 800 elements\n")
    print("| gamma | kappa | gap_quadrature | loop time (ms) | error |")
    print("|---:|---:|---|---:|---:|")
    for gamma, kappa in ((GAMMA, 100), (1.0, 1000)):
        exact = wavecontact.collide(gamma, kappa, solver="delay").restitution
        for quadrature in ("substeps", "gauss"):
            setup = build_setup(wavecontact.two_rods(gamma, kappa), elements=800, gap_quadrature=quadrature)
            seconds = median_time(lambda s=setup: run_collision(s), repeats)
            epsilon = wavecontact.collide(gamma, kappa, solver="fem", elements=800,
                                          gap_quadrature=quadrature).restitution
            print(f"| {gamma} | {kappa:g} | {quadrature} | {seconds * 1e3:.2f} | {abs(epsilon - exact):.1e} |")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--only", choices=("discretizations",), help="print only this table")
    parser.add_argument("--update-docs", action="store_true",
                        help="also write the tables into docs/fem.md (between its bench-fem markers; not with --only)")
    args = parser.parse_args(argv)
    argv_used = None if argv is None else ["benchmarks/bench_fem.py", *argv]
    run_and_write(lambda: measure(args), "fem.md", "bench-fem", args.update_docs and not args.only, argv_used)


def measure(args):
    """Print the tables (only the discretizations table with ``--only discretizations``)."""
    print(f"wavecontact FE benchmark ({platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, numba {wavecontact._jit.NUMBA_ENABLED})")
    wavecontact.collide(GAMMA, 100, solver="fem", elements=50)  # compile / load the kernels
    reference = {kappa: wavecontact.collide(GAMMA, kappa, solver="delay").restitution for kappa in (100, 1e4, 1e6)}
    reference[float("inf")] = GAMMA
    if args.only == "discretizations":
        table_discretizations(args.repeats, reference)
        return
    table_loop(args.repeats)
    table_peer(args.repeats, reference)
    table_time_to_accuracy(args.repeats, reference)
    table_stiffness(args.repeats, reference)
    table_discretizations(args.repeats, reference)
    table_gap_quadrature(args.repeats)


if __name__ == "__main__":
    main()
