"""Benchmark of the rod gas: collisions per second of the event kernel, and a plain-Python heapq loop.

Run: ``python benchmarks/bench_gas.py [--repeats 5] [--collisions 2000000] [--only rates|heapq] [--update-docs]``

Prints two markdown tables (one core; the kernel is warmed up first, so no
compilation is timed).  Every time is given twice: wall-clock, and the CPU
time of this process (``time.process_time``).  On a machine shared with
other jobs the wall time grows with their load while the CPU time stays
close to what the work costs on an idle core, so both are shown:

1. the vibration rule (the shipped hard-core collision law, a table lookup in the kernel; and the same with a
   contact stiffness ``--stiffness ALPHA``, where each collision's kappa = alpha V l also looks up the soft law)
   and the fixed rule (r = 1) against N: median
   over ``--repeats`` runs of ``--collisions`` collisions each, continuing
   one gas (so the gas has left its initial state), as collisions per second
   and nanoseconds per collision;
2. at N = 10,000 with the fixed rule (r = 1), the same fresh gas run by the
   kernel (set-up included) and by :func:`wavecontact.gas.reference.heapq_ring_gas`
   (the straightforward ``heapq`` loop of Python granular-gas codes),
   repeats alternating between the two so that both see the same load, and
   the ratio of the medians.

``--update-docs`` also writes both tables into ``docs/gas.md`` between the
markers ``<!-- bench_gas:begin -->`` and ``<!-- bench_gas:end -->``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import wavecontact
from wavecontact.gas import (
    FixedRestitution,
    GasSimulation,
    UniformLengths,
    VibrationLaw,
    default_law,
    default_soft_law,
    random_gas,
)
from wavecontact.gas.reference import heapq_ring_gas

_LENGTHS = UniformLengths(0.6, 1.0)  # gamma in [0.6, 1], inside the default table
_DOCS = Path(__file__).resolve().parent.parent / "docs" / "gas.md"
_BEGIN, _END = "<!-- bench_gas:begin -->", "<!-- bench_gas:end -->"


def _timed(function):
    """(wall seconds, CPU seconds of this process) of one call."""
    wall, cpu = time.perf_counter(), time.process_time()
    function()
    return time.perf_counter() - wall, time.process_time() - cpu


def _medians(samples):
    """Median wall and CPU seconds of a list of ``_timed`` results."""
    return tuple(float(np.median([s[i] for s in samples])) for i in (0, 1))


def kernel_rate(rods, rule, collisions, repeats, stiffness=None):
    """Median (wall, CPU) seconds per collision of ``repeats`` runs continuing one gas."""
    gas = random_gas(rods, seed=1, packing_fraction=0.2, lengths=_LENGTHS)
    sim = GasSimulation(gas, rule, seed=2, record_every=collisions, max_frames=0, energy_floor=0.0,
                        contact_stiffness=stiffness)
    sim.run(min(collisions, 20 * rods))  # warm-up: compile/load the kernels, leave the initial transient
    samples = [_timed(lambda: sim.run(collisions)) for _ in range(repeats)]
    return tuple(s / collisions for s in _medians(samples))


def comparison_gas(rods):
    """The fresh gas of the heapq comparison (ring, lengths in [0.6, 1], packing fraction 0.2)."""
    return random_gas(rods, seed=1, packing_fraction=0.2, lengths=_LENGTHS)


def kernel_task(gas, restitution, collisions):
    """The kernel's side of the heapq comparison: a fresh simulation of ``gas`` (set-up included, the same
    task as the heapq loop's) run for ``collisions`` collisions with the fixed rule."""
    GasSimulation(gas, FixedRestitution(restitution), seed=2, record_every=10**9, max_frames=0,
                  energy_floor=0.0).run(collisions)


def kernel_against_heapq(rods, restitution, collisions, repeats):
    """Median (wall, CPU) seconds per collision of the kernel and of the heapq loop, alternating."""
    gas = comparison_gas(rods)
    GasSimulation(gas, FixedRestitution(restitution), seed=2, record_every=10**9, max_frames=0).run(10)  # warm-up

    def ours():
        kernel_task(gas, restitution, collisions)

    args = (gas.lengths, gas.positions, gas.velocities, gas.system_length, restitution, collisions)
    samples = {"ours": [], "heapq": []}
    for _ in range(repeats):
        samples["ours"].append(_timed(ours))
        samples["heapq"].append(_timed(lambda: heapq_ring_gas(*args)))
    return {name: tuple(s / collisions for s in _medians(values)) for name, values in samples.items()}


def _revision():
    """Short git commit of the imported package's tree (``+`` if it has uncommitted changes), or ``unknown``."""
    root = Path(wavecontact.__file__).resolve().parent
    try:
        commit = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True, timeout=10, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--", "."], capture_output=True,
                               text=True, timeout=10, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return commit + ("+" if dirty else "")


