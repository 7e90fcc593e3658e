"""Benchmark of the modal solver: the paper's Fig. 1 ring run and one collision vs scipy's solve_ivp.

Run: ``python benchmarks/bench_modal.py [--collisions 4500] [--repeats 5] [--skip-ring] [--accuracy-only] [--update-docs]``

Prints three tables (``--accuracy-only``: the first alone):

0. accuracy against the delay solver over gamma in [0.1, 1] and kappa in [1, 1e4] and inf, per
   correction of the omitted modes (none, static, end-response) and number of modes, plus a random
   sample of 200 collisions with the end-response correction at 10 modes (docs/modal.md);

1. the full ring run of Fig. 1 (gamma = 0.6173, kappa = 4000, N_mod = 75,
   4500 collisions): wall time, cost per collision, energy drift;
2. one collision (same gamma, N = 75, kappa = 100 and 4000) of the modal
   integrators (collocation, the default, and the splitting) against
   ``solve_ivp`` (DOP853, Radau) on the same modal equations (static correction)
   (``benchmarks/peers/modal_solve_ivp.py``): error against a DOP853
   reference at rtol 1e-12, median wall time of the whole ``collide`` call
   (set-up included; "cold" rows refill the collocation tables, as a first
   call does), and the speed-up at matched accuracy (the cheapest DOP853
   run at least as accurate as ours; "none" when no DOP853 run was).
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import modal_solve_ivp
import numpy as np
from docs_block import captured_stdout, run_header, write_block

import wavecontact
from wavecontact.modal import RingSimulation
from wavecontact.modal import solver as modal_solver
from wavecontact.scene import two_rods, two_rods_on_a_ring

GAMMA = 0.6173
MODES = 75


def ring_run(collisions: int) -> dict:
    start = time.perf_counter()
    ring = RingSimulation(two_rods_on_a_ring(GAMMA, 4000), MODES)
    steps = 0
    worst = 0.0
    for _ in range(collisions):
        record = ring.next_collision()
        steps += record.steps
        worst = max(worst, abs(record.total_energy - ring.total_energy) / ring.total_energy)
    wall = time.perf_counter() - start
    return {"wall": wall, "per_collision_ms": 1e3 * wall / collisions, "steps": steps / collisions,
            "final_drift": (record.total_energy - ring.total_energy) / ring.total_energy, "worst_drift": worst}


def median_time(function, repeats):
    times = []
    value = None
    for _ in range(repeats):
        start = time.perf_counter()
        value = function()
        times.append(time.perf_counter() - start)
    return value, statistics.median(times)


GAMMAS = (0.1, 0.2173, 0.45, 0.6, 0.8, 0.95, 1.0)
KAPPAS = (1.0, 10.0, 100.0, 500.0, 1e4, math.inf)
CORRECTIONS = ("none", "static", "end-response")


def _error(gamma, kappa, reference, **options):
    result = wavecontact.collide(gamma, kappa, solver="modal", history=False, **options)
    return abs(result.restitution - reference), result


def accuracy_table(modes=(10, 25, 100)) -> None:
    """Largest error against the delay solver over the (gamma, kappa) grid, per correction and N."""
    references = {(g, k): g if k == math.inf else wavecontact.collide(g, k, solver="delay").restitution
                  for g in GAMMAS for k in KAPPAS}
    print(f"\nAccuracy against the delay solver: gamma in {GAMMAS}, kappa in {KAPPAS}")
    print(f"{'correction':>13} {'modes':>6} {'max |error|':>12} {'at (gamma, kappa)':>20} {'median ms':>10}")
    for correction in CORRECTIONS:
        for n in modes:
            worst, where, times = 0.0, None, []
            for (g, k), reference in references.items():
                if correction == "none" and k == math.inf:
                    continue  # refused: a hard impact on a truncated end is undefined
                start = time.perf_counter()
                error, _ = _error(g, k, reference, modes=n, correction=correction,
                                  static_correction=correction != "none")
                times.append(time.perf_counter() - start)
                if error >= worst:
                    worst, where = error, (g, k)
            print(f"{correction:>13} {n:6d} {worst:12.2e} {where!s:>20} {1e3 * statistics.median(times):10.2f}")
    rng = np.random.default_rng(np.random.SeedSequence(2026))
    gammas = rng.uniform(0.1, 1.0, 200)
    kappas = np.where(rng.uniform(size=200) < 0.1, math.inf, 10.0 ** rng.uniform(0.0, 4.0, 200))
    errors, drifts = [], []
    for g, k in zip(gammas, kappas):
        reference = g if k == math.inf else wavecontact.collide(float(g), float(k), solver="delay").restitution
        error, result = _error(float(g), float(k), reference, modes=10)
        errors.append(error)
        drifts.append(result.diagnostics["energy_drift"])
    print(f"random sample (200 collisions, gamma in [0.1, 1], log10 kappa in [0, 4] or inf with 10 %), "
          f"end-response, 10 modes: max |error| {max(errors):.2e}, median {statistics.median(errors):.2e}, "
          f"max energy check {max(drifts):.2e}")


def _collide(kappa, **options):
    options.setdefault("correction", "static")  # the peer integrates the statically corrected equations
    return wavecontact.collide(GAMMA, kappa, solver="modal", modes=MODES, history=False, **options)


def _cold(kappa, **options):
    """One collision with the collocation tables of every step size recomputed (a first call)."""
    modal_solver._TABLE_CACHE.clear()
    return _collide(kappa, **options)


def single_collision(kappa: float, repeats: int) -> list:
    reference, _ = modal_solve_ivp.restitution(GAMMA, kappa, MODES, 1e-12)
    rows = []
    for stages, tolerance in ((6, 1e-1), (6, 1e-2), (6, 1e-3), (4, 1e-1)):
        options = {"collocation_tolerance": tolerance, "collocation_stages": stages}
        for label, function in (("", _collide), (" cold", _cold)):
            result, wall = median_time(lambda f=function, o=options: f(kappa, **o), repeats)
            rows.append(("modal", f"coll s={stages} tol={tolerance:g}{label}", abs(result.restitution - reference),
                         wall, result.work["steps"] + result.work["rejected_steps"]))
    for order, eta in ((2, 0.05), (2, 0.0125), (4, 0.2), (4, 0.1)):
        result, wall = median_time(
            lambda order=order, eta=eta: _collide(kappa, step_method="splitting", step_accuracy=eta,
                                                  step_order=order),
            repeats,
        )
        rows.append(("modal", f"split o{order} eta={eta}", abs(result.restitution - reference), wall,
                     result.work["steps"]))
    for rtol in (1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10):
        (value, _), wall = median_time(lambda rtol=rtol: modal_solve_ivp.restitution(GAMMA, kappa, MODES, rtol),
                                       max(3, repeats // 2))
        rows.append(("DOP853", f"rtol={rtol:g}", abs(value - reference), wall, None))
    (value, _), wall = median_time(lambda: modal_solve_ivp.restitution(GAMMA, kappa, MODES, 1e-6, "Radau"), 1)
    rows.append(("Radau", "rtol=1e-06", abs(value - reference), wall, None))
    return rows


def setup_cost(kappa: float, repeats: int) -> float:
    """Median time of the solver's Python set-up alone (modes, system, start), seconds."""
    scene = two_rods(GAMMA, kappa)
    _, wall = median_time(lambda: modal_solver._build(scene, MODES, "static", "analytic", None, 1, 0.0125), repeats)
    return wall


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--collisions", type=int, default=4500)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--skip-ring", action="store_true")
    parser.add_argument("--accuracy-only", action="store_true")
    parser.add_argument("--update-docs", action="store_true",
                        help="also write tables 1 and 2 into docs/modal.md (between its bench-modal markers)")
    args = parser.parse_args(argv)
    header = run_header(None if argv is None else ["benchmarks/bench_modal.py", *argv])

    # compile (numba caches on disk) before any timing
    wavecontact.collide(GAMMA, 100, solver="modal", modes=10)
    RingSimulation(two_rods_on_a_ring(GAMMA, 4000), 5).next_collision()
    print(f"machine load average (1, 5, 15 min): {os.getloadavg()}")
    accuracy_table()
    if args.accuracy_only:
        return
    with captured_stdout() as tee:
        performance_tables(args)
    if args.update_docs:
        write_block("modal.md", "bench-modal", f"{header}\n\n```text\n{tee.copy.getvalue().strip()}\n```")


