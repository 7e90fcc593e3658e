"""How many chunks (SIMD lanes) the interleaved layout should use, and from what size it pays, one command:

    python benchmarks/interleaved_lanes.py [--repeats 5] [--update-docs]

Prints two Markdown tables, CPU time of the calling thread (``time.thread_time``), per element of one
rod of equal elements, its step alone in a compiled loop:

1. the interleaved step (``interleaved_step.step_tridiagonal`` for P1 consistent, ``step_condensed`` for
   P2 consistent) with the rod's unknowns in 4, 8, 16 and 32 chunks, at 800, 1333, 3200 and 12800
   elements.  Each lane count is a copy of ``wavecontact/fem/interleaved_step.py`` with its ``LANES``
   changed, imported under another name (the set-up, ``explicit_step.prepare_mass``, is pointed at it
   while it builds that copy's tables), so every column runs the library's own code;
2. the flat step (``explicit_step.step_rod`` on ``prepare_mass(..., interleaved=False)``) against the
   interleaved one with the library's ``LANES`` on small rods, where the chunks' coupling covers most of
   their rows: where the thresholds ``LANE_MIN_UNKNOWNS``, ``LANE_MIN_VERTICES`` come from.

Every figure is the median over ``PLACEMENTS`` set-ups of the tables (kept alive, so that each lies on
pages of its own: the step's speed follows the pages, docs/fem.md section 7) times ``--repeats`` runs,
all alternated.  ``--update-docs`` writes the tables into docs/fem.md (block ``interleaved-lanes``).
"""

from __future__ import annotations

