"""Calibrate the cost-and-error model of ``solver="auto"``: ``python benchmarks/cost_model.py``.

Runs every solver at every resolution of its ladder on the calibration scenes of each scene class
(:func:`wavecontact.solvers.cost_model.scene_class`), with its error estimate (as ``auto`` runs
them), and records the error estimate and the CPU time (``time.process_time``, median of up to
``--repeats`` runs, fewer for runs over 0.2 s; a first untimed run per scene and solver prepares
the numba kernels).  Writes ``wavecontact/data/cost_model.json``: the ladders, the points and the
fits (:func:`wavecontact.solvers.cost_model.fit_points`).

``--refit`` recomputes the fits from the stored points (no runs).  ``--check`` writes nothing: it verifies that the stored file has the current format, the ladders
and calibration scenes of this script, and fits that are what its points give (exit 1 otherwise).

Runs whose estimated work is over :data:`MAX_WORK` are skipped (bounded: about 3 min on a quiet
core).  The evaluation scenes of ``benchmarks/auto_choice.py`` are different scenes.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the checkout this script lives in

from wavecontact import Exponential, Hard, PiecewiseRod, RigidBody, Rod, Scene, Segment, two_rods
from wavecontact.bath.collide import thermal_scene
from wavecontact.bath.model import ThermalBath
from wavecontact.errors import WavecontactError
from wavecontact.solvers import SOLVER_NAMES, get_solver
from wavecontact.solvers.auto import _accepts, run_cost
from wavecontact.solvers.cost_model import DATA_PATH, FORMAT, fit_points, scene_class, scene_features

LADDERS = {
    "delay": [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13],
    "fem": [25, 50, 100, 200, 400, 800, 1600, 3200],
    "modal": [8, 16, 32, 64, 128, 256],
}
#: Runs over this estimated work (updates, the error estimate's runs included) are skipped.
MAX_WORK = 2e9
#: The same for line scenes, whose estimated work is the fem loop's bound (105 round trips of the longest
#: body) where the runs stop at the last separation, a few round trips: 1600 elements take about 0.5 s.
LINE_MAX_WORK = 6e10


def two_material_scene(impedance_ratio: float, time_ratio: float, kappa: float) -> Scene:
    """Rod 1: ``rho = E = A = 1``, ``l = 1``; rod 2 with impedance ``impedance_ratio`` and round trip
    ``1 / time_ratio`` times rod 1's, speed 1 against rod 1 at rest, ``kappa = alpha V mu / Z_s``."""
    wave_speed = 1.0
    density = impedance_ratio / wave_speed
    rods = (Rod(1.0), Rod(wave_speed / time_ratio, density=density, youngs_modulus=density * wave_speed**2))
    hard = Scene(rods=rods, velocities=(1.0, 0.0), contact=Hard())
    from wavecontact.delay.parameters import delay_parameters

    return Scene(rods=rods, velocities=(1.0, 0.0), contact=Exponential(kappa / delay_parameters(hard).time_unit))


def thermal(gamma: float, kappa: float, temperature: float, seed: int) -> Scene:
    return thermal_scene(gamma, kappa, ThermalBath(temperature, 250), seed)


