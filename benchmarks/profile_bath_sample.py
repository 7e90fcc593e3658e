"""Where the time of one finite-kappa thermal sample goes (issue 11): one command, one table.

    python benchmarks/profile_bath_sample.py [--kappa 250] [--modes 250] [--samples 6]
    python benchmarks/profile_bath_sample.py --hard-core [--modes 250] [--resolution 8]

``--hard-core``: what NumPy's per-sample objects cost (SeedSequence children, Generators,
the normals), then the pieces of the batched stochastic hard-core sampler (kappa = inf) per
sample, CPU microseconds (medians of repeats over blocks of 256 samples): the seed words,
the 1000 normals, the noise coefficients, the FFT tables with their bounds, the recursion
kernel, and the whole ``ensemble`` call; and the grid nodes a sample takes.

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


def hard_core_pieces(modes, resolution, samples=256, repeats=15):
    """CPU microseconds per sample of each piece of the batched hard-core sampler (medians of repeats)."""
    import math

    from wavecontact.bath.streams import SpawnedSeeds, seed_states, standard_normals
    from wavecontact.delay.stochastic_hardcore_batch import (
        SampleTables,
        _temperature_rows,
        cached_grid,
        max_plus_batch,
    )
    from wavecontact.studies.ensemble import ensemble

    grid = cached_grid(GAMMA, modes, resolution)
    seeds = SpawnedSeeds(1, 0, samples)
    states = seed_states(seeds)
    normals = standard_normals(states, 4 * modes).reshape(samples, 2, 2, modes)
    temperatures = _temperature_rows(1.0, samples)
    block = slice(0, 32)  # the sampler's block of samples (BLOCK)
    coefficients = [c.copy() for c in grid.coefficients(normals[block], temperatures[block])]
    tables = [t.copy() for t in grid.tables(*coefficients)]
    q1, q2v, q2s, cell2, block2, reach2, _reach, starts = tables
    rows = SampleTables(q1, q2v, q2s, cell2, block2, reach2, starts)
    capacity = int(starts.max()) + 6 * grid.n1 + 4 * grid.j2
    work = np.empty(capacity), np.empty(capacity)
    w, nodes, status = np.empty(32), np.empty(32, dtype=np.int64), np.empty(32, dtype=np.int64)

    def kernel():
        max_plus_batch(grid.steps, rows, capacity, work, (w, nodes, status))

    pieces = {
        "seed words (SpawnedSeeds -> PCG64 state)": (lambda: seed_states(seeds), samples),
        f"{4 * modes} standard normals (PCG64 + ziggurat kernel)": (lambda: standard_normals(states, 4 * modes),
                                                                     samples),
        "noise coefficients": (lambda: grid.coefficients(normals[block], temperatures[block]), 32),
        "FFT tables and their bounds": (lambda: grid.tables(*coefficients), 32),
        "recursion kernel (max_plus_batch)": (kernel, 32),
        "ensemble(...) per sample, all included": (
            lambda: ensemble(GAMMA, math.inf, 1.0, samples, 1, bath_modes=modes, hard_core_resolution=resolution),
            samples),
    }
    ensemble(GAMMA, math.inf, 1.0, 8, 0, bath_modes=modes, hard_core_resolution=resolution)  # kernels ready
    kernel()
    out = {}
    for name, (function, count) in pieces.items():
        out[name] = 1e6 * float(np.median([cpu(function) for _ in range(repeats)])) / count
    return out, float(np.mean(nodes)), grid


def numpy_object_costs(modes, samples=2000, repeats=5):
    """CPU microseconds per sample of NumPy's per-sample objects, the path bath/streams.py replaces."""
    seed = 1
    children = [np.random.SeedSequence(seed, spawn_key=(j,)) for j in range(samples)]
    generator = np.random.default_rng(0)
    out = np.empty(4 * modes)
    pieces = {
        "SeedSequence(seed).spawn(n), per child": lambda: np.random.SeedSequence(seed).spawn(samples),
        "SeedSequence(seed, spawn_key=(j,)) built directly": lambda: [
            np.random.SeedSequence(seed, spawn_key=(j,)) for j in range(samples)],
        "default_rng(child)": lambda: [np.random.default_rng(c) for c in children],
        "Generator(PCG64(child))": lambda: [np.random.Generator(np.random.PCG64(c)) for c in children],
        "child.generate_state(4, uint64) (what PCG64 seeds from)": lambda: [
            c.generate_state(4, np.uint64) for c in children],
        f"Generator.standard_normal(out=...) of {4 * modes}, one call": lambda: [
            generator.standard_normal(out=out) for _ in range(samples)],
    }
    return {name: 1e6 * float(np.median([cpu(function) for _ in range(repeats)])) / samples
            for name, function in pieces.items()}


def main_hard_core(args):
    print("NumPy's per-sample objects (the path before bath/streams.py); CPU us per sample, medians")
    print("| piece | CPU us per sample |")
    print("|---|---|")
    for name, value in numpy_object_costs(args.modes).items():
        print(f"| {name} | {value:.1f} |")
    print()
    pieces, nodes, grid = hard_core_pieces(args.modes, args.resolution)
    print(f"hard-core mode: gamma {GAMMA}, T_B/E_tr 1, nu_max {args.modes}, {args.resolution} points per period "
          f"(n_1 = {grid.n1} nodes per Gamma_1, rod 2's table {grid.n2}); CPU us per sample, medians")
    print("| piece | CPU us per sample |")
    print("|---|---|")
    for name, value in pieces.items():
        print(f"| {name} | {value:.1f} |")
    print(f"\ngrid nodes per sample (mean over a block): {nodes:.0f}")
    return 0


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kappa", type=float, default=250.0)
    parser.add_argument("--modes", type=int, default=250)
    parser.add_argument("--samples", type=int, default=6)
    parser.add_argument("--hard-core", action="store_true", help="the batched hard-core sampler's pieces instead")
    parser.add_argument("--resolution", type=int, default=8, help="hard-core grid points per period (--hard-core)")
    args = parser.parse_args(argv)
    if args.hard_core:
        return main_hard_core(args)
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