def performance_tables(args):
    """Print table 1 (the ring run, unless skipped) and table 2 (one collision against solve_ivp)."""
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
        print(f"(set-up alone, included below: {1e3 * setup_cost(kappa, args.repeats):.2f} ms; 'cold' = "
              "collocation tables filled anew, as on a first call)")
        print(f"{'integrator':>10} {'setting':>26} {'|error|':>10} {'wall [ms]':>10} {'steps':>8} "
              f"{'matched DOP853':>16} {'speed-up':>9}")
        for name, setting, error, wall, steps in rows:
            matched = ""
            ratio = ""
            if name == "modal":
                # the cheapest DOP853 run at least as accurate; if none is, the most accurate one
                candidates = [r for r in rows if r[0] == "DOP853" and r[2] <= error]
                if candidates:
                    best = min(candidates, key=lambda r: r[3])
                    matched = best[1]
                    ratio = f"{best[3] / wall:.0f}x"
                else:
                    best = min((r for r in rows if r[0] == "DOP853"), key=lambda r: r[2])
                    # DOP853 would need a tighter rtol than its most accurate run, hence more time
                    matched = f"none ({best[2]:.0e})"
                    ratio = f">{best[3] / wall:.0f}x"
            print(f"{name:>10} {setting:>26} {error:10.2e} {1e3 * wall:10.2f} {steps if steps else '':>8} "
                  f"{matched:>16} {ratio:>9}")


if __name__ == "__main__":
    main()
