"""Cross-solver random audit: every pair of solvers that takes a scene agrees within their stated estimates.

One command::

    python benchmarks/cross_solver_audit.py [--scenes 300] [--seed 2323] [--families cold hard materials bath]
        [--elements 400] [--modes 60] [--max-work 2e9] [--verbose]

draws ``--scenes`` random scenes, one random stream each (``SeedSequence(seed).spawn``), the
families in turn:

cold
    the paper's two rods, gamma uniform in (0.05, 1], kappa log-uniform in [1, 1e5];
hard
    the same rods with hard contact (kappa = inf);
materials
    two rods of different materials and sections (rod 1: l = rho = E = A = 1; rod 2: impedance ratio
    and ratio of the wave's transit times log-uniform in [1/4, 4], wave speed and section in [1/2, 2]),
    rod 1 moving at 1 towards rod 2 at rest, hard contact or the exponential law with
    ``kappa = alpha V l / c`` log-uniform in [1, 1e4] (in the delay solver's units), all in a random
    unit system (length unit 10^[-1, 1], mass unit 10^[-3, 3], time unit 10^[-4, 0]: the restitution
    does not depend on it);
bath
    the paper's rods with a thermal bath: T_B / E_tr log-uniform in [0.1, 3], 10 to 40 bath modes,
    gamma in [0.3, 1], kappa log-uniform in [10, 1000], one realisation per scene.

Each scene goes to every solver of the registry (:data:`wavecontact.solvers.SOLVER_NAMES`); a solver
that refuses the scene (``UnsupportedSceneError``) does not take it.  The solvers run at their
defaults except the resolution (the option named by ``solver.resolution``): ``--elements`` for FE,
``--modes`` for the modal solver, the delay solver's own tolerance.  For every pair of solvers that
took a scene the audit checks ``|eps_a - eps_b| <= est_a + est_b`` (the sum of their stated error
estimates) and prints one table row per family and pair: scenes, pairs that agree, that disagree, that
have no estimate, and the largest disagreement in units of the summed estimates; then one line per
failure with a reproducer (Python that rebuilds the scene and solves it with both solvers).

A solve over ``--max-work`` estimated updates is refused up front (``LimitError``) and counted, as
are solver failures (``SolverFailure``); neither is an agreement.  The machine is shared: no timing is
part of the verdict.
"""

from __future__ import annotations

import argparse
import itertools
import math
import time

import numpy as np

import wavecontact
from wavecontact import Exponential, Hard, Rod, Scene
from wavecontact.bath.collide import thermal_scene
from wavecontact.bath.model import ThermalBath
from wavecontact.delay.parameters import delay_parameters
from wavecontact.errors import LimitError, SolverFailure, UnsupportedSceneError
from wavecontact.solvers import SOLVER_NAMES, get_solver

FAMILIES = ("cold", "hard", "materials", "bath")


def draw_scene(family: str, stream: np.random.Generator) -> dict:
    """One random scene of ``family``: ``{"family", "scene", "code"}`` (``code``: Python that rebuilds it)."""
    if family in ("cold", "hard"):
        gamma = float(1.0 - stream.uniform(0.0, 0.95))
        kappa = math.inf if family == "hard" else float(10.0 ** stream.uniform(0.0, 5.0))
        return {"family": family, "scene": wavecontact.two_rods(gamma, kappa),
                "code": f"two_rods({gamma!r}, {kappa!r})", "label": f"gamma={gamma:.4g} kappa={kappa:.4g}"}
    if family == "materials":
        impedance_ratio, time_ratio = (float(4.0 ** stream.uniform(-1.0, 1.0)) for _ in range(2))
        speed, area = (float(2.0 ** stream.uniform(-1.0, 1.0)) for _ in range(2))
        hard = stream.random() < 0.3
        kappa = math.inf if hard else float(10.0 ** stream.uniform(0.0, 4.0))
        # a random unit system (length, mass and time units): the restitution does not depend on it
        length, mass, tick = (float(10.0 ** stream.uniform(*span)) for span in ((-1.0, 1.0), (-3.0, 3.0), (-4.0, 0.0)))
        density = impedance_ratio / (speed * area)
        rods = tuple(Rod(l * length, density=rho * mass / length**3, youngs_modulus=rho * c**2 * mass / (length * tick**2),
                         area=a * length**2)
                     for l, rho, c, a in ((1.0, 1.0, 1.0, 1.0), (speed / time_ratio, density, speed, area)))
        velocities = (length / tick, 0.0)
        if hard:
            contact, contact_code = Hard(), "Hard()"
        else:
            unit = delay_parameters(Scene(rods=rods, velocities=velocities, contact=Hard())).time_unit
            alpha = kappa / (unit * velocities[0])
            contact, contact_code = Exponential(alpha), f"Exponential({alpha!r})"
        scene = Scene(rods=rods, velocities=velocities, contact=contact)
        code = ("Scene(rods=(" + ", ".join(f"Rod({r.length!r}, density={r.density!r}, youngs_modulus={r.youngs_modulus!r}, "
                                           f"area={r.area!r})" for r in rods)
                + f"), velocities=({velocities[0]!r}, 0.0), contact={contact_code})")
        return {"family": family, "scene": scene, "code": code,
                "label": f"Z2/Z1={impedance_ratio:.3g} T1/T2={time_ratio:.3g} kappa={kappa:.4g} units L={length:.2g} "
                         f"M={mass:.2g} T={tick:.2g}"}
    if family == "bath":
        gamma = float(stream.uniform(0.3, 1.0))
        kappa = float(10.0 ** stream.uniform(1.0, 3.0))
        temperature = float(10.0 ** stream.uniform(-1.0, math.log10(3.0)))
        modes = int(stream.integers(10, 41))
        seed = int(stream.integers(0, 2**31))
        scene = thermal_scene(gamma, kappa, ThermalBath(temperature, modes), seed)
        code = f"thermal_scene({gamma!r}, {kappa!r}, ThermalBath({temperature!r}, {modes}), {seed})"
        return {"family": family, "scene": scene, "code": code,
                "label": f"gamma={gamma:.4g} kappa={kappa:.4g} T_B/E_tr={temperature:.3g} bath_modes={modes}"}
    raise ValueError(f"unknown family {family!r}")


