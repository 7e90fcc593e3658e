"""``wavecontact collide``: one collision of the paper's two rods."""

from __future__ import annotations

import json
from pathlib import Path

from .common import (
    CONTACT_HELP,
    FIGURE_SUFFIXES,
    add_limit_options,
    contact_law,
    files_summary,
    gamma_value,
    kappa_text,
    kappa_value,
    option_choices,
    option_text,
    positive_float,
    positive_int,
    report_written,
)
from .guard import check_outputs

PLOT_SUFFIXES = FIGURE_SUFFIXES


def duration_text(seconds: float) -> str:
    """``seconds`` in ms below a second, else in s, with 3 significant digits (``'3.11 ms'``, ``'58.6 s'``)."""
    if seconds < 0.9995:
        return f"{1e3 * seconds:#.3g}".rstrip(".") + " ms"
    if seconds < 999.5:
        return f"{seconds:#.3g}".rstrip(".") + " s"
    return f"{seconds:.0f} s"


def add_parser(subparsers):
    p = subparsers.add_parser(
        "collide",
        help="one collision: print the coefficient of restitution",
        description="Collide two rods of length ratio gamma at softness kappa = alpha V l / c "
        "(--kappa inf: hard contact) and print the coefficient of restitution. The time printed is the "
        "solve alone; numba's one-time kernel preparation (compilation or cache loading, once per "
        "process) is measured by a second, identical solve and reported separately.",
    )
    p.add_argument("--gamma", type=gamma_value, required=True, help="length ratio l1/l2 in (0, 1]")
    p.add_argument("--kappa", type=kappa_value, required=True,
                   help="softness alpha V l / c in (0, inf]; 'inf' is the hard-core limit")
    p.add_argument("--solver", choices=("delay", "fem", "modal"), default="delay", help="which solver")
    p.add_argument("--contact", choices=("exponential", "penalty", "hard"), help=CONTACT_HELP)
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.add_argument("--plot", metavar="FILE",
                   help="draw W(tau) or v_rel(tau) with the asymptotic curve (.png, .pdf or .svg)")
    p.add_argument("--save", metavar="FILE", help="save scalars and histories to an .npz file")
    p.add_argument("--no-warmup", dest="warmup", action="store_false",
                   help="solve once only; the time printed then includes numba's kernel preparation")
    add_limit_options(p)
    delay = p.add_argument_group("delay solver")
    delay.add_argument("--rtol", type=positive_float, help=option_text("delay", "rtol"))
    delay.add_argument("--max-steps", type=positive_int, metavar="N", help=option_text("delay", "max_steps"))
    fem = p.add_argument_group("finite-element solver")
    fem.add_argument("--elements", type=positive_int, metavar="N", help=option_text("fem", "elements"))
    fem.add_argument("--order", type=int, choices=option_choices("fem", "order"), help=option_text("fem", "order"))
    fem.add_argument("--mass", choices=option_choices("fem", "mass"), help=option_text("fem", "mass"))
    fem.add_argument("--fields", metavar="DIR", help="write displacement, velocity and stress for ParaView into DIR (fields.pvd and one "
                     "VTU file per sample; units and parameters in each file's field data)")
    fem.add_argument("--xt-plot", metavar="FILE", help="draw the x-t diagram of stress in both rods")
    modal = p.add_argument_group("modal solver")
    modal.add_argument("--modes", type=positive_int, metavar="N", help=option_text("modal", "modes"))
    modal.add_argument(
        "--no-static-correction", dest="static_correction", action="store_false", default=None,
        help="plain truncation: no correction for the omitted modes (the modal solver's static_correction=False; "
        "not for hard contact). Default: corrected",
    )
    p.set_defaults(run=run)
    return p


_SOLVER_FLAGS = {
    "delay": ("rtol", "max_steps"),
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
    if args.fields or args.xt_plot:
        if args.solver != "fem":
            raise ValueError("--fields and --xt-plot need --solver fem")
        options["record_fields"] = True
    return options


def _check_outputs(args) -> None:
    check_outputs(files=[("--plot", args.plot, PLOT_SUFFIXES), ("--xt-plot", args.xt_plot, PLOT_SUFFIXES),
                         ("--save", args.save, (".npz",))],
                  directories=[("--fields", args.fields, ("fields.pvd",))])


def timed_collide(gamma, kappa, solver, contact, options, warmup=True):
    """Solve; if numba prepared kernels during the call, solve again to time the solve alone.

    Returns
    -------
    result : CollisionResult
        The (second, when repeated) result; ``wall_time_s`` is then the solve alone.
    preparation_s : float or None
        Kernel preparation time in seconds (first call minus second), None if
        there was none or it was not measured (``warmup=False``).
    """
    from ..api import collide

    result = collide(gamma, kappa, solver=solver, contact=contact, **options)
    if not (warmup and result.diagnostics.get("includes_kernel_preparation")):
        return result, None
    first = result.wall_time_s
    result = collide(gamma, kappa, solver=solver, contact=contact, **options)
    return result, max(first - result.wall_time_s, 0.0)


def run(args) -> int:
    contact = contact_law(args.kappa, args.contact)
    options = {**_options(args), "tolerance": args.tolerance, "max_work": args.max_work,
               "max_memory": args.max_memory}
    _check_outputs(args)
    if contact == "penalty" and args.solver != "fem":
        raise ValueError("--contact penalty needs --solver fem")
    result, preparation = timed_collide(args.gamma, args.kappa, args.solver, contact, options, args.warmup)
    written = []
    if args.fields:
        from ..io.fields import write_fields

        fields = write_fields(result, args.fields, units="dimensionless").files
        written += [path for path in fields if Path(path).suffix == ".pvd"]
        written.append(files_summary(args.fields, "fields_*.vtu"))
    if args.xt_plot:
        from ..plotting.xt import plot_xt_diagram

        written.append(plot_xt_diagram(result, args.xt_plot))
    if args.plot:
        from ..plotting.history import plot_velocity_history

        written.append(plot_velocity_history(result, args.plot))
    if args.save:
        result.save_npz(args.save)
        written.append(args.save)
    files = report_written(written)
    if args.json:
        record = json.loads(result.to_json())
        record["contact"] = contact
        record["kernel_preparation_s"] = preparation
        record["files_written"] = files
        print(json.dumps(record))
        return 0
    line = (f"epsilon = {result.restitution:.12g}  (gamma = {args.gamma:g}, kappa = {kappa_text(args.kappa, contact)}, "
            f"contact = {contact}, solver = {result.solver}")
    if result.error_estimate is not None:
        line += f", error estimate {result.error_estimate:.1e}"
    line += f"; solve {duration_text(result.wall_time_s)}"
    if preparation is not None:
        line += f", numba kernel preparation {duration_text(preparation)} (once per process)"
    elif result.diagnostics.get("includes_kernel_preparation"):
        line += " including numba's kernel preparation (--no-warmup)"
    print(line + ")")
    return 0
