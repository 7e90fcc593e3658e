"""Do two checkouts run the rod gas bit for bit alike?  Final states of 19 runs, compared byte for byte.

Run: ``python benchmarks/gas_bit_identity.py --before DIR [--after DIR] [--pure] [--quick]``

``DIR`` is the root of a checkout of this repository (for instance
``git worktree add /tmp/before <commit>``); ``--after`` defaults to the
checkout this script belongs to.  Each side runs, in its own process with
its checkout first on ``PYTHONPATH``, the same 19 configurations: ring and
walls; the fixed rule (elastic, inelastic, collapsing), the analytic test
table (``tests/analytic_kick_table.py``), the hard-core law, the law with a
contact stiffness, a solve-per-collision rule; with and without bath
damping; 2, 3 and up to 10^5 rods (up to 300,000 collisions); two runs
resumed from a checkpoint halfway.  For each it saves the simulation state
(``GasSimulation._STATE``: rods, event times, collapse window, energies,
counters), the energy history and the status, and the two sides' arrays
must be equal in dtype, shape and bytes.  ``--pure`` runs the after side
without numba (``WAVECONTACT_PURE_PYTHON=1``; use it with ``--quick``, which
leaves out the two runs above 60,000 collisions).  About a minute compiled.
Prints one line per differing array and a summary; exit status 1 if any differ.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

_HERE = Path(__file__).resolve().parent


def _configurations():
    """``(name, make, collisions)``: ``make()`` returns ``(gas, rule, keyword arguments)``."""
    from analytic_kick_table import analytic_kick_table

    from wavecontact.gas import (
        EqualLengths,
        FixedRestitution,
        UniformLengths,
        VibrationLaw,
        VibrationSolve,
        VibrationTable,
        default_law,
        default_soft_law,
        random_gas,
    )

    table = VibrationTable(analytic_kick_table(levels=101))
    law = VibrationLaw(default_law())
    soft = VibrationLaw(default_law(), default_soft_law())
    lengths, wide = UniformLengths(0.6, 1.0), UniformLengths(0.5, 1.0)

    def solve_draw(gamma, ratio, seed):
        u = np.random.default_rng(seed).random()
        return 0.5 + 0.5 * u, u

    def gas(rods, seed, **options):
        return lambda: random_gas(rods, seed=seed, **options)

    def config(name, make_gas, rule, collisions, **keywords):
        return name, (lambda: (make_gas(), rule, keywords)), collisions

    return [
        config("ring_fixed1_1e4", gas(10_000, 1, packing_fraction=0.2, lengths=lengths), FixedRestitution(1.0), 200_000),
        config("ring_fixed09_200", gas(200, 3), FixedRestitution(0.9), 20_000),
        config("ring_fixed07_50", gas(50, 4), FixedRestitution(0.7), 50_000),
        config("walls_fixed1_equal", gas(300, 5, lengths=EqualLengths(0.2), boundary="walls"), FixedRestitution(1.0),
               30_000),
        config("walls_fixed095", gas(400, 6, lengths=lengths, boundary="walls"), FixedRestitution(0.95), 30_000),
        config("ring_table", gas(500, 7, lengths=wide, bath_temperature=1e-3), table, 30_000),
        config("ring_table_damped", gas(500, 8, lengths=wide, bath_temperature=1e-3), table, 30_000, damping=3.0),
        config("walls_table_damped", gas(300, 9, lengths=wide, bath_temperature=1e-3, boundary="walls"), table,
               30_000, damping=2.0),
        config("ring_law", gas(1000, 10, lengths=lengths), law, 50_000),
        config("ring_law_damped", gas(1000, 11, lengths=lengths), law, 50_000, damping=5.0),
        config("ring_law_stiff", gas(1000, 12, lengths=lengths), soft, 50_000, contact_stiffness=100.0),
        config("walls_law_stiff_damped", gas(500, 13, lengths=lengths, boundary="walls"), soft, 30_000,
               contact_stiffness=30.0, damping=4.0),
        config("ring_solve", gas(100, 14, lengths=wide), VibrationSolve(solve_draw, bath_modes=10), 3_000),
        config("ring_3_rods", gas(3, 15), FixedRestitution(0.5), 10_000),
        config("ring_2_rods", gas(2, 16), FixedRestitution(0.99), 1000),
        config("walls_2_rods", gas(2, 17, boundary="walls"), FixedRestitution(0.9), 1000),
        config("ring_law_1e5", gas(100_000, 18, lengths=lengths), law, 300_000),
        config("resumed_law_stiff_damped", gas(300, 20, lengths=lengths, bath_temperature=0.01), soft, -6000,
               contact_stiffness=50.0, damping=5.0),
        config("resumed_walls_table_damped", gas(200, 21, lengths=wide, bath_temperature=0.01, boundary="walls"),
               table, -6000, damping=5.0),
    ]


def _worker(path, quick):
    """Run every configuration with the importable package and save the states to ``path`` (npz)."""
    sys.path.insert(0, str(_HERE.parent / "tests"))
    from wavecontact.gas import GasSimulation

    arrays = {}

    def keep(name, sim):
        for key in GasSimulation._STATE:
            arrays[f"{name}/{key}"] = np.asarray(getattr(sim, key)).copy()
        for key, values in sim.history.items():
            arrays[f"{name}/history_{key}"] = np.asarray(values)
        arrays[f"{name}/status"] = np.asarray(sim.status)

    with tempfile.TemporaryDirectory() as scratch:
        for name, make, collisions in _configurations():
            if quick and abs(collisions) > 60_000:
                continue
            gas, rule, keywords = make()
            if collisions > 0:
                sim = GasSimulation(gas, rule, seed=2, record_every=max(1, collisions // 7), **keywords)
                sim.run(collisions)
            else:  # half, a checkpoint, the other half from the checkpoint
                first = GasSimulation(gas, rule, seed=2, record_every=250, **keywords)
                first.run(-collisions // 2 + 13)
                sim = GasSimulation.resume(first.save_checkpoint(Path(scratch) / f"{name}.npz"))
                sim.run(-collisions - (-collisions // 2 + 13))
            keep(name, sim)
    np.savez(path, **arrays)


def _run_side(root, path, quick, pure):
    env = dict(os.environ, PYTHONPATH=str(root), WAVECONTACT_PURE_PYTHON="1" if pure else "0")
    command = [sys.executable, str(Path(__file__).resolve()), "--worker", str(path)] + (["--quick"] if quick else [])
    subprocess.run(command, env=env, cwd=root, check=True, timeout=3600)
    with np.load(path) as data:
        return {key: data[key] for key in data.files}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, help="root of the checkout to compare against")
    parser.add_argument("--after", type=Path, default=_HERE.parent, help="root of the checkout checked (default: this one)")
    parser.add_argument("--pure", action="store_true", help="run the after side without numba")
    parser.add_argument("--quick", action="store_true", help="leave out the two runs above 60,000 collisions")
    parser.add_argument("--worker", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        _worker(args.worker, args.quick)
        return 0
    if args.before is None:
        parser.error("--before DIR is required")
    for name in ("before", "after"):
        root = getattr(args, name).resolve()
        if not (root / "wavecontact" / "__init__.py").is_file():
            parser.error(f"--{name} {root} is not the root of a checkout (no wavecontact/__init__.py)")
    with tempfile.TemporaryDirectory() as scratch:
        before = _run_side(args.before.resolve(), Path(scratch) / "before.npz", args.quick, False)
        after = _run_side(args.after.resolve(), Path(scratch) / "after.npz", args.quick, args.pure)
    differ = 0
    for key, value in before.items():
        other = after.get(key)
        if other is None or other.dtype != value.dtype or other.shape != value.shape or other.tobytes() != value.tobytes():
            differ += 1
            print(f"differs: {key}")
    runs = len({key.split("/")[0] for key in before})
    side = "pure Python" if args.pure else "compiled"
    print(f"{len(before)} arrays of {runs} runs compared (after side {side}): {differ} differ")
    return 1 if differ or set(after) != set(before) else 0


if __name__ == "__main__":
    sys.exit(main())
