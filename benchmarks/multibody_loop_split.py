"""Where the multi-body loop's time per step goes on the 3-rod chain of bench_multibody.py, P1 lumped:

    python benchmarks/multibody_loop_split.py [--elements 200 400] [--repeats 9]

Per step (ns), medians and minima over ``repeats`` runs that alternate: the whole loop
(:func:`wavecontact.fem.multibody_kernel.advance_line` from a fresh start over the steps of a
run to separation), the rods' own steps alone (the same three P1 lumped leapfrog steps on the
loop's store, as many steps), and the two-rod loop of the same discretization (bench_multibody.py's
two-rod scene and step).  The difference of the first two is the loop's fixed cost per step: the two
soft contacts' gaps, forces, kicks and records, and the loop's checks.  Only the loops are timed.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
sys.path.insert(1, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the checkout this script lives in

from bench_multibody import common_step, scenes, two_rod_loop

from wavecontact._jit import kernel
from wavecontact.fem import multibody as mb
from wavecontact.fem import multibody_store as ms
from wavecontact.fem.kernels import _leapfrog_p1
from wavecontact.fem.multibody_setup import build_line_setup


@kernel
def _rods_alone(store, layout, dt, steps):
    """``steps`` P1 lumped leapfrog steps of every rod of the store, nothing else."""
    for _ in range(steps):
        for b in range(layout.shape[0]):
            n = layout[b, ms.G_NODES]
            _leapfrog_p1(ms.segment(store, layout[b, ms.G_STEPPED_U], n), ms.segment(store, layout[b, ms.G_STEPPED_V], n),
                         ms.block(store, layout[b, ms.G_BANDS], np.int64(2), n),
                         ms.segment(store, layout[b, ms.G_TABLE], layout[b, ms.G_TABLE_COLS]), dt)


def measure(elements: int, repeats: int) -> dict:
    two, chain = scenes()
    dt = common_step(elements)
    setup = build_line_setup(chain, elements, 1, "lumped", dt)
    loop = mb._start(chain, setup)
    _status, steps = mb._advance(setup, loop, 10**8)  # the steps of a run to separation
    times = {"loop": [], "rods": [], "two-rod": []}
    for _ in range(repeats + 1):  # the first, compiling, discarded below
        loop = mb._start(chain, setup)
        started = time.perf_counter()
        mb._advance(setup, loop, steps)
        times["loop"].append((time.perf_counter() - started) / steps)
        loop = mb._start(chain, setup)
        store, layout = loop["args_rods"]
        started = time.perf_counter()
        _rods_alone(store, layout, setup.dt, steps)
        times["rods"].append((time.perf_counter() - started) / steps)
        times["two-rod"].append(two_rod_loop(two, elements, 1, "lumped", dt) * 2 * elements)
    return {name: np.array(values[1:]) * 1e9 for name, values in times.items()} | {"steps": steps}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elements", type=int, nargs="+", default=[200, 400])
    parser.add_argument("--repeats", type=int, default=9)
    args = parser.parse_args(argv)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores at the start; ns per step, median (min) "
          f"of {args.repeats} alternating runs\n")
    print("| elements per rod | steps | 3-rod chain, whole loop | its rods' steps alone | fixed cost per step | "
          "two-rod loop |")
    print("|---|---|---|---|---|---|")
    for elements in args.elements:
        t = measure(elements, args.repeats)
        cell = {name: f"{np.median(t[name]):.0f} ({t[name].min():.0f})" for name in ("loop", "rods", "two-rod")}
        fixed = np.median(t["loop"] - t["rods"])
        print(f"| {elements} | {t['steps']} | {cell['loop']} | {cell['rods']} | {fixed:.0f} | {cell['two-rod']} |")
    print(f"\nload average {os.getloadavg()[0]:.1f} at the end.")


if __name__ == "__main__":
    main()
