"""``wavecontact collide``: one collision of the paper's two rods."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from .._jit import answer_first, compile_deferred, deferred_count
from ..solvers import get_solver, solver_names
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
    solver_option,
    solvers_with_option,
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
    p.add_argument("--solver", choices=("auto",) + tuple(solver_names()), default="auto",
                   help="which solver; auto (default; the solver of the solver options given, if any): the method "
                   "and resolution predicted cheapest to meet --tolerance (default 1e-6), refined until it does "
                   "(docs/performance.md)")
    p.add_argument("--contact", choices=("exponential", "penalty", "hard"), help=CONTACT_HELP)
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.add_argument("--plot", metavar="FILE",
                   help="draw W(tau) or v_rel(tau) with the asymptotic curve (.png, .pdf or .svg)")
    p.add_argument("--save", metavar="FILE", help="save scalars and histories to an .npz file")
    p.add_argument("--no-warmup", dest="warmup", action="store_false",
                   help="solve once only; the time printed then includes numba's kernel preparation")
    add_limit_options(p, tolerance_help="fail (exit 2, with advice) if the error estimate exceeds this (default: no "
                      "check; with --solver auto the target of the choice, default 1e-6)")
    _add_solver_flags(p)
    p.set_defaults(run=run)
    return p


def _add_solver_flags(p) -> None:
    """One group of flags per registered solver: the options it exposes (``cli_flags``), built from their
    declarations (type, allowed values, help); the field outputs go with the solver that records fields."""
    fields_added = False
    for name in solver_names():
        solver = get_solver(name)
        group = p.add_argument_group(solver.title)
        for option, help_text in solver.cli_flags.items():
            spec = solver_option(name, option)[1]
            flag = "--" + option.replace("_", "-")
            text = help_text or option_text(name, option)
            if spec["kind"] == "bool":  # a switch that turns a default-on option off
                group.add_argument("--no-" + flag[2:], dest=option, action="store_false", default=None, help=text)
            elif spec["kind"] == "choice":
                kind = int if all(isinstance(c, int) for c in spec["choices"]) else None
                group.add_argument(flag, **({"type": kind} if kind else {}), choices=option_choices(name, option),
                                   help=text)
            elif spec["kind"] == "int":
                group.add_argument(flag, type=positive_int, metavar="N", help=text)
            else:
                group.add_argument(flag, type=positive_float, help=text)
        if not fields_added and "record_fields" in solver.Options.__dataclass_fields__:
            fields_added = True
            group.add_argument("--fields", metavar="DIR", help="write displacement, velocity and stress for ParaView "
                               "into DIR (fields.pvd and one VTU file per sample; units and parameters in each "
                               "file's field data)")
            group.add_argument("--xt-plot", metavar="FILE", help="draw the x-t diagram of stress in both rods")


def _implied_solver(args) -> str:
    """``--solver`` as given; without it (auto) the one solver whose options are given, if any
    (``--elements 200`` means the FE solver, as ``--rtol`` meant the delay solver before auto)."""
    if args.solver != "auto":
        return args.solver
    named = {solver for solver in solver_names()
             if any(getattr(args, n) is not None for n in get_solver(solver).cli_flags)}
    if args.fields or args.xt_plot:
        named.update(solvers_with_option("record_fields"))
    return named.pop() if len(named) == 1 else "auto"


def _options(args) -> dict:
    args.solver = _implied_solver(args)
    options = {}
    for solver in solver_names():
        for name in get_solver(solver).cli_flags:
            value = getattr(args, name)
            if value is None:
                continue
            if solver != args.solver:
                raise ValueError(f"--{name.replace('_', '-')} applies to --solver {solver}, not {args.solver}")
            options[name] = value
    if args.fields or args.xt_plot:
        recording = solvers_with_option("record_fields")
        if args.solver not in recording:
            raise ValueError(f"--fields and --xt-plot need --solver {' or '.join(recording)}")
        options["record_fields"] = True
    return options


def _check_outputs(args) -> None:
    check_outputs(files=[("--plot", args.plot, PLOT_SUFFIXES), ("--xt-plot", args.xt_plot, PLOT_SUFFIXES),
                         ("--save", args.save, (".npz",))],
                  directories=[("--fields", args.fields, ("fields.pvd",))])


def timed_collide(gamma, kappa, solver, contact, options, warmup=True):
    """Solve; if numba prepared kernels during the call (or a kernel ran interpreted, whose first call also
    pays the solver's one-time imports), solve again to time the solve alone.

    Returns
    -------
    result : CollisionResult
        The (second, when repeated) result; ``wall_time_s`` is then the solve alone.
    preparation_s : float or None
        Kernel preparation time in seconds (first call minus second), None if
        there was none (also when the kernels ran interpreted) or it was not
        measured (``warmup=False``).
    """
    from ..api import collide

    result = collide(gamma, kappa, solver=solver, contact=contact, **options)
    first_call = result.diagnostics.get("includes_kernel_preparation") or result.diagnostics.get("interpreted_kernels")
    if not (warmup and first_call):
        return result, None
    first = result.wall_time_s
    result = collide(gamma, kappa, solver=solver, contact=contact, **options)
    if result.diagnostics.get("interpreted_kernels"):
        return result, None  # no numba preparation: the first call's extra time was the solver's imports
    return result, max(first - result.wall_time_s, 0.0)


def _solver_text(result) -> str:
    """``delay``, or for the auto choice ``auto (delay: rtol=1e-07)``."""
    auto = result.diagnostics.get("auto")
    return result.solver if auto is None else f"auto ({auto['method']})"


def run(args) -> int:
    contact = contact_law(args.kappa, args.contact)
    options = {**_options(args), "tolerance": args.tolerance, "max_work": args.max_work,
               "max_memory": args.max_memory}
    _check_outputs(args)
    if args.solver != "auto" and contact not in get_solver(args.solver).contact_names:
        accepting = [name for name in solver_names() if contact in get_solver(name).contact_names]
        raise ValueError(f"--contact {contact} needs --solver {' or '.join(accepting)}")
    with answer_first():  # a short solve numba has no compiled kernel for runs interpreted; compiled after the answer
        result, preparation = timed_collide(args.gamma, args.kappa, args.solver, contact, options, args.warmup)
    status = _report(args, result, preparation, contact)
    sys.stdout.flush()  # the answer first
    compile_deferred()  # then the kernels that ran interpreted, for the next runs to load from numba's cache
    return status


def _report(args, result, preparation, contact) -> int:
    """Write the files asked for and print the answer (a line, or JSON with ``--json``)."""
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
            f"contact = {contact}, solver = {_solver_text(result)}")
    if result.error_estimate is not None:
        line += f", error estimate {result.error_estimate:.1e}"
    line += f"; solve {duration_text(result.wall_time_s)}"
    if result.diagnostics.get("interpreted_kernels"):
        line += ", interpreted (numba had no compiled kernel for this short run: faster than compiling first"
        line += "; compiled after this answer for the next runs)" if deferred_count() else ")"
    elif preparation is not None:
        line += f", numba kernel preparation {duration_text(preparation)} (once per process)"
    elif result.diagnostics.get("includes_kernel_preparation"):
        line += " including numba's kernel preparation (--no-warmup)"
    print(line + ")")
    return 0
