"""Accuracy tables of docs/fem.md, one command:

    python benchmarks/fem_accuracy_tables.py [--quick]

1. epsilon_FE - epsilon_delay (signed; hard contact: - gamma) for the default discretization
   (P1 lumped, exact lattice) at N = 200, 800, 3200 elements (docs/fem.md section 7);
2. two-material hard impacts (steel 0.1 m on aluminium 0.3 m and on CFRP 0.15 m, 1 cm^2, 1 m/s)
   against the characteristic solution of tests/test_fem_far_ends.py (section 1);
3. orders at fixed far-end remainders (gamma = 0.6, kappa = 100);
4. the other discretizations (P1 consistent, P2, P1 lumped at Courant 0.9, user meshes) at gamma = 0.6,
   kappa = 20 on 24 .. 192 elements (``discretizations``) and at kappa = 100 on 96 .. 768 elements
   (``discretizations-100``, ``quadrature``, ``gamma-one``, ``dispersive``), with the force scheme ('auto') and the interface scheme forced.
``--quick`` prints only tables 2 and 3; ``--table NAME`` (repeatable) only the named ones
(``default``, ``two-materials``, ``remainder-orders``, ``discretizations``,
``discretizations-100``, ``quadrature``, ``gamma-one``, ``dispersive``), which is how ``python docs/generate.py``
writes each table into docs/fem.md; ``--max-work 3e11`` lets the default table's finest cell run (2.3e11
updates, above the library's default limit).
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


DEFAULT_TABLE_MAX_WORK = 3e11


def table_default(max_work=None):
    """``max_work``: the cost limit of each FE solve (None: the library's default, which refuses the
    finest cell, gamma = 0.12 and kappa = 0.1 at 3200 elements, 2.3e11 updates; docs/fem.md passes 3e11)."""
    limits = {} if max_work is None else {"max_work": max_work}
    print("\n| gamma | kappa | N = 200 | 800 | 3200 |\n|---|---|---|---|---|")
    for gamma in GAMMAS:
        for kappa in KAPPAS:
            exact = gamma if math.isinf(kappa) else wc.collide(gamma, kappa, solver="delay", rtol=1e-13).restitution
            errors = [wc.collide(gamma, kappa, solver="fem", elements=n, **limits).restitution - exact
                      for n in (200, 800, 3200)]
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


DISCRETIZATIONS = (
    ("P1 consistent", {"order": 1, "mass": "consistent"}),
    ("P2 lumped", {"order": 2, "mass": "lumped"}),
    ("P2 consistent", {"order": 2, "mass": "consistent"}),
    ("P1 lumped, Courant 0.9", {"courant": 0.9}),
    ("P1 lumped, user meshes (N and 5N/4 elements)", {"unequal": True}),
)


def table_discretizations(gamma=0.6, kappa=20.0, meshes=(24, 48, 96, 192)):
    """Errors and log-log orders of the other discretizations (the long rod a whole number of elements)."""
    print(f"\n| discretization (gamma = {gamma}, kappa = {kappa:g}) | scheme | "
          + " | ".join(f"N = {n}" for n in meshes) + " | observed order |\n|---|---|" + "---|" * len(meshes) + "---|")
    reference = wc.collide(gamma, kappa, solver="delay", rtol=1e-13).restitution
    l1, l2 = (1 + gamma) / 2, (1 + gamma) / (2 * gamma)
    for scheme in ("auto", "interface"):
        for label, options in DISCRETIZATIONS:
            if scheme == "interface" and "unequal" in options:
                continue
            errors = []
            for n in meshes:
                kwargs = dict(options, scheme=scheme)
                if kwargs.pop("unequal", False):
                    kwargs["nodes"] = (np.linspace(0.0, l1, n + 1), np.linspace(0.0, l2, n * 5 // 4 + 1))
                result = wc.collide(gamma, kappa, solver="fem", elements=n, **kwargs)
                errors.append(abs(result.restitution - reference))
            order = -np.polyfit(np.log(meshes), np.log(errors), 1)[0]
            shown = "auto (force)" if scheme == "auto" else "interface (forced)"
            print(f"| {label} | {shown} | " + " | ".join(f"{e:.1e}" for e in errors) + f" | {order:.2f} |")


def table_quadrature():
    """gamma near 1: the two gap quadratures of the characteristic scheme at 800 and 3200 elements."""
    print("\n| gamma | kappa | substeps 800 | substeps 3200 | gauss 800 | gauss 3200 |\n|---|---|---|---|---|---|")
    for gamma in (0.95, 0.99, 1.0):
        for kappa in (100.0, 1e3, 1e4, 1e5, 1e6):
            exact = wc.collide(gamma, kappa, solver="delay", rtol=1e-13).restitution
            errors = [wc.collide(gamma, kappa, solver="fem", elements=n, gap_quadrature=q).restitution - exact
                      for q in ("substeps", "gauss") for n in (800, 3200)]
            print(f"| {gamma} | {kappa:g} | " + " | ".join(f"{e:+.1e}" for e in errors) + " |")


def table_gamma_one():
    """Equal rods at unresolved finite stiffness: |epsilon - 1| until the mesh resolves the release."""
    meshes = (800, 3200, 6400, 12800, 25600, 51200)
    print("\n| kappa | " + " | ".join(f"N = {n}" for n in meshes) + " |\n|---|" + "---|" * len(meshes))
    for kappa, largest in ((1e4, 3200), (1e5, 51200), (1e6, 51200)):
        errors = [f"{abs(wc.collide(1.0, kappa, solver='fem', elements=n).restitution - 1.0):.1e}" if n <= largest
                  else "" for n in meshes]
        print(f"| {kappa:.0e} | " + " | ".join(errors) + " |")


def table_dispersive(meshes=(200, 400, 800, 1600, 3200)):
    """Hard contact (gamma = 0.6) on the dispersive discretizations: |epsilon - gamma| and its order."""
    print("\n| discretization (hard contact, gamma = 0.6) | " + " | ".join(f"N = {n}" for n in meshes)
          + " | observed order |\n|---|" + "---|" * len(meshes) + "---|")
    for label, options in DISCRETIZATIONS[1:2] + DISCRETIZATIONS[0:1] + DISCRETIZATIONS[3:4]:
        errors = [abs(wc.collide(0.6, math.inf, solver="fem", elements=n, **options).restitution - 0.6) for n in meshes]
        order = -np.polyfit(np.log(meshes), np.log(errors), 1)[0]
        print(f"| {label} | " + " | ".join(f"{e:.1e}" for e in errors) + f" | {order:.2f} |")


def table_discretizations_100():
    table_discretizations(kappa=100.0, meshes=(96, 192, 384, 768))


TABLES = {"dispersive": table_dispersive, "quadrature": table_quadrature, "gamma-one": table_gamma_one, "discretizations": table_discretizations, "discretizations-100": table_discretizations_100, "two-materials": table_two_materials, "remainder-orders": table_remainder_orders, "default": table_default}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="only the two-materials and remainder-orders tables")
    parser.add_argument("--table", action="append", choices=sorted(TABLES), help="only this table (repeatable)")
    parser.add_argument("--max-work", type=float, default=DEFAULT_TABLE_MAX_WORK,
                        help="cost limit (updates) of each FE solve of the default table (default 3e11: its finest "
                        "cell, gamma 0.12 and kappa 0.1 at 3200 elements, needs 2.3e11, above the library's 2e11)")
    args = parser.parse_args(argv)
    names = args.table or ["two-materials", "remainder-orders"] + ([] if args.quick else ["default", "discretizations", "discretizations-100", "quadrature", "gamma-one", "dispersive"])
    for name in names:
        TABLES[name](**({"max_work": args.max_work} if name == "default" and args.max_work else {}))


if __name__ == "__main__":
    main()
