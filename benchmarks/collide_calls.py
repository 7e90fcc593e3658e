"""Warm ``collide(0.6, kappa, rtol=...)`` calls of the checkout in the current directory, one command:

    cd CHECKOUT && python /path/to/benchmarks/collide_calls.py [--repeats 300]

Prints one line per row of docs/performance.md's recommendation table: median wall and CPU time
of a whole call, the steps taken and epsilon (to compare builds: the same steps and the same
epsilon mean the same solve).  It imports the package of the current directory, so the same
script times an older commit checked out elsewhere (``git worktree add --detach DIR COMMIT``);
run the two one after the other on the same machine and compare the CPU columns (per-core
cost, less disturbed by other jobs than wall time).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.getcwd())  # the checkout being timed, not the one this script lives in

ROWS = ((20.0, 1e-3), (20.0, 1e-7), (100.0, 1e-3), (100.0, 1e-5), (1e4, 1e-3), (1e4, 1e-7), (1e6, 1e-3),
        (1e6, 1e-11), (float("inf"), 1e-3))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=300)
    args = parser.parse_args()
    from wavecontact import __file__ as package
    from wavecontact import collide

    print(f"package: {os.path.dirname(package)}")
    print("| kappa | rtol | wall (ms) | CPU (ms) | steps | epsilon |")
    print("|---|---|---|---|---|---|")
    for kappa, rtol in ROWS:
        result = collide(0.6, kappa, rtol=rtol)
        wall, cpu = [], []
        for _ in range(args.repeats):
            started, started_cpu = time.perf_counter(), time.process_time()
            result = collide(0.6, kappa, rtol=rtol)
            cpu.append(time.process_time() - started_cpu)
            wall.append(time.perf_counter() - started)
        print(f"| {kappa:g} | {rtol:g} | {1e3 * np.median(wall):.3f} | {1e3 * np.median(cpu):.3f} | "
              f"{result.work.get('steps')} | {result.restitution!r} |")


if __name__ == "__main__":
    main()
