"""Cost per element-step of the multi-body fem loop against the two-rod loop, one command:

    python benchmarks/bench_multibody.py [--repeats 5] [--elements 200 400 1600] [--update-docs]

Same discretization on both sides: rods of length 1 and one material, ``elements`` elements per
rod, the same step ``dt`` (0.9 of the stable step of P2 consistent, the smallest of the four,
so that every discretization runs the same number of steps), the exponential law
``alpha = 20, B = 0.01``.  Two-rod loop: :func:`wavecontact.fem.simulation.run_collision` with
``scheme='force'`` (plain central differences, the contact force at the end nodes, the same
scheme as the multi-body loop's soft contacts); multi-body loop: a chain of 3 rods (the first
and the last close in on the middle one at rest) through :func:`wavecontact.fem.multibody.run_line`.  Only the time
loop is timed on both sides (set-up excluded); ns per element-step = loop seconds / (steps x
elements of all rods).  Runs alternate two-rod / chain; medians of ``repeats`` runs.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
sys.path.insert(1, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the checkout this script lives in

from docs_block import run_and_write

from wavecontact import Exponential, Rod, Scene
from wavecontact.fem.multibody import run_line
from wavecontact.fem.multibody_setup import build_line_setup
from wavecontact.fem.simulation import build_setup, run_collision

DISCRETIZATIONS = ((1, "lumped"), (1, "consistent"), (2, "lumped"), (2, "consistent"))
LAW = Exponential(20.0, 0.01)
#: the multi-body loop's cost per element-step may be at most this multiple of the two-rod loop's (issue 26)
TARGET_RATIO = 1.5


def scenes():
    two = Scene(rods=(Rod(1.0), Rod(1.0)), velocities=(0.5, -0.5), contact=LAW)
    chain = Scene(rods=(Rod(1.0), Rod(1.0), Rod(1.0)), velocities=(1.0, 0.0, -1.0), contact=LAW)
    return two, chain


def common_step(elements: int) -> float:
    """0.9 of the smallest stable step of the four discretizations (time)."""
    _two, chain = scenes()
    return 0.9 * min(build_line_setup(chain, elements, order, mass).stable_step for order, mass in DISCRETIZATIONS)


def two_rod_loop(scene, elements, order, mass, dt):
    setup = build_setup(scene, elements=elements, order=order, mass=mass, dt=dt, scheme="force")
    started = time.perf_counter()
    out = run_collision(setup)
    seconds = time.perf_counter() - started
    return seconds / (out["steps"] * sum(d.n_elements for d in setup.rods))


def chain_loop(scene, elements, order, mass, dt):
    work = run_line(scene, elements=elements, order=order, mass=mass, dt=dt)["work"]
    return work["loop_seconds"] / work["element_steps"]


def measure_size(elements: int, repeats: int) -> float:
    """Print one table (``elements`` per rod); return its largest ratio."""
    two, chain = scenes()
    dt = common_step(elements)
    print(f"{elements} elements per rod, dt = {dt:.6g}:\n")
    print("| discretization | two-rod loop (ns / element-step) | 3-rod chain, multi-body loop (ns / element-step) "
          "| ratio |")
    print("|---|---|---|---|")
    worst = 0.0
    for order, mass in DISCRETIZATIONS:
        two_rod_loop(two, elements, order, mass, dt)
        chain_loop(chain, elements, order, mass, dt)
        old, new = [], []
        for _ in range(repeats):
            old.append(two_rod_loop(two, elements, order, mass, dt))
            new.append(chain_loop(chain, elements, order, mass, dt))
        a, b = float(np.median(old)) * 1e9, float(np.median(new)) * 1e9
        worst = max(worst, b / a)
        print(f"| P{order} {mass} | {a:.2f} | {b:.2f} | {b / a:.2f} |")
    print()
    return worst


def measure(args):
    print(f"Exponential law alpha = {LAW.alpha:g}, B = {LAW.strength:g}; medians of {args.repeats} alternating runs "
          "(the first, compiling, discarded)\n")
    worst = {elements: measure_size(elements, args.repeats) for elements in args.elements}
    sizes = ", ".join(f"{w:.2f} at {e}" for e, w in worst.items())
    print(f"Largest ratio per size (elements per rod): {sizes} (target: at most {TARGET_RATIO:g}); load average "
          f"{os.getloadavg()[0]:.1f} at the end.")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--elements", type=int, nargs="+", default=[200, 400, 1600], help="elements per rod, "
                        "one table each")
    parser.add_argument("--update-docs", action="store_true", help="write the table into docs/performance.md")
    args = parser.parse_args(argv)
    run_and_write(lambda: measure(args), "performance.md", "multibody-loop", args.update_docs, argv)


if __name__ == "__main__":
    main()
