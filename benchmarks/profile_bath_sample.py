"""Where the time of one finite-kappa thermal sample goes (issue 11): one command, one table.

    python benchmarks/profile_bath_sample.py [--kappa 250] [--modes 250] [--samples 6]

For gamma = 0.6173, T_B/E_tr = 1: the CPU time (median over samples) of the pieces of a
sample (drawing the scene, the noise tables, the delay integration at rtol 1e-11, at the
previous ensemble setting rtol 1e-6 and at the ensemble's defaults ENSEMBLE_DELAY_OPTIONS, the
energy split, ``solve`` and ``collide`` around them, and a sample of the batched ensemble path,
``thermal_restitutions`` over 64 seeds divided by 64), and the integration's steps by phase at
the ensemble's defaults: free (W' below 1e-13), ramp (1e-13 .. 1e-3) and contact (above), with
their median step and evaluations of the exponent per step.  CPU times (``time.process_time``):
the machine may be shared.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import wavecontact
from wavecontact.api import solve
from wavecontact.bath import ThermalBath
from wavecontact.bath.collide import thermal_scene
from wavecontact.bath.scene import scene_noise
from wavecontact.delay import solver as delay
from wavecontact.solvers import get_solver
from wavecontact.studies.ensemble import ENSEMBLE_DELAY_OPTIONS, sample_seed

GAMMA = 0.6173


def cpu(function):
    started = time.process_time()
    function()
    return time.process_time() - started


def _pieces(kappa, bath, modes, seed, scene, a0, tables):
    fast = scene_noise(scene, kappa, a0, ENSEMBLE_DELAY_OPTIONS["noise_resolution"])
    seeds = [sample_seed(seed, j) for j in range(BATCH)]
    return {
        "draw the scene (thermal_scene)": lambda: thermal_scene(GAMMA, kappa, bath, seed),
        "noise tables (scene_noise), 32 nodes": lambda: scene_noise(scene, kappa, a0),
        "noise tables (scene_noise), 16 nodes": lambda: scene_noise(scene, kappa, a0, 16),
        "integration, rtol 1e-11": lambda: delay._integrate(GAMMA, kappa, 1e-11, a0, None, None, 2_000_000, 1.0,
                                                            tables),
        "integration, rtol 1e-6 (the previous ensemble setting)": lambda: delay._integrate(
            GAMMA, kappa, 1e-6, a0, None, None, 2_000_000, 1.0, tables),
        "integration, ensemble defaults": lambda: _defaults(kappa, a0, fast),
        "solve, ensemble defaults, no energy split": lambda: solve(scene, "delay", energy_split=False,
                                                                   **ENSEMBLE_DELAY_OPTIONS),
        "solve, rtol 1e-6, energy split": lambda: solve(scene, "delay", rtol=1e-6),
        f"batched ensemble path, per sample ({BATCH} a batch)": lambda: get_solver("delay").thermal_restitutions(
            GAMMA, kappa, bath, seeds, ENSEMBLE_DELAY_OPTIONS),
        "collide() defaults (rtol 1e-11, energy split)": lambda: wavecontact.collide(
            GAMMA, kappa, bath_temperature=1.0, bath_modes=modes, seed=seed, estimate_error=False),
    }


BATCH = 64


def _defaults(kappa, a0, tables):
    return delay._integrate(GAMMA, kappa, ENSEMBLE_DELAY_OPTIONS["rtol"], a0, None, None, 2_000_000, 1.0, tables,
                            ENSEMBLE_DELAY_OPTIONS["quadrature"])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kappa", type=float, default=250.0)
    parser.add_argument("--modes", type=int, default=250)
    parser.add_argument("--samples", type=int, default=6)
    args = parser.parse_args(argv)
    kappa, bath = args.kappa, ThermalBath(1.0, args.modes)
    seeds = range(args.samples)
    solve(thermal_scene(GAMMA, kappa, bath, 0), "delay", rtol=1e-6)  # kernels ready
    times = {}
    per_step = []
    phases = {"free": [], "ramp": [], "contact": []}
    for seed in seeds:
        scene = thermal_scene(GAMMA, kappa, bath, seed)
        a0 = kappa * scene.gaps[0]
        tables = scene_noise(scene, kappa, a0)
        for name, function in _pieces(kappa, bath, args.modes, seed, scene, a0, tables).items():
            per = BATCH if name.startswith("batched") else 1
            times.setdefault(name, []).append(cpu(function) / per)
        fast = scene_noise(scene, kappa, a0, ENSEMBLE_DELAY_OPTIONS["noise_resolution"])
        t, _w, d1, _d2, _error, work, _a0 = _defaults(kappa, a0, fast)
        per_step.append(work["evaluations"] / (work["steps"] + work["rejected_steps"]))
        h, force = np.diff(t), d1[1:]
        for name, mask in (("free", force < 1e-13), ("ramp", (force >= 1e-13) & (force < 1e-3)),
                           ("contact", force >= 1e-3)):
            phases[name].append((int(mask.sum()), float(np.median(h[mask])) if mask.any() else 0.0,
                                 float(h[mask].sum())))
    print(f"gamma {GAMMA}, kappa {kappa:g}, nu_max {args.modes}, T_B/E_tr 1, {args.samples} samples; CPU ms, medians")
    print("| piece | CPU ms |")
    print("|---|---|")
    for name, values in times.items():
        print(f"| {name} | {1e3 * np.median(values):.2f} |")
    print()
    print(f"integration at the ensemble defaults: {np.median(per_step):.2f} evaluations of the exponent per step "
          "(median; accepted and rejected steps)")
    print()
    print("| phase of the integration at the ensemble defaults | steps | median step | time span |")
    print("|---|---|---|---|")
    for name, rows in phases.items():
        rows = np.array(rows)
        print(f"| {name} | {np.median(rows[:, 0]):.0f} | {np.median(rows[:, 1]):.2e} | {np.median(rows[:, 2]):.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
