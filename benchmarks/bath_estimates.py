"""Error estimates with a thermal bath: the delay solver's noise tables and the FE estimate's rule.

    python benchmarks/bath_estimates.py delay [--seed 2324] [--scenes 200]
    python benchmarks/bath_estimates.py fem [--seed 2324 ...] [--scenes 200] [--elements 400 200]

The scenes are the bath family of the cross-solver audit (``benchmarks/cross_solver_audit.py``: scene
``i`` of ``--scenes`` streams of ``SeedSequence(seed).spawn``, every fourth from index 3, what
``--part 4/4`` of the audit runs).

``delay``
    per scene, how far the noise tables alone move epsilon (rtol 1e-13, tables of 32, 64 and 128 nodes a
    period of the fastest mode, not refined, against 1024) and that distance over the tables' interpolation bound
    divided by kappa (:func:`wavecontact.bath.noise.interpolation_error`, the part of the estimate the
    tables add), then the largest such ratio.
``fem``
    per scene the FE restitutions at ``N/4 ... 2N`` (``--elements`` N, estimate off) and the delay
    solver's (rtol 1e-12); then, per N, how often the estimate is below the distance to the delay
    solver (minus the delay estimate) under the present rule (the solver's own
    ``estimate_from_levels`` on the runs it makes: N, N/2, N/4 and 2N) and under the previous one
    (commit bcab3d6: N, N/2 and N/4 with ``alpha V h / c`` from the rods' speed alone and no run at 2N;
    no estimate where the run at N/2 fails), with the median and 95th percentile of estimate / error.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import cross_solver_audit as audit

import wavecontact
from wavecontact.errors import SolverFailure
from wavecontact.fem.error_estimate import estimate_from_levels
from wavecontact.solvers import get_solver


def bath_scenes(seed: int, scenes: int) -> list:
    """``(index, drawn)`` of the audit's bath scenes among ``scenes`` streams of ``seed``."""
    streams = np.random.SeedSequence(seed).spawn(scenes)
    return [(i, audit.draw_scene("bath", np.random.default_rng(streams[i]))) for i in range(3, scenes, 4)]


def _fixed_tables(scene, nodes: int) -> float:
    """epsilon of the delay solver at rtol 1e-13 with tables of ``nodes`` nodes a period of the fastest mode,
    not refined (the solver's own start gap and integration)."""
    from wavecontact.bath.scene import scene_noise
    from wavecontact.delay.parameters import delay_parameters
    from wavecontact.delay.solver import _integrate, _start

    solver = get_solver("delay")
    options = solver.options({"rtol": 1e-13})
    params = delay_parameters(scene)
    gap = _start(scene, params, options)[0]
    tables = scene_noise(scene, params.kappa, float(gap), nodes)  # no tolerance: exactly these nodes
    w = _integrate(params.time_ratio, params.kappa, options.rtol, gap, None, None, options.max_steps,
                   params.impedance_ratio, tables)[1]
    return float(w[-1] / params.kappa - 1.0)


def delay_table(seed: int, scenes: int) -> list:
    from wavecontact.bath.noise import interpolation_error, table_points

    lines = ["| scene | label | 32 nodes: distance | / bound | 64 nodes: distance | / bound | 128 nodes: distance | / bound |",
             "|---|---|---|---|---|---|---|---|"]
    worst = 0.0
    for index, drawn in bath_scenes(seed, scenes):
        scene = drawn["scene"]
        kappa = scene.metadata["two_rods"].kappa
        coefficients = scene.vibrations.noise_coefficients(kappa)
        spans = [np.hypot(a, b) for _omega, a, b in coefficients]
        modes = max(len(s) for s in spans)
        fine = _fixed_tables(scene, 1024)
        cells = []
        for nodes in (32, 64, 128):
            value = _fixed_tables(scene, nodes)
            bound = interpolation_error(spans, table_points(modes, nodes)) / kappa
            worst = max(worst, abs(value - fine) / bound)
            cells += [f"{abs(value - fine):.3g}", f"{abs(value - fine) / bound:.3f}"]
        lines.append(f"| {index} | {drawn['label']} | " + " | ".join(cells) + " |")
    lines += ["", f"largest distance / bound: {worst:.3f}"]
    return lines


