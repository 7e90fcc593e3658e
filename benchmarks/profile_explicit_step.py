"""Where the general explicit step spends its time, one command:

    python benchmarks/profile_explicit_step.py [--repeats 7] [--update-docs]

Prints two Markdown tables, CPU time of the calling thread (``time.thread_time``, so
that other jobs on a shared machine do not count), medians of ``--repeats`` runs:

1. per element of one rod's step, for each discretization of the general path at 800
   and 12800 elements (the long rod of the gamma = 0.6 pair, 1333 and 21333
   elements): the step as the time loop runs it (consistent masses from
   ``interleaved_step.LANE_MIN_UNKNOWNS`` unknowns or ``LANE_MIN_VERTICES`` vertices in the
   interleaved layout, ``interleaved_step.py``, on the packed state), the same interleaved step reading the coefficients of its uniform
   rows from the table's arrays instead of holding them as constants (the step before
   they were), the same step in the flat layout (``prepare_mass(...,
   interleaved=False)``; the three measured alternately), and two parts of the
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

import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(1, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the checkout this script lives in

from docs_block import repeats_main
from peers.fem_scipy_loop import scipy_fem_run

import wavecontact
from wavecontact._jit import kernel
from wavecontact.fem import explicit_step, interleaved_step, kernels
from wavecontact.fem.simulation import _Run, build_setup

PLACEMENTS = 5  # set-ups of the tables timed per row of table 1 (their median)
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
    return lambda dt: kernels._step(u, v, a, rod.stiffness_bands, kind, table, rows, dt, -1, 0.0)  # no end load


def profile_row(name, order, mass, elements, repeats):
    """One row of table 1: CPU ns per element of the long rod's step and of its parts.

    The step's speed depends on the physical pages its table lands on (docs/fem.md section 7), so the step
    as the loop runs it and the one without held constants are timed on ``PLACEMENTS`` set-ups of their
    tables, all kept alive (a freed table's memory would be handed to the next one), and the median over
    them is reported."""
    setup = build_setup(wavecontact.two_rods(0.6, 100), elements=elements, order=order, mass=mass)
    disc = setup.rods[1]
    dt, per = setup.dt, 1e9 / disc.n_elements
    steps, arrays_steps = [], []
    for _ in range(PLACEMENTS):
        run = _Run(setup, 0.05)
        kind, table = run.mass_solves[1]
        interleaved = table[interleaved_step.L_SHAPE, 0] > 0
        # the same step reading its uniform rows' coefficients from the arrays (aligned as the table itself)
        arrays_table = interleaved_step.aligned_table(*table.shape) if interleaved else np.zeros(table.shape)
        arrays_table[:] = table
        arrays_table[interleaved_step.L_UNIFORM, :2] = 1.0
        steps.append(loop_step(disc, run.u[1].copy(), run.v[1].copy(), kind, table))
        arrays_steps.append(loop_step(disc, run.u[1].copy(), run.v[1].copy(), kind, arrays_table))
    flat_kind, flat_table = explicit_step.prepare_mass(disc, interleaved=False)
    u, v, a = run.u[1].copy(), run.v[1].copy(), np.zeros(disc.n_nodes)
    bands = disc.stiffness_bands
    for step in steps + arrays_steps:
        step(dt)  # compile / load
    explicit_step.step_rod(u, v, a, bands, flat_kind, flat_table, dt)
    times = alternated([lambda s=s: s(dt) for s in steps + arrays_steps]
                       + [lambda: explicit_step.step_rod(u, v, a, bands, flat_kind, flat_table, dt)], repeats)
    ours, arrays, flat = (float(np.median(times[:PLACEMENTS])), float(np.median(times[PLACEMENTS:-1])),
                          times[-1])
    layout = "interleaved" if table[interleaved_step.L_SHAPE, 0] > 0 else "flat"
    held = f"{arrays * per:.2f}" if layout == "interleaved" else "-"
    stiffness = cpu_per_call(lambda: explicit_step._stiffness_forces(u, bands, a), repeats)
    if mass == "lumped":
        return (f"| {name} | {disc.n_elements} | {ours * per:.2f} ({layout}) | {held} | {flat * per:.2f} | "
                f"{stiffness * per:.2f} | - |")
    unknowns = disc.n_elements + 1
    zeros = np.zeros(disc.n_nodes)
    explicit_step._scaled_solve(flat_table, zeros, unknowns)
    solve = cpu_per_call(lambda: explicit_step._scaled_solve(flat_table, zeros, unknowns), repeats)
    return (f"| {name} | {disc.n_elements} | {ours * per:.2f} ({layout}) | {held} | {flat * per:.2f} | "
            f"{stiffness * per:.2f} | {solve * per:.2f} |")


@kernel
def _stream(u, v, a, dt):
    """``v += dt a``, ``u += dt v``: the plainest pass, 5 doubles moved per entry (3 read, 2 written)."""
    for i in range(u.size):
        velocity = v[i] + dt * a[i]
        v[i] = velocity
        u[i] += dt * velocity


@kernel
def _p2_lumped_floor(uv, um, vv, vm, uv_new, um_new, constants, dt):
    """The cheapest P2 lumped step we can write: interior elements of equal size only (no ends, no contact), the
    coefficients ``constants = (near, far, dt / m_vertex, dt / m_midpoint)`` held in registers, vertices ``uv``
    and midpoints ``um`` (midpoint ``k`` between vertices ``k`` and ``k + 1``) in separate arrays and the new
    displacements written to ``uv_new``, ``um_new`` (two buffers swapped from step to step), so that one pass
    with no dependence between elements does the step and the compiler vectorizes it; the same differences as
    the real step (rigid motion exact).  Per element: 14 additions or subtractions, 7 multiplications (one
    negation folded into the constants); 8 doubles read or written (``uv, um`` read, ``vv, vm`` read and
    written, ``uv_new, um_new`` written)."""
    near = constants[0]  # -K[2k, 2k+1] = -K[2k+1, 2k+2] (vertex to midpoint), sign folded in
    far = constants[1]  # -K[2k, 2k+2] (vertex to vertex across an element)
    kick_vertex = constants[2]
    kick_midpoint = constants[3]
    for k in range(1, uv.size - 1):
        current = uv[k]
        following = uv[k + 1]
        middle = um[k]
        vertex_force = near * ((um[k - 1] - current) + (middle - current)) + far * ((uv[k - 1] - current)
                                                                                  + (following - current))
        midpoint_force = near * ((current - middle) + (following - middle))
        velocity = vv[k] + kick_vertex * vertex_force
        vv[k] = velocity
        uv_new[k] = current + dt * velocity
        velocity = vm[k] + kick_midpoint * midpoint_force
        vm[k] = velocity
        um_new[k] = middle + dt * velocity


@kernel
def _p2_lumped_floor_steps(rod1, rod2, constants, dt, steps):
    """``steps`` pairs of :func:`_p2_lumped_floor` over both rods' arrays, the buffers swapped every step."""
    for step in range(steps):
        for uv, um, vv, vm, uv2, um2 in (rod1, rod2):
            if step % 2 == 0:
                _p2_lumped_floor(uv, um, vv, vm, uv2, um2, constants, dt)
            else:
                _p2_lumped_floor(uv2, um2, vv, vm, uv, um, constants, dt)


FLOOR_ADDITIONS, FLOOR_MULTIPLICATIONS = 14, 7  # per element of _p2_lumped_floor (counted in its source)
FLOOR_DOUBLES = 8  # doubles read or written per element of _p2_lumped_floor
CLOCK_GHZ = 2.6  # this CPU (AMD EPYC, Zen 4)
ADDITIONS_PER_CYCLE = 8  # doubles: two 256-bit adders (a 512-bit instruction takes one of them two cycles)


def floor_row(elements, repeats, per_double):
    """One row of table 3: the cheapest P2 lumped step (:func:`_p2_lumped_floor`) on both rods of the pair, CPU
    ns per element-step, against its additions alone at the adders' rate, its traffic at the streaming pass's
    rate per double (``per_double``, ns), the real P2 lumped step (both rods, compiled loop of steps) and the
    20x target (the scikit-fem + scipy.sparse peer's CPU time per element-step over 20)."""
    setup = build_setup(wavecontact.two_rods(0.6, 100), elements=elements, order=2, mass="lumped")
    disc = setup.rods[1]
    k = 2 * (disc.n_elements // 2)  # an interior vertex (node 2k is vertex k), its coefficients those of every one
    inverse = 1.0 / disc.lumped_mass
    constants = np.array([-disc.stiffness_bands[1, k], -disc.stiffness_bands[2, k], setup.dt * inverse[k],
                          setup.dt * inverse[k + 1]])
    rng = np.random.default_rng(0)
    # a floor is the best case: the arrays in PLACEMENTS places (all kept alive), the fastest place's median
    placements = [tuple(tuple(1e-6 * rng.normal(size=d.n_elements + 1) for _ in range(6)) for d in setup.rods)
                  for _ in range(PLACEMENTS)]
    both = sum(d.n_elements for d in setup.rods)
    steps = max(100, int(2e7 / both))
    for rods in placements:
        _p2_lumped_floor_steps(rods[0], rods[1], constants, setup.dt, 2)
    run = _Run(setup, 0.05)
    real = [(run.u[i], run.v[i], run.a[i], setup.rods[i].stiffness_bands) for i in range(2)]
    kinds = np.array([kind for kind, _ in run.mass_solves])
    tables = (run.mass_solves[0][1], run.mass_solves[1][1])
    shape = np.zeros(2, dtype=np.int64)
    _steps_only(real[0], real[1], kinds, tables, shape, setup.dt, 1)
    floor, step = [[] for _ in placements], []
    for _ in range(repeats):
        for rods, times in zip(placements, floor):
            started = time.thread_time()
            _p2_lumped_floor_steps(rods[0], rods[1], constants, setup.dt, steps)
            times.append((time.thread_time() - started) / (steps * both))
        started = time.thread_time()
        _steps_only(real[0], real[1], kinds, tables, shape, setup.dt, steps)
        step.append((time.thread_time() - started) / (steps * both))
    peer = []
    for _ in range(max(3, repeats // 2)):
        _, seconds, _, element_steps = scipy_fem_run(0.6, 100, elements, 2, "lumped", dt=setup.dt,
                                                     max_steps=max(20, int(3e6 / both)), clock=time.thread_time)
        peer.append(seconds / element_steps)
    step_ns, peer_ns = (float(np.median(x)) * 1e9 for x in (step, peer))
    floor_ns = min(float(np.median(times)) for times in floor) * 1e9
    additions = FLOOR_ADDITIONS / ADDITIONS_PER_CYCLE / CLOCK_GHZ
    return (f"| {elements} | {floor_ns:.2f} | {additions:.2f} | {FLOOR_DOUBLES * per_double:.2f} | {step_ns:.2f} | "
            f"{peer_ns / 20:.2f} ({peer_ns:.1f} / 20) |")


@kernel
def _steps_only(rod1, rod2, kinds, tables, shape, dt, steps):
    """``steps`` elastic steps of both rods (no contact, no histories, no energy checks)."""
    u1, v1, a1, bands1 = rod1
    u2, v2, a2, bands2 = rod2
    for _ in range(steps):
        kernels._step(u1, v1, a1, bands1, kinds[0], tables[0], shape[0], dt, -1, 0.0)
        kernels._step(u2, v2, a2, bands2, kinds[1], tables[1], shape[1], dt, -1, 0.0)


def loop_row(name, order, mass, elements, repeats):
    """One row of table 2: the time loop against the two rods' steps alone, CPU ns per element-step."""
    setup = build_setup(wavecontact.two_rods(0.6, 100), elements=elements, order=order, mass=mass)
    both = sum(d.n_elements for d in setup.rods)
    steps = max(100, int(1e7 / both))
    loop, alone, kept = [], [], []
    for _ in range(repeats):
        run = _Run(setup, 0.05)
        kept.append(run)  # each repeat on tables of its own pages (a freed table's memory would be reused)
        started = time.thread_time()
        _, history, _ = run.advance(steps)
        loop.append((time.thread_time() - started) / (len(history[0]) * both))
        run = _Run(setup, 0.05)
        kept.append(run)
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
    repeats_main(argv, __doc__.splitlines()[0], "benchmarks/profile_explicit_step.py", measure, "fem.md",
                 "profile-explicit-step", repeats=7)


def measure(args):
    """Print the tables."""
    print("| discretization | elements (long rod) | step as the loop runs it: ns/element (layout) | "
          "interleaved, no held constants | flat layout | stiffness stencil alone | flat tridiagonal solve alone |")
    print("|---|---:|---:|---:|---:|---:|---:|")
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
    per_double = stream * 1e9 / (5 * entries)
    print(f"Streaming pass (v += dt a, u += dt v over three arrays of {entries} doubles, 1 MB, the size of the L2 "
          f"cache): {per_double:.3f} ns per double read or written.\n")
    print("| elements (short rod) | cheapest P2 lumped step: ns/element-step | its additions alone, "
          f"{ADDITIONS_PER_CYCLE} per cycle at {CLOCK_GHZ} GHz | its {FLOOR_DOUBLES} doubles at the streaming rate | "
          "the P2 lumped step (both rods) | 20x target: peer / 20 |")
    print("|---:|---:|---:|---:|---:|---:|")
    for elements in (800, 12800):
        print(floor_row(elements, args.repeats, per_double))
    print(f"\n(cheapest step: {FLOOR_ADDITIONS} additions or subtractions and {FLOOR_MULTIPLICATIONS} multiplications "
          f"per element, {FLOOR_ADDITIONS + FLOOR_MULTIPLICATIONS} floating-point operations.)\n")
    print("| discretization | elements (short rod) | time loop: ns/element-step | the two rods' steps alone | "
          "rest of the loop |")
    print("|---|---:|---:|---:|---:|")
    for name, order, mass in DISCRETIZATIONS:
        for elements in (800, 12800):
            print(loop_row(name, order, mass, elements, args.repeats))


if __name__ == "__main__":
    main()
