"""How good is ``solver="auto"``: ``python benchmarks/auto_choice.py [--update-docs]``.

For each evaluation scene (none of them a calibration scene of ``benchmarks/cost_model.py``) and each
tolerance 1e-3, 1e-6, 1e-9:

* the **cheapest fixed method**: every solver at every resolution of its ladder (the model's
  ladders), each solve with its error estimate, CPU time (``time.process_time``, median of up to
  ``--repeats`` runs); the cheapest whose error estimate and actual error against the reference both
  meet the tolerance (what ``solve(scene, solver, tolerance=...)`` accepts, and right); the
  **oracle**: the cheapest whose actual error alone meets it (no user could know it in advance);
* the **auto answer**: ``wavecontact.solve(scene, tolerance=...)``, the CPU time of the whole call
  (refinements included, same median), its actual error against the reference, what it chose, and
  the model's predicted CPU time.

References: the delay solver at rtol = 1e-13 (the exact recursion for the hard core); for penalty
contact, which the delay solver does not take, the modal solver at 512 modes, checked against FE at
6400 elements (their difference is printed).  Cost is CPU time, not a work count: the solvers count
different things.  With ``--update-docs`` the table goes into docs/performance.md (block
``auto-choice``).
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, os.path.dirname(__file__))
sys.path.insert(1, str(Path(__file__).resolve().parents[1]))  # the checkout this script lives in

from cost_model import scan, thermal, two_material_scene
from docs_block import run_and_write

from wavecontact import solve, two_rods
from wavecontact.errors import WavecontactError

TOLERANCES = (1e-3, 1e-6, 1e-9)


def evaluation_scenes() -> list:
    """``(label, scene, reference kind)`` of every evaluation scene."""
    scenes = [(f"cold gamma={g:g} kappa={k:g}", two_rods(g, k), "delay")
              for g, k in ((0.5, 50.0), (0.7, 3e4), (0.2, 300.0), (0.9, 5.0))]
    scenes.append(("hard gamma=0.5", two_rods(0.5, math.inf), "delay"))
    scenes += [(f"penalty gamma={g:g} kappa={k:g}", two_rods(g, k, contact="penalty"), "modal")
               for g, k in ((0.5, 50.0), (0.7, 500.0))]
    scenes += [(f"thermal gamma={g:g} kappa={k:g} T={t:g}", thermal(g, k, t, seed), "delay")
               for g, k, t, seed in ((0.6, 100.0, 0.05, 2), (0.5, 30.0, 0.02, 3))]
    scenes += [(f"two materials Z2/Z1={z:g} kappa={k:g}", two_material_scene(z, 0.6, k), "delay")
               for z, k in ((0.7, 100.0), (4.0, 3000.0))]
    return scenes


def reference(scene, kind: str) -> tuple:
    """``(restitution, note)`` of the reference."""
    if kind == "delay":
        return solve(scene, "delay", rtol=1e-13).restitution, "delay rtol=1e-13"
    modal = solve(scene, "modal", modes=512).restitution
    fem = solve(scene, "fem", elements=6400).restitution
    return modal, f"modal 512 modes (FE 6400 el. differs by {abs(modal - fem):.1g})"


def timed_auto(scene, tolerance: float, repeats: int):
    times, result = [], None
    for _ in range(repeats):
        start = time.process_time()
        try:
            result = solve(scene, tolerance=tolerance)
        except WavecontactError as error:
            return None, None, str(error)
        times.append(time.process_time() - start)
        if sum(times) > 0.2:
            break
    return result, statistics.median(times), ""


def _method(row) -> str:
    name = {"delay": "rtol", "fem": "elements", "modal": "modes"}[row["solver"]]
    return f"{row['solver']}: {name}={row['resolution']:g}"


def measure(args) -> None:
    began = time.monotonic()
    rows, notes = [], []
    for label, scene, kind in evaluation_scenes():
        ref, note = reference(scene, kind)
        notes.append(f"{label}: reference {note}")
        fixed = [r for r in scan(scene, args.repeats) if r["restitution"] is not None]
        for r in fixed:
            r["error"] = abs(r["restitution"] - ref)
        for tolerance in TOLERANCES:
            # what solve(scene, solver, tolerance=...) accepts and is right: estimate and actual error meet it
            meeting = [r for r in fixed if r["error"] <= tolerance and r["estimate"] is not None
                       and r["estimate"] <= tolerance]
            cheapest = min(meeting, key=lambda r: r["cpu_s"]) if meeting else None
            right = [r for r in fixed if r["error"] <= tolerance]  # an oracle: the actual error alone
            oracle = min(right, key=lambda r: r["cpu_s"]) if right else None
            if tolerance == TOLERANCES[0]:
                solve(scene, tolerance=tolerance)  # kernels prepared
            result, cpu, failure = timed_auto(scene, tolerance, args.repeats)
            rows.append((label, tolerance, result, cpu, failure, ref, cheapest, oracle))
        print(f"{label}: {time.monotonic() - began:.0f} s", file=sys.stderr, flush=True)
    print("| scene | tolerance | auto chose | runs | actual error | CPU ms | predicted ms | cheapest fixed "
          "| its CPU ms | auto / cheapest | oracle | its CPU ms |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    met = within = compared = misses = 0
    ratios, predicted = [], []
    for label, tolerance, result, cpu, failure, ref, cheapest, oracle in rows:
        if result is None:
            print(f"| {label} | {tolerance:.0e} | refused: {failure[:80]} | | | | | | | | | |")
            continue
        auto = result.diagnostics["auto"]
        error = abs(result.restitution - ref)
        met += error <= tolerance
        misses += len(auto["misses"])
        predicted.append(auto["predicted_cpu_s"] / auto["actual_cpu_s"])
        cheap_text, cheap_cpu, ratio = "none meets it", "", ""
        if cheapest is not None:
            compared += 1
            r = cpu / cheapest["cpu_s"]
            ratios.append(r)
            within += r <= 2.0
            cheap_text, cheap_cpu, ratio = _method(cheapest), f"{cheapest['cpu_s'] * 1e3:.3g}", f"{r:.2f}"
        oracle_text = "none" if oracle is None else _method(oracle)
        oracle_cpu = "" if oracle is None else f"{oracle['cpu_s'] * 1e3:.3g}"
        print(f"| {label} | {tolerance:.0e} | {auto['method']} | {len(auto['attempts'])} | {error:.1e} | "
              f"{cpu * 1e3:.3g} | {auto['predicted_cpu_s'] * 1e3:.3g} | {cheap_text} | {cheap_cpu} | {ratio} | "
              f"{oracle_text} | {oracle_cpu} |")
    print()
    print(f"Auto met the tolerance (actual error against the reference) on {met} of {len(rows)} scene-tolerance "
          f"pairs; it cost at most 2x the cheapest fixed method on {within} of {compared} pairs where a fixed method "
          f"met the tolerance ({100.0 * within / max(compared, 1):.0f} %; median ratio "
          f"{statistics.median(ratios) if ratios else math.nan:.2f}, largest {max(ratios, default=math.nan):.2f}). "
          f"The first choice's predicted CPU time over the whole call's actual: median {statistics.median(predicted):.2f}, range "
          f"{min(predicted):.2f} to {max(predicted):.2f}; the model logged {misses} misses. "
          f"Whole run {time.monotonic() - began:.0f} s.")
    print()
    for note in notes:
        print(f"- {note}")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--update-docs", action="store_true",
                        help="also write the table into docs/performance.md (block auto-choice)")
    args = parser.parse_args(argv)
    run_and_write(lambda: measure(args), "performance.md", "auto-choice", args.update_docs)


if __name__ == "__main__":
    main()
