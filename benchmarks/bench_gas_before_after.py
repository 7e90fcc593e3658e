"""The kernel's side of bench_gas's heapq comparison, timed for two checkouts side by side.

Run: ``python benchmarks/bench_gas_before_after.py --before DIR [--after DIR] [--rounds 3] [--repeats 7]``

``DIR`` is the root of a checkout of this repository (for instance
``git worktree add /tmp/before <commit>``); ``--after`` defaults to the
checkout this script belongs to.  Each side runs in its own process with
its checkout first on ``PYTHONPATH`` (so that its package, and its numba
cache, is the one imported), and the two alternate, ``--rounds`` times each,
so that both see the same load.  Each process warms its kernels up and then
times ``--repeats`` runs of :func:`bench_gas.kernel_task` (a fresh simulation
of 10,000 rods, fixed rule r = 1, 200,000 collisions, set-up included) in
CPU time of the process.  Prints a markdown table: the median over all
runs of each side, in milliseconds per task and nanoseconds per collision,
and how much less CPU time the after side takes.  About a minute.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

_HERE = Path(__file__).resolve().parent


def _worker(rods, collisions, repeats):
    """Time the task in this process (its package is whatever ``PYTHONPATH`` makes importable); print JSON."""
    sys.path.insert(0, str(_HERE))
    import bench_gas

    import wavecontact

    gas = bench_gas.comparison_gas(rods)
    bench_gas.kernel_task(gas, 1.0, 10)  # compile or load the kernels
    cpu = []
    for _ in range(repeats):
        start = time.process_time()
        bench_gas.kernel_task(gas, 1.0, collisions)
        cpu.append(time.process_time() - start)
    print(json.dumps({"package": str(Path(wavecontact.__file__).resolve().parent), "revision": bench_gas._revision(),
                      "cpu": cpu}))


def _side(root, args):
    env = dict(os.environ, PYTHONPATH=str(root))
    command = [sys.executable, str(Path(__file__).resolve()), "--worker", "--rods", str(args.rods),
               "--collisions", str(args.collisions), "--repeats", str(args.repeats)]
    out = subprocess.run(command, env=env, cwd=root, capture_output=True, text=True, check=True, timeout=600)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, help="root of the checkout to compare against")
    parser.add_argument("--after", type=Path, default=_HERE.parent, help="root of the checkout measured (default: this one)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--rods", type=int, default=10_000)
    parser.add_argument("--collisions", type=int, default=200_000)
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    for name, low, high in (("rounds", 1, 20), ("repeats", 1, 50), ("rods", 10, 100_000), ("collisions", 1000, 10**7)):
        if not low <= getattr(args, name) <= high:
            parser.error(f"--{name} must lie in [{low}, {high}], got {getattr(args, name)}")
    if args.worker:
        _worker(args.rods, args.collisions, args.repeats)
        return 0
    if args.before is None:
        parser.error("--before DIR is required")
    sides = {"before": args.before.resolve(), "after": args.after.resolve()}
    for name, root in sides.items():
        if not (root / "wavecontact" / "__init__.py").is_file():
            parser.error(f"--{name} {root} is not the root of a checkout (no wavecontact/__init__.py)")
    load = os.getloadavg()[0]
    runs = {name: [] for name in sides}
    revisions = {}
    for _ in range(args.rounds):
        for name, root in sides.items():
            result = _side(root, args)
            runs[name] += result["cpu"]
            revisions[name] = f"{result['revision']} ({result['package']})"
    print(f"`python benchmarks/bench_gas_before_after.py --rounds {args.rounds} --repeats {args.repeats} --rods "
          f"{args.rods} --collisions {args.collisions}`, run at {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
          f"load average {load:.1f} at the start and {os.getloadavg()[0]:.1f} at the end on {os.cpu_count()} cores; "
          f"fixed rule r = 1, a fresh simulation per run (set-up included); CPU time, medians of "
          f"{args.rounds * args.repeats} runs per side.")
    print()
    print("| side | commit (package) | ms per run | ns per collision | collisions/s |")
    print("|---|---|---|---|---|")
    medians = {name: float(np.median(values)) for name, values in runs.items()}
    for name in sides:
        m = medians[name]
        print(f"| {name} | {revisions[name]} | {1e3 * m:.2f} | {1e9 * m / args.collisions:.1f} | "
              f"{args.collisions / m:,.0f} |")
    print()
    print(f"after / before: {medians['after'] / medians['before']:.3f} of the CPU time "
          f"({100 * (1 - medians['after'] / medians['before']):.1f} % less).")
    return 0


if __name__ == "__main__":
    sys.exit(main())
