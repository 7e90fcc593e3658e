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
from dataclasses import dataclass

import numpy as np

from ..contact import Exponential
from ..errors import InvalidParameterError
from ..limits import Cost
from ..scene import Scene
from ..solvers.base import SolverBase, SolverOptions, option
from .simulation import build_setup, run_collision

__all__ = ["EXPECTED_ORDER", "SOLVER", "FemOptions", "FemSolver"]


def _nodes(value):
    if not (isinstance(value, (tuple, list)) and len(value) == 2):
        raise InvalidParameterError("fem option nodes must be a pair (rod 1 vertices, rod 2 vertices) or None")
    return tuple(np.asarray(v, dtype=float) for v in value)


@dataclass(frozen=True)
class FemOptions(SolverOptions):
    """Options of the finite-element solver (times in the scene's time units)."""

    solver_name = "fem"
    elements: int = option(800, "elements on the shorter rod (the other rod: same element travel time h/c)",
                           kind="int", low=1, high=10**6)
    order: int = option(1, "Lagrange order of the elements", kind="choice", choices=(1, 2))
    mass: str = option("lumped", "mass matrix", kind="choice", choices=("lumped", "consistent"))
    nodes: tuple | None = option(None, "element end points per rod (rod coordinate 0..length); overrides elements",
                                 kind="object", allow_none=True, check=_nodes)
    dt: float | None = option(None, "time step (time units), at most the stable step; None: chosen",
                              low=0.0, allow_none=True)
    courant: float | None = option(None, "fraction of the stable step when dt is None; None: chosen",
                                   low=1e-6, high=1.0, allow_none=True)
    hard_scheme: str = option("plastic", "end-node impact rule of hard contact in the 'splitting' scheme",
                              kind="choice", choices=("plastic", "elastic"))
    scheme: str = option("auto", "contact treatment (docs/fem.md)", kind="choice",
                         choices=("auto", "characteristic", "force", "interface", "splitting"))
    gap_quadrature: str = option("substeps", "integration of the gap equation inside a step",
                                 kind="choice", choices=("substeps", "gauss"))
    record_fields: bool = option(False, "sample displacement, velocity and stress fields (a second run)",
                                 kind="bool")
    field_samples: int = option(300, "number of field samples", kind="int", low=2, high=100_000)
    energy_tolerance: float = option(0.05, "relative energy error that stops the run with SolverFailure",
                                     low=1e-15, high=1e3)
    max_time: float | None = option(None, "give up if the rods have not separated by then (time units)",
                                    low=0.0, allow_none=True)

# Convergence order of epsilon where the contact is resolved (alpha V h / c <= 1), per discretization
# with scheme='auto': P1 lumped on matched meshes at Courant number 1 uses the characteristic
# interface on the exact lattice (at least second order; about third where the error keeps one
# sign); the others (and P1 lumped at Courant < 1 or on user meshes) use plain central differences
# with the contact force at the end nodes, second order (fits 1.9-2.2 at gamma = 0.6, kappa = 20
# and 100, docs/fem.md).  Where the mesh does not resolve the contact they fall back to the
# massless-end interface (first order in h, stable for any stiffness).  Tests compare a log-log
# fit with these.
EXPECTED_ORDER = {(1, "lumped"): 2, (1, "consistent"): 2, (2, "lumped"): 2, (2, "consistent"): 2}
# Order assumed by the error estimate where the facing elements do not resolve the contact
# (alpha V h / c > RESOLVED_BELOW, hard and penalty contact): the front spreads like h^(2/3)
# (docs/fem.md); the threshold is the measured best trade-off of coverage and sharpness
# (docs/error_estimates.md)
UNRESOLVED_ORDER = 2.0 / 3.0
RESOLVED_BELOW = 3.0
# Stable step in units of the element travel time h/c (MODEL.md 7), for the cost estimate
_STABLE_COURANT = {(1, "lumped"): 1.0, (1, "consistent"): 0.577, (2, "lumped"): 0.408, (2, "consistent"): 0.258}
# Doubles held per node (state, masses, matrices, kernel buffers) and per step (histories)
_BYTES_PER_NODE = 8 * 48
_BYTES_PER_STEP = 8 * 8