def _row(*cells):
    return "| " + " | ".join(cells) + " |"


def tables(args):
    """The report as markdown lines (printed as they are measured)."""
    lines = []

    def emit(line=""):
        lines.append(line)
        print(line, flush=True)

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    emit(f"wavecontact {wavecontact.__version__} at commit {_revision()} (the package imported; run from a "
         f"worktree with `PYTHONPATH=.` to measure its code rather than the installed one's).")
    emit()
    emit(f"`python benchmarks/bench_gas.py --repeats {args.repeats} --collisions {args.collisions} "
         f"--heapq-collisions {args.heapq_collisions} --stiffness {args.stiffness:g} "
         f"--rods {' '.join(map(str, args.rods))}{' --only ' + args.only if args.only else ''}`, run at {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())} "
         f"on a machine shared with other jobs (load average {load:.1f} on {os.cpu_count()} cores at the start). "
         f"Medians of {args.repeats} repeats; wall-clock and CPU time of this process.")
    emit()
    if args.only != "heapq":
        _rate_table(args, emit)
    if args.only != "rates":
        _heapq_table(args, emit)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    emit(f"(load average {load:.1f} at the end)")
    return lines


def _rate_table(args, emit):
    """Table 1: the kernel's collisions per second against N, per rule."""
    emit(_row("N", "rule", "collisions/s (wall)", "ns per collision (wall)", "collisions/s (CPU)",
              "ns per collision (CPU)"))
    emit("|---|---|---|---|---|---|")
    table = VibrationLaw(default_law(), default_soft_law())  # covers every pair state: never stops for the rule
    rows = (("vibration (hard-core law)", table, None),
            (f"vibration, contact stiffness alpha = {args.stiffness:g}", table, args.stiffness),
            ("fixed r = 1 (elastic)", FixedRestitution(1.0), None))
    for rods in args.rods:
        for name, rule, stiffness in rows:
            wall, cpu = kernel_rate(rods, rule, args.collisions, args.repeats, stiffness)
            emit(_row(f"{rods:,}", name, f"{1 / wall:,.0f}", f"{1e9 * wall:.0f}", f"{1 / cpu:,.0f}", f"{1e9 * cpu:.0f}"))
    emit()


def _heapq_table(args, emit):
    """Table 2: the kernel against the plain-Python heapq loop on the same gas."""
    rods, c = 10_000, args.heapq_collisions
    per = kernel_against_heapq(rods, 1.0, c, args.repeats)
    emit(f"Fixed rule r = 1, N = {rods:,}, {c:,} collisions from the same initial gas (a fresh simulation per "
         f"repeat, set-up included; repeats alternating between the two loops):")
    emit()
    emit(_row("loop", "collisions/s (wall)", "ratio (wall)", "collisions/s (CPU)", "ratio (CPU)"))
    emit("|---|---|---|---|---|")
    base_wall, base_cpu = per["heapq"]
    for name, key in (("wavecontact kernel (numba)", "ours"), ("plain Python heapq", "heapq")):
        wall, cpu = per[key]
        emit(_row(name, f"{1 / wall:,.0f}", f"{base_wall / wall:.0f}x", f"{1 / cpu:,.0f}", f"{base_cpu / cpu:.0f}x"))
    emit()


def update_docs(lines, path=_DOCS):
    """Replace the block between the markers in ``docs/gas.md`` by ``lines``."""
    text = path.read_text()
    if text.count(_BEGIN) != 1 or text.count(_END) != 1:
        raise SystemExit(f"{path} must contain the markers {_BEGIN} and {_END} once each")
    head, rest = text.split(_BEGIN)
    tail = rest.split(_END)[1]
    path.write_text(head + _BEGIN + "\n" + "\n".join(lines) + "\n" + _END + tail)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--collisions", type=int, default=2_000_000)
    parser.add_argument("--heapq-collisions", type=int, default=200_000)
    parser.add_argument("--rods", type=int, nargs="+", default=[100, 1_000, 10_000, 100_000, 1_000_000])
    parser.add_argument("--stiffness", type=float, default=100.0,
                        help="contact stiffness alpha of the soft-law rows (default 100)")
    parser.add_argument("--only", choices=("rates", "heapq"),
                        help="run only the rates against N, or only the comparison with the heapq loop")
    parser.add_argument("--update-docs", action="store_true", help=f"write the tables into {_DOCS}")
    args = parser.parse_args(argv)
    if args.update_docs and args.only:
        parser.error("--update-docs writes both tables: leave out --only")
    lines = tables(args)
    if args.update_docs:
        update_docs(lines)
    return 0


if __name__ == "__main__":
    np.seterr(all="raise")
    sys.exit(main())
