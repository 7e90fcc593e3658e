"""How much of the shipped hard-core collision law is grid error: writes the block ``law_grid`` of docs/gas.md.

Run from the repository root: ``python docs/law_grid_study.py --samples 60 [--update-docs]`` (about 4 minutes
of CPU; ``--samples`` and ``--workers`` change the cost; from a git worktree put ``PYTHONPATH=.`` in front).

The law (:func:`wavecontact.gas.default_law`) is built with the hard-core max-plus solve at 16 grid points
per period of the fastest mode, except its ``gamma = 1`` rows, where the grid grows like ``sqrt(1/x)`` up
to a cap (``CollisionLaw.point_resolution``).  That grid's error is first order in the step and
proportional to the noise amplitude, which grows like ``sqrt(T_B/E_tr) = sqrt(1/x - 1)``.  For a few
``gamma`` and ``log10 x = 0 ... -4`` (both rods equally warm, ``s = 1/2``) this script solves the same
realisations (the same seeds at every resolution) at 16, 64, 256 and, where affordable, 1024 points per
period, and at the law's own resolution of that row, and prints the mean ``eps^2``, the short rod's mean
gain, and the error of the law's resolution against the finest grid as a paired mean with its standard
error.  A row of the law is *grid-limited* where that error exceeds the sampling error of the law's own
row mean (its ``eps^2`` spread over ``sqrt(400)``).  At ``gamma = 1`` the exact hard-core answer is
``eps^2 = 1`` in every realisation (the paper): there the error is measured against that exact value.
"""

from __future__ import annotations

import argparse
import math
import shlex
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
from docs_block import run_header, write_block

from wavecontact.gas import default_law
from wavecontact.gas.collision_law import REGENERATE, parser, point_samples, row_resolutions

GAMMAS = (0.6, 0.85, 0.9, 0.95, 1.0)
LOG_XS = (0.0, -1.0, -2.0, -3.0, -4.0)
RESOLUTIONS = (16, 64, 256, 1024)
LAW_RESOLUTION = 16  # the law's resolution where it does not refine
SEED = 4242


def affordable(gamma, log_x, resolution):
    """Resolution 1024 only down to ``x = 1e-3`` and for ``gamma = 0.6, 0.85, 1`` (at ``x = 1e-4`` it costs about
    2 s a solve, and some realisations exceed the solver's bound on grid points)."""
    return resolution < 1024 or (log_x > -4.0 and gamma in (0.6, 0.85, 1.0))


def law_resolution(gamma, log_x):
    """Grid points per period the shipped law's command (:data:`REGENERATE`) uses at ``(gamma, log_x)``: the
    nearest ``gamma`` row's cap (the resolution is decided per ``gamma`` row), its rule at ``log_x``.  Taken from
    the command so that the solves can run before the law is rebuilt; :func:`run` checks it against the file."""
    args = parser().parse_args(shlex.split(REGENERATE)[3:])
    caps = args.resolution_cap or [None]
    caps = caps * len(args.gamma) if len(caps) == 1 else caps
    a = int(np.argmin(np.abs(np.array(args.gamma) - gamma)))
    return row_resolutions([log_x], args.resolution, caps[a])[0]


def _task(args):
    gamma, log_x, resolution, samples, index = args
    seed = np.random.SeedSequence(SEED).spawn(len(GAMMAS) * len(LOG_XS))[index]
    cpu = time.process_time()
    eps2, gain = point_samples(gamma, log_x, samples, seed, resolution=resolution)
    return (gamma, log_x, resolution), eps2, gain, time.process_time() - cpu


def law_row(law, gamma, log_x):
    """``(mean eps^2, its sampling error)`` of the shipped law's row at ``s = 1/2`` (None if not on its grid)."""
    if gamma not in law.gamma or log_x not in law.log_x:
        return None
    a, b = list(law.gamma).index(gamma), list(law.log_x).index(log_x)
    quantiles = law.eps2_quantiles[0, a, b, list(law.short_share).index(0.5)]
    weights = np.zeros(law.probability.size)
    weights[1:] += 0.5 * np.diff(law.probability)
    weights[:-1] += 0.5 * np.diff(law.probability)
    mean = float(np.sum(quantiles * weights))
    spread = math.sqrt(max(float(np.sum((quantiles - mean) ** 2 * weights)), 0.0))
    return mean, spread / math.sqrt(law.samples_per_point)