def fem_runs(seed: int, scenes: int, elements: list) -> list:
    """Per scene ``{"scene", "label", "reference", "reference_estimate", "levels": {n: eps or None}}``."""
    sizes = sorted({m for n in elements for m in (n // 4, n // 2, n, 2 * n)})
    out = []
    for index, drawn in bath_scenes(seed, scenes):
        scene = drawn["scene"]
        reference = wavecontact.solve(scene, "delay", rtol=1e-12, energy_split=False)
        levels = {}
        for n in sizes:
            try:
                levels[n] = wavecontact.solve(scene, "fem", elements=n, estimate_error=False).restitution
            except SolverFailure:
                levels[n] = None
        out.append({"seed": seed, "index": index, "scene": scene, "label": drawn["label"], "reference": reference.restitution,
                    "reference_estimate": reference.error_estimate, "levels": levels})
    return out


def estimates(run: dict, n: int) -> tuple:
    """``(present, previous)`` estimates of the FE run on ``n`` elements (NaN: none)."""
    solver = get_solver("fem")
    options = solver.options({"elements": n})
    levels = run["levels"]
    coarse = [(n, levels[n])]
    for m in (n // 2, n // 4):
        if levels.get(m) is None:
            break
        coarse.append((m, levels[m]))
    scene = run["scene"]
    if levels.get(2 * n) is not None:
        present = solver.estimate_from_levels(scene, options, [*coarse, (2 * n, levels[2 * n])])[0]
    else:
        present = math.nan
    previous = math.nan
    if len(coarse) > 1:
        cold = solver._contact_resolution(scene, options, thermal=False)
        previous = estimate_from_levels(coarse, cold, solver.expected_order(options),
                                        solver._characteristic(scene, options), solver._scheme_order(options))[0]
    return present, previous


def fem_table(runs: list, elements: list) -> list:
    lines = ["| elements | rule | scenes | below the error | no estimate | median estimate / error | p95 | worst |",
             "|---|---|---|---|---|---|---|---|"]
    misses = []
    for n in elements:
        for k, rule in enumerate(("present", "previous (bcab3d6)")):
            ratios, below, none = [], 0, 0
            for run in runs:
                value = run["levels"][n]
                if value is None:
                    continue
                estimate = estimates(run, n)[k]
                error = abs(value - run["reference"])
                if math.isnan(estimate):
                    none += 1
                    continue
                ratios.append(estimate / error)
                if error > estimate + run["reference_estimate"]:
                    below += 1
                    if k == 0:
                        misses.append(f"{n} elements, seed {run['seed']} scene {run['index']} ({run['label']}): estimate "
                                      f"{estimate / error:.3g} of the error; errors at N/4 ... 2N: "
                                      + ", ".join("fail" if run["levels"][m] is None else
                                                  f"{run['levels'][m] - run['reference']:+.3g}"
                                                  for m in (n // 4, n // 2, n, 2 * n)))
            solved = len(ratios) + none
            lines.append(f"| {n} | {rule} | {solved} | {below} | {none} | {np.median(ratios):.3g} | "
                         f"{np.percentile(ratios, 95):.3g} | {min(ratios):.3g} |")
    return lines + ["", "Present rule below the error:"] + (misses or ["none"])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("delay", "fem"))
    parser.add_argument("--seed", type=int, nargs="+", default=[2324])
    parser.add_argument("--scenes", type=int, default=200, help="the audit's --scenes (a quarter are bath scenes)")
    parser.add_argument("--elements", type=int, nargs="+", default=[400, 200])
    args = parser.parse_args(argv)
    print(f"`python benchmarks/bath_estimates.py {args.what} --seed {' '.join(map(str, args.seed))} "
          f"--scenes {args.scenes}" + (f" --elements {' '.join(map(str, args.elements))}`" if args.what == "fem" else "`"))
    print()
    if args.what == "delay":
        for seed in args.seed:
            print("\n".join(delay_table(seed, args.scenes)))
    else:
        runs = [run for seed in args.seed for run in fem_runs(seed, args.scenes, args.elements)]
        print("\n".join(fem_table(runs, args.elements)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
