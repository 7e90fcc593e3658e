"""Finite-element solver: Lagrange elements in space, central differences in time.

Each rod is discretized with scikit-fem (:mod:`wavecontact.fem.discretization`);
the time loop (:mod:`wavecontact.fem.kernels`) is central differences with
the contact handled per run: through the characteristic interface on the
exact lattice (P1 lumped, Courant number 1), as a plain force at the end
nodes where the mesh and step resolve the contact, and through the exact
massless-end gap equation where they do not, which keeps it stable for any
contact stiffness (docs/fem.md).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InvalidParameterError
from ..fem.simulation import build_setup, run_collision
from ..result import CollisionResult
from ..scene import Scene, two_rod_parameters

NAME = "fem"
OPTIONS = {
    "elements": 800,
    "order": 1,
    "mass": "lumped",
    "nodes": None,
    "dt": None,
    "courant": None,
    "hard_scheme": "plastic",
    "scheme": "auto",
    "gap_quadrature": "substeps",
    "record_fields": False,
    "field_samples": 300,
    "energy_tolerance": 0.05,
    "max_time": None,
}

# Convergence order of epsilon where the contact is resolved (alpha V h / c <= 1), per discretization
# with scheme='auto': P1 lumped on matched meshes at Courant number 1 uses the characteristic
# interface on the exact lattice (at least second order; about third where the error keeps one
# sign); the others (and P1 lumped at Courant < 1 or on user meshes) use plain central differences
# with the contact force at the end nodes, second order (fits 1.9-2.2 at gamma = 0.6, kappa = 20
# and 100, docs/fem.md).  Where the mesh does not resolve the contact they fall back to the
# massless-end interface (first order in h, stable for any stiffness).  Tests compare a log-log
# fit with these.
EXPECTED_ORDER = {(1, "lumped"): 2, (1, "consistent"): 2, (2, "lumped"): 2, (2, "consistent"): 2}

_FORCE_THRESHOLD = 1e-2  # of the peak: contact start and end (as the delay solver)


def solve(scene: Scene, **options) -> CollisionResult:
    """One collision of two rods with the finite-element solver.

    Parameters
    ----------
    scene : Scene
        Two rods on a line, any materials; cold or with initial fields.
    elements : int
        Elements on the shorter rod (the other rod: same element travel time ``h/c``).
    order : {1, 2}
        Lagrange order of the elements.
    mass : {'lumped', 'consistent'}
        Mass matrix.
    nodes : pair of arrays or None
        Element end points per rod (rod coordinate from 0 to its length); overrides ``elements``.
    dt : float or None
        Time step (time units); refused above the stable step ``2/sqrt(lambda_max(M^-1 K))``.
    courant : float or None
        Fraction of the stable step when ``dt`` is None (default: see :func:`build_setup`).
    hard_scheme : {'plastic', 'elastic'}
        End-node impact rule for hard contact in the 'splitting' scheme.
    scheme : {'auto', 'characteristic', 'force', 'interface', 'splitting'}
        Contact treatment (see :func:`wavecontact.fem.simulation.build_setup`).
    gap_quadrature : {'substeps', 'gauss'}
        Integration of the gap equation inside a step where the characteristic
        scheme reconstructs the incoming rate (see :func:`build_setup`).
    record_fields : bool
        Sample displacement, velocity and stress fields over the collision
        into ``result.extra['fields']`` (runs the collision a second time).
    field_samples : int
        Number of field samples (about 200-400 is plenty for a picture).
    energy_tolerance : float
        Relative energy error (of the energy in the centre-of-mass frame)
        above which the run is stopped with :class:`~wavecontact.errors.SolverFailure`.
    max_time : float or None
        Give up (SolverFailure) if the rods have not separated by then.

    Returns
    -------
    CollisionResult
    """
    _check_options(options)
    setup = build_setup(
        scene,
        elements=options["elements"],
        order=options["order"],
        mass=options["mass"],
        nodes=options["nodes"],
        dt=options["dt"],
        courant=options["courant"],
        hard_scheme=options["hard_scheme"],
        scheme=options["scheme"],
        gap_quadrature=options["gap_quadrature"],
    )
    out = run_collision(
        setup,
        energy_tolerance=options["energy_tolerance"],
        max_time=options["max_time"],
        record_fields=options["record_fields"],
        field_samples=options["field_samples"],
    )
    run = out["run"]
    approach = run.approach
    force = out["contact_force"]
    # centre-of-mass bookkeeping with the rods' true masses (a matched mesh may leave out
    # less than one element at the far end of the long rod when the contact is stiff)
    masses = [rod.mass for rod in scene.rods]
    impulse = np.cumsum(force) * setup.dt
    relative_velocity = -approach + impulse * (1.0 / masses[0] + 1.0 / masses[1])
    restitution = abs(relative_velocity[-1]) / abs(approach)
    time = out["time"]
    start, duration = _contact_window(time, force, setup.dt)
    total_energy = out["kinetic"] + out["strain"] + out["contact"]
    energy_drift = abs(total_energy[-1] - run.energy0) / run.energy_scale if total_energy.size else 0.0
    max_drift = float(np.max(np.abs(total_energy - run.energy0))) / run.energy_scale if total_energy.size else 0.0
    momentum_end = run.momentum()
    momentum_drift = abs(momentum_end - run.momentum0) / abs(run.momentum_scale)
    elements = [d.n_elements for d in setup.rods]
    try:
        params = two_rod_parameters(scene)
        gamma, kappa = params.gamma, params.kappa
    except InvalidParameterError:
        gamma = kappa = None
    extra = {
        "energies": {
            "time": out["energy_time"],
            "kinetic": out["kinetic"],
            "strain": out["strain"],
            "contact": out["contact"],
        },
        "rod_energy_after": [float(out["internal"][0][-1]), float(out["internal"][1][-1])]
        if out["energy_time"].size
        else [math.nan, math.nan],
        "gap": out["gap"],
        "initial_gap": setup.gap,
        "stable_step": setup.stable_step,
        "scheme": _scheme_name(setup, options),
        "nodes_per_rod": [d.n_nodes for d in setup.rods],
    }
    if "fields" in out:
        extra["fields"] = out["fields"]
    return CollisionResult(
        restitution=float(restitution),
        solver=NAME,
        wall_time_s=0.0,
        time=time,
        relative_velocity=relative_velocity,
        gamma=gamma,
        kappa=kappa,
        contact_force=force,
        contact_start=start,
        contact_duration=duration,
        error_estimate=None,
        work={
            "steps": out["steps"],
            "element_steps": out["steps"] * sum(elements),
            "elements": elements,
            "dt": setup.dt,
            "order": options["order"],
            "mass": options["mass"],
        },
        diagnostics={
            "energy_drift": float(energy_drift),
            "max_energy_drift": float(max_drift),
            "momentum_drift": float(momentum_drift),
        },
        extra=extra,
    )


def _contact_window(time, force, dt):
    if force.size == 0 or force.max() <= 0.0:
        return None, None
    active = np.flatnonzero(force > _FORCE_THRESHOLD * force.max())
    # force[i] is the mean over the step ending at time[i]
    begin = time[active[0]] - dt
    end = time[active[-1]]
    return float(begin), float(end - begin)


def _scheme_name(setup, options) -> str:
    contact = {0: "exponential", 1: "penalty", 2: "hard (elastic node impact)", 3: "hard"}[setup.law]
    base = f"P{options['order']} {options['mass']} mass, central differences, {contact} contact"
    if setup.scheme == 0:
        return base + " through the characteristic interface (incoming characteristics, exact gap equation)"
    if setup.scheme == 1:
        return base + " through the massless-end interface (exact gap equation)"
    if setup.scheme == 3:
        return base + " applied as a force at the end nodes (plain central differences, contact-resolving step)"
    return base + " through the impulse splitting (exact flow of the end-node pair)"


def _check_options(options):
    if not isinstance(options["record_fields"], (bool, np.bool_)):
        raise InvalidParameterError(f"record_fields must be True or False, got {options['record_fields']!r}")
    samples = options["field_samples"]
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or not 2 <= samples <= 100000:
        raise InvalidParameterError(f"field_samples must be an integer in [2, 100000], got {samples!r}")
    tol = options["energy_tolerance"]
    if not (isinstance(tol, (int, float)) and 0.0 < tol < math.inf):
        raise InvalidParameterError(f"energy_tolerance must be a positive number, got {tol!r}")
