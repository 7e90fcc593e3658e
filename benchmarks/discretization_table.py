"""Which finite-element discretization is cheapest per target error, for users who must use one; one command:

    python benchmarks/discretization_table.py            # measures, then rewrites the block in docs/performance.md
    python benchmarks/discretization_table.py --print    # measures and prints the block only

For gamma = 0.6 and each kappa in {20, 100, 1e4, 1e6, inf}, every discretization (P1 lumped on the exact
lattice, P1 consistent, P2 lumped, P2 consistent; the step and contact scheme 'auto' picks) runs on meshes of
25, 50, 100, ... elements (short rod) until its error is below 1e-9 or one run takes longer than ``TIME_CAP``.
The error is |epsilon - reference| with the reference of :func:`wavecontact.studies.compare.reference_restitution`
(the delay equation at rtol = 1e-13; the hard-core recursion for kappa = inf); the time is the wall time of the
whole ``collide`` call, compiled kernels loaded beforehand, median of ``--repeats`` runs for runs under a second.
The table lists, per target error, the coarsest mesh of each discretization that reaches it and its time.

The block sits between ``<!-- discretizations:start -->`` and ``<!-- discretizations:end -->`` in
docs/performance.md; ``python benchmarks/performance.py`` writes the same block from its own runs
(:func:`discretization_block`), so either command regenerates it.
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))  # this checkout's package, not whichever one is installed

import wavecontact
from wavecontact.errors import WavecontactError
from wavecontact.studies.compare import reference_restitution

GAMMA = 0.6
KAPPAS = (20.0, 100.0, 1e4, 1e6, math.inf)
DISCRETIZATIONS = ((1, "lumped"), (1, "consistent"), (2, "lumped"), (2, "consistent"))
TARGETS = (1e-3, 1e-6, 1e-9)
ELEMENTS = tuple(25 * 2**k for k in range(10))  # 25 ... 12800
TIME_CAP = 3.0  # s: a discretization's meshes stop growing once one run takes longer
REPEAT_BELOW = 1.0  # s: shorter runs are repeated and the median kept
START, END = "<!-- discretizations:start -->", "<!-- discretizations:end -->"
HEADING = "Which discretization, for users who must use one"


def kappa_text(kappa):
    return "inf" if math.isinf(kappa) else f"{kappa:g}"


def name(order, mass):
    return f"P{order} {mass}"


def timed_collide(kappa, elements, order, mass, repeats):
    """``(epsilon, seconds)``: one ``collide`` call, its wall time the median of ``repeats`` if below 1 s."""
    options = {"solver": "fem", "elements": elements, "order": order, "mass": mass}
    started = time.perf_counter()
    epsilon = wavecontact.collide(GAMMA, kappa, **options).restitution
    times = [time.perf_counter() - started]
    while times[0] < REPEAT_BELOW and len(times) < repeats:
        started = time.perf_counter()
        wavecontact.collide(GAMMA, kappa, **options)
        times.append(time.perf_counter() - started)
    return epsilon, float(np.median(times))


def measure(kappa, repeats):
    """``{name: [(elements, error, seconds), ...]}`` for one kappa, meshes in increasing size."""
    reference = reference_restitution(GAMMA, kappa)[0]
    runs = {}
    for order, mass in DISCRETIZATIONS:
        rows = runs.setdefault(name(order, mass), [])
        for elements in ELEMENTS:
            try:
                epsilon, seconds = timed_collide(kappa, elements, order, mass, repeats)
            except WavecontactError as error:
                print(f"kappa = {kappa_text(kappa)}, {name(order, mass)}, {elements} elements: {error}",
                      file=sys.stderr)
                break
            rows.append((elements, abs(epsilon - reference), seconds))
            print(f"kappa = {kappa_text(kappa)}, {name(order, mass)}, {elements} elements: error "
                  f"{rows[-1][1]:.1e}, {seconds * 1e3:.1f} ms", file=sys.stderr, flush=True)
            if rows[-1][1] <= min(TARGETS) or seconds > TIME_CAP:
                break
    return runs


def runs_from_tables(tables):
    """The same ``{kappa: {name: [(elements, error, seconds)]}}`` from performance.py's comparison tables."""
    out = {}
    for kappa in KAPPAS:
        table = tables.get((GAMMA, kappa))
        if table is None:
            continue
        runs = out.setdefault(kappa, {})
        for row in table.rows:
            if row.solver != "fem" or not row.ok:
                continue
            label, _, size = row.resolution.partition(", ")
            runs.setdefault(label, []).append((int(size.split()[0]), row.error, row.wall_time_s))
    return out