def solver_options(name: str, elements: int, modes: int) -> dict:
    """The audit's options of solver ``name``: its defaults with the resolution option set
    (``elements`` or ``modes``; other resolutions, the delay solver's tolerance, stay at their default)."""
    resolution = get_solver(name).resolution
    return {"elements": {"elements": elements}, "modes": {"modes": modes, "history": False}}.get(resolution, {})


def run_scene(drawn: dict, elements: int, modes: int, max_work: float | None) -> dict:
    """Every registered solver on one scene: ``{name: {"status", "restitution", "estimate", "options", "seconds"}}``
    (status ``ok``, ``unsupported``, ``refused`` or ``failed``)."""
    out = {}
    for name in SOLVER_NAMES:
        options = solver_options(name, elements, modes)
        start = time.perf_counter()
        try:
            result = wavecontact.solve(drawn["scene"], name, max_work=max_work, **options)
        except UnsupportedSceneError:
            out[name] = {"status": "unsupported", "options": options}
            continue
        except LimitError:
            out[name] = {"status": "refused", "options": options}
            continue
        except SolverFailure as failure:
            out[name] = {"status": "failed", "options": options, "why": str(failure)}
            continue
        out[name] = {"status": "ok", "restitution": result.restitution, "estimate": result.error_estimate,
                     "options": options, "seconds": time.perf_counter() - start,
                     "method": result.diagnostics["error_estimate_method"]}
    return out


def compare(runs: dict) -> list:
    """``(a, b, verdict, difference, allowed)`` for every pair of solvers that solved the scene: verdict
    ``agree`` (``|eps_a - eps_b| <= est_a + est_b``), ``disagree`` or ``no estimate`` (one is NaN)."""
    solved = [name for name in SOLVER_NAMES if runs.get(name, {}).get("status") == "ok"]
    pairs = []
    for a, b in itertools.combinations(solved, 2):
        difference = abs(runs[a]["restitution"] - runs[b]["restitution"])
        allowed = runs[a]["estimate"] + runs[b]["estimate"]
        verdict = "no estimate" if math.isnan(allowed) else "agree" if difference <= allowed else "disagree"
        pairs.append((a, b, verdict, difference, allowed))
    return pairs


def reproducer(drawn: dict, runs: dict, a: str, b: str) -> str:
    """One line of Python that rebuilds the scene and solves it with solvers ``a`` and ``b``."""
    def call(name):
        options = "".join(f", {key}={value!r}" for key, value in runs[name]["options"].items())
        return f"solve(s, {name!r}{options}).restitution"
    return (f"from wavecontact import *; from wavecontact.bath.collide import thermal_scene; "
            f"from wavecontact.bath.model import ThermalBath; s = {drawn['code']}; "
            f"print({call(a)}, {call(b)})")


