"""Where the time of one finite-kappa thermal sample goes (issue 11): one command, one table.

    python benchmarks/profile_bath_sample.py [--kappa 250] [--modes 250] [--samples 6]

For gamma = 0.6173, T_B/E_tr = 1: the CPU time (median over samples) of the pieces of a
sample (drawing the scene, the noise tables, the delay integration at rtol 1e-11 and 1e-6,
the energy split, ``solve`` and ``collide`` around them), and the integration's steps by
phase: free (W' below 1e-13), ramp (1e-13 .. 1e-3) and contact (above), with their median
step.  CPU times (``time.process_time``): the machine may be shared.
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

GAMMA = 0.6173


def cpu(function):
    started = time.process_time()
    function()
    return time.process_time() - started


def _pieces(kappa, bath, modes, seed, scene, a0, tables):
    return {
        "draw the scene (thermal_scene)": lambda: thermal_scene(GAMMA, kappa, bath, seed),
        "noise tables (scene_noise)": lambda: scene_noise(scene, kappa, a0),
        "integration, rtol 1e-11": lambda: delay._integrate(GAMMA, kappa, 1e-11, a0, None, None, 2_000_000, 1.0,
                                                            tables),
        "integration, rtol 1e-6": lambda: delay._integrate(GAMMA, kappa, 1e-6, a0, None, None, 2_000_000, 1.0,
                                                           tables),
        "solve, rtol 1e-6, no energy split": lambda: solve(scene, "delay", rtol=1e-6, energy_split=False),
        "solve, rtol 1e-6, energy split": lambda: solve(scene, "delay", rtol=1e-6),
        "collide() defaults (rtol 1e-11, energy split)": lambda: wavecontact.collide(
            GAMMA, kappa, bath_temperature=1.0, bath_modes=modes, seed=seed, estimate_error=False),
    }


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
    phases = {"free": [], "ramp": [], "contact": []}
    for seed in seeds:
        scene = thermal_scene(GAMMA, kappa, bath, seed)
        a0 = kappa * scene.gaps[0]
        tables = scene_noise(scene, kappa, a0)
        for name, function in _pieces(kappa, bath, args.modes, seed, scene, a0, tables).items():
            times.setdefault(name, []).append(cpu(function))
        t, _w, d1, *_rest = delay._integrate(GAMMA, kappa, 1e-6, a0, None, None, 2_000_000, 1.0, tables)
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
    print("| phase of the rtol 1e-6 integration | steps | median step | time span |")
    print("|---|---|---|---|")
    for name, rows in phases.items():
        rows = np.array(rows)
        print(f"| {name} | {np.median(rows[:, 0]):.0f} | {np.median(rows[:, 1]):.2e} | {np.median(rows[:, 2]):.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
