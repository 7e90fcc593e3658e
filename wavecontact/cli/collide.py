"""``wavecontact collide``: one collision of the paper's two rods."""

from __future__ import annotations

import math

from .common import gamma_value, kappa_value, positive_int


def add_parser(subparsers):
    p = subparsers.add_parser(
        "collide",
        help="one collision: print the coefficient of restitution",
        description="Collide two rods of length ratio gamma at softness kappa = alpha V l / c "
        "(--kappa inf: hard contact) and print the coefficient of restitution.",
    )
    p.add_argument("--gamma", type=gamma_value, required=True, help="length ratio l1/l2 in (0, 1]")
    p.add_argument("--kappa", type=kappa_value, required=True, help="alpha V l / c in (0, inf]; 'inf' = hard")
    p.add_argument("--solver", choices=("delay", "fem", "modal"), default="delay")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.add_argument("--plot", metavar="FILE", help="draw W(tau) or v_rel(tau) with the asymptotic curve (PNG/PDF/SVG)")
    p.add_argument("--save", metavar="FILE", help="save scalars and histories to an .npz file")
    p.add_argument("--tolerance", type=float, help="fail (exit 2, with advice) if the error estimate exceeds this")
    p.add_argument("--max-work", type=float, help="limit on the estimated work in updates (default 2e11)")
    p.add_argument("--max-memory", type=float, help="limit on the estimated memory in bytes "
                   "(default: half the available memory)")
    delay = p.add_argument_group("delay solver")
    delay.add_argument("--rtol", type=float, help="target accuracy of epsilon (default 1e-11)")
    fem = p.add_argument_group("finite-element solver")
    fem.add_argument("--elements", type=positive_int, help="elements on the shorter rod")
    fem.add_argument("--order", type=positive_int, help="Lagrange element order (1, 2, ...)")
    fem.add_argument("--mass", choices=("lumped", "consistent"))
    fem.add_argument("--contact", choices=("exponential", "penalty", "hard"), default="exponential")
    fem.add_argument("--fields", metavar="DIR", help="write stress/velocity fields for ParaView into DIR")
    fem.add_argument("--fields-format", choices=("vtu", "xdmf"), default="vtu",
                     help="VTU files with a PVD index (default) or one XDMF time series")
    fem.add_argument("--xt-plot", metavar="FILE", help="draw the x-t diagram of stress in both rods")
    modal = p.add_argument_group("modal solver")
    modal.add_argument("--modes", type=positive_int, help="modes per rod")
    modal.add_argument(
        "--no-static-correction", dest="static_correction", action="store_false", default=None,
        help="plain modal truncation (no residual flexibility)",
    )
    p.set_defaults(run=run)
    return p


_SOLVER_FLAGS = {
    "delay": ("rtol",),
    "fem": ("elements", "order", "mass"),
    "modal": ("modes", "static_correction"),
}


def _options(args) -> dict:
    options = {}
    for solver, names in _SOLVER_FLAGS.items():
        for name in names:
            value = getattr(args, name)
            if value is None:
                continue
            if solver != args.solver:
                raise ValueError(f"--{name.replace('_', '-')} applies to --solver {solver}, not {args.solver}")
            options[name] = value
    wants_fields = args.fields or args.xt_plot
    if wants_fields:
        if args.solver != "fem":
            raise ValueError("--fields and --xt-plot need --solver fem")
        options["record_fields"] = True
    return options


def run(args) -> int:
    from ..api import collide

    contact = "hard" if math.isinf(args.kappa) else args.contact
    result = collide(args.gamma, args.kappa, solver=args.solver, contact=contact, tolerance=args.tolerance,
                     max_work=args.max_work, max_memory=args.max_memory, **_options(args))
    if args.fields:
        from ..io.fields import write_fields

        write_fields(result, args.fields, format=args.fields_format)
    if args.xt_plot:
        from ..plotting.xt import plot_xt_diagram

        plot_xt_diagram(result, args.xt_plot)
    if args.plot:
        from ..plotting.history import plot_velocity_history

        plot_velocity_history(result, args.plot)
    if args.save:
        result.save_npz(args.save)
    if args.json:
        print(result.to_json())
    else:
        kappa = "inf" if math.isinf(args.kappa) else f"{args.kappa:g}"
        line = f"epsilon = {result.restitution:.12g}  (gamma = {args.gamma:g}, kappa = {kappa}, solver = {result.solver}"
        if result.error_estimate is not None:
            line += f", error estimate {result.error_estimate:.1e}"
        line += f", {1e3 * result.wall_time_s:.3g} ms"
        if result.diagnostics.get("includes_kernel_preparation"):
            line += ", including numba's one-time compilation or cache loading"
        print(line + ")")
    return 0
