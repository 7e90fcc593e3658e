"""``wavecontact restitution-table``: export p(eps^2) on a (gamma, T_B/E_tr) grid for other codes."""

from __future__ import annotations

import itertools
import math

from ..errors import InvalidParameterError
from .common import kappa_value, nonnegative_int, positive_int, report_written
from .costs import add_work_option, check_run, thermal_samples_cost
from .executors import executor_from
from .guard import check_outputs

TABLE_SUFFIXES = (".csv", ".npz", ".json")


def add_parser(subparsers):
    p = subparsers.add_parser(
        "restitution-table",
        help="tabulate the law of epsilon^2 for DEM / event-driven codes (CSV, NPZ, JSON)",
        description="Run one thermal ensemble per (gamma, T_B/E_tr) point and write the quantile functions of "
        "epsilon^2 and the short rod's share of the lost energy.  The suffix of each --out picks the format: "
        ".csv (long format with a header naming columns and units), .npz or .json (with a schema).",
    )
    p.add_argument("--gamma", type=float, nargs="+", required=True, help="length ratios, ascending in (0, 1]")
    p.add_argument("--temperature", type=float, nargs="+", required=True, help="T_B/E_tr values, ascending, >= 0")
    p.add_argument("--samples", type=positive_int, required=True, help="collisions per point")
    p.add_argument("--seed", type=nonnegative_int, required=True, help="root seed (>= 0)")
    p.add_argument("--kappa", type=kappa_value, default=100.0, help="finite softness (default 100.0)")
    p.add_argument("--bath-modes", type=positive_int, default=250, help="nu_max (default 250)")
    p.add_argument("--levels", type=positive_int, default=101, help="probability levels (default 101)")
    p.add_argument("--out", metavar="FILE", nargs="+", required=True, help="one or more of .csv/.npz/.json")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=positive_int, default=1, help="local worker processes")
    where.add_argument("--scheduler", metavar="ADDRESS", help="a running dask.distributed scheduler (default: none, local processes)")
    p.add_argument("--no-progress", dest="progress", action="store_false", help="no progress bar")
    add_work_option(p)
    p.set_defaults(run=run)
    return p


def _ascending(option: str, values, low: float, high: float, text: str) -> None:
    if not all(math.isfinite(v) and low <= v <= high for v in values) or any(b <= a for a, b in itertools.pairwise(values)):
        raise InvalidParameterError(f"{option} must be strictly ascending values {text}, got {' '.join(map(str, values))}")


def check(args) -> None:
    """Refuse, before any work, a bad grid, a hard-core kappa, bad outputs and too large a run."""
    from ..studies.restitution_tables import MAX_TABLE_SAMPLES

    _ascending("--gamma", args.gamma, 1e-300, 1.0, "in (0, 1]")
    _ascending("--temperature", args.temperature, 0.0, math.inf, ">= 0")
    if math.isinf(args.kappa):
        raise InvalidParameterError("--kappa must be finite: the hard-core grid gives no per-rod split")
    if not 2 <= args.levels <= 100_001:
        raise InvalidParameterError(f"--levels must lie in [2, 100001], got {args.levels}")
    points = len(args.gamma) * len(args.temperature)
    if points * args.samples > MAX_TABLE_SAMPLES:
        raise InvalidParameterError(f"--samples: a table holds at most {MAX_TABLE_SAMPLES} collisions in all, got "
                                    f"{points} points x {args.samples}")
    check_outputs(files=[("--out", path, TABLE_SUFFIXES) for path in args.out])
    check_run(args, f"restitution-table: {points} points x {args.samples} samples",
              thermal_samples_cost(points * args.samples, args.kappa, args.bath_modes),
              "use fewer --samples, points or --bath-modes")


def run(args) -> int:
    from ..studies.restitution_tables import restitution_table

    check(args)
    with executor_from(args.workers, args.scheduler) as executor:
        table = restitution_table(args.gamma, args.temperature, args.samples, args.seed, kappa=args.kappa,
                                  bath_modes=args.bath_modes, levels=args.levels, executor=executor,
                                  progress=args.progress, rtol=1e-6)
    written = []
    for path in args.out:
        table.save(path)
        written.append(path)
    report_written(written)
    # each rod's mean vibrational gain with its standard error: defined at any T_B (a ratio of the two, the
    # file's rod1_share, is not a fraction where a bath gives energy back)
    print("gamma    T_B/E_tr  mean eps   mean eps^2  gain rod 1 / E_tr       gain rod 2 / E_tr")
    for i, g in enumerate(table.gamma):
        for j, r in enumerate(table.temperature_ratio):
            gain, error = table.rod_gain[i, j], table.rod_gain_standard_error[i, j]
            print(f"{g:<8g} {r:<9g} {table.mean_restitution(g, r):.4f}     {table.mean_eps2(g, r):.4f}      "
                  f"{gain[0]:+.4f} +/- {error[0]:.4f}    {gain[1]:+.4f} +/- {error[1]:.4f}")
    return 0
