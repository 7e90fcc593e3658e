"""``wavecontact solve FILE``: one collision of any scene read from a TOML or JSON file."""

from __future__ import annotations

import json
import math

from ..solvers import get_solver, solver_names
from .common import (
    FIGURE_SUFFIXES,
    add_limit_options,
    option_choices,
    option_text,
    positive_float,
    positive_int,
    solvers_with_option,
)
from .guard import check_outputs

# the solver options the command passes on, by solver (only those given; the file's [solve] table adds more)
_SOLVER_FLAGS = ("elements", "order", "mass", "modes", "rtol", "max_steps")


def _flags_of(solver: str) -> tuple:
    """The flags of this command that are options of ``solver`` (its declared ``cli_flags``)."""
    return tuple(flag for flag in _SOLVER_FLAGS if flag in get_solver(solver).cli_flags)


def _line_solver() -> str:
    """The solver that takes every line scene and records fields: the file's ``[solve]`` options without a
    solver name are its options."""
    return solvers_with_option("record_fields")[0]


def add_parser(subparsers):
    p = subparsers.add_parser(
        "solve",
        help="one collision of a scene read from a TOML or JSON file",
        description="Read a scene (bodies from left to right, contact laws, gaps, walls; schema in docs/usage.md, "
        "'Scene files') from FILE (.toml or .json), solve it and print each body's velocity and internal "
        "energy after the last separation and each contact's impulse and times. Options given here "
        "override the file's [solve] table, which applies only to the solver it names.",
    )
    p.add_argument("file", metavar="FILE", help="the scene file (.toml or .json)")
    p.add_argument("--solver", help="which solver (default: the file's [solve] solver, else the one solver whose "
                   "options are given, else auto: the method and resolution predicted cheapest to meet --tolerance, "
                   "default 1e-6 on the velocities' error estimate relative to the largest initial speed)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.add_argument("--out", metavar="FILE", help="write the results as JSON to FILE (.json)")
    p.add_argument("--xt-plot", metavar="FILE", help="draw the x-t diagram of stress over all bodies (.png, .pdf "
                   "or .svg; fem: the fields are sampled in a second run)")
    p.add_argument("--fields", metavar="DIR", help="write displacement, velocity and stress of every body for "
                   "ParaView into DIR (fields.pvd and one VTU file per sample, each body at its place on the line; "
                   "units and parameters in each file's field data; fem)")
    add_limit_options(p, tolerance_help="fail (exit 2, with advice) if the error estimate exceeds this (default: no "
                      "check; with auto the target of the choice, default 1e-6; a line scene's estimate is of its "
                      "velocities over the largest initial speed)")
    options = p.add_argument_group("solver options (passed to the solver, which refuses those it does not take)")
    options.add_argument("--elements", type=positive_int, metavar="N", help="fem: " + option_text("fem", "elements"))
    options.add_argument("--order", type=int, choices=option_choices("fem", "order"),
                         help="fem: " + option_text("fem", "order"))
    options.add_argument("--mass", choices=option_choices("fem", "mass"), help="fem: " + option_text("fem", "mass"))
    options.add_argument("--modes", type=positive_int, metavar="N", help="modal: " + option_text("modal", "modes"))
    options.add_argument("--rtol", type=positive_float, help="delay: " + option_text("delay", "rtol"))
    options.add_argument("--max-steps", type=positive_int, metavar="N",
                         help="delay: " + option_text("delay", "max_steps"))
    p.set_defaults(run=run)
    return p


def _two_rod_record(result, scene, names) -> dict:
    """The paper's two-rod scenes return a CollisionResult (restitution, contact window): the bodies'
    velocities follow from momentum and ``v2' - v1' = epsilon (v1 - v2)``; the vibration energy is
    not split between the rods (null)."""
    (m1, m2), (v1, v2) = [r.mass for r in scene.rods], scene.velocities
    approach = v1 - v2
    after1 = (m1 * v1 + m2 * v2 - m2 * result.restitution * approach) / (m1 + m2)
    after2 = after1 + result.restitution * approach
    start, duration = float(result.contact_start), float(result.contact_duration)
    estimate = result.error_estimate
    return {
        "solver": result.solver, "bodies": list(names), "velocities": [after1, after2],
        "internal_energies": [None, None], "restitution": float(result.restitution),
        "contacts": [{"impulse": m1 * (v1 - after1), "duration": duration, "first_contact": start,
                      "last_contact": start + duration, "intervals": 1, "name": "0-1"}],
        "error_estimate": None if estimate is None or math.isnan(estimate) else float(estimate),
        "wall_time_s": float(result.wall_time_s),
        "options": {k: v for k, v in (result.options or {}).items() if isinstance(v, (int, float, str, bool))},
    }


def _record(result, names) -> dict:
    """The scalars of a scene result as plain JSON types."""
    contacts = []
    for record in getattr(result, "contacts", ()) or ():
        contacts.append({
            "impulse": float(record.impulse), "duration": float(record.duration),
            "first_contact": float(record.first_contact), "last_contact": float(record.last_contact),
            "intervals": int(record.intervals), "name": str(record.name),
        })
    estimate = getattr(result, "error_estimate", math.nan)
    return {
        "solver": result.solver,
        "bodies": list(names),
        "velocities": [float(v) for v in result.velocities],
        "internal_energies": [float(e) for e in result.internal_energies],
        "contacts": contacts,
        "error_estimate": None if estimate is None or math.isnan(estimate) else float(estimate),
        "wall_time_s": float(result.wall_time_s),
        "options": {k: v for k, v in (result.options or {}).items() if isinstance(v, (int, float, str, bool))},
    }


def _text(record: dict, path) -> str:
    lines = [f"{path}: solver {record['solver']}"
             + (f", error estimate {record['error_estimate']:.1e}" if record["error_estimate"] is not None else "")]
    if "auto" in record:
        lines.append(f"  auto: {record['auto']['method']} ({record['auto']['reason']})")
    lines.append("  body                velocity        internal energy")
    for name, v, e in zip(record["bodies"], record["velocities"], record["internal_energies"]):
        lines.append(f"  {name:<16} {v:>15.9g} {'(not split)' if e is None else format(e, '.9g'):>18}")
    if record["contacts"]:
        lines.append("  contact      impulse         duration        first           last            intervals")
        for c in record["contacts"]:
            lines.append(f"  {c['name']:<10} {c['impulse']:>15.9g} {c['duration']:>15.9g} {c['first_contact']:>15.9g} "
                         f"{c['last_contact']:>15.9g} {c['intervals']:>5d}")
    return "\n".join(lines)


def _implied_solver(args, scene_file) -> str:
    """``--solver``, else the file's, else the one solver whose options are given (the file's [solve] options
    without a solver and an x-t plot are fem's), else ``auto``."""
    if args.solver or scene_file.solver:
        return args.solver or scene_file.solver
    named = {name for name in solver_names() if any(getattr(args, f) is not None for f in _flags_of(name))}
    if scene_file.options or args.xt_plot or args.fields:
        named.add(_line_solver())
    return named.pop() if len(named) == 1 else "auto"


def run(args) -> int:
    from ..api import solve
    from ..io.scene_file import read_scene_file
    from .common import report_written

    check_outputs(files=[("--out", args.out, (".json",)), ("--xt-plot", args.xt_plot, FIGURE_SUFFIXES)],
                  directories=[("--fields", args.fields, ("fields.pvd",))])
    scene_file = read_scene_file(args.file)
    solver = _implied_solver(args, scene_file)
    # the file's [solve] options belong to the file's solver (fem if it names none): another --solver starts
    # from its defaults
    options = dict(scene_file.options) if solver == (scene_file.solver or _line_solver()) else {}
    options.update({name: getattr(args, name) for name in _SOLVER_FLAGS if getattr(args, name) is not None})
    if args.xt_plot or args.fields:
        if solver != _line_solver():
            raise ValueError(f"--fields and --xt-plot need --solver {_line_solver()} (the solver that records fields), "
                             f"not {solver}")
        options["record_fields"] = True
    result = solve(scene_file.scene, solver=solver, tolerance=args.tolerance, max_work=args.max_work,
                   max_memory=args.max_memory, **options)
    if hasattr(result, "velocities"):
        record = _record(result, scene_file.names)
    else:
        record = _two_rod_record(result, scene_file.scene, scene_file.names)
    auto = (getattr(result, "diagnostics", None) or {}).get("auto")
    if auto is not None:
        record["auto"] = {name: auto[name] for name in ("method", "reason", "tolerance", "predicted_cpu_s",
                                                         "actual_cpu_s")}
    written = []
    if args.out:
        with open(args.out, "w", encoding="utf-8") as stream:
            json.dump({"file": str(args.file), **record}, stream, indent=1)
        written.append(args.out)
    if args.fields:
        from ..io.fields import write_fields
        from .common import files_summary

        parameters = {"scene_file": str(args.file), "bodies": ", ".join(scene_file.names)}
        if scene_file.title:
            parameters["title"] = scene_file.title
        files = write_fields(result, args.fields, units="scene", parameters=parameters).files
        written += [path for path in files if str(path).endswith(".pvd")]
        written.append(files_summary(args.fields, "fields_*.vtu"))
    if args.xt_plot:
        from ..plotting.xt import plot_xt_diagram

        written.append(plot_xt_diagram(result, args.xt_plot, names=scene_file.names,
                                       title=scene_file.title or str(args.file)))
    files = report_written(written)
    print(json.dumps({"file": str(args.file), **record, "files_written": files}) if args.json
          else _text(record, args.file))
    return 0
