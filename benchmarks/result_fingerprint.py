"""SHA-256 fingerprints of a fixed set of results, to prove a refactoring changed no number.

Run it before a change and after it (``python benchmarks/result_fingerprint.py --json before.json``,
then ``--compare before.json``): every case whose numbers moved by even one bit is named.  The cases
cover the cold two-rod collision with each solver and discretization, the hard core, a thermal
realisation, two materials, a ring run, a gas run, Markov chains and an ensemble.  Only computed
numbers enter a fingerprint (restitution, estimates of the error, state arrays), never timings.

Each case is small (the whole set takes about a minute once the kernels are compiled).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import sys

import numpy as np


def _digest(*values) -> str:
    digest = hashlib.sha256()
    for value in values:
        array = np.ascontiguousarray(np.asarray(value, dtype=float))
        digest.update(str(array.shape).encode())
        digest.update(array.tobytes())
    return digest.hexdigest()[:16]


def _collide(gamma, kappa, solver="delay", **options):
    import wavecontact

    result = wavecontact.collide(gamma, kappa, solver=solver, **options)
    return _digest(result.restitution, result.error_estimate)


def _two_materials(solver, **options):
    from wavecontact import Hard, Rod, Scene, solve

    scene = Scene(rods=(Rod(0.16538, 1813.71, 1.97261e11, 3.16684e-5), Rod(0.50474, 3367.81, 4.07944e10, 3.21736e-5)),
                  velocities=(1.62297, 0.0), contact=Hard())
    result = solve(scene, solver, **options)
    return _digest(result.restitution)


def _ring():
    from wavecontact.studies.ring import run_ring

    run = run_ring(0.6173, 400.0, 10, 60, progress=False)
    return _digest(run.time, run.restitution, run.translational_energy, run.modal_energies)


def _gas():
    from wavecontact.gas import FixedRestitution, random_gas
    from wavecontact.gas.simulation import GasSimulation

    simulation = GasSimulation(random_gas(40, seed=3), FixedRestitution(0.9), seed=3, record_every=100)
    result = simulation.run(2000)
    return _digest(*(result.history[name] for name in sorted(result.history)), simulation.gas.velocities)


def _markov(kappa):
    from wavecontact.studies.markov import markov_chains

    result = markov_chains(0.6, kappa=kappa, chains=2, steps=8 if math.isfinite(kappa) else 200, seed=5,
                           bath_modes=50)
    return _digest(result.energy, result.temperature, result.eps2)


def _ensemble():
    import wavecontact

    result = wavecontact.ensemble(0.6173, math.inf, 1.0, samples=200, seed=8)
    return _digest(result.restitution)


CASES = {
    "delay cold gamma 0.6 kappa 100": lambda: _collide(0.6, 100),
    "delay cold gamma 0.6 kappa 5": lambda: _collide(0.6, 5),
    "delay hard core gamma 0.6": lambda: _collide(0.6, math.inf),
    "delay thermal T 1 seed 7": lambda: _collide(0.6173, 100, bath_temperature=1.0, bath_modes=250, seed=7),
    "fem P1 lumped 200": lambda: _collide(0.6, 100, "fem", elements=200, order=1, mass="lumped"),
    "fem P1 consistent 200": lambda: _collide(0.6, 100, "fem", elements=200, order=1, mass="consistent"),
    "fem P2 lumped 100": lambda: _collide(0.6, 100, "fem", elements=100, order=2, mass="lumped"),
    "fem P2 consistent 100": lambda: _collide(0.6, 100, "fem", elements=100, order=2, mass="consistent"),
    "fem hard 100": lambda: _collide(0.6, math.inf, "fem", elements=100),
    "modal cold 100 modes": lambda: _collide(0.6, 100, "modal", modes=100),
    "two materials delay": lambda: _two_materials("delay"),
    "two materials fem": lambda: _two_materials("fem", elements=100),
    "ring 60 collisions": _ring,
    "gas 40 rods": _gas,
    "markov hard core": lambda: _markov(math.inf),
    "markov kappa 100": lambda: _markov(100.0),
    "ensemble hard core": _ensemble,
}


def fingerprints(names=None) -> dict:
    """Compute the fingerprint of each case (all of them by default); a failing case gives its error."""
    out = {}
    for name, case in CASES.items():
        if names and name not in names:
            continue
        try:
            out[name] = case()
        except Exception as error:  # noqa: BLE001 - a case that cannot run is reported, not fatal
            out[name] = f"error: {type(error).__name__}: {error}"
        print(f"{name:36s} {out[name]}", file=sys.stderr)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the fingerprints to this JSON file")
    parser.add_argument("--compare", help="compare with fingerprints written earlier by --json")
    args = parser.parse_args(argv)
    current = fingerprints()
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(current, handle, indent=1)
    total = hashlib.sha256(json.dumps(current, sort_keys=True).encode()).hexdigest()
    print(f"overall SHA-256: {total}")
    if args.compare:
        with open(args.compare) as handle:
            before = json.load(handle)
        changed = [name for name in before if before[name] != current.get(name)]
        print("| case | before | after |\n|---|---|---|")
        for name in before:
            mark = "" if name not in changed else " **changed**"
            print(f"| {name} | {before[name]} | {current.get(name)}{mark} |")
        print(f"{len(changed)} of {len(before)} cases changed")
        return 1 if changed else 0
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
