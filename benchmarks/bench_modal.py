"""Benchmark of the modal solver: the paper's Fig. 1 ring run and one collision vs scipy's solve_ivp.

Run: ``python benchmarks/bench_modal.py [--collisions 4500] [--repeats 5] [--skip-ring]``

Prints two tables:

1. the full ring run of Fig. 1 (gamma = 0.6173, kappa = 4000, N_mod = 75,
   4500 collisions): wall time, cost per collision, energy drift;
2. one collision (same gamma, N = 75) of the modal integrator against
   ``solve_ivp`` (DOP853, Radau) on the same modal equations
   (``benchmarks/peers/modal_solve_ivp.py``): error against a DOP853
   reference at rtol 1e-12, median wall time, and the speed-up at matched
   accuracy (the cheapest DOP853 run at least as accurate as ours).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers"))

import modal_solve_ivp

import wavecontact
from wavecontact.modal import RingSimulation

GAMMA = 0.6173
MODES = 75


def ring_run(collisions: int) -> dict:
    start = time.perf_counter()
    ring = RingSimulation(GAMMA, 4000, MODES)
    steps = 0
    worst = 0.0
    for _ in range(collisions):
        record = ring.next_collision()
        steps += record["steps"]
        worst = max(worst, abs(record["E_total"] - ring.total_energy) / ring.total_energy)
    wall = time.perf_counter() - start
    return {"wall": wall, "per_collision_ms": 1e3 * wall / collisions, "steps": steps / collisions,
            "final_drift": (record["E_total"] - ring.total_energy) / ring.total_energy, "worst_drift": worst}


def median_time(function, repeats):
    times = []
    value = None
    for _ in range(repeats):
        start = time.perf_counter()
        value = function()
        times.append(time.perf_counter() - start)
    return value, statistics.median(times)


def single_collision(kappa: float, repeats: int) -> list:
    reference, _ = modal_solve_ivp.restitution(GAMMA, kappa, MODES, 1e-12)
    rows = []
    for eta in (0.05, 0.025, 0.0125):
        result, wall = median_time(
            lambda eta=eta: wavecontact.collide(GAMMA, kappa, solver="modal", modes=MODES, step_accuracy=eta,
                                                history=False),
            repeats,
        )
        rows.append(("modal", f"eta={eta}", abs(result.restitution - reference), wall, result.work["steps"]))
    for eta in (0.2, 0.1, 0.05):
        result, wall = median_time(
            lambda eta=eta: wavecontact.collide(GAMMA, kappa, solver="modal", modes=MODES, step_accuracy=eta,
                                                step_order=4, history=False),
            repeats,
        )
        rows.append(("modal", f"o4 eta={eta}", abs(result.restitution - reference), wall, result.work["steps"]))
    for rtol in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8):
        (value, _), wall = median_time(lambda rtol=rtol: modal_solve_ivp.restitution(GAMMA, kappa, MODES, rtol),
                                       max(1, repeats // 2))
        rows.append(("DOP853", f"rtol={rtol:g}", abs(value - reference), wall, None))
    (value, _), wall = median_time(lambda: modal_solve_ivp.restitution(GAMMA, kappa, MODES, 1e-6, "Radau"), 1)
    rows.append(("Radau", "rtol=1e-06", abs(value - reference), wall, None))
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--collisions", type=int, default=4500)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--skip-ring", action="store_true")
    args = parser.parse_args(argv)

    # compile (numba caches on disk) before any timing
    wavecontact.collide(GAMMA, 100, solver="modal", modes=10)
    RingSimulation(GAMMA, 4000, 5).next_collision()
    print(f"machine load average (1, 5, 15 min): {os.getloadavg()}")

    if not args.skip_ring:
        ring = ring_run(args.collisions)
        print(f"\nRing run of Fig. 1: gamma={GAMMA}, kappa=4000, N_mod={MODES}, {args.collisions} collisions")
        print(f"{'wall time [s]':>14} {'ms/collision':>13} {'steps/collision':>16} {'final drift':>12} "
              f"{'worst drift':>12}")
        print(f"{ring['wall']:14.1f} {ring['per_collision_ms']:13.2f} {ring['steps']:16.0f} "
              f"{ring['final_drift']:12.2e} {ring['worst_drift']:12.2e}   (target: < 120 s)")

    for kappa in (100.0, 4000.0):
        rows = single_collision(kappa, args.repeats)
        print(f"\nOne collision, gamma={GAMMA}, kappa={kappa:g}, N={MODES} per rod "
              f"(error against DOP853 at rtol 1e-12; median of repeats)")
        print(f"{'integrator':>10} {'setting':>12} {'|error|':>10} {'wall [ms]':>10} {'steps':>8}")
        for name, setting, error, wall, steps in rows:
            print(f"{name:>10} {setting:>12} {error:10.2e} {1e3 * wall:10.2f} {steps if steps else '':>8}")
        for name, setting, error, wall, _ in rows:
            if name != "modal":
                continue
            matched = [r for r in rows if r[0] == "DOP853" and r[2] <= error]
            if matched:
                best = min(matched, key=lambda r: r[3])
                print(f"  modal {setting}: DOP853 at matched accuracy ({best[1]}, {best[2]:.1e}) takes "
                      f"{best[3] / wall:.0f}x longer")
            else:
                print(f"  modal {setting}: no DOP853 run was as accurate")


if __name__ == "__main__":
    main()
