"""Mesh-convergence study of the finite-element restitution.

For each discretization (element order x mass treatment) the paper's
collision is run on a sequence of meshes through the public entry point
``wavecontact.collide(gamma, kappa, solver="fem", elements=N, order=p,
mass=..., contact=...)``; the error of epsilon against an independent
reference is tabulated with the cost, and the observed order of convergence
is the slope of a least-squares line through ``log(error)`` against
``log(N)``.  Nothing here knows how the solver works.

References (``reference=None``):

* exponential contact, finite kappa: the delay-equation solver
  (``collide(gamma, kappa, solver="delay")``, exact for the continuum);
* hard contact or ``kappa = inf``, penalty contact included (at ``kappa =
  inf`` the solver ties its stiffness to the mesh, so it tends to hard
  contact as the mesh is refined): the hard-core limit, ``epsilon = gamma`` for ``0.5 <= gamma <= 1``
  (wave theory of impact) and the delay solver's hard-core mode otherwise;
* penalty contact at finite kappa (a spring of stiffness ``kappa Z_eff c /
  l``, docs/fem.md): none; pass ``reference=``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field

import numpy as np

from ..errors import InvalidParameterError, SolverFailure, require_integer
from ..progress import Progress
from ..result import to_jsonable

__all__ = [
    "ConvergenceRow",
    "ConvergenceTable",
    "DiscretizationFit",
    "convergence_study",
    "fit_order",
    "reference_restitution",
]

SOLVER = "fem"  # the study: mesh convergence of the finite elements
MASSES = ("lumped", "consistent")
CONTACTS = ("exponential", "penalty", "hard")
DEFAULT_ELEMENTS = (25, 50, 100, 200)
ERROR_FLOOR = 1e-13  # errors below this are round-off: kept in the table, left out of the fit


@dataclass(frozen=True)
class ConvergenceRow:
    """One run of the study.

    Attributes
    ----------
    order : int
        Lagrange element order.
    mass : {'lumped', 'consistent'}
        Mass treatment.
    elements : int
        Elements on the shorter rod.
    restitution : float or None
        epsilon from the fem solver (None if the run failed).
    error : float or None
        ``|epsilon - reference|``.
    local_order : float or None
        ``log(e_prev / e) / log(N / N_prev)`` against the previous mesh of the
        same discretization (None on the first mesh or at round-off).
    wall_time_s : float or None
        Wall-clock time of the solve (s).
    steps : int or None
        Time steps taken (``result.work["steps"]``).
    failure : str or None
        The solver's refusal message if it raised :class:`SolverFailure`.
    """

    order: int
    mass: str
    elements: int
    restitution: float | None
    error: float | None
    local_order: float | None
    wall_time_s: float | None
    steps: int | None
    failure: str | None = None


@dataclass(frozen=True)
class DiscretizationFit:
    """Observed order of one discretization: ``error ~ constant * N**(-observed_order)``.

    ``observed_order`` is None (and ``note`` says why) when fewer than two
    meshes have an error above round-off.
    """

    order: int
    mass: str
    observed_order: float | None
    constant: float | None
    points: int
    note: str = ""

    @property
    def label(self) -> str:
        return f"P{self.order} {self.mass}"


@dataclass
class ConvergenceTable:
    """Result of :func:`convergence_study`.

    Attributes
    ----------
    gamma, kappa : float
        The collision studied (``kappa = inf``: hard contact).
    contact : str
        Contact law name.
    reference : float
        The reference epsilon the errors are measured against.
    reference_source : str
        Where it comes from.
    rows : list of ConvergenceRow
        Every run, grouped by discretization, meshes ascending.
    fits : list of DiscretizationFit
        One per discretization, in the order of ``rows``.
    solver_options : dict
        Extra options passed to every fem run.
    """

    gamma: float
    kappa: float
    contact: str
    reference: float
    reference_source: str
    rows: list = field(default_factory=list)
    fits: list = field(default_factory=list)
    solver_options: dict = field(default_factory=dict)

    def rows_for(self, order: int, mass: str) -> list:
        """The rows of one discretization, meshes ascending."""
        return [r for r in self.rows if r.order == order and r.mass == mass]

    def fit_for(self, order: int, mass: str) -> DiscretizationFit:
        """The fitted order of one discretization."""
        for fit in self.fits:
            if fit.order == order and fit.mass == mass:
                return fit
        raise KeyError(f"no discretization P{order} {mass} in this study")

    def to_dict(self) -> dict:
        """JSON-ready dict: the collision, the reference, and per discretization its fit and rows."""
        return to_jsonable(
            {
                "gamma": self.gamma,
                "kappa": self.kappa,
                "contact": self.contact,
                "reference": self.reference,
                "reference_source": self.reference_source,
                "solver_options": dict(self.solver_options),
                "discretizations": [
                    {**asdict(fit), "rows": [asdict(r) for r in self.rows_for(fit.order, fit.mass)]}
                    for fit in self.fits
                ],
            }
        )

    def to_json(self, **kwargs) -> str:
        """:meth:`to_dict` as one JSON object (``inf`` written as ``"inf"``)."""
        return json.dumps(self.to_dict(), **kwargs)

    def format_text(self) -> str:
        """Plain-text table per discretization (what ``wavecontact converge`` prints)."""
        kappa = "inf" if math.isinf(self.kappa) else f"{self.kappa:g}"
        lines = [
            f"mesh convergence of epsilon: gamma = {self.gamma:g}, kappa = {kappa}, contact = {self.contact}",
            f"reference epsilon = {self.reference:.12g} ({self.reference_source})",
        ]
        for fit in self.fits:
            lines.append("")
            if fit.observed_order is None:
                lines.append(f"{fit.label}: observed order n/a ({fit.note})")
            else:
                lines.append(
                    f"{fit.label}: observed order {fit.observed_order:.3f} "
                    f"(least-squares fit over {fit.points} meshes)"
                )
            lines.append(
                f"{'elements':>9} {'restitution':>16} {'error':>10} {'order':>7} "
                f"{'wall time [ms]':>15} {'steps':>9}"
            )
            for r in self.rows_for(fit.order, fit.mass):
                if r.failure is not None:
                    lines.append(f"{r.elements:>9d}  failed: {r.failure}")
                    continue
                local = "-" if r.local_order is None else f"{r.local_order:.2f}"
                steps = "-" if r.steps is None else f"{r.steps:d}"
                lines.append(
                    f"{r.elements:>9d} {r.restitution:>16.12f} {r.error:>10.3e} {local:>7} "
                    f"{1e3 * r.wall_time_s:>15.3f} {steps:>9}"
                )
        return "\n".join(lines)


def fit_order(elements: Sequence[float], errors: Sequence[float], floor: float = ERROR_FLOOR):
    """Least-squares fit ``log(error) = log(constant) - p log(N)``.

    Parameters
    ----------
    elements : sequence of float
        Mesh sizes ``N`` (elements).
    errors : sequence of float or None
        Errors on those meshes; None, non-finite values and values below
        ``floor`` (round-off) are left out.
    floor : float
        Smallest error taken as a truncation error.

    Returns
    -------
    (order, constant, points) : (float or None, float or None, int)
        ``order = p`` (positive when the error falls), or None when fewer
        than two distinct meshes remain.
    """
    pairs = [
        (float(n), float(e))
        for n, e in zip(elements, errors)
        if e is not None and math.isfinite(e) and e > floor
    ]
    if len({n for n, _ in pairs}) < 2:
        return None, None, len(pairs)
    log_n = np.log([n for n, _ in pairs])
    log_e = np.log([e for _, e in pairs])
    slope, intercept = np.polyfit(log_n, log_e, 1)
    return float(-slope), float(math.exp(intercept)), len(pairs)


def reference_restitution(
    gamma: float, kappa: float, contact: str = "exponential", collide: Callable | None = None
) -> tuple:
    """The reference epsilon of the study and where it comes from.

    Returns
    -------
    (value, source) : (float, str)
    """
    if collide is None:
        from ..api import collide
    if contact == "exponential" and math.isfinite(kappa):
        return float(collide(gamma, kappa, solver="delay").restitution), "delay solver"
    if contact == "penalty" and math.isfinite(kappa):
        raise InvalidParameterError(
            "penalty contact at finite kappa (stiffness kappa Z_eff c / l, docs/fem.md) has no independent "
            "reference: pass reference=, or use kappa=inf (stiffness tied to the mesh, tending to hard contact)"
        )
    if 0.5 <= gamma <= 1.0:
        return float(gamma), "hard-core limit epsilon = gamma (wave theory of impact)"
    return float(collide(gamma, math.inf, solver="delay").restitution), "delay solver, hard-core limit"


def convergence_study(
    gamma: float,
    kappa: float,
    orders: Sequence[int] = (1, 2),
    masses: Sequence[str] = MASSES,
    elements: Sequence[int] = DEFAULT_ELEMENTS,
    contact: str = "exponential",
    reference: float | None = None,
    *,
    solver_options: dict | None = None,
    progress: bool | None = None,
    warmup: bool = True,
    collide: Callable | None = None,
) -> ConvergenceTable:
    """Run the fem solver on a sequence of meshes for each discretization.

    Parameters
    ----------
    gamma : float
        Length ratio ``l1 / l2`` in (0, 1].
    kappa : float
        ``alpha V l / c`` in (0, inf]; ``inf`` selects hard contact.
    orders : sequence of int
        Lagrange element orders (>= 1).
    masses : sequence of {'lumped', 'consistent'}
        Mass treatments.
    elements : sequence of int
        Elements on the shorter rod; at least two distinct values (duplicates
        are dropped, the meshes run in ascending order).
    contact : {'exponential', 'penalty', 'hard'}
        Contact law (``kappa = inf`` forces ``'hard'``).
    reference : float or None
        The exact epsilon; None picks it as described in the module docstring.
    solver_options : dict or None
        Further fem options passed to every run (e.g. ``{"courant": 0.5}``).
    progress : bool or None
        Show a progress bar on stderr; None: only when stderr is a terminal.
    warmup : bool
        Before the timed runs of each discretization, solve once on the
        coarsest mesh and discard the result, so that one-off costs (numba
        compilation, caches) do not land in the wall time of the first row.
    collide : callable or None
        The entry point to call, ``collide(gamma, kappa, solver=..., contact=...,
        **options) -> CollisionResult``; None means :func:`wavecontact.collide`
        (tests pass a stand-in with a known error).

    Returns
    -------
    ConvergenceTable
        Rows (order, mass, elements, restitution, error, local order, wall
        time, steps) and one least-squares fit per discretization.

    Raises
    ------
    InvalidParameterError
        For bad orders, masses, element counts or contact names.

    Notes
    -----
    A run the solver refuses with :class:`~wavecontact.errors.SolverFailure`
    (say, a contact it cannot resolve on a coarse mesh) is kept as a failed
    row and left out of the fit; every other error propagates.
    """
    from ..scene import validate_gamma_kappa

    gamma, kappa = validate_gamma_kappa(gamma, kappa)
    orders = _positive_ints("orders", orders)
    masses = _unique(masses)
    if not masses or any(m not in MASSES for m in masses):
        raise InvalidParameterError(f"masses must be taken from {', '.join(MASSES)}, got {list(masses)!r}")
    meshes = sorted(set(_positive_ints("elements", elements)))
    if len(meshes) < 2:
        raise InvalidParameterError(
            f"elements needs at least two different mesh sizes to fit an order, got {meshes}"
        )
    if contact not in CONTACTS:
        raise InvalidParameterError(f"contact must be one of {', '.join(CONTACTS)}, got {contact!r}")
    if math.isinf(kappa):
        contact = "hard"
    if collide is None:
        from ..api import collide
    if reference is None:
        reference, source = reference_restitution(gamma, kappa, contact, collide)
    else:
        reference, source = float(reference), "given"
        if not math.isfinite(reference):
            raise InvalidParameterError(f"reference must be a finite number, got {reference!r}")
    options = dict(solver_options or {})
    for reserved in ("elements", "order", "mass"):
        if reserved in options:
            raise InvalidParameterError(f"solver_options may not set {reserved!r}; the study varies it")

    table = ConvergenceTable(
        gamma=gamma,
        kappa=kappa,
        contact=contact,
        reference=reference,
        reference_source=source,
        solver_options=options,
    )
    runs = [(p, m, n) for p in orders for m in masses for n in meshes]
    bar = Progress(len(runs), "converge", unit="run", enabled=progress)
    try:
        for p in orders:
            for m in masses:
                rows = []
                if warmup:
                    bar.describe(f"P{p} {m} warm-up")
                    _warm_up(collide, gamma, kappa, contact, p, m, meshes[0], options)
                for n in meshes:
                    bar.describe(f"P{p} {m} N={n}")
                    rows.append(_one_run(collide, gamma, kappa, contact, p, m, n, reference, options, rows))
                    bar.advance()
                table.rows.extend(rows)
                table.fits.append(_fit(p, m, rows))
    finally:
        bar.close()
    return table


def _warm_up(collide, gamma, kappa, contact, order, mass, elements, options) -> None:
    try:
        collide(
            gamma, kappa, solver=SOLVER, contact=contact, elements=elements, order=order, mass=mass, **options
        )
    except SolverFailure:
        pass  # the timed run meets it again and records it


def _one_run(
    collide, gamma, kappa, contact, order, mass, elements, reference, options, previous
) -> ConvergenceRow:
    try:
        result = collide(
            gamma, kappa, solver=SOLVER, contact=contact, elements=elements, order=order, mass=mass, **options
        )
    except SolverFailure as exc:
        return ConvergenceRow(order, mass, elements, None, None, None, None, None, failure=str(exc))
    restitution = float(result.restitution)
    if not math.isfinite(restitution):
        return ConvergenceRow(
            order,
            mass,
            elements,
            None,
            None,
            None,
            float(result.wall_time_s),
            None,
            failure=f"non-finite restitution {restitution!r}",
        )
    error = abs(restitution - reference)
    local = None
    last = next((r for r in reversed(previous) if r.error is not None), None)
    if last is not None and last.error > ERROR_FLOOR and error > ERROR_FLOOR:
        local = math.log(last.error / error) / math.log(elements / last.elements)
    steps = result.work.get("steps") if isinstance(result.work, dict) else None
    return ConvergenceRow(
        order,
        mass,
        elements,
        restitution,
        error,
        local,
        float(result.wall_time_s),
        None if steps is None else int(steps),
    )


def _fit(order: int, mass: str, rows: list) -> DiscretizationFit:
    done = [r for r in rows if r.error is not None]
    p, constant, points = fit_order([r.elements for r in done], [r.error for r in done])
    note = ""
    if p is None:
        if len(done) < 2:
            note = "fewer than two meshes ran"
        else:
            note = f"fewer than two errors above round-off ({ERROR_FLOOR:g})"
    return DiscretizationFit(order, mass, p, constant, points, note)


def _positive_ints(name: str, values) -> list:
    out = []
    for v in values:
        out.append(require_integer(name, v, 1, allowed="positive integers"))
    if not out:
        raise InvalidParameterError(f"{name} must not be empty")
    return _unique(out)


def _unique(values) -> list:
    seen = []
    for v in values:
        if v not in seen:
            seen.append(v)
    return seen