import functools
import importlib.util
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(1, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the checkout this script lives in

from docs_block import repeats_main

from wavecontact import Rod
from wavecontact._jit import NUMBA_ENABLED, kernel
from wavecontact.fem import explicit_step, interleaved_step
from wavecontact.fem.discretization import discretize_rod

LANE_COUNTS = (4, 8, 16, 32)
PLACEMENTS = 4
STEP_WORK = 3e6  # elements x steps per timed run


def lanes_module(lanes: int, directory: Path):
    """A copy of ``interleaved_step`` with ``LANES = lanes``, imported from ``directory``."""
    source = Path(interleaved_step.__file__).read_text(encoding="utf-8")
    line = f"LANES = {interleaved_step.LANES}"
    if source.count(f"\n{line}") != 1:
        raise RuntimeError(f"no single '{line}' line in {interleaved_step.__file__}")
    source = source.replace(f"\n{line}", f"\nLANES = {lanes}").replace("from .._jit import", "from wavecontact._jit import")
    path = directory / f"interleaved_lanes_{lanes}.py"
    path.write_text(source, encoding="utf-8")
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _compiled_loop(step):
    """A compiled loop of ``steps`` calls of the compiled ``step(table, dt)``."""
    if not NUMBA_ENABLED:
        raise SystemExit("this benchmark times compiled kernels: it needs numba")
    import numba

    @numba.njit(nogil=True)
    def loop(table, dt, steps):
        for _ in range(steps):
            step(table, dt)

    return loop


@kernel(fastmath=False)
def _flat_loop(u, v, a, bands, kind, table, dt, steps):
    for _ in range(steps):
        explicit_step.step_rod(u, v, a, bands, kind, table, dt)


def _rod(order: int, elements: int):
    return discretize_rod(Rod(1.0), np.linspace(0.0, 1.0, elements + 1), order, "consistent")


def _interleaved_tables(module, disc):
    """``PLACEMENTS`` interleaved tables of ``disc`` built by ``module``, the rod's state packed in."""
    saved = explicit_step.lanes
    explicit_step.lanes = module
    try:
        tables = [explicit_step.prepare_mass(disc)[1] for _ in range(PLACEMENTS)]
    finally:
        explicit_step.lanes = saved
    u = 1e-3 * np.sin(3.0 * disc.x)
    for table in tables:
        rows = int(table[module.L_SHAPE, 0])
        if rows == 0:
            raise RuntimeError(f"{disc.n_elements} elements: the set-up chose the flat layout")
        module.pack_nodes(u, table[module.L_U], rows, disc.order)
    return tables


def _alternated(runs, repeats):
    """Median CPU seconds of each of ``runs`` (lists of zero-argument callables, one per placement)."""
    samples = [[] for _ in runs]
    for _ in range(repeats):
        for placements, times in zip(runs, samples):
            for run in placements:
                started = time.thread_time()
                run()
                times.append(time.thread_time() - started)
    return [float(np.median(times)) for times in samples]


def table_lanes(repeats, directory):
    print("\n#### The interleaved step with the rod's unknowns in 4, 8, 16 and 32 chunks\n")
    print("CPU ns per element of one rod of equal elements, the step alone in a compiled loop; medians over "
          f"{PLACEMENTS} set-ups of the tables x {repeats} runs, alternated.\n")
    modules = {lanes: lanes_module(lanes, directory) for lanes in LANE_COUNTS}
    print("| discretization | elements | " + " | ".join(f"{lanes} chunks" for lanes in LANE_COUNTS) + " |")
    print("|---|---:|" + "---:|" * len(LANE_COUNTS))
    for name, order in (("P1 consistent", 1), ("P2 consistent", 2)):
        for elements in (800, 1333, 3200, 12800):
            disc = _rod(order, elements)
            dt = 1e-5 / elements
            steps = max(20, int(STEP_WORK / elements))
            runs = []
            for module in modules.values():
                loop = _compiled_loop(module.step_tridiagonal if order == 1 else module.step_condensed)
                tables = _interleaved_tables(module, disc)
                loop(tables[0], dt, 2)  # compile
                runs.append([functools.partial(loop, table, dt, steps) for table in tables])
            seconds = _alternated(runs, repeats)
            cells = " | ".join(f"{s / steps / elements * 1e9:.2f}" for s in seconds)
            print(f"| {name} | {elements} | {cells} |")


def table_threshold(repeats):
    lanes = interleaved_step.LANES
    print(f"\n#### Flat layout against {lanes} interleaved chunks on small rods\n")
    print("CPU ns per element of one rod of equal elements, the step alone in a compiled loop (flat: "
          "`step_rod` on the flat tables; interleaved: the interleaved step, the set-up's thresholds lowered "
          f"for the measurement); the library switches to the interleaved layout from {interleaved_step.LANE_MIN_UNKNOWNS} "
          f"unknowns (P1) and {interleaved_step.LANE_MIN_VERTICES} vertices (P2).\n")
    print("| discretization | elements | rows per chunk | flat | interleaved |")
    print("|---|---:|---:|---:|---:|")
    saved = interleaved_step.LANE_MIN_UNKNOWNS, interleaved_step.LANE_MIN_VERTICES
    for name, order in (("P1 consistent", 1), ("P2 consistent", 2)):
        for elements in (40, 60, 100, 150, 200, 300):
            disc = _rod(order, elements)
            dt = 1e-5 / elements
            steps = max(20, int(STEP_WORK / elements))
            interleaved_step.LANE_MIN_UNKNOWNS = interleaved_step.LANE_MIN_VERTICES = 0
            try:
                tables = _interleaved_tables(interleaved_step, disc)
            finally:
                interleaved_step.LANE_MIN_UNKNOWNS, interleaved_step.LANE_MIN_VERTICES = saved
            loop = _compiled_loop(interleaved_step.step_tridiagonal if order == 1 else interleaved_step.step_condensed)
            flat = [explicit_step.prepare_mass(disc, interleaved=False) for _ in range(PLACEMENTS)]
            states = [(1e-3 * np.sin(3.0 * disc.x), np.zeros(disc.n_nodes), np.zeros(disc.n_nodes)) for _ in flat]
            bands = disc.stiffness_bands
            loop(tables[0], dt, 2)
            _flat_loop(*states[0], bands, *flat[0], dt, 2)
            runs = [[functools.partial(_flat_loop, *state, bands, *solve, dt, steps) for state, solve in zip(states, flat)],
                    [functools.partial(loop, table, dt, steps) for table in tables]]
            seconds = _alternated(runs, repeats)
            rows = int(tables[0][interleaved_step.L_SHAPE, 0])
            print(f"| {name} | {elements} | {rows} | {seconds[0] / steps / elements * 1e9:.2f} | "
                  f"{seconds[1] / steps / elements * 1e9:.2f} |")


def measure(args):
    print(f"wavecontact interleaved layout: lanes and thresholds ({os.cpu_count()} cores)")
    with tempfile.TemporaryDirectory() as directory:
        table_lanes(args.repeats, Path(directory))
    table_threshold(args.repeats)


def main(argv=None):
    repeats_main(argv, __doc__.splitlines()[0], "benchmarks/interleaved_lanes.py", measure, "fem.md",
                 "interleaved-lanes", repeats=5)


if __name__ == "__main__":
    main()