def audit(scenes: int, seed: int, families=FAMILIES, elements: int = 400, modes: int = 60,
          max_work: float | None = 2e9, verbose: bool = False, indices=None) -> list:
    """Run the audit: one record per scene, ``{"index", "family", "label", "code", "runs", "pairs"}``
    (``indices``: only these scenes of the ``scenes`` streams, the others skipped; same streams)."""
    records = []
    streams = np.random.SeedSequence(seed).spawn(scenes)
    for index, sequence in enumerate(streams):
        if indices is not None and index not in indices:
            continue
        family = families[index % len(families)]
        drawn = draw_scene(family, np.random.default_rng(sequence))
        runs = run_scene(drawn, elements, modes, max_work)
        record = {"index": index, "family": family, "label": drawn["label"], "code": drawn["code"],
                  "runs": runs, "pairs": compare(runs), "drawn": drawn}
        records.append(record)
        if verbose:
            text = "; ".join(f"{n} {r['restitution']:.10g} +- {r['estimate']:.2g}" if r["status"] == "ok"
                             else f"{n} {r['status']}" for n, r in runs.items())
            print(f"{index} {family} {drawn['label']}: {text}", flush=True)
    return records


def table_lines(records: list) -> list:
    """The table: one row per family and pair of solvers, then the refusals and failures per solver."""
    lines = ["| family | pair | scenes | agree | disagree | no estimate | largest |difference| / (est_a + est_b) |",
             "|---|---|---|---|---|---|---|"]
    keys = sorted({(r["family"], a, b) for r in records for a, b, *_ in r["pairs"]},
                  key=lambda k: (FAMILIES.index(k[0]), k[1], k[2]))
    for family, a, b in keys:
        rows = [p for r in records if r["family"] == family for p in r["pairs"] if p[:2] == (a, b)]
        counts = {v: sum(p[2] == v for p in rows) for v in ("agree", "disagree", "no estimate")}
        worst = max((p[3] / p[4] if p[4] > 0 else math.inf for p in rows if not math.isnan(p[4])), default=math.nan)
        lines.append(f"| {family} | {a} - {b} | {len(rows)} | {counts['agree']} | {counts['disagree']} | "
                     f"{counts['no estimate']} | {worst:.3g} |")
    lines.append("")
    for name in SOLVER_NAMES:
        statuses = [r["runs"][name]["status"] for r in records if name in r["runs"]]
        lines.append(f"{name}: solved {statuses.count('ok')}, did not take {statuses.count('unsupported')}, "
                     f"refused over the work limit {statuses.count('refused')}, failed {statuses.count('failed')}")
    return lines


def failure_lines(records: list) -> list:
    """One line per disagreeing (or estimate-less) pair: scene, both results and a reproducer."""
    lines = []
    for r in records:
        for a, b, verdict, difference, allowed in r["pairs"]:
            if verdict == "agree":
                continue
            ra, rb = r["runs"][a], r["runs"][b]
            lines.append(f"[{verdict}] scene {r['index']} ({r['family']}: {r['label']}): {a} {ra['restitution']:.10g} "
                         f"+- {ra['estimate']:.2g}, {b} {rb['restitution']:.10g} +- {rb['estimate']:.2g}, "
                         f"|difference| {difference:.3g} = {difference / allowed:.3g} x the estimates\n    "
                         + reproducer(r["drawn"], r["runs"], a, b))
        for name, run in r["runs"].items():
            if run["status"] == "failed":
                lines.append(f"[failed] scene {r['index']} ({r['family']}: {r['label']}): {name}: {run['why']}\n    "
                             f"from wavecontact import *; s = {r['code']}; solve(s, {name!r})")
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", type=int, default=300, help="random scenes (default 300)")
    parser.add_argument("--seed", type=int, default=2323)
    parser.add_argument("--families", nargs="+", choices=FAMILIES, default=list(FAMILIES))
    parser.add_argument("--elements", type=int, default=400, help="FE elements on the shorter rod (default 400)")
    parser.add_argument("--modes", type=int, default=60, help="modal solver's modes per rod (default 60)")
    parser.add_argument("--max-work", type=float, default=2e9, help="work limit of each solve (updates)")
    parser.add_argument("--part", default="1/1", metavar="K/N", help="only the K-th of N slices of the scenes")
    parser.add_argument("--verbose", action="store_true", help="print every scene's results")
    args = parser.parse_args(argv)
    part, parts = (int(x) for x in args.part.split("/"))
    print(f"seed {args.seed}, {args.scenes} scenes, families {' '.join(args.families)}, FE elements {args.elements}, "
          f"modal modes {args.modes}, part {args.part}", flush=True)
    indices = {i for i in range(args.scenes) if i % parts == part - 1}
    records = audit(args.scenes, args.seed, tuple(args.families), args.elements, args.modes, args.max_work,
                    args.verbose, indices)
    print("\n".join(table_lines(records)))
    failures = failure_lines(records)
    print(f"\n{len(failures)} failures" + (":" if failures else ""))
    print("\n".join(failures), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
