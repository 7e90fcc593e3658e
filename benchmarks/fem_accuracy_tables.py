"""Accuracy tables of docs/fem.md, one command:

    python benchmarks/fem_accuracy_tables.py [--quick]

1. epsilon_FE - epsilon_delay (signed; hard contact: - gamma) for the default discretization
   (P1 lumped, exact lattice) at N = 200, 800, 3200 elements (docs/fem.md section 7);
2. two-material hard impacts (steel 0.1 m on aluminium 0.3 m and on CFRP 0.15 m, 1 cm^2, 1 m/s)
   against the characteristic solution of tests/test_fem_far_ends.py (section 1);
3. orders at fixed far-end remainders (gamma = 0.6, kappa = 100).
``--quick`` prints only tables 2 and 3.
"""

from __future__ import annotations

import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))

from test_fem_far_ends import ALUMINIUM, CFRP, STEEL, characteristic_impact

import wavecontact as wc
from wavecontact import Hard, Scene

GAMMAS = (0.6, 0.6173, 0.3, 0.12, 0.95, 0.99, 1.0)
KAPPAS = (0.1, 1.0, 5.0, 20.0, 100.0, 1e3, 1e4, 1e5, 1e6, math.inf)


def table_default():
    print("\n| gamma | kappa | N = 200 | 800 | 3200 |\n|---|---|---|---|---|")
    for gamma in GAMMAS:
        for kappa in KAPPAS:
            exact = gamma if math.isinf(kappa) else wc.collide(gamma, kappa, solver="delay", rtol=1e-13).restitution
            errors = [wc.collide(gamma, kappa, solver="fem", elements=n).restitution - exact for n in (200, 800, 3200)]
            print(f"| {gamma} | {kappa:g} | " + " | ".join(f"{e:+.1e}" for e in errors) + " |")


def table_two_materials():
    print("\n| long rod | N (steel) | far-end remainder (elements) | epsilon_FE - epsilon_exact |\n|---|---:|---:|---:|")
    for name, other in (("aluminium 0.3 m", ALUMINIUM), ("CFRP 0.15 m", CFRP)):
        exact, _ = characteristic_impact(STEEL, other, 1.0, 0.0)
        for n in (200, 800, 3200, 12800):
            result = wc.solve(Scene(rods=(STEEL, other), velocities=(1.0, 0.0), contact=Hard()), "fem", elements=n)
            size = STEEL.length / n / STEEL.wave_speed * other.wave_speed
            remainder = other.length / size % 1.0
            print(f"| {name} (exact {exact:.10f}) | {n} | {remainder:.3f} | {result.restitution - exact:+.1e} |")


def table_remainder_orders():
    print("\n| remainder | N | error | | N | error | | N | error | fitted order |\n|---|---:|---:|---|---:|---:|---|---:|---:|---:|")
    reference = wc.collide(0.6, 100, solver="delay", rtol=1e-13).restitution
    for remainder, meshes in (("0", (24, 96, 384)), ("1/3", (50, 200, 800)), ("2/3", (25, 100, 400))):
        errors = [abs(wc.collide(0.6, 100, solver="fem", elements=n).restitution - reference) for n in meshes]
        order = -np.polyfit(np.log(meshes), np.log(errors), 1)[0]
        cells = " | |".join(f" {n} | {e:.1e}" for n, e in zip(meshes, errors))
        print(f"| {remainder} |{cells} | {order:.2f} |")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args(argv)
    table_two_materials()
    table_remainder_orders()
    if not args.quick:
        table_default()


if __name__ == "__main__":
    main()
