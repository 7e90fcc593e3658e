"""``wavecontact compare``: one collision by every solver, side by side."""

from __future__ import annotations

from .common import gamma_value, kappa_value, positive_int


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
    p.add_argument("--repeats", type=positive_int, default=1, help="median over this many solves")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="FILE", help="error against wall time, one marker per solver")
    p.add_argument("--no-progress", dest="progress", action="store_false", default=None)
    p.set_defaults(run=run)
    return p


def run(args) -> int:
    from ..studies.compare import compare_solvers

    table = compare_solvers(args.gamma, args.kappa, repeats=args.repeats, progress=args.progress)
    if args.plot:
        from ..plotting.compare import plot_comparison

        plot_comparison(table, args.plot)
    print(table.to_json() if args.json else table.format())
    return 0
