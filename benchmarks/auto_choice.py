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
6400 elements (their difference is printed).  Line scenes (a rigid mass on a bar, chains, a stepped
bar, a taper; ``--line-only`` runs only them) are compared on every body's velocity (initial speed 1)
with the independent references of tests/references/: Saint-Venant's closed form, the characteristics
on the exact lattice, central differences extrapolated at their observed order.  Cost is CPU time, not a work count: the solvers count
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

from cost_model import LINE_MAX_WORK, MAX_WORK, scan, thermal, two_material_scene
from docs_block import run_and_write

from wavecontact import Hard, PiecewiseRod, RigidBody, Rod, Scene, Segment, solve, two_rods
from wavecontact.errors import WavecontactError

sys.path.insert(2, str(Path(__file__).resolve().parents[1] / "tests"))  # the independent references

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
    return scenes + line_scenes()


#: Line scenes of one wave speed as (length, impedance) segments per body, for the characteristics reference.
CHAIN_LAYOUTS = {
    "chain 0.5/1.5/1.0": [[(0.5, 1.0)], [(1.5, 1.0)], [(1.0, 1.0)]],
    "chain with a stepped rod and a re-contact": [[(0.5, 1.0)], [(1.5, 1.0)], [(1.0, 2.0), (0.75, 1.0)],
                                                  [(0.25, 0.5)]],
    "stepped bar Z2/Z1=2": [[(1.0, 1.0)], [(1.0, 1.0), (1.0, 2.0)]],
}
#: The taper of the central-difference reference: (length, area start, area end, E, rho) per segment.
TAPER = [[(0.5, 1.0, 1.0, 1.0, 1.0)], [(1.0, 1.0, 0.25, 1.0, 1.0)]]


def _lattice_body(segments):
    if len(segments) == 1:
        (length, z), = segments
        return Rod(length, density=z, youngs_modulus=z)
    return PiecewiseRod(tuple(Segment(length=length, youngs_modulus=z, density=z) for length, z in segments))


def line_scenes() -> list:
    """``(label, scene, reference kind)`` of the line scenes: hammers (Saint-Venant), chains and a stepped
    bar (characteristics), a taper (central differences)."""
    scenes = [(f"hammer M/m={ratio:g} on a bar",
               Scene(rods=(RigidBody(mass=ratio), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,)),
               "saint_venant") for ratio in (1.0, 0.25)]
    for label, layout in CHAIN_LAYOUTS.items():
        velocities = (1.0,) + (0.0,) * (len(layout) - 1)
        scenes.append((label, Scene(rods=tuple(_lattice_body(s) for s in layout), velocities=velocities,
                                    contact=Hard(), gaps=(0.0,) * (len(layout) - 1)), "characteristics"))
    horn = PiecewiseRod((Segment(length=1.0, area=1.0, end_area=0.25),))
    scenes.append(("taper A 1 -> 1/4, striker 0.5",
                   Scene(rods=(Rod(0.5), horn), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,)),
                   "central_differences"))
    return scenes


def line_reference(label: str, scene, kind: str) -> tuple:
    """``(velocities, note)`` of a line scene's independent reference (tests/references/)."""
    if kind == "saint_venant":
        from references.saint_venant import saint_venant

        outcome = saint_venant(mass=scene.rods[0].mass, rod_length=1.0, impedance=1.0, wave_speed=1.0, velocity=1.0)
        return [outcome.mass_velocity, outcome.rod_velocity], "Saint-Venant (method of steps, closed form)"
    if kind == "characteristics":
        from references.characteristics import chain

        layout = CHAIN_LAYOUTS[label]
        return list(chain(layout, [1.0] + [0.0] * (len(layout) - 1)).velocities), "characteristics (exact lattice)"
    from references.central_differences import extrapolate, run

    levels = [run(TAPER, [1.0, 0.0], n, 5.0) for n in (400, 800, 1600)]
    value, bound, order = extrapolate([o.velocities for o in levels])
    return [float(v) for v in value], (
        f"central differences at 400/800/1600 cells per unit length, extrapolated at the observed orders "
        f"{', '.join(f'{o:.2f}' for o in order)} (bound {float(max(bound)):.1g}: errors below it are not resolved)")


def error_against(value, ref) -> float:
    """|restitution - reference|, or for a line scene the largest |velocity - reference| (initial speed 1)."""
    if isinstance(ref, (list, tuple)):
        return max(abs(a - b) for a, b in zip(value, ref))
    return abs(value - ref)


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
        if args.line_only and not scene.is_line_scene:
            continue
        ref, note = line_reference(label, scene, kind) if scene.is_line_scene else reference(scene, kind)
        notes.append(f"{label}: reference {note}")
        line = scene.is_line_scene
        fixed = [r for r in scan(scene, args.repeats, max_work=LINE_MAX_WORK if line else MAX_WORK)
                 if r["velocities" if line else "restitution"] is not None]
        for r in fixed:
            r["error"] = error_against(r["velocities" if line else "restitution"], ref)
        for tolerance in TOLERANCES:
            # what solve(scene, solver, tolerance=...) accepts and is right: estimate and actual error meet it
            meeting = [r for r in fixed if r["error"] <= tolerance and r["estimate"] is not None
                       and r["estimate"] <= tolerance]
            cheapest = min(meeting, key=lambda r: r["cpu_s"]) if meeting else None
            right = [r for r in fixed if r["error"] <= tolerance]  # an oracle: the actual error alone
            oracle = min(right, key=lambda r: r["cpu_s"]) if right else None
            if tolerance == TOLERANCES[0]:
                try:
                    solve(scene, tolerance=tolerance)  # kernels prepared
                except WavecontactError:
                    pass
            result, cpu, failure = timed_auto(scene, tolerance, args.repeats)
            rows.append((label, tolerance, result, cpu, failure, ref, cheapest, oracle))
        print(f"{label}: {time.monotonic() - began:.0f} s", file=sys.stderr, flush=True)
    print("| scene | tolerance | auto chose | runs | actual error | CPU ms | predicted ms | cheapest fixed "
          "| its CPU ms | auto / cheapest | oracle | its CPU ms |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    met = within = compared = misses = refused_wrongly = 0
    ratios, predicted = [], []
    for label, tolerance, result, cpu, failure, ref, cheapest, oracle in rows:
        if result is None:
            cheap_text = "none meets it | " if cheapest is None else f"{_method(cheapest)} | {cheapest['cpu_s'] * 1e3:.3g}"
            refused_wrongly += cheapest is not None
            print(f"| {label} | {tolerance:.0e} | refused: {failure[:200]} | | | | | {cheap_text} | | | |")
            continue
        auto = result.diagnostics["auto"]
        error = error_against(result.velocities if hasattr(result, "velocities") else result.restitution, ref)
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
          f"Refused: {sum(r[2] is None for r in rows)} pairs, {refused_wrongly} of them met by a fixed method. "
          f"Whole run {time.monotonic() - began:.0f} s.")
    print()
    for note in notes:
        print(f"- {note}")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--update-docs", action="store_true",
                        help="also write the table into docs/performance.md (block auto-choice)")
    parser.add_argument("--line-only", action="store_true",
                        help="the line scenes only (prints their rows; not for --update-docs)")
    args = parser.parse_args(argv)
    if args.line_only and args.update_docs:
        parser.error("--line-only prints a subset: run without it to update the docs")
    run_and_write(lambda: measure(args), "performance.md", "auto-choice", args.update_docs)


if __name__ == "__main__":
    main()
