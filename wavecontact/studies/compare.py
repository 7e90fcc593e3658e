"""One collision by every solver at a few resolutions: do they agree, and at what cost?

Built only on :func:`wavecontact.collide`; the reference is the delay
equation solved far tighter than any entry (``rtol = 1e-13``), or the exact
hard-core recursion for ``kappa = inf``.  A solver that refuses a case (an
error it raises on purpose) appears as a row with its message, never as a
number.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from ..api import collide
from ..errors import WavecontactError, require_integer
from ..progress import Progress
from ..solvers import get_solver, solver_names

__all__ = ["ComparisonRow", "ComparisonTable", "Method", "compare_solvers", "default_methods", "method_labels",
           "reference_restitution"]


@dataclass(frozen=True)
class Method:
    """One solver at one resolution: what :func:`wavecontact.collide` receives."""

    solver: str
    options: dict = field(default_factory=dict)
    label: str = ""
    work_unit: str = "steps"  # the counter in result.work that measures the effort

    def describe(self) -> str:
        if self.label:
            return self.label
        return ", ".join(f"{k}={v}" for k, v in self.options.items()) or "defaults"


@dataclass
class ComparisonRow:
    """The outcome of one :class:`Method` on the compared collision."""

    solver: str
    resolution: str
    restitution: float | None
    error: float | None
    wall_time_s: float | None
    work_unit: str
    work: float | None
    status: str  # "ok" or the solver's error message
    family: str = ""  # the series of a figure: one per solver and discretization (solver.comparison_family)
    point: str = ""  # the resolution written next to the point: elements, modes or the tolerance

    @property
    def ok(self) -> bool:
        return self.status == "ok"


@dataclass
class ComparisonTable:
    """All rows of one comparison, with the reference they are measured against."""

    gamma: float
    kappa: float
    reference: float
    reference_source: str
    rows: list

    def to_dict(self) -> dict:
        kappa = "inf" if math.isinf(self.kappa) else self.kappa
        return {
            "gamma": self.gamma,
            "kappa": kappa,
            "reference": self.reference,
            "reference_source": self.reference_source,
            "rows": [asdict(row) for row in self.rows],
        }

    def to_json(self, **kwargs) -> str:
        return json.dumps(self.to_dict(), **kwargs)

    def format(self) -> str:
        """A plain-text table for the terminal."""
        kappa = "inf" if math.isinf(self.kappa) else f"{self.kappa:g}"
        lines = [
            (f"gamma = {self.gamma:g}, kappa = {kappa}: reference epsilon = {self.reference:.12f} "
            f"({self.reference_source})"),
            f"{'solver':<7} {'resolution':<34} {'epsilon':>15} {'error':>9} {'time (ms)':>10} {'work':>16}",
        ]
        for row in self.rows:
            if not row.ok:
                lines.append(f"{row.solver:<7} {row.resolution:<34} FAILED: {row.status}")
                continue
            work = f"{row.work:.3g} {row.work_unit}" if row.work is not None else "-"
            lines.append(
                f"{row.solver:<7} {row.resolution:<34} {row.restitution:>15.11f} {row.error:>9.1e} "
                f"{1e3 * row.wall_time_s:>10.3f} {work:>16}"
            )
        return "\n".join(lines)


def default_methods(kappa: float) -> list:
    """A few resolutions of every registered solver and discretization, cheap to expensive
    (each solver's ``comparison_methods``)."""
    return [Method(name, options, label, work_unit) for name in solver_names()
            for options, label, work_unit in get_solver(name).comparison_methods(kappa)]


def method_labels(method: Method) -> tuple:
    """``(family, point)`` of a method: its solver's series and the value of its resolution option."""
    solver = get_solver(method.solver)
    try:
        family = solver.comparison_family(solver.options(method.options))
    except WavecontactError:
        family = method.solver
    value = method.options.get(solver.resolution)
    return family, method.describe() if value is None else format(value, "g")


def reference_restitution(gamma: float, kappa: float) -> tuple:
    """``(epsilon, source)``: the tight delay solution or the exact hard-core value."""
    value = collide(gamma, kappa, "delay", rtol=1e-13).restitution
    source = "delay equation, hard-core recursion" if math.isinf(kappa) else "delay equation, rtol = 1e-13"
    return value, source


def compare_solvers(gamma: float, kappa: float, methods=None, *, repeats: int = 1,
                    progress: bool | None = None, warmup: bool = True) -> ComparisonTable:
    """Run every method on the collision ``(gamma, kappa)``.

    Parameters
    ----------
    gamma, kappa : float
        The collision (``kappa = inf``: hard contact).
    methods : list of Method or None
        What to run; default :func:`default_methods`.
    repeats : int
        Repeat each solve and keep the median wall time (s).
    progress : bool or None
        tqdm bar on stderr (default: when stderr is a terminal).
    warmup : bool
        Repeat any solve during which numba compiled or loaded kernels
        (``diagnostics["includes_kernel_preparation"]``), so that this one-time
        cost is charged to no row.

    Returns
    -------
    ComparisonTable
    """
    repeats = require_integer("repeats", repeats, 1, allowed="a positive integer")
    reference, source = reference_restitution(gamma, kappa)
    methods = default_methods(kappa) if methods is None else list(methods)
    bar = Progress(len(methods), "compare", unit="method", enabled=progress)
    contact = "hard" if math.isinf(kappa) else "exponential"
    rows = []
    for method in methods:
        bar.advance()
        family, point = method_labels(method)
        times, untimed = [], 0
        try:
            while len(times) < int(repeats):
                started = time.perf_counter()
                result = collide(gamma, kappa, method.solver, contact=contact, **method.options)
                elapsed = time.perf_counter() - started
                # numba compiled or loaded a kernel during this call (the first one of a solver,
                # or a discretization with kernels of its own): not the method's cost, run again
                if warmup and result.diagnostics.get("includes_kernel_preparation") and untimed < 3:
                    untimed += 1
                else:
                    times.append(elapsed)
        except WavecontactError as exc:
            rows.append(ComparisonRow(method.solver, method.describe(), None, None, None,
                                      method.work_unit, None, str(exc), *method_labels(method)))
            continue
        work = result.work.get(method.work_unit)
        rows.append(
            ComparisonRow(
                solver=method.solver,
                resolution=method.describe(),
                restitution=result.restitution,
                error=abs(result.restitution - reference),
                wall_time_s=float(np.median(times)),
                work_unit=method.work_unit,
                work=None if work is None else float(work),
                status="ok",
                family=family,
                point=point,
            )
        )
    bar.close()
    return ComparisonTable(gamma, kappa, reference, source, rows)
