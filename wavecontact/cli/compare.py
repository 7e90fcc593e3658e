"""``wavecontact compare``: one collision by every solver, side by side."""

from __future__ import annotations

from .common import FIGURE_SUFFIXES, gamma_value, kappa_value, positive_int, print_outcome
from .costs import add_work_option, check_run, compare_cost
from .guard import check_outputs


def add_parser(subparsers):
    p = subparsers.add_parser(
        "compare",
        help="one collision by every solver at a few resolutions: epsilon, error, time, work",
        description="Run the collision (gamma, kappa) with every solver and discretization at a few "
        "resolutions and print epsilon, its error against the delay-equation reference, the wall "
        "time and the work.",
    )
    p.add_argument("--gamma", type=gamma_value, required=True, help="length ratio l1/l2 in (0, 1]")
    p.add_argument("--kappa", type=kappa_value, required=True, help="alpha V l / c in (0, inf]; 'inf' = hard")
    p.add_argument("--repeats", type=positive_int, default=1, help="median wall time over this many solves of each method")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="FILE", help="draw error against wall time, one line per solver and discretization (.png, .pdf or .svg)")
    p.add_argument("--no-progress", dest="progress", action="store_false", default=None,
                   help="no progress bar (it is shown on stderr only when that is a terminal)")
    p.add_argument("--no-warmup", dest="warmup", action="store_false",
                   help="time every first call too (numba's kernel preparation then shows in the times)")
    add_work_option(p)
    p.set_defaults(run=run)
    return p


def run(args) -> int:
    from ..studies.compare import compare_solvers

    check_outputs(files=[("--plot", args.plot, FIGURE_SUFFIXES)])
    check_run(args, f"compare: every solver at {args.repeats} repeat(s)", compare_cost(args.gamma, args.kappa, args.repeats),
              "use fewer --repeats or a stiffer --kappa")
    table = compare_solvers(args.gamma, args.kappa, repeats=args.repeats, progress=args.progress,
                            warmup=args.warmup)
    written = []
    if args.plot:
        from ..plotting.compare import plot_comparison

        written.append(plot_comparison(table, args.plot))
    return print_outcome(table.to_dict(), table.format(), written, args.json)