def run(samples, workers):
    tasks = [(g, lx, r, samples, i * len(LOG_XS) + j) for i, g in enumerate(GAMMAS) for j, lx in enumerate(LOG_XS)
             for r in sorted(set(RESOLUTIONS) | {law_resolution(g, lx)}) if affordable(g, lx, r)]
    tasks.sort(key=lambda t: -t[2] * 10.0 ** (-t[1] / 2))  # dearest first
    with ProcessPoolExecutor(workers) as pool:
        results = {key: (eps2, gain, cpu) for key, eps2, gain, cpu in pool.map(_task, tasks)}
    law = default_law()  # read after the solves: the file must be the one its command builds
    for gamma in GAMMAS:
        if gamma in law.gamma:
            a = list(law.gamma).index(gamma)
            for log_x in LOG_XS:
                if law.point_resolution(a, list(law.log_x).index(log_x)) != law_resolution(gamma, log_x):
                    raise SystemExit("the shipped law's resolution differs from its command's: rebuild it first")
    cpu_total = sum(v[2] for v in results.values())
    print(f"{samples} hard-core solves per point (the same seeds at every resolution), 250 modes per bath, "
          f"s = 1/2; mean eps^2 +- standard error, in brackets the short rod's mean gain in units of "
          f"E_tr + T_pair. 'law's r' is the resolution the shipped law used for that row; 'grid error' the mean "
          "at the law's resolution minus the finest grid's on the same realisations (paired standard error), at "
          "gamma = 1 minus the exact 1; "
          f"'law' the shipped law's row mean +- its sampling error ({law.samples_per_point} solves). CPU time of "
          f"all solves: {cpu_total:.0f} s.")
    print()
    head = " | ".join(f"r = {r}" for r in RESOLUTIONS)
    print(f"| gamma | log10 x | {head} | law's r | grid error of the law's r | law | grid-limited |")
    print("|---|---|" + "---|" * len(RESOLUTIONS) + "---|---|---|---|")
    for gamma in GAMMAS:
        for log_x in LOG_XS:
            cells, finest = [], None
            for r in RESOLUTIONS:
                if (gamma, log_x, r) not in results:
                    cells.append("-")
                    continue
                eps2, gain, _cpu = results[(gamma, log_x, r)]
                sem = eps2.std(ddof=1) / math.sqrt(eps2.size)
                cells.append(f"{eps2.mean():.4g} +- {sem:.2g} ({gain.mean():+.3g})")
                finest = r
            own = law_resolution(gamma, log_x)
            finest = max(finest, own)
            # gamma = 1: the exact eps^2 = 1 is the reference; otherwise the finest grid on the same realisations
            reference = 1.0 if gamma == 1.0 else results[(gamma, log_x, finest)][0]
            diff = results[(gamma, log_x, own)][0] - reference
            paired = diff.std(ddof=1) / math.sqrt(diff.size)
            row = law_row(law, gamma, log_x)
            law_cell = "-" if row is None else f"{row[0]:.4g} +- {row[1]:.2g}"
            limited = "-" if row is None else ("yes" if abs(diff.mean()) > max(row[1], 2 * paired, 1e-9) else "no")
            versus = "exact 1" if gamma == 1.0 else finest
            error = "finest grid" if own == finest and gamma != 1.0 else \
                f"{diff.mean():+.3g} +- {paired:.2g} (vs {versus})"
            own_cell = f"{own}" if own in RESOLUTIONS else \
                f"{own}: {results[(gamma, log_x, own)][0].mean():.4g}"
            print(f"| {gamma:g} | {log_x:g} | " + " | ".join(cells)
                  + f" | {own_cell} | {error} | {law_cell} | {limited} |")
    print()
    print("CPU seconds per solve (mean over the point's solves):")
    print()
    print("| gamma | log10 x | " + head + " |")
    print("|---|---|" + "---|" * len(RESOLUTIONS))
    for gamma in GAMMAS:
        for log_x in LOG_XS:
            cells = [f"{results[(gamma, log_x, r)][2] / samples:.3g}" if (gamma, log_x, r) in results else "-"
                     for r in RESOLUTIONS]
            print(f"| {gamma:g} | {log_x:g} | " + " | ".join(cells) + " |")
    print()
    rebuild_costs(law, {k: v for k, v in results.items() if k[0] in (0.6, 0.85, 1.0)}, samples)


