"""How accurate must an ensemble sample be? One command, two tables (issue 11, docs/bath.md section 4).

    python benchmarks/ensemble_accuracy.py [--samples 200] [--quick] [--update-docs]

``--update-docs`` writes the tables into docs/bath.md (between its ensemble-accuracy markers).

Table 1: for Fig. 8 points (kappa = 250, nu_max = 250) the same samples (same seeds) are
solved at the ensemble's defaults (``ENSEMBLE_DELAY_OPTIONS``: rtol 1e-3, Lobatto-Kronrod rule,
16 noise table nodes per period of the fastest mode) and at other settings, against a reference
at rtol 1e-10 with the Gauss-Kronrod rule and 64 nodes. Per row:
the shift of the ensemble mean (with the standard error of that paired shift), the largest
per-sample difference, the largest per-sample error estimate, the standard error of the mean
itself, and the CPU time per sample (``time.process_time``; the machine may be shared).

Table 2: the step control's claimed local errors against the actual ones on the contact
steps of a few samples at the ensemble's defaults. For each accepted step with ``W' > 1e-3``:
the quadrature estimate (Kronrod against its embedded rule) against the error of the step's
increment, recomputed with the same history by 64-point Gauss-Legendre; and the
interpolation estimate (quintic against quartic Hermite) against the largest distance between
the stored quintic Hermite and the step's own solution, recomputed at 16 points.

Table 3: what the resolution of the noise tables alone moves, at rtol 1e-9.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from docs_block import run_and_write

from wavecontact.bath import ThermalBath
from wavecontact.delay import kernels
from wavecontact.solvers import get_solver
from wavecontact.studies.ensemble import ENSEMBLE_DELAY_OPTIONS, sample_seed

KAPPA = 250.0
CASES = ((0.6173, 0.1), (0.6173, 0.5), (0.6173, 1.0), (0.2173, 0.1), (0.2173, 0.5), (0.2173, 1.0))
REFERENCE = {"rtol": 1e-10, "noise_resolution": 64}
VARIANTS = (("ensemble default", ENSEMBLE_DELAY_OPTIONS),
            ("same, 32 noise nodes", {**ENSEMBLE_DELAY_OPTIONS, "noise_resolution": 32}),
            ("same, rtol 1e-2", {**ENSEMBLE_DELAY_OPTIONS, "rtol": 1e-2}),
            ("rtol 1e-3, Gauss", {"rtol": 1e-3}),
            ("rtol 1e-6, Gauss (before)", {"rtol": 1e-6}))


def solve_all(gamma, temperature, seeds, options):
    """epsilon, error estimates and CPU seconds per sample of the batched fast path."""
    solver = get_solver("delay")
    started = time.process_time()
    eps, errors = solver.thermal_restitutions(gamma, KAPPA, ThermalBath(temperature, 250), seeds, options)
    return eps, errors, (time.process_time() - started) / len(seeds)


def accuracy_table(samples):
    get_solver("delay").thermal_restitutions(0.6173, KAPPA, ThermalBath(1.0, 250), [0],
                                             ENSEMBLE_DELAY_OPTIONS)  # kernels ready
    print(f"kappa {KAPPA:g}, nu_max 250, {samples} samples a point (seed 8, as Fig. 8); reference rtol 1e-10, "
          "64 noise nodes")
    print("| gamma | T_B/E_tr | solve | mean shift (paired SE) | max abs difference | max error estimate "
          "| SE of the mean | CPU ms/sample |")
    print("|---|---|---|---|---|---|---|---|")
    for gamma, temperature in CASES:
        seeds = [sample_seed(8, j) for j in range(samples)]
        reference = solve_all(gamma, temperature, seeds, REFERENCE)[0]
        standard_error = reference.std(ddof=1) / math.sqrt(samples)
        for name, options in VARIANTS:
            eps, errors, cpu = solve_all(gamma, temperature, seeds, options)
            diff = eps - reference
            print(f"| {gamma} | {temperature:g} | {name} | {diff.mean():+.1e} ({diff.std(ddof=1) / math.sqrt(samples):.0e})"
                  f" | {np.max(np.abs(diff)):.1e} | {np.max(errors):.1e} | {standard_error:.1e} | {1e3 * cpu:.2f} |",
                  flush=True)


def _gauss(points):
    x, w = np.polynomial.legendre.leggauss(points)
    return 0.5 * (x + 1.0), 0.5 * w


def _quintic(t, w, d1, d2, j, s):
    return kernels.hermite5_on(t, w, d1, d2, j, s)[0]


def step_claims(gamma, temperature, seed, options):
    """Claimed and actual local errors (units of W / kappa) of the contact steps of one sample."""
    from wavecontact.bath.collide import thermal_scene
    from wavecontact.bath.scene import scene_noise
    from wavecontact.delay import solver as delay

    scene = thermal_scene(gamma, KAPPA, ThermalBath(temperature, 250), seed)
    a0 = KAPPA * scene.gaps[0]
    tables = scene_noise(scene, KAPPA, a0, options["noise_resolution"])
    t, w, d1, d2, _error, _work, _a0 = delay._integrate(gamma, KAPPA, options["rtol"], a0, None, None, 2_000_000, 1.0,
                                                        tables, options["quadrature"])
    delays = np.array([1.0 + gamma, 1.0 + 1.0 / gamma])
    weights = np.ones(2)
    comb = np.zeros((6, t.size))
    significant = np.nonzero(d1 > 1e-18 * KAPPA)[0]
    t_significant = t[max(significant[0] - 1, 0)]
    nodes, weights_k, weights_g = kernels.QUADRATURE_RULES[options["quadrature"]]
    fine_x, fine_w = _gauss(64)
    out = []

    def g(s, last):
        return kernels._exponent((s, KAPPA, a0, t_significant), t, w, d1, d2, last, delays, weights, None,
                                 (tables.periods, tables.values, tables.slopes), comb, None)[0]

    def log_integral(t0, t1, last):
        values = np.array([g(t0 + (t1 - t0) * x, last) for x in fine_x])
        top = values.max()
        return top + math.log((t1 - t0) * float(np.sum(fine_w * np.exp(values - top))))

    for j in np.nonzero(d1[1:] > 1e-3)[0]:
        t0, t1 = t[j], t[j + 1]
        h = t1 - t0
        exact = np.logaddexp(w[j], log_integral(t0, t1, j))
        # the rule's own estimate, as the kernel forms it (secant taken out, nodes in e^{a s})
        g0, g1 = g(t0, j), g(t1, j)
        a = (g1 - g0) / h
        z = a * h
        s = h + np.log1p((1.0 - nodes) * math.expm1(-z)) / a if abs(z) > 1e-9 else h * nodes
        r = np.array([g(t0 + x, j) for x in s]) - g0 - a * s
        share = math.exp(log_integral(t0, t1, j) - w[j + 1])  # the increment's share of e^W
        claimed_quadrature = share * abs(1.0 - np.sum(weights_g * np.exp(r)) / np.sum(weights_k * np.exp(r)))
        top = 12.0 * (w[j] - w[j + 1]) + 6.0 * h * (d1[j] + d1[j + 1]) + h * h * (d2[j] - d2[j + 1])
        claimed_interpolation = kernels._QUARTIC_GAP * abs(top)
        inner = np.linspace(0.0, 1.0, 18)[1:-1]
        actual_interpolation = max(abs(_quintic(t, w, d1, d2, j, t0 + x * h)
                                       - np.logaddexp(w[j], log_integral(t0, t0 + x * h, j))) for x in inner)
        out.append((claimed_quadrature, abs(w[j + 1] - exact), claimed_interpolation, actual_interpolation))
    return np.array(out) / KAPPA


def claims_table(samples):
    options = ENSEMBLE_DELAY_OPTIONS
    print()
    print(f"contact steps (W' > 1e-3) of {samples} samples per point at the ensemble defaults {options}; "
          "errors in units of epsilon")
    print("| gamma | T_B/E_tr | steps | quadrature: claimed sum | actual sum | median claimed/actual "
          "| interpolation: claimed sum | actual sum | median claimed/actual |")
    print("|---|---|---|---|---|---|---|---|---|")
    for gamma, temperature in ((0.6173, 1.0), (0.2173, 0.5)):
        rows = np.concatenate([step_claims(gamma, temperature, sample_seed(8, j), options) for j in range(samples)])
        floor = 1e-16  # round-off of W / kappa: ratios of errors below it say nothing
        ratio_q = np.median(rows[:, 0] / np.maximum(rows[:, 1], floor))
        ratio_i = np.median(rows[:, 2] / np.maximum(rows[:, 3], floor))
        print(f"| {gamma} | {temperature:g} | {rows.shape[0]} | {rows[:, 0].sum():.1e} | {rows[:, 1].sum():.1e} "
              f"| {ratio_q:.0f} | {rows[:, 2].sum():.1e} | {rows[:, 3].sum():.1e} | {ratio_i:.0f} |", flush=True)


def resolution_table(samples):
    """Table 3: what the noise tables' resolution alone moves (rtol 1e-9, against 128 nodes a period)."""
    print()
    print(f"noise table nodes per period of the fastest mode, rtol 1e-9 (Gauss-Kronrod), {samples} samples a point; "
          "differences to 128 nodes")
    print("| gamma | T_B/E_tr | nodes | mean shift | max abs difference |")
    print("|---|---|---|---|---|")
    for gamma, temperature in ((0.6173, 0.1), (0.6173, 1.0), (0.2173, 0.5)):
        seeds = [sample_seed(8, j) for j in range(samples)]
        reference = solve_all(gamma, temperature, seeds, {"rtol": 1e-9, "noise_resolution": 128})[0]
        for nodes in (8, 16, 32):
            diff = solve_all(gamma, temperature, seeds, {"rtol": 1e-9, "noise_resolution": nodes})[0] - reference
            print(f"| {gamma} | {temperature:g} | {nodes} | {diff.mean():+.1e} | {np.max(np.abs(diff)):.1e} |",
                  flush=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=200, help="samples per point of table 1 (default 200)")
    parser.add_argument("--quick", action="store_true", help="50 samples a point, 1 sample in table 2")
    parser.add_argument("--update-docs", action="store_true",
                        help="write the tables into docs/bath.md (its ensemble-accuracy block)")
    args = parser.parse_args(argv)
    samples = 50 if args.quick else args.samples

    def tables():
        accuracy_table(samples)
        claims_table(1 if args.quick else 3)
        resolution_table(10 if args.quick else 40)

    run_and_write(tables, "bath.md", "ensemble-accuracy", args.update_docs)
    return 0


if __name__ == "__main__":
    sys.exit(main())
