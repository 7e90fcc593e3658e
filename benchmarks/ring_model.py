"""Calibrate the ring's mode model (``wavecontact ring`` without ``--modes``): ``python benchmarks/ring_model.py``.

For every ``(gamma, kappa, N)`` of the grid and :data:`REALISATIONS` ring circumferences, runs the ring
(:func:`wavecontact.studies.ring.run_ring`'s simulation) for :data:`COLLISIONS` collisions and measures the
per-collision restitution error of the first three collisions and of every :data:`STRIDE`-th collision
from :data:`FIRST_SAMPLED` on: the collision is run again from the state before it with ``REFERENCE N``
modes (the added ones at rest) and the error is ``|eps_N - eps_ref| / (1 - 1/REFERENCE)`` (exact where the
error falls like ``1/N``, an overestimate where it falls faster).  Records the
:data:`~wavecontact.solvers.auto_ring.ERROR_QUANTILE` quantile of these errors per point and the CPU time
per collision of the run itself (``time.process_time``), and writes ``wavecontact/data/ring_model.json``:
the grid, the points and the fits (:func:`wavecontact.solvers.auto_ring.fit_points`).

``--refit`` recomputes the fits from the stored points; ``--check`` verifies the stored fits are what its
points give (exit 1 otherwise); ``--table`` prints the docs' table (docs/ring.md) from the stored file.
Bounded: about 5 min on a quiet core.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the checkout this script lives in

import numpy as np

from wavecontact.scene import two_rods_on_a_ring
from wavecontact.solvers import get_solver
from wavecontact.solvers.auto_ring import DATA_PATH, ERROR_QUANTILE, FORMAT, fit_points, padded_state

GAMMAS = (0.6173, 0.3)
KAPPAS = (10.0, 40.0, 400.0, 4000.0, math.inf)
#: The soft error fit takes the points with N / kappa at least this (where the error falls with N; docs/ring.md).
SOFT_FROM = 0.2
MODES = (10, 20, 40, 80)
#: Ring circumferences: the default one, then this many more, 1.5 % longer each.
REALISATIONS = 2
COLLISIONS = 200
FIRST_SAMPLED = 80
STRIDE = 8
#: The reference has this many times the run's modes.
REFERENCE = 4


def default_circumference(gamma: float, kappa: float) -> float:
    return float(two_rods_on_a_ring(gamma, kappa).ring_circumference)


def sampled(collisions: int) -> list:
    """Indices (0-based) of the collisions whose error is measured."""
    return sorted({0, 1, 2, *range(FIRST_SAMPLED, collisions, STRIDE)})


def collision_errors(gamma: float, kappa: float, modes: int, circumference: float, collisions: int,
                     reference: int = REFERENCE) -> tuple:
    """``(errors of the sampled collisions, CPU seconds per collision of the run)``."""
    scene = two_rods_on_a_ring(gamma, kappa, circumference)
    engine = get_solver("modal")
    simulation = engine.simulate(scene, {"modes": modes})
    finer = engine.simulate(scene, {"modes": reference * modes})
    wanted = set(sampled(collisions))
    errors, cpu = [], 0.0
    for j in range(collisions):
        state = simulation.get_state() if j in wanted else None
        start = time.process_time()
        record = simulation.next_collision()
        cpu += time.process_time() - start
        if state is not None:
            finer.set_state(padded_state(state, modes, finer))
            errors.append(abs(record.restitution - finer.next_collision().restitution) / (1.0 - 1.0 / reference))
    return errors, cpu / collisions


def calibrate() -> dict:
    collision_errors(GAMMAS[0], KAPPAS[0], MODES[0], default_circumference(GAMMAS[0], KAPPAS[0]), 3)  # compile
    points = []
    for gamma in GAMMAS:
        for kappa in KAPPAS:
            base = default_circumference(gamma, kappa)
            for modes in MODES:
                began = time.monotonic()
                errors, cpus = [], []
                for r in range(REALISATIONS):
                    e, c = collision_errors(gamma, kappa, modes, base * (1.0 + 0.015 * r), COLLISIONS)
                    errors += e
                    cpus.append(c)
                points.append({"gamma": gamma, "kappa": "inf" if math.isinf(kappa) else kappa, "modes": modes,
                               "samples": len(errors),
                               "error_quantile": float(np.quantile(errors, ERROR_QUANTILE)),
                               "error_median": float(np.median(errors)), "error_max": float(np.max(errors)),
                               "first_collision_error": float(errors[0]),
                               "cpu_s_per_collision": float(np.median(cpus))})
                print(f"gamma={gamma:g} kappa={kappa:g} N={modes}: q{ERROR_QUANTILE:g} {points[-1]['error_quantile']:.2g}"
                      f" max {points[-1]['error_max']:.2g}, {time.monotonic() - began:.1f} s", file=sys.stderr,
                      flush=True)
    return document(points)


def document(points: list) -> dict:
    return {
        "format": FORMAT,
        "generated_by": "python benchmarks/ring_model.py",
        "error_unit": (f"the {ERROR_QUANTILE:g} quantile of |eps_N - eps_ref| / (1 - 1/{REFERENCE}) over the sampled "
                       f"collisions (the first three, then every {STRIDE}th from collision {FIRST_SAMPLED + 1} to "
                       f"{COLLISIONS}), eps_ref from the same state with {REFERENCE} N modes"),
        "cost_unit": "CPU seconds (time.process_time) per ring collision, checks not included",
        "grid": {"gamma": list(GAMMAS), "kappa": ["inf" if math.isinf(k) else k for k in KAPPAS],
                 "modes": list(MODES), "realisations": REALISATIONS, "collisions": COLLISIONS},
        "points": points,
        "soft_from": SOFT_FROM,
        "fits": fit_points(points, SOFT_FROM),
    }


def table(data: dict) -> str:
    """The docs' table: per point, the measured quantile and maximum and the model's prediction."""
    from wavecontact.solvers.auto_ring import RingModel

    model = RingModel(data)
    lines = [(f"| gamma | kappa | N | collisions measured | median error | {ERROR_QUANTILE:.0%} quantile | largest | "
             "predicted (model) | first collision | ms per collision |"),
             "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for p in data["points"]:
        kappa = math.inf if p["kappa"] == "inf" else float(p["kappa"])
        predicted = model.predict(p["gamma"], kappa, p["modes"])[0]
        lines.append(f"| {p['gamma']:g} | {p['kappa']} | {p['modes']} | {p['samples']} | {p['error_median']:.2g} | "
                     f"{p['error_quantile']:.2g} | {p['error_max']:.2g} | {predicted:.2g} | "
                     f"{p['first_collision_error']:.2g} | {p['cpu_s_per_collision'] * 1e3:.2g} |")
    lines.append("")
    for kind, fit in data["fits"].items():
        names = ["1", "log10 (1/gamma)", "log10 N" if kind == "hard" else "log10 (N/kappa)"]
        terms = " + ".join(f"{c:.3g} {n}" if n != "1" else f"{c:.3g}" for c, n in zip(fit["error"]["coef"], names))
        lines.append(f"- {kind} contact: log10 error = {terms}, + margin {fit['error']['margin']:.2g} "
                     f"(largest residual; rms {fit['error']['rms_residual']:.2g}), {fit['runs']} points"
                     + (f" with N/kappa >= {data['soft_from']:g}" if kind == "soft" else ""))
    lines += ["", choices_table(model)]
    return "\n".join(lines)


def choices_table(model, gamma: float = 0.6173, collisions: int = 4500) -> str:
    """What ``wavecontact ring`` without ``--modes`` chooses for the paper's gamma and run length."""
    from wavecontact.errors import WavecontactError
    from wavecontact.solvers.auto_ring import choose_modes

    lines = [f"Choices for gamma = {gamma:g}, {collisions} collisions, default limits:", "",
             "| kappa | tolerance | N | predicted error | predicted CPU s | or refused |", "|---:|---:|---:|---:|---:|---|"]
    for kappa in KAPPAS:
        for tolerance in (3e-2, 1e-2, 1e-3, 1e-6):
            try:
                c = choose_modes(gamma, kappa, collisions, tolerance=tolerance, model=model)
            except WavecontactError as error:
                lines.append(f"| {kappa:g} | {tolerance:g} | | | | {error} |")
                continue
            cpu = "n/a" if c.predicted_cpu_s is None else f"{c.predicted_cpu_s:.3g}"
            lines.append(f"| {kappa:g} | {tolerance:g} | {c.modes} | {c.predicted_error:.2g} | {cpu} | |")
    return "\n".join(lines)