def rebuild_costs(law, results, samples):
    """Print the CPU a rebuild of the shipped law would take under the rule ``min(cap, ceil(16 sqrt(1/x)))``.

    Per-solve CPU of the law's rows is interpolated from the measured table (mean over ``GAMMAS``), log-linear
    in ``log10 x`` and log-log in the resolution; the law's grid is ``gamma x log_x x s`` with
    ``samples_per_point`` solves per point.
    """
    measured = np.array([[np.mean([v[2] / samples for (g, x, q), v in results.items() if (x, q) == (lx, r)])
                          for r in RESOLUTIONS[:3]] for lx in LOG_XS])  # r = 1024 is missing at some rows
    ascending = np.argsort(LOG_XS)
    points = law.gamma.size * law.short_share.size * law.samples_per_point

    def per_solve(lx, r):
        logs = [np.interp(lx, np.array(LOG_XS)[ascending], np.log(measured[ascending, k])) for k in range(3)]
        return float(np.exp(np.interp(math.log(r), np.log(RESOLUTIONS[:3]), logs, right=None)
                            if r <= RESOLUTIONS[2] else
                            logs[2] + (logs[2] - logs[1]) / math.log(4) * math.log(r / RESOLUTIONS[2])))

    print(f"Estimated CPU of a rebuild of the whole law ({law.gamma.size} gamma x {law.log_x.size} log10 x x "
          f"{law.short_share.size} s x {law.samples_per_point} solves; per-solve CPU interpolated from the table "
          f"above, gamma = 0.6, 0.85, 1 and s = 1/2 only), resolution min(cap, ceil({LAW_RESOLUTION} sqrt(1/x))) "
          "per row, the same cap for every gamma; one gamma row costs a sixth:")
    print()
    print("| cap | resolution per row, log10 x = " + " ... ".join(f"{law.log_x[i]:g}" for i in (0, -1))
          + " | estimated CPU |")
    print("|---|---|---|")
    for cap in (None, 64, 256, 1024):
        rows = row_resolutions(law.log_x, LAW_RESOLUTION, cap)
        total = points * sum(per_solve(lx, r) for lx, r in zip(law.log_x, rows))
        print(f"| {'fixed' if cap is None else cap} | {', '.join(map(str, rows))} | {total:.0f} s |")
    print()
    print(f"(The shipped law, `{REGENERATE[:40]}...`, refines its gamma = 1 rows only: "
          f"resolution per row {', '.join(map(str, law.row_resolution[-1] if law.row_resolution else ()))}.)")


def main(argv=None):
    p = argparse.ArgumentParser(prog="python docs/law_grid_study.py", description=__doc__.splitlines()[0])
    p.add_argument("--samples", type=int, default=60, help="solves per point and resolution (default 60)")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--update-docs", action="store_true", help="write the output into docs/gas.md, block law_grid")
    args = p.parse_args(argv)
    header = run_header([sys.argv[0], *(argv if argv is not None else sys.argv[1:])])
    import contextlib
    import io

    buffer = io.StringIO()
    started = time.time()
    with contextlib.redirect_stdout(buffer):
        run(args.samples, args.workers)
        print(f"\n(wall time {time.time() - started:.0f} s)")
    print(buffer.getvalue())
    if args.update_docs:
        write_block("gas.md", "law_grid", header + "\n\n" + buffer.getvalue())
    return 0


if __name__ == "__main__":
    sys.exit(main())
