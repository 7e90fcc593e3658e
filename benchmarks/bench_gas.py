"""Benchmark of the rod gas: collisions per second of the event kernel, and a plain-Python heapq loop.

Run: ``python benchmarks/bench_gas.py [--repeats 5] [--collisions 2000000]``

Prints two tables (one core; the kernel is warmed up first, so no
compilation is timed):

1. the vibration (table) rule and the fixed rule against N: median
   collisions per second over ``--repeats`` runs of ``--collisions``
   collisions each, continuing one gas (so the gas is in its cooled/clustered
   state, not the initial one), and the cost per collision in nanoseconds;
2. at N = 10,000 with the fixed rule (r = 0.98), the same gas run by the kernel
   and by :func:`wavecontact.gas.reference.heapq_ring_gas` (the
   straightforward ``heapq`` loop of Python granular-gas codes), side by side,
   and the ratio.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from timing import median_time

from wavecontact.gas import (
    FixedRestitution,
    GasSimulation,
    UniformLengths,
    VibrationTable,
    random_gas,
    thermal_kick_table,
)
from wavecontact.gas.reference import heapq_ring_gas

_LENGTHS = UniformLengths(0.6, 1.0)  # gamma in [0.6, 1], inside the default table


def kernel_rate(rods, rule, collisions, repeats):
    gas = random_gas(rods, seed=1, packing_fraction=0.2, lengths=_LENGTHS)
    sim = GasSimulation(gas, rule, seed=2, record_every=collisions, max_frames=0, energy_floor=0.0)
    sim.run(min(collisions, 20 * rods))  # warm-up: compile/load the kernels, leave the initial transient
    seconds = median_time(lambda: sim.run(collisions), repeats)
    return collisions / seconds, sim


def heapq_rate(rods, restitution, collisions, repeats):
    gas = random_gas(rods, seed=1, packing_fraction=0.2, lengths=_LENGTHS)
    args = (gas.lengths, gas.positions, gas.velocities, gas.system_length, restitution, collisions)
    return collisions / median_time(lambda: heapq_ring_gas(*args), repeats)


def kernel_rate_fresh(rods, restitution, collisions, repeats):
    """The kernel on exactly the heapq loop's task: the same fresh gas, the same number of collisions."""
    gas = random_gas(rods, seed=1, packing_fraction=0.2, lengths=_LENGTHS)
    GasSimulation(gas, FixedRestitution(restitution), seed=2, record_every=10**9, max_frames=0).run(10)

    def once():
        GasSimulation(gas, FixedRestitution(restitution), seed=2, record_every=10**9, max_frames=0,
                      energy_floor=0.0).run(collisions)

    return collisions / median_time(once, repeats)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--collisions", type=int, default=2_000_000)
    parser.add_argument("--heapq-collisions", type=int, default=200_000)
    args = parser.parse_args(argv)
    table = VibrationTable(thermal_kick_table())
    print(f"# rod gas, one core, median of {args.repeats} runs; machine shared with other jobs")
    print(f"# {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
    print()
    print("| N | rule | collisions/s | ns per collision |")
    print("|---|---|---|---|")
    for rods in (100, 1_000, 10_000, 100_000, 1_000_000):
        for name, rule in (("vibration (table)", table), ("fixed r = 1 (elastic)", FixedRestitution(1.0))):
            rate, _ = kernel_rate(rods, rule, args.collisions, args.repeats)
            print(f"| {rods:,} | {name} | {rate:,.0f} | {1e9 / rate:.0f} |", flush=True)
    print()
    rods, c = 10_000, args.heapq_collisions
    ours = kernel_rate_fresh(rods, 1.0, c, args.repeats)
    theirs = heapq_rate(rods, 1.0, c, max(1, args.repeats // 2))
    print(f"Fixed rule r = 1, N = {rods:,}, {c:,} collisions from the same initial gas (a fresh simulation "
          f"per repeat, set-up included):")
    print()
    print("| loop | collisions/s | ratio |")
    print("|---|---|---|")
    print(f"| wavecontact kernel (numba) | {ours:,.0f} | {ours / theirs:.0f}x |")
    print(f"| plain Python heapq | {theirs:,.0f} | 1x |")
    return 0


if __name__ == "__main__":
    np.seterr(all="raise")
    sys.exit(main())