def discretization_block(all_runs, command):
    """The Markdown block: per kappa and target, each discretization's coarsest mesh that reaches it."""
    names = [name(order, mass) for order, mass in DISCRETIZATIONS]
    lines = [
        START,
        (f"Generated {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M UTC} by `{command}` (gamma = {GAMMA}; "
         "the coarsest mesh that reaches the target: elements of the short rod, time of the whole `collide` call "
         "in ms; the cheapest of the four in bold; "
         "'-' where no mesh up to the largest one run reached the target, with its error; load average "
         f"{os.getloadavg()[0]:.1f} when the table was written, on {os.cpu_count()} cores)."),
        "",
        "| kappa | target error | " + " | ".join(names) + " |",
        "|---|---|" + "---|" * len(names),
    ]
    for kappa in KAPPAS:
        runs = all_runs.get(kappa)
        if runs is None:
            continue
        for target in TARGETS:
            cells, best = {}, None
            for label in names:
                rows = [r for r in runs.get(label, []) if math.isfinite(r[1])]
                good = [r for r in rows if r[1] <= target]
                if good:  # the coarsest mesh that reaches the target (times of neighbouring meshes are noisy)
                    elements, error, seconds = min(good, key=lambda r: r[0])
                    cells[label] = (f"{elements} el, {seconds * 1e3:.3g} ms", seconds)
                    best = label if best is None or seconds < cells[best][1] else best
                elif rows:
                    elements, error, _ = rows[-1]
                    cells[label] = (f"- ({error:.0e} at {elements})", None)
                else:
                    cells[label] = ("not run", None)
            texts = [f"**{cells[n][0]}**" if n == best else cells[n][0] for n in names]
            lines.append(f"| {kappa_text(kappa)} | {target:.0e} | " + " | ".join(texts) + " |")
    lines.append(END)
    return "\n".join(lines)


def write_block(path, block):
    """Replace the marked block in ``path`` (or append it under its own heading)."""
    text = path.read_text()
    if START in text and END in text:
        head, rest = text.split(START, 1)
        text = head + block + rest.split(END, 1)[1]
    else:  # first time: after the method recommendations, before the sections performance.py re-measures alone
        section = f"## {HEADING}\n\n{block}\n\n"
        head, marker, tail = text.partition("## Error against wall time")
        text = head + section + marker + tail if marker else text.rstrip("\n") + "\n\n" + section
    path.write_text(text)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="median over this many runs below 1 s (default 3)")
    parser.add_argument("--print", action="store_true", help="print the block instead of writing docs/performance.md")
    args = parser.parse_args(argv)
    wavecontact.collide(GAMMA, 100.0, solver="fem", elements=50)  # compile / load the kernels before timing
    for order, mass in DISCRETIZATIONS[1:]:
        wavecontact.collide(GAMMA, 100.0, solver="fem", elements=200, order=order, mass=mass)
    command = "python benchmarks/discretization_table.py" + (f" --repeats {args.repeats}" if args.repeats != 3 else "")
    block = discretization_block({kappa: measure(kappa, args.repeats) for kappa in KAPPAS}, command)
    if args.print:
        print(block)
        return
    report = ROOT / "docs" / "performance.md"
    write_block(report, block)
    print(f"wrote the discretization block of {report}", file=sys.stderr)


if __name__ == "__main__":
    main()
