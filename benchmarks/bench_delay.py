"""Benchmark of the delay-equation solver (issue: foundation), one command:

    python benchmarks/bench_delay.py [--repeats 20] [--no-peer]

Prints Markdown tables:
1. time to epsilon within 1e-9 per kappa (the cheapest rtol that reaches it,
   error measured against a solve at rtol = 1e-13), median of repeats;
2. cost at kappa = 1e6 against kappa = 100 at the same rtol;
3. a 1000-point (gamma, kappa) sweep;
4. JiTCDDE on the same equation at matched accuracy (optional peer; its C
   compilation is timed separately), with the speed-up;
5. where the time of one warm ``collide`` call goes, for the rows of
   docs/performance.md's recommendation table (CPU time, medians): the
   integration (``solve_delay_equation``: option check and kernel), the
   per-rod energy split (``energy_split=True``, the default) and the rest
   (scene, options, limits, result).  ``--breakdown-only`` prints only this.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
sys.path.insert(1, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the checkout this script lives in

from timing import median_cpu_time, median_time

import wavecontact
from wavecontact.delay.solver import solve_delay_equation
from wavecontact.studies.sweep import restitution_map

TARGET = 1e-9
RTOLS = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)


def reference(gamma, kappa):
    return wavecontact.collide(gamma, kappa, rtol=1e-13).restitution


def cheapest_delay(gamma, kappa, repeats):
    exact = reference(gamma, kappa)
    for rtol in RTOLS:
        result = wavecontact.collide(gamma, kappa, rtol=rtol)
        error = abs(result.restitution - exact)
        if error <= TARGET:
            seconds = median_time(lambda rtol=rtol: wavecontact.collide(gamma, kappa, rtol=rtol), repeats)
            return rtol, error, result.work["steps"], seconds
    return None


def table_accuracy(repeats):
    print(f"\n### Delay solver: time to |epsilon error| <= {TARGET:g} (gamma = 0.6)\n")
    print("| kappa | rtol used | error | steps | median time (ms) |")
    print("|---|---|---|---|---|")
    out = {}
    for kappa in (0.1, 1.0, 5.0, 20.0, 100.0, 250.0, 1000.0, 1e4, 1e6):
        found = cheapest_delay(0.6, kappa, repeats)
        if found is None:
            print(f"| {kappa:g} | none reaches the target | | | |")
            continue
        rtol, error, steps, seconds = found
        out[kappa] = (rtol, error, seconds)
        print(f"| {kappa:g} | {rtol:.0e} | {error:.1e} | {steps} | {1e3 * seconds:.3f} |")
    return out


def table_kappa_cost(repeats):
    print("\n### Cost against kappa at the same rtol (1e-8), gamma = 0.6\n")
    print("| kappa | steps | median time (ms) | ratio to kappa = 100 |")
    print("|---|---|---|---|")
    base = None
    for kappa in (100.0, 1e3, 1e4, 1e5, 1e6):
        steps = solve_delay_equation(0.6, kappa, rtol=1e-8)[4]["steps"]
        seconds = median_time(lambda kappa=kappa: solve_delay_equation(0.6, kappa, rtol=1e-8), repeats)
        base = base or seconds
        print(f"| {kappa:g} | {steps} | {1e3 * seconds:.3f} | {seconds / base:.2f} |")


def table_sweep():
    gammas = np.linspace(0.1, 1.0, 25)
    kappas = np.logspace(0, 6, 40)
    restitution_map(gammas[:1], kappas[:1], rtol=1e-8, progress=False)
    started = time.perf_counter()
    values = restitution_map(gammas, kappas, rtol=1e-8, progress=False)
    seconds = time.perf_counter() - started
    print("\n### Sweep: 25 gamma in [0.1, 1] x 40 kappa in [1, 1e6] (log), rtol = 1e-8\n")
    print("| points | wall time (s) | all finite |")
    print("|---|---|---|")
    print(f"| {values.size} | {seconds:.2f} | {bool(np.isfinite(values).all())} |")


def table_peer(repeats, ours):
    try:
        from peers.jitcdde_delay import JitcddePeer, timed_restitution
    except ImportError as exc:  # pragma: no cover
        print(f"\nJiTCDDE peer skipped: {exc}")
        return
    try:
        peer = JitcddePeer(0.6, t_max=60.0)
    except ImportError as exc:
        print(f"\nJiTCDDE peer skipped ({exc}); install with: pip install jitcdde")
        return
    print(f"\n### JiTCDDE at matched accuracy (|error| <= {TARGET:g}), gamma = 0.6\n")
    print(f"JiTCDDE C compilation (once, kappa as a control parameter): {peer.compile_time:.2f} s\n")
    print("| kappa | JiTCDDE rtol | JiTCDDE error | JiTCDDE median (ms) | ours median (ms) | speed-up |")
    print("|---|---|---|---|---|---|")
    for kappa in (5.0, 20.0, 100.0, 1000.0, 1e4):
        exact = reference(0.6, kappa)
        row = None
        for rtol in (1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12):
            seconds, value = timed_restitution(peer, kappa, rtol, repeats=1)
            if math.isfinite(value) and abs(value - exact) <= TARGET:
                seconds, value = timed_restitution(peer, kappa, rtol, repeats=max(3, repeats // 4))
                row = (rtol, abs(value - exact), seconds)
                break
        if kappa not in ours:
            continue
        mine = ours[kappa][2]
        if row is None:
            print(f"| {kappa:g} | none reaches the target (down to rtol 1e-12) | | | {1e3 * mine:.3f} | |")
            continue
        print(f"| {kappa:g} | {row[0]:.0e} | {row[1]:.1e} | {1e3 * row[2]:.2f} | {1e3 * mine:.3f} | "
              f"{row[2] / mine:.1f}x |")


BREAKDOWN_ROWS = ((20.0, 1e-3), (20.0, 1e-7), (100.0, 1e-3), (100.0, 1e-5), (1e4, 1e-3), (1e4, 1e-7),
                  (1e6, 1e-3), (1e6, 1e-11), (math.inf, 1e-3))


def table_breakdown(repeats):
    print("\n### Where one warm `collide(0.6, kappa, rtol=...)` spends its time (CPU ms, medians)\n")
    print("| kappa | rtol | steps | whole call | integration | energy split | rest (scene, options, result) |")
    print("|---|---|---|---|---|---|---|")
    for kappa, rtol in BREAKDOWN_ROWS:
        steps = wavecontact.collide(0.6, kappa, rtol=rtol).work["steps"]
        whole = median_cpu_time(lambda k=kappa, r=rtol: wavecontact.collide(0.6, k, rtol=r), repeats)
        if math.isinf(kappa):
            print(f"| inf | (hard core) | {steps} knots | {1e3 * whole:.3f} | | | |")
            continue
        no_split = median_cpu_time(lambda k=kappa, r=rtol: wavecontact.collide(0.6, k, rtol=r, energy_split=False),
                              repeats)
        integration = median_cpu_time(lambda k=kappa, r=rtol: solve_delay_equation(0.6, k, rtol=r), repeats)
        print(f"| {kappa:g} | {rtol:g} | {steps} | {1e3 * whole:.3f} | {1e3 * integration:.3f} | "
              f"{1e3 * (whole - no_split):.3f} | {1e3 * (no_split - integration):.3f} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--no-peer", action="store_true")
    parser.add_argument("--breakdown-only", action="store_true", help="only the per-call breakdown (table 5)")
    args = parser.parse_args()
    wavecontact.collide(0.6, 100.0)  # load the compiled kernels
    print(f"Machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"numpy {np.__version__}, wavecontact {wavecontact.__version__}")
    if args.breakdown_only:
        table_breakdown(10 * args.repeats)
        return
    ours = table_accuracy(args.repeats)
    table_kappa_cost(args.repeats)
    table_sweep()
    if not args.no_peer:
        table_peer(args.repeats, ours)
    table_breakdown(10 * args.repeats)


if __name__ == "__main__":
    main()
