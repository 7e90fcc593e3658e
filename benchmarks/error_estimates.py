"""Coverage and sharpness of the FE and modal error estimates against the delay reference.

One command::

    python benchmarks/error_estimates.py [--samples 200] [--seed 2026] [--solver fem modal]

(``--part K/N --verbose > part_K.txt`` in N processes, then ``--summarize part_*.txt``, gives
the same table.)

draws ``--samples`` random collisions per solver (gamma uniform in [0.05, 1];
kappa log-uniform in [0.1, 1e6], or inf with probability 0.15; FE: elements
log-uniform in [10, 2000], the four discretizations in turn; modal: modes
log-uniform in [10, 300]), solves each with the solver (its ``error_estimate``
included) and with the delay reference, and prints one table:

coverage
    share of the solved collisions whose true error ``|eps - eps_delay|`` is at
    most the estimate plus the reference's own estimate (the reference is only
    known to that accuracy);
within 10x
    share, among errors above 1e-10, with ``estimate / error`` in [0.1, 10];
median, p95 ratio
    of ``estimate / error`` over errors above 1e-10;
refused, failed
    collisions refused up front (LimitError: over the default work or memory
    limit) or stopped by the solver (SolverFailure); not counted above.

Each sample has its own random stream (``SeedSequence(seed).spawn``); the
machine the numbers in docs/error_estimates.md came from was shared.
"""

from __future__ import annotations

import argparse
import ast
import math
import time

import numpy as np

from wavecontact import collide
from wavecontact.errors import LimitError, SolverFailure

DISCRETIZATIONS = ((1, "lumped"), (1, "consistent"), (2, "lumped"), (2, "consistent"))
SHARP_ABOVE = 1e-10


def draw(solver: str, index: int, stream: np.random.Generator) -> dict:
    """One random collision: ``gamma``, ``kappa`` and the solver's options."""
    gamma = float(stream.uniform(0.05, 1.0))
    kappa = math.inf if stream.random() < 0.15 else float(10.0 ** stream.uniform(-1.0, 6.0))
    if solver == "fem":
        order, mass = DISCRETIZATIONS[index % 4]
        options = {"elements": round(10.0 ** stream.uniform(1.0, math.log10(2000.0))), "order": order,
                   "mass": mass}
    else:
        options = {"modes": round(10.0 ** stream.uniform(1.0, math.log10(300.0))), "history": False}
    return {"gamma": gamma, "kappa": kappa, "options": options}


def run_sample(solver: str, sample: dict, max_work: float | None = None) -> dict:
    """Solve one sample with ``solver`` and the delay reference (``max_work``: the solve's work limit)."""
    out = dict(sample)
    start = time.perf_counter()
    try:
        result = collide(sample["gamma"], sample["kappa"], solver=solver, max_work=max_work, **sample["options"])
    except LimitError:
        out["status"] = "refused"
        return out
    except SolverFailure:
        out["status"] = "failed"
        return out
    reference = collide(sample["gamma"], sample["kappa"])
    out.update(status="ok", error=abs(result.restitution - reference.restitution),
               estimate=result.error_estimate, reference_estimate=reference.error_estimate,
               restitution=result.restitution, reference=reference.restitution,
               levels=result.diagnostics.get("error_estimate_levels", []),
               estimate_seconds=result.diagnostics["error_estimate_seconds"], solve_seconds=result.wall_time_s,
               seconds=time.perf_counter() - start)
    return out


def summarize(rows: list) -> dict:
    """Coverage, sharpness and counts of a list of :func:`run_sample` rows."""
    solved = [r for r in rows if r["status"] == "ok"]
    covered = [r["error"] <= r["estimate"] + r["reference_estimate"] for r in solved]
    ratios = np.array([r["estimate"] / r["error"] for r in solved if r["error"] > SHARP_ABOVE])
    return {
        "solved": len(solved),
        "coverage": float(np.mean(covered)) if covered else math.nan,
        "within10": float(np.mean((ratios >= 0.1) & (ratios <= 10.0))) if ratios.size else math.nan,
        "sharp_count": int(ratios.size),
        "median_ratio": float(np.median(ratios)) if ratios.size else math.nan,
        "p95_ratio": float(np.quantile(ratios, 0.95)) if ratios.size else math.nan,
        "refused": sum(r["status"] == "refused" for r in rows),
        "failed": sum(r["status"] == "failed" for r in rows),
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=200, help="collisions per solver (default 200)")
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--solver", nargs="+", choices=("fem", "modal"), default=["fem", "modal"])
    parser.add_argument("--max-work", type=float, default=None,
                        help="work limit of each solve (default: the library's, 2e11 updates); larger ones are refused")
    parser.add_argument("--verbose", action="store_true", help="print every sample (one dict per line)")
    parser.add_argument("--part", default="1/1", metavar="K/N",
                        help="run only the K-th of N slices of the samples (same streams; to use N processes)")
    parser.add_argument("--summarize", nargs="+", metavar="FILE",
                        help="print the table from the --verbose output of earlier runs instead of running")
    args = parser.parse_args(argv)
    if args.summarize:
        rows = []
        for name in args.summarize:
            with open(name, encoding="utf-8") as handle:
                rows += [ast.literal_eval(line.replace("inf", "1e999")) for line in handle if line.startswith("{")]
        _table({solver: [r for r in rows if r["solver"] == solver] for solver in args.solver})
        return 0
    part, parts = (int(x) for x in args.part.split("/"))
    tables = {}
    for solver in args.solver:
        streams = [np.random.default_rng(s) for s in np.random.SeedSequence(args.seed).spawn(args.samples)]
        rows = []
        for index, stream in enumerate(streams):
            if index % parts != part - 1:
                continue
            row = {"solver": solver, "index": index, **run_sample(solver, draw(solver, index, stream), args.max_work)}
            rows.append(row)
            if args.verbose:
                print(row, flush=True)
        tables[solver] = rows
    _table(tables)
    return 0


def _table(tables: dict) -> None:
    print(f"{'solver':<22}{'solved':>7}{'coverage':>10}{'within 10x':>12}{'(n)':>6}{'median':>9}{'p95':>9}"
          f"{'refused':>9}{'failed':>8}")
    for solver, rows in tables.items():
        groups = {solver: rows}
        if solver == "fem":
            for order, mass in DISCRETIZATIONS:
                groups[f"  P{order} {mass}"] = [r for r in rows if (r["options"]["order"], r["options"]["mass"])
                                                == (order, mass)]
        for name, group in groups.items():
            s = summarize(group)
            print(f"{name:<22}{s['solved']:>7}{s['coverage']:>10.3f}{s['within10']:>12.3f}{s['sharp_count']:>6}"
                  f"{s['median_ratio']:>9.3g}{s['p95_ratio']:>9.3g}{s['refused']:>9}{s['failed']:>8}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
