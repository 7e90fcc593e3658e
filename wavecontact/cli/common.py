"""Argument types shared by the commands."""

from __future__ import annotations

import argparse
import math


def kappa_value(text: str) -> float:
    """``--kappa``: a number in the supported range [KAPPA_MIN, KAPPA_MAX] or ``inf`` (hard-core limit);
    every command refuses the same values, while parsing, before any work (:func:`wavecontact.limits.check_kappa`)."""
    from ..errors import InvalidParameterError
    from ..limits import check_kappa

    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"kappa must be a positive number or 'inf', got {text!r}") from None
    if math.isnan(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"kappa must lie in (0, inf], got {text!r}")
    try:
        check_kappa(value)
    except InvalidParameterError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return value


def gamma_value(text: str) -> float:
    """``--gamma``: a number in (0, 1]."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"gamma must be a number in (0, 1], got {text!r}") from None
    if not (0.0 < value <= 1.0):
        raise argparse.ArgumentTypeError(f"gamma must lie in (0, 1], got {text!r}")
    return value


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value


def nonnegative_int(text: str) -> int:
    """An integer >= 0 (seeds, burn-in, worker counts)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}")
    return value


def add_limit_options(parser: argparse.ArgumentParser, tolerance_help: str | None = None) -> None:
    """``--tolerance``, ``--max-work`` and ``--max-memory`` of one solve (``collide``, ``solve``)."""
    parser.add_argument("--tolerance", type=positive_float, help=tolerance_help
                        or "fail (exit 2, with advice) if the error estimate exceeds this (default: no check)")
    parser.add_argument("--max-work", type=positive_float,
                        help="limit on the estimated work in updates (default 2e11)")
    parser.add_argument("--max-memory", type=positive_float, help="limit on the estimated memory in bytes "
                        "(default: half the available memory)")


def add_ring_options(parser: argparse.ArgumentParser) -> None:
    """``--out``, ``--no-progress`` and ``--no-static-correction``, shared by the ring commands."""
    parser.add_argument("--out", metavar="DIR", required=True, help="output directory (created if missing)")
    parser.add_argument("--no-progress", dest="progress", action="store_false", help="no progress bar")
    parser.add_argument("--no-static-correction", dest="static_correction", action="store_false",
                        help="plain modal truncation (no residual flexibility)")


class HelpFormatter(argparse.HelpFormatter):
    """Help that states every option's default (``--json`` flags and required options have none)."""

    def _get_help_string(self, action):
        text = action.help or ""
        default = action.default
        if (
            "default" in text
            or action.required
            or default is None
            or default is argparse.SUPPRESS
            or isinstance(default, bool)
            or not action.option_strings
        ):
            return text
        if isinstance(default, (list, tuple)):
            default = " ".join(map(str, default))
        return f"{text} (default: {default})"


def solver_option(solver: str, name: str) -> tuple:
    """``(default, spec)`` of one option, read from the solver's ``Options`` dataclass (never restated here)."""
    import dataclasses

    from ..solvers import get_solver

    for f in dataclasses.fields(get_solver(solver).Options):
        if f.name == name:
            return f.default, f.metadata["option"]
    raise KeyError(f"solver {solver!r} has no option {name!r}")


def solvers_with_option(name: str) -> tuple:
    """The registered solvers that declare the option ``name``, in registry order."""
    from ..solvers import get_solver, solver_names

    return tuple(s for s in solver_names() if name in get_solver(s).Options.__dataclass_fields__)


def option_text(solver: str, name: str) -> str:
    """Help of a solver option as the solver declares it: meaning, allowed values, default."""
    from ..solvers.base import option_help

    (row,) = [r for r in option_help(_options_class(solver)) if r[0] == name]
    _, default, allowed, text = row
    if isinstance(default, bool):
        return f"{text} (default: {'on' if default else 'off'})"
    shown = f"{default:g}" if isinstance(default, float) else str(default)
    return f"{text}; {allowed} (default: {shown})"


def option_choices(solver: str, name: str) -> tuple:
    """The allowed values of a solver option of kind 'choice'."""
    return tuple(solver_option(solver, name)[1]["choices"])


def _options_class(solver: str):
    from ..solvers import get_solver

    return get_solver(solver).Options


def print_outcome(record: dict, text: str, written, as_json: bool) -> int:
    """List the files ``written`` on stderr, then print ``record`` (with them) as JSON or ``text``."""
    import json

    files = report_written(written)
    print(json.dumps({**record, "files_written": files}) if as_json else text)
    return 0


def number_type(accept, requirement: str):
    """An argparse type: a float for which ``accept(value)`` holds, else "``requirement``, got ..."."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {requirement}, got {text!r}") from None
        if not accept(value):
            raise argparse.ArgumentTypeError(f"expected {requirement}, got {text!r}")
        return value

    return parse


def report_written(paths) -> list:
    """List the files written on stderr, once each, one line each; return them as strings (for JSON output).

    Bulky outputs enter as one :func:`files_summary` line (count and folder), not one line per file.
    """
    import sys

    names = list(dict.fromkeys(str(p) for p in paths))
    for name in names:
        print(f"wavecontact: wrote {name}", file=sys.stderr)
    return names


def files_summary(folder, pattern: str) -> str:
    """``"DIR/pattern (N files)"``: one entry for many files of one kind in ``folder``."""
    from pathlib import Path

    count = sum(1 for _ in Path(folder).glob(pattern))
    return f"{Path(folder) / pattern} ({count} file{'s' if count != 1 else ''})"


def contact_law(kappa: float, contact: str | None) -> str:
    """The contact law to use; refuse combinations whose printed kappa would not be the one computed."""
    if contact is None:
        return "hard" if math.isinf(kappa) else "exponential"
    if math.isinf(kappa) and contact == "exponential":
        raise ValueError("--contact exponential needs a finite --kappa; --kappa inf is the hard-core limit "
                         "(use --contact hard or leave --contact out)")
    if contact == "hard" and math.isfinite(kappa):
        raise ValueError(f"--contact hard is the limit kappa -> inf; --kappa {kappa:g} would not be used "
                         "(pass --kappa inf)")
    return contact


#: ``--contact`` help shared by the commands that take it: what kappa means for each law
CONTACT_HELP = ("contact law (default: exponential for finite --kappa, hard for --kappa inf); hard needs --kappa inf; "
                "penalty (fem only) is a spring of stiffness kappa Z_eff c / l, or at --kappa inf one of E A / h "
                "(the stiffer facing element), which tends to hard contact as the mesh is refined")


def kappa_text(kappa: float, contact: str) -> str:
    """How the printed kappa was used: the exponential law's softness, or the penalty spring it sets."""
    text = "inf" if math.isinf(kappa) else f"{kappa:g}"
    if contact == "penalty":
        text += (" (penalty stiffness E A / h of the stiffer facing element)" if math.isinf(kappa)
                 else " (penalty stiffness kappa Z_eff c / l)")
    return text


#: ``--rtol``, ``--initial-energy`` ...: a finite number > 0.
positive_float = number_type(lambda v: math.isfinite(v) and v > 0, "a finite positive number")


#: Figure formats every command writes (matplotlib would silently add ``.png`` to any other name).
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")
