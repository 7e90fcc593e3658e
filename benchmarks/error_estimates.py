"""Coverage and sharpness of the FE and modal error estimates against the delay reference.

One command::

    python benchmarks/error_estimates.py [--samples 200] [--seed 2026] [--solver fem modal]
        [--max-work 2e10] [--save FILE] [--update-docs]

(``--part K/N --verbose > part_K.txt`` in N processes, then ``--summarize part_*.txt``, gives
the same table.)  ``--save FILE`` also stores every sample (options, the restitutions of the
estimate's runs, the reference and its estimate) as one JSON object a line; ``--offline FILE``
re-applies the library's FE rule (:mod:`wavecontact.fem.error_estimate`, a pure function of
those runs) to a stored sweep in seconds instead of solving.  ``--update-docs`` writes the table
of one solver into docs/error_estimates.md (the block ``sweep:SOLVER:SEED``); the FE tables there
come from ``--solver fem --seed S --offline benchmarks/sweeps/fem_S.jsonl --update-docs`` for
S = 2027 ... 2031, the stored sweeps of ``--solver fem --seed S --max-work 2e10 --save FILE``.
``--add-finer FILE`` adds to a sweep stored before the solver ran the level at twice the elements
(below ``FINER_BELOW`` elements) that level, in seconds, so that ``--offline`` applies the
present rule (seeds 2027 ... 2030).  ``--distribution probe`` draws the FE collisions as issue 23's
probe did (see :func:`draw`; the sweeps ``benchmarks/sweeps/fem_probe_S.jsonl``), and ``--rule-from REV``
re-applies, with ``--offline``, the FE rule of an earlier git revision to the same stored runs.

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
    collisions refused up front (LimitError: over the work limit ``--max-work``
    or the memory limit) or stopped by the solver (SolverFailure); not counted above.

The FE rows are also split by discretization, by regime (``alpha V h / c`` at the
requested mesh, hard contact), by mesh size (under ``FINER_BELOW`` elements the estimate
uses a run at 2N) and by the rough flag, and a last line gives the time of the estimate's
runs relative to the requested run.

Each sample has its own random stream (``SeedSequence(seed).spawn``); the
machine the numbers in docs/error_estimates.md came from was shared.
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import importlib
import json
import math
import os
import time

import numpy as np

from wavecontact import collide, two_rods
from wavecontact.errors import LimitError, SolverFailure
from wavecontact.fem.solver import FINER_BELOW
from wavecontact.fem.solver import SOLVER as FEM
from wavecontact.solvers.base import excess_bound

DISCRETIZATIONS = ((1, "lumped"), (1, "consistent"), (2, "lumped"), (2, "consistent"))
DOCS_PAGE = os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, "docs", "error_estimates.md")
SHARP_ABOVE = 1e-10


def draw(solver: str, index: int, stream: np.random.Generator, distribution: str = "acceptance") -> dict:
    """One random collision: ``gamma``, ``kappa`` and the solver's options.

    ``distribution``: ``"acceptance"`` (the module docstring's) or ``"probe"`` (FE only, the draws of
    issue 23's probe: gamma uniform in (0.05, 1], kappa log-uniform in [1, 1e5], order 1 or 2 and
    lumped or consistent mass at random, elements uniform among the integers 8 ... 400).
    """
    if distribution == "probe":
        gamma = float(1.0 - stream.uniform(0.0, 0.95))
        kappa = float(10.0 ** stream.uniform(0.0, 5.0))
        options = {"elements": int(stream.integers(8, 401)), "order": int(stream.integers(1, 3)),
                   "mass": ("lumped", "consistent")[int(stream.integers(0, 2))]}
        return {"gamma": gamma, "kappa": kappa, "options": options}
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
               levels=[list(level) for level in result.diagnostics.get("error_estimate_levels", [])],
               scheme=result.extra.get("contact_scheme", ""),
               estimate_seconds=result.diagnostics["error_estimate_seconds"], solve_seconds=result.wall_time_s,
               seconds=time.perf_counter() - start)
    return out


def load_rows(name: str) -> list:
    """The samples stored in ``name``: one JSON object a line (``--save``) or the dicts ``--verbose`` prints."""
    rows = []
    with open(name, encoding="utf-8") as handle:
        for line in handle:
            if line.startswith("{"):
                rows.append(json.loads(line) if line.startswith('{"') else
                            ast.literal_eval(line.replace("inf", "1e999")))
    return rows


def reapply(row: dict) -> dict:
    """``row`` with ``estimate`` (and ``rough``) recomputed by the library's FE rule from its stored levels,
    exactly as ``collide`` would from the same runs (the rule is a pure function of them)."""
    if row["status"] != "ok":
        return row
    scene = two_rods(row["gamma"], row["kappa"])
    options = FEM._estimate_options(FEM.options(row["options"]), {"contact_scheme": row.get("scheme")})
    levels = [tuple(level) for level in row["levels"]]
    estimate, rule = FEM.estimate_from_levels(scene, options, levels)
    return {**row, "estimate": excess_bound(estimate, row["restitution"], cold=True), "rule": rule,
            "rough": FEM.rough_estimate(scene, options)}


def use_rule_from(revision: str) -> None:
    """Make :func:`reapply` use the FE rule of git revision ``revision`` (its
    ``wavecontact/fem/error_estimate.py``, run from git's copy) instead of the present one, to compare a
    rule with an earlier one on the same stored runs (``--rule-from``).  Rules older than the
    ``scheme_order`` argument are called without it."""
    import inspect
    import subprocess
    import types

    source = subprocess.run(["git", "show", f"{revision}:wavecontact/fem/error_estimate.py"], check=True,
                            capture_output=True, text=True, cwd=os.path.dirname(os.path.abspath(__file__))).stdout
    module = types.ModuleType(f"error_estimate_{revision}")
    exec(compile(source, module.__name__, "exec"), module.__dict__)  # noqa: S102 - the repository's own file

    def adapted(function, count):
        takes = len(inspect.signature(function).parameters)
        return lambda *args: function(*args[:min(count, takes)])

    fem_solver = importlib.import_module("wavecontact.fem.solver")
    fem_solver._estimate_from_levels = adapted(module.estimate_from_levels, 5)
    fem_solver._estimate_with_finer = adapted(module.estimate_with_finer, 6)


def add_finer(row: dict) -> tuple:
    """``(row, drift)``: ``row`` with the run at twice the elements appended to its levels where the solver
    now runs it (fewer than ``FINER_BELOW`` elements) and the stored sweep lacks it (sweeps saved before the
    solver did), and ``|eps(N)|`` rerun now minus the stored one (NaN where nothing was added): the added
    level is only consistent with the stored ones if the code still gives the stored runs."""
    elements = row["options"]["elements"]
    if row["status"] != "ok" or elements >= FINER_BELOW or any(n > elements for n, _ in row["levels"]):
        return row, math.nan
    scene = two_rods(row["gamma"], row["kappa"])
    options = FEM._estimate_options(FEM.options(row["options"]), {"contact_scheme": row.get("scheme")})
    value = float(FEM._collide(scene, options.replace(elements=2 * elements, record_fields=False)).restitution)
    again = float(FEM._collide(scene, options.replace(record_fields=False)).restitution)
    return ({**row, "levels": [*row["levels"], [2 * elements, value]], "finer_added": True},
            abs(again - row["restitution"]))


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
    parser.add_argument("--distribution", choices=("acceptance", "probe"), default="acceptance",
                        help="how the collisions are drawn (probe: issue 23's FE draws, see draw())")
    parser.add_argument("--solver", nargs="+", choices=("fem", "modal"), default=["fem", "modal"])
    parser.add_argument("--max-work", type=float, default=None,
                        help="work limit of each solve (default: the library's, 2e11 updates); larger ones are refused")
    parser.add_argument("--verbose", action="store_true", help="print every sample (one dict per line)")
    parser.add_argument("--part", default="1/1", metavar="K/N",
                        help="run only the K-th of N slices of the samples (same streams; to use N processes)")
    parser.add_argument("--summarize", nargs="+", metavar="FILE",
                        help="print the table from the --verbose output of earlier runs instead of running")
    parser.add_argument("--save", metavar="FILE",
                        help="also write every sample (levels, reference, estimate) to FILE, one JSON object a line")
    parser.add_argument("--offline", nargs="+", metavar="FILE",
                        help="re-apply the library's FE rule to the levels stored by --save (or --verbose) "
                             "instead of running, and print the table")
    parser.add_argument("--add-finer", metavar="FILE",
                        help="run the level at twice the elements for the stored FE samples under "
                             f"{FINER_BELOW} elements that lack it, and rewrite FILE with it (seconds)")
    parser.add_argument("--rule-from", metavar="REV",
                        help="with --offline: apply the FE rule of git revision REV instead of the present one")
    parser.add_argument("--misses", action="store_true",
                        help="also list the FE collisions the estimate does not bound or is not within 10x of")
    parser.add_argument("--update-docs", action="store_true",
                        help="also write the table into docs/error_estimates.md (block sweep:SOLVER:SEED, one solver)")
    parser.add_argument("--block", metavar="NAME",
                        help="with --update-docs: write block sweep:NAME instead (e.g. fem:2027-2030 for several "
                             "--offline files together)")
    args = parser.parse_args(argv)
    if args.add_finer:
        pairs = [add_finer(row) if row["solver"] == "fem" else (row, math.nan) for row in load_rows(args.add_finer)]
        with open(args.add_finer, "w", encoding="utf-8") as handle:
            handle.writelines(json.dumps(row) + "\n" for row, _ in pairs)
        drifts = [drift for _, drift in pairs if not math.isnan(drift)]
        print(f"added the run at 2N to {len(drifts)} samples; the requested runs rerun now differ from the stored "
              f"ones by at most {max(drifts, default=0.0):.2g}")
        return 0
    if args.summarize or args.offline:
        rows = [row for name in args.summarize or args.offline for row in load_rows(name)]
        if args.offline:
            if args.rule_from:
                use_rule_from(args.rule_from)
            rows = [reapply(row) for row in rows if row["solver"] == "fem"]
        return _report({solver: [r for r in rows if r["solver"] == solver] for solver in args.solver}, args)
    part, parts = (int(x) for x in args.part.split("/"))
    print(f"seed {args.seed}, distribution {args.distribution}, {args.samples} samples, part {args.part}", flush=True)
    tables = {}
    with open(args.save, "w", encoding="utf-8") if args.save else contextlib.nullcontext() as save:
        for solver in args.solver:
            streams = [np.random.default_rng(s) for s in np.random.SeedSequence(args.seed).spawn(args.samples)]
            rows = []
            for index, stream in enumerate(streams):
                if index % parts != part - 1:
                    continue
                row = {"solver": solver, "index": index,
                       **run_sample(solver, draw(solver, index, stream, args.distribution), args.max_work)}
                rows.append(row)
                if args.verbose:
                    print(row, flush=True)
                if save is not None:
                    save.write(json.dumps(row) + "\n")
                    save.flush()
            tables[solver] = rows
    return _report(tables, args)


def _report(tables: dict, args) -> int:
    lines = table_lines(tables)
    print("\n".join(lines), flush=True)
    if getattr(args, "misses", False):
        print("\n".join(miss_lines(tables.get("fem", []))), flush=True)
    if args.update_docs:
        if len(tables) != 1:
            raise SystemExit("--update-docs writes one solver's table: give one --solver")
        update_docs(lines, args.block or f"{next(iter(tables))}:{args.seed}")
    return 0


def regime(row: dict) -> str:
    """The FE regime of a sample: how well the facing elements resolve the contact (``alpha V h / c``)."""
    if math.isinf(row["kappa"]):
        return "hard contact"
    # units of the two-rod builder: c = V = 1, alpha = kappa, shorter rod (1 + gamma) / 2
    resolution = row["kappa"] * (1.0 + row["gamma"]) / (2.0 * row["options"]["elements"])
    if resolution <= 1.0:
        return "alpha V h/c <= 1"
    return "alpha V h/c in (1, 30]" if resolution <= 30.0 else "alpha V h/c > 30"


def rough(row: dict) -> bool:
    """Whether the library flags the sample's estimate as an order of magnitude
    (``diagnostics["error_estimate_rough"]``, which ``tolerance=`` refuses): a function of
    gamma, kappa and the options only."""
    return bool(FEM.rough_estimate(two_rods(row["gamma"], row["kappa"]), FEM.options(row["options"])))


def miss_lines(rows: list) -> list:
    """One line per solved FE sample outside the coverage or the factor 10: its options, the regime
    ``x = alpha V h / c``, error, estimate, their ratio, the errors of the estimate's runs and the rough flag."""
    lines = ["index | discretization | N | x | error | estimate | ratio | errors of the runs N, N/2, ... (then 2N) | flag"]
    for r in rows:
        if r["status"] != "ok":
            continue
        covered = r["error"] <= r["estimate"] + r["reference_estimate"]
        sharp = r["error"] <= SHARP_ABOVE or 0.1 <= r["estimate"] / r["error"] <= 10.0
        if covered and sharp:
            continue
        o = r["options"]
        x = r["kappa"] * (1.0 + r["gamma"]) / (2.0 * o["elements"])
        runs = " ".join(f"{value - r['reference']:+.2e}" for _, value in r["levels"])
        lines.append(f"{r['index']} | P{o['order']} {o['mass']} | {o['elements']} | {x:.3g} | {r['error']:.2e} | "
                     f"{r['estimate']:.2e} | {r['estimate'] / r['error']:.3g} | {runs} | "
                     f"{'rough' if rough(r) else ''}{'' if covered else ' not bounded'}")
    return lines


def estimate_share(rows: list) -> tuple:
    """Time of the estimate's coarser runs over the requested runs' time: summed over the solved
    samples, and the median over the samples whose requested run took at least a second (in
    shorter ones the per-call overhead of each run dominates)."""
    solved = [r for r in rows if r["status"] == "ok" and "estimate_seconds" in r]
    requested = [max(r["solve_seconds"] - r["estimate_seconds"], 1e-12) for r in solved]
    if not solved:
        return math.nan, math.nan, 0
    total = sum(r["estimate_seconds"] for r in solved) / sum(requested)
    long = [r["estimate_seconds"] / t for r, t in zip(solved, requested) if t >= 1.0]
    return total, float(np.median(long)) if long else math.nan, len(long)


def finer_share(rows: list) -> tuple:
    """Time of the estimate's runs (2N included) over the requested run's, for the FE samples under
    ``FINER_BELOW`` elements whose run at 2N was timed with the solve (not added by ``--add-finer``):
    the median ratio, the largest estimate time in seconds and the count."""
    small = [r for r in rows if r["status"] == "ok" and "estimate_seconds" in r and not r.get("finer_added")
             and r["options"].get("elements", math.inf) < FINER_BELOW]
    if not small:
        return math.nan, math.nan, 0
    ratios = [r["estimate_seconds"] / max(r["solve_seconds"] - r["estimate_seconds"], 1e-12) for r in small]
    return float(np.median(ratios)), max(r["estimate_seconds"] for r in small), len(small)


def table_lines(tables: dict) -> list:
    """The table (markdown) of every solver's rows; FE also per discretization and per regime."""
    lines = ["| sample | solved | coverage | within 10x | (n) | median | p95 | refused | failed |",
             "|---|---|---|---|---|---|---|---|---|"]
    for solver, rows in tables.items():
        groups = {solver: rows}
        if solver == "fem":
            for order, mass in DISCRETIZATIONS:
                groups[f"P{order} {mass}"] = [r for r in rows if (r["options"]["order"], r["options"]["mass"])
                                              == (order, mass)]
            for name in ("alpha V h/c <= 1", "alpha V h/c in (1, 30]", "alpha V h/c > 30", "hard contact"):
                groups[name] = [r for r in rows if regime(r) == name]
            groups[f"under {FINER_BELOW} elements"] = [r for r in rows if r["options"]["elements"] < FINER_BELOW]
            groups[f"{FINER_BELOW} elements or more"] = [r for r in rows if r["options"]["elements"] >= FINER_BELOW]
            flagged = [r for r in rows if r["status"] == "ok" and rough(r)]
            groups["flagged rough"] = flagged
            groups["not flagged"] = [r for r in rows if r not in flagged]
        for name, group in groups.items():
            s = summarize(group)
            lines.append(f"| {name} | {s['solved']} | {s['coverage']:.3f} | {s['within10']:.3f} | {s['sharp_count']} "
                         f"| {s['median_ratio']:.3g} | {s['p95_ratio']:.3g} | {s['refused']} | {s['failed']} |")
        total, median, count = estimate_share(rows)
        long_runs = (f"{median:.2f} (median) for the {count} requested runs of a second or more" if count
                     else "no requested run took a second or more")
        lines.append(f"\n{solver}: the coarser runs of the estimate took {total:.2f} of the requested runs' time in "
                     f"all, {long_runs}.")
        if solver == "fem":
            solved = [r for r in rows if r["status"] == "ok"]
            bound = [r["estimate"] + r["reference_estimate"] for r in solved]
            under = sum(r["error"] > b for r, b in zip(solved, bound))
            far = sum(r["error"] > 10.0 * b for r, b in zip(solved, bound))
            lines.append(f"Not bounded: {under} of {len(solved)}, {far} of them by more than 10x.")
        ratio, longest, small = finer_share(rows) if solver == "fem" else (math.nan, math.nan, 0)
        if small:
            lines.append(f"Under {FINER_BELOW} elements (with the run at 2N): {ratio:.2f} of the requested run's time "
                         f"(median of {small}), at most {longest:.2g} s.")
        lines.append("")
    return lines


def update_docs(lines: list, block: str, page: str = DOCS_PAGE) -> None:
    """Replace the block ``<!-- sweep:BLOCK:start/end -->`` of ``page`` (BLOCK: ``SOLVER:SEED``) with ``lines``."""
    start, end = f"<!-- sweep:{block}:start -->\n", f"<!-- sweep:{block}:end -->"
    with open(page, encoding="utf-8") as handle:
        text = handle.read()
    if start not in text or end not in text:
        raise SystemExit(f"{page} has no block {start.strip()} ... {end}")
    head, rest = text.split(start, 1)
    tail = rest.split(end, 1)[1]
    with open(page, "w", encoding="utf-8") as handle:
        handle.write(head + start + "\n".join(lines).strip("\n") + "\n" + end + tail)


if __name__ == "__main__":
    raise SystemExit(main())
