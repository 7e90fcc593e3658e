"""``wavecontact converge``: mesh-convergence study of the finite-element restitution."""

from __future__ import annotations

from .common import gamma_value, kappa_value, positive_int


def add_parser(subparsers):
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
        type=positive_int,
        nargs="+",
        default=[1, 2],
        metavar="P",
        help="Lagrange element orders (default: 1 2)",
    )
    p.add_argument(
        "--mass",
        nargs="+",
        choices=("lumped", "consistent"),
        default=["lumped", "consistent"],
        help="mass treatments (default: lumped consistent)",
    )
    p.add_argument(
        "--elements",
        type=positive_int,
        nargs="+",
        default=[25, 50, 100, 200],
        metavar="N",
        help="elements on the shorter rod, at least two sizes (default: 25 50 100 200)",
    )
    p.add_argument(
        "--contact",
        choices=("exponential", "penalty", "hard"),
        default="exponential",
        help="contact law (--kappa inf forces hard)",
    )
    p.add_argument(
        "--reference",
        type=float,
        metavar="EPS",
        help="exact epsilon to measure errors against (default: delay solver / hard limit)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object instead of tables")
    p.add_argument(
        "--plot", metavar="FILE", help="draw error vs elements and error vs wall time (PNG/PDF/SVG)"
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
    p.set_defaults(run=run)
    return p


def run(args) -> int:
    from ..studies.convergence import convergence_study

    if len(set(args.elements)) < 2:
        raise ValueError("--elements needs at least two different mesh sizes to fit an order")
    table = convergence_study(
        args.gamma,
        args.kappa,
        orders=args.order,
        masses=args.mass,
        elements=args.elements,
        contact=args.contact,
        reference=args.reference,
        progress=args.progress,
        warmup=args.warmup,
    )
    if args.plot:
        from ..plotting.convergence import plot_convergence

        plot_convergence(table, args.plot)
    print(table.to_json() if args.json else table.format_text())
    return 0