class FemSolver(SolverBase):
    """Finite elements (scikit-fem) in space, explicit central differences in time."""

    name = "fem"
    Options = FemOptions
    resolution = "elements"
    refines = 1
    error_safety = 4.0

    def expected_order(self, options: FemOptions) -> float:
        """Order of epsilon in ``h`` where the contact is resolved (:data:`EXPECTED_ORDER`)."""
        return float(EXPECTED_ORDER[(options.order, options.mass)])

    def _collide(self, scene: Scene, options: FemOptions) -> dict:
        return _collide(scene, options.as_dict())

    def coarser_options(self, options: FemOptions):
        """Half the elements (a user mesh ``nodes`` has no coarser twin: no estimate)."""
        if options.nodes is not None or options.elements < 2:
            return None
        return options.replace(elements=options.elements // 2, record_fields=False)

    def estimate_order(self, scene: Scene, options: FemOptions) -> float:
        """:data:`EXPECTED_ORDER` where ``alpha V h / c <= RESOLVED_BELOW``, else :data:`UNRESOLVED_ORDER`."""
        contact = scene.contact
        if isinstance(contact, Exponential) and len(scene.rods) == 2:
            shorter = min(scene.rods, key=lambda rod: rod.length)
            travel = shorter.length / options.elements / shorter.wave_speed
            if contact.alpha * abs(scene.velocities[0] - scene.velocities[1]) * travel <= RESOLVED_BELOW:
                return self.expected_order(options)
        return UNRESOLVED_ORDER

    def estimate_cost(self, scene: Scene, options: FemOptions) -> Cost | None:
        """Nodes, steps (at least: a contact-resolving step may be smaller) and memory, from the options."""
        if scene.is_ring or len(scene.rods) != 2:
            return None
        rods = scene.rods
        if options.nodes is not None:
            elements = [max(len(n) - 1, 1) for n in options.nodes]
            travel = min(float(np.min(np.diff(n))) / rod.wave_speed if len(n) > 1 else rod.length / rod.wave_speed
                         for n, rod in zip(options.nodes, rods))
        else:
            shorter = min(rods, key=lambda rod: rod.length)
            travel = shorter.length / options.elements / shorter.wave_speed
            elements = [math.ceil(rod.length / (travel * rod.wave_speed)) for rod in rods]
        nodes = options.order * sum(elements) + 2
        stable = _STABLE_COURANT[(options.order, options.mass)] * travel
        if options.dt is not None:
            dt = options.dt
        elif options.courant is not None:
            dt = options.courant * stable
        else:
            dt = stable if (options.order, options.mass) == (1, "lumped") else 0.95 * stable
        speed = max(abs(scene.velocities[0] - scene.velocities[1]), 1e-300)
        span = 4.0 * sum(rod.length / rod.wave_speed for rod in rods)
        if isinstance(scene.contact, Exponential):
            span += 100.0 / (scene.contact.alpha * speed)  # in from and out to where the force is negligible
        if options.max_time is not None:
            span = min(span, options.max_time)
        steps = span / dt
        runs = 2 if options.record_fields else 1  # fields are sampled in a second run
        return Cost(steps=steps, work=runs * steps * nodes,
                    memory=nodes * _BYTES_PER_NODE + steps * _BYTES_PER_STEP,
                    detail=f"{nodes:.3g} nodes, at least {steps:.3g} steps of dt = {dt:.3g}")


def _collide(scene: Scene, options: dict) -> dict:
    """One collision of two rods with the finite-element solver (options: :class:`FemOptions`).

    Returns
    -------
    dict
        The fields of the result (see :class:`wavecontact.solvers.base.SolverBase`).
    """
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
    total_energy = out["kinetic"] + out["strain"] + out["contact"]
    energy_drift = abs(total_energy[-1] - run.energy0) / run.energy_scale if total_energy.size else 0.0
    max_drift = float(np.max(np.abs(total_energy - run.energy0))) / run.energy_scale if total_energy.size else 0.0
    momentum_end = run.momentum()
    momentum_drift = abs(momentum_end - run.momentum0) / abs(run.momentum_scale)
    elements = [d.n_elements for d in setup.rods]
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
    return {
        "restitution": restitution,
        "time": time,
        "relative_velocity": relative_velocity,
        "contact_force": force,
        "force_sampling": "interval",  # force[i] is the mean over the step ending at time[i]
        "energy_drift": energy_drift,
        "momentum_drift": momentum_drift,
        "work": {
            "steps": out["steps"],
            "element_steps": out["steps"] * sum(elements),
            "elements": elements,
            "dt": setup.dt,
        },
        "extra": {**extra, "max_energy_drift": float(max_drift)},
    }


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


SOLVER = FemSolver()