def line_calibration_scenes() -> list:
    """``(label, scene)`` of the line scenes, three per line class, hard contact.  Their lengths are not
    commensurate with the meshes of the FE ladder (25 x 2^k elements on the body of the shortest travel
    time), so that no run is on the exact lattice, where the FE is exact and says nothing of its
    convergence elsewhere."""
    def striker_on(body, length):
        return Scene(rods=(Rod(length), body), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,))

    scenes = []
    for ratio in (0.5, 1.5, 4.0):
        scenes.append((f"line rigid mass M/m={ratio:g} on a rod",
                       Scene(rods=(RigidBody(mass=ratio), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(),
                             gaps=(0.0,))))
    for lengths in ((1.0, 0.7, 0.45), (0.61, 1.0, 0.83, 1.3), (0.37, 0.37, 1.0)):
        n = len(lengths)
        scenes.append((f"line chain lengths {'/'.join(f'{x:g}' for x in lengths)}",
                       Scene(rods=tuple(Rod(x) for x in lengths), velocities=(1.0,) + (0.0,) * (n - 1),
                             contact=Hard(), gaps=(0.0,) * (n - 1))))
    for a2, length, striker in ((1.5, 0.71, 0.83), (0.6, 0.47, 0.83), (3.0, 1.13, 0.59)):
        bar = PiecewiseRod((Segment(length=1.0, area=1.0), Segment(length=length, area=a2)))
        scenes.append((f"line stepped bar A2/A1={a2:g} l2={length:g} striker {striker:g}", striker_on(bar, striker)))
    for end_area, striker in ((0.3, 0.61), (2.0, 0.93), (0.1, 0.37)):
        horn = PiecewiseRod((Segment(length=1.0, area=1.0, end_area=end_area),))
        scenes.append((f"line taper A_end/A={end_area:g} striker {striker:g}", striker_on(horn, striker)))
    return scenes


def calibration_scenes() -> list:
    """``(label, scene)`` of every calibration scene."""
    scenes = []
    for gamma in (0.3, 0.8):
        for kappa in (10.0, 1e3, 1e5):
            scenes.append((f"cold gamma={gamma:g} kappa={kappa:g}", two_rods(gamma, kappa)))
        scenes.append((f"hard gamma={gamma:g}", two_rods(gamma, math.inf)))
        for kappa in (10.0, 1e3):
            scenes.append((f"penalty gamma={gamma:g} kappa={kappa:g}", two_rods(gamma, kappa, contact="penalty")))
    for kappa, temperature in ((10.0, 0.01), (1e3, 0.1)):
        scenes.append((f"thermal gamma=0.6 kappa={kappa:g} T={temperature:g}", thermal(0.6, kappa, temperature, 1)))
    for ratio, kappa in ((0.4, 10.0), (2.5, 1e3)):
        scenes.append((f"two materials Z2/Z1={ratio:g} kappa={kappa:g}", two_material_scene(ratio, 0.6, kappa)))
    return scenes + line_calibration_scenes()


def cpu_run(solver, scene, option: dict, repeats: int):
    """``(result, median CPU seconds)`` of ``solver.solve`` with its error estimate; None on refusal."""
    times, result = [], None
    for _ in range(repeats):
        start = time.process_time()
        try:
            result = solver.solve(scene, option, estimate_error=True)
        except WavecontactError:
            return None, None
        times.append(time.process_time() - start)
        if sum(times) > 0.2:
            break
    return result, statistics.median(times)


def accepts(solver, scene) -> bool:
    return _accepts(solver, scene)


def estimated_work(solver, scene, option: dict):
    """The estimated work of a run with its error estimate (as ``auto`` checks it; None: bounded)."""
    cost = run_cost(solver, scene, option)
    return None if cost is None else cost.work


def scan(scene, repeats: int, ladders=LADDERS, max_work=MAX_WORK):
    """Every solver that takes ``scene`` at every resolution of its ladder: a list of dicts with
    ``solver``, ``resolution``, ``restitution`` (a line scene: ``velocities``), ``estimate`` (None when the run was refused or
    failed, or skipped over ``max_work``) and ``cpu_s``."""
    rows = []
    for name in SOLVER_NAMES:
        solver = get_solver(name)
        if not accepts(solver, scene):
            continue
        warm = False
        for value in ladders[name]:
            option = {solver.resolution: value}
            try:
                work = estimated_work(solver, scene, option)
            except WavecontactError:
                continue
            if work is not None and work > max_work:
                continue
            if not warm:
                cpu_run(solver, scene, option, 1)
                warm = True
            result, cpu = cpu_run(solver, scene, option, repeats)
            if result is None:
                rows.append({"solver": name, "resolution": value, "restitution": None, "velocities": None,
                             "estimate": None, "cpu_s": None})
                continue
            rough = bool(result.diagnostics.get("error_estimate_rough"))
            estimate = result.error_estimate
            rows.append({"solver": name, "resolution": value, "restitution": getattr(result, "restitution", None),
                         "velocities": getattr(result, "velocities", None),
                         "estimate": None if rough or not math.isfinite(estimate) else estimate, "cpu_s": cpu})
    return rows


def calibrate(repeats: int, stored=None) -> dict:
    """The document of every calibration scene's points; with ``stored`` (a document) only the line scenes
    run, the two-rod scenes' points are kept from it."""
    points = []
    scenes = calibration_scenes()
    if stored is not None:
        lines = {label for label, _scene in line_calibration_scenes()}
        points = [p for p in stored["points"] if p["scene"] not in lines]
        scenes = line_calibration_scenes()
    for label, scene in scenes:
        began = time.monotonic()
        features = scene_features(scene)
        for row in scan(scene, repeats, max_work=LINE_MAX_WORK if scene.is_line_scene else MAX_WORK):
            points.append({"scene": label, "class": scene_class(scene), "solver": row["solver"],
                           "resolution": row["resolution"], "features": features,
                           "estimate": row["estimate"], "cpu_s": row["cpu_s"]})
        print(f"{label}: {time.monotonic() - began:.1f} s", file=sys.stderr, flush=True)
    return document(points)


def document(points: list) -> dict:
    """The file's content from the calibration points (what ``--check`` compares against)."""
    return {
        "format": FORMAT,
        "generated_by": "python benchmarks/cost_model.py",
        "cost_unit": "CPU seconds (time.process_time) of one solve with its error estimate",
        "error_unit": "the solve's error estimate of the restitution (absolute)",
        "ladders": LADDERS,
        "scenes": [label for label, _scene in calibration_scenes()],
        "points": points,
        "fits": fit_points(points),
    }


def check(path: Path) -> list:
    """What is wrong with the stored file (empty: it is what this script writes for its points)."""
    try:
        stored = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as error:
        return [f"cannot read {path}: {error}"]
    problems = []
    if stored.get("format") != FORMAT:
        problems.append(f"format {stored.get('format')!r}, expected {FORMAT}")
    points = stored.get("points", [])
    expected = document(points)
    for key in ("generated_by", "cost_unit", "error_unit", "ladders", "scenes", "fits"):
        if stored.get(key) != expected[key]:
            problems.append(f"{key} differs from what python benchmarks/cost_model.py writes for the stored points")
    labels = {p["scene"] for p in points}
    missing = [label for label in expected["scenes"] if label not in labels]
    if missing:
        problems.append(f"no points for {', '.join(missing)}")
    return problems


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per point (median; default 3)")
    parser.add_argument("--output", type=Path, default=DATA_PATH, help="where to write the model")
    parser.add_argument("--check", action="store_true", help="verify the stored model instead of writing one")
    parser.add_argument("--refit", action="store_true",
                        help="recompute the fits from the stored points (no runs), after a change of the fit")
    parser.add_argument("--line-only", action="store_true",
                        help="run the line scenes only (chains, stepped and tapered bars, a rigid mass), keeping the "
                        "stored points of the two-rod scenes")
    args = parser.parse_args(argv)
    if args.refit:
        stored = json.loads(args.output.read_text(encoding="utf-8"))
        data = {**document(stored["points"]), "load_average_at_start": stored.get("load_average_at_start")}
        args.output.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
        print(f"refitted {args.output} from its {len(stored['points'])} points")
        return 0
    if args.check:
        problems = check(args.output)
        for problem in problems:
            print(f"{args.output}: {problem}")
        if not problems:
            print(f"{args.output}: format {FORMAT}, fits match the stored points")
        return 1 if problems else 0
    began = time.monotonic()
    load = os.getloadavg()[0]
    data = calibrate(args.repeats, json.loads(args.output.read_text(encoding="utf-8")) if args.line_only else None)
    data["load_average_at_start"] = round(load, 2)
    args.output.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {args.output}: {len(data['points'])} points in {time.monotonic() - began:.0f} s "
          f"(load average {load:.1f} at the start)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