def check_cost(repeats: int = 3, collisions: int = 300) -> str:
    """CPU seconds of the paper's ring (N = 75, kappa 4000) for ``collisions`` collisions with and without the
    checks (``tolerance=`` given or not), alternating, medians."""
    from wavecontact.solvers import auto_ring
    from wavecontact.studies.ring import run_ring

    run_ring(0.6173, 4000.0, 75, 3, progress=False, tolerance=auto_ring.DEFAULT_TOLERANCE)  # compile or load
    times: dict = {"without": [], "with": []}
    for _ in range(repeats):
        for label, tolerance in (("without", None), ("with", auto_ring.DEFAULT_TOLERANCE)):
            start = time.process_time()
            run_ring(0.6173, 4000.0, 75, collisions, progress=False, tolerance=tolerance)
            times[label].append(time.process_time() - start)
    plain, checked = (float(np.median(times[k])) for k in ("without", "with"))
    checks = len(range(0, collisions, auto_ring.CHECK_EVERY))
    return (f"gamma 0.6173, kappa 4000, N = 75, {collisions} collisions ({checks} checked), median of {repeats} CPU "
            f"times: {plain:.2f} s without the checks, {checked:.2f} s with them (+{checked / plain - 1:.0%}; load "
            f"{os.getloadavg()[0]:.1f})")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--refit", action="store_true", help="recompute the fits from the stored points")
    parser.add_argument("--check", action="store_true", help="verify the stored fits (writes nothing)")
    parser.add_argument("--table", action="store_true", help="print the docs' table from the stored file")
    parser.add_argument("--check-cost", action="store_true", help="time a ring run with and without the checks")
    parser.add_argument("--out", default=str(DATA_PATH))
    args = parser.parse_args(argv)
    if args.check_cost:
        print(check_cost())
        return 0
    if args.check or args.refit or args.table:
        stored = json.loads(Path(args.out).read_text(encoding="utf-8"))
        if args.table:
            print(table(stored))
            return 0
        fresh = document(stored["points"])
        if args.check:
            ok = fresh == {k: v for k, v in stored.items() if k != "load_average_at_start"}
            print("ring model: stored fits match the points" if ok else "ring model: stale; run --refit")
            return 0 if ok else 1
        data = {**fresh, "load_average_at_start": stored.get("load_average_at_start")}
    else:
        load = os.getloadavg()[0]
        data = calibrate()
        data["load_average_at_start"] = load
    Path(args.out).write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
