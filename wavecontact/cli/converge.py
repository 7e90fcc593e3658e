"""``wavecontact converge``: mesh-convergence study of the finite-element restitution."""

from __future__ import annotations

from .common import (
    CONTACT_HELP,
    FIGURE_SUFFIXES,
    contact_law,
    gamma_value,
    kappa_value,
    option_choices,
    positive_int,
    print_outcome,
)
from .costs import add_work_option, check_run, methods_cost
from .guard import check_outputs


def add_parser(subparsers):
    orders, masses = option_choices("fem", "order"), option_choices("fem", "mass")
    p = subparsers.add_parser(
        "converge",
        help="mesh-convergence study of the fem solver against the delay equation",
        description="Run the finite-element solver on a sequence of meshes for each element order and mass "
        "treatment; print per discretization the error of epsilon against the reference (delay solver, or "
        "epsilon = gamma in the hard limit), the observed order (least-squares fit), wall time and steps.",
    )
    p.add_argument("--gamma", type=gamma_value, required=True, help="length ratio l1/l2 in (0, 1]")
    p.add_argument("--kappa", type=kappa_value, required=True, help="alpha V l / c in (0, inf]; 'inf' = hard")
    p.add_argument(
        "--order",
        type=int,
        nargs="+",
        choices=orders,
        default=list(orders),
        metavar="P",
        help=f"Lagrange element orders, each one of {', '.join(map(str, orders))}",
    )
    p.add_argument(
        "--mass",
        nargs="+",
        choices=masses,
        default=list(masses),
        help="mass treatments",
    )
    p.add_argument(
        "--elements",
        type=positive_int,
        nargs="+",
        default=[25, 50, 100, 200],
        metavar="N",
        help="elements on the shorter rod, at least two sizes",
    )
    p.add_argument(
        "--contact",
        choices=("exponential", "penalty", "hard"),
        help=CONTACT_HELP,
    )
    p.add_argument(
        "--reference",
        type=float,
        metavar="EPS",
        help="exact epsilon to measure errors against (default: delay solver / hard limit)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object instead of tables")
    p.add_argument(
        "--plot", metavar="FILE", help="draw error vs elements and error vs wall time (.png, .pdf or .svg)"
    )
    p.add_argument(
        "--no-progress",
        dest="progress",
        action="store_false",
        default=None,
        help="no progress bar (it is shown on stderr only when that is a terminal)",
    )
    p.add_argument(
        "--no-warmup",
        dest="warmup",
        action="store_false",
        help="do not run each discretization once untimed first (numba compilation then shows in the first row)",
    )
    add_work_option(p)
    p.set_defaults(run=run)
    return p


def run(args) -> int:
    from ..studies.convergence import SOLVER, convergence_study

    if len(set(args.elements)) < 2:
        raise ValueError("--elements needs at least two different mesh sizes to fit an order")
    contact = contact_law(args.kappa, args.contact)
    check_outputs(files=[("--plot", args.plot, FIGURE_SUFFIXES)])
    runs = [(SOLVER, {"elements": n, "order": p, "mass": m}) for p in args.order for m in args.mass
            for n in args.elements]
    check_run(args, f"converge: {len(runs)} finite-element solves",
              methods_cost(args.gamma, args.kappa, runs, 1 if args.warmup is False else 2),
              "use fewer or smaller --elements, --order or --mass")
    table = convergence_study(
        args.gamma,
        args.kappa,
        orders=args.order,
        masses=args.mass,
        elements=args.elements,
        contact=contact,
        reference=args.reference,
        progress=args.progress,
        warmup=args.warmup,
    )
    written = []
    if args.plot:
        from ..plotting.convergence import plot_convergence

        written.append(plot_convergence(table, args.plot))
    return print_outcome(table.to_dict(), table.format_text(), written, args.json)
