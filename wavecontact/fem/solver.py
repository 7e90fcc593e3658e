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
from types import MappingProxyType

import numpy as np

from ..bath.scene import end_speed
from ..errors import InvalidParameterError, SolverFailure
from ..limits import Cost
from ..scene import Scene
from ..solvers.base import ENERGY_SPLIT, CollisionFields, SolverBase, SolverOptions, option
from . import kernels
from .error_estimate import ESTIMATE_SAFETY
from .error_estimate import estimate_from_levels as _estimate_from_levels
from .error_estimate import estimate_with_finer as _estimate_with_finer
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
# The massless-end interface (the contact scheme of P1 consistent and P2 where the mesh does not resolve the
# contact, and of hard and penalty contact) is first order in h (docs/fem.md section 4, its forced rows:
# fitted orders 0.96-1.03); the error estimate's runs are held to it where the requested run used it
INTERFACE_ORDER = 1.0
# The error estimate (docs/error_estimates.md section 1) is the pure function
# error_estimate.estimate_from_levels of the coarser runs' restitutions.
# Below this many elements the runs at N/2 and N/4 have fewer than 16 and 8 elements, their errors
# (up to 1e-2 with an unresolved or hard contact) are in no asymptotic regime, and the coarse rule
# bounded them in only 79 to 97 % of the sweeps' collisions; there the solver also runs 2N elements
# (four times the requested run's work, milliseconds at these sizes) and estimates the error from
# the difference to that run (error_estimate.estimate_with_finer)
FINER_BELOW = 32
# P1 lumped on the characteristic lattice with alpha V dt above this (dt = h / c) and both far-end echoes
# within one step (gamma near 1): epsilon is low by about 0.7 / kappa on every mesh until alpha V dt falls
# below it (docs/fem.md section 7), a plateau the coarser runs cannot see
PLATEAU_ABOVE = 10.0
# Stable step in units of the element travel time h/c (docs/fem.md section 2), for the cost estimate
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
    title = "finite-element solver"
    cli_flags = MappingProxyType({"elements": None, "order": None, "mass": None})
    contact_names = ("exponential", "penalty", "hard")
    capabilities = frozenset({ENERGY_SPLIT})
    order_case = MappingProxyType({"resolutions": (24, 48, 96, 192), "options": {"order": 1, "mass": "consistent"}})
    agreement_case = ({"elements": 400}, 1e-5)
    error_safety = ESTIMATE_SAFETY
    error_levels = 2

    def expected_order(self, options: FemOptions) -> float:
        """Order of epsilon in ``h`` where the contact is resolved (:data:`EXPECTED_ORDER`)."""
        return float(EXPECTED_ORDER[(options.order, options.mass)])

    def _collide(self, scene: Scene, options: FemOptions) -> CollisionFields:
        return _collide(scene, options.as_dict())

    def comparison_methods(self, kappa: float) -> list:
        """P1 and P2, lumped and consistent mass, at 100 and 400 elements."""
        del kappa
        return [({"elements": elements, "order": order, "mass": mass}, f"P{order} {mass}, {elements} elements",
                 "element_steps")
                for order, mass in ((1, "lumped"), (1, "consistent"), (2, "lumped"), (2, "consistent"))
                for elements in (100, 400)]

    def comparison_family(self, options: FemOptions) -> str:
        """``fem: P<order> <mass>``."""
        return f"{self.name}: P{options.order} {options.mass}"

    def vibration_energy_gain(self, fields: CollisionFields, scene: Scene):
        """The rods' internal energy after the collision minus the realisation's (continuous) energy."""
        after = np.asarray(fields.extra["rod_energy_after"], dtype=float)
        return after - np.array([float(e.sum()) for e in scene.vibrations.modal_energies()])

    def solve_line(self, scene: Scene, options=None, **limits):
        """A scene of many bodies on a line: :func:`wavecontact.fem.multibody.solve_line` (an ImpactResult)."""
        from .multibody import solve_line

        given = options.as_dict() if isinstance(options, FemOptions) else dict(options or {})
        return solve_line(scene, given, **limits)
    def _error_estimate(self, scene: Scene, options: FemOptions, fields: CollisionFields) -> tuple:
        """Richardson with the coarser runs held to the contact scheme of the requested run: with
        scheme='auto' a coarser mesh may no longer resolve the contact and switch from the force
        scheme (second order) to the massless-end interface (first order, errors near 1e-3), and the
        difference of two schemes says nothing about the finer run's error.  Below
        :data:`FINER_BELOW` elements one more run at ``2N`` (same scheme) joins the levels."""
        held = self._estimate_options(options, fields.extra)
        estimate, method, levels = super()._error_estimate(scene, held, fields)
        if not levels or not self._finer_run(scene, held):
            return estimate, method, levels
        finer = held.replace(elements=2 * held.elements, record_fields=False)
        try:
            value = float(self._collide(scene, finer).restitution)
        except SolverFailure as failure:
            needed = "with a thermal bath" if scene.vibrations is not None else f"below {FINER_BELOW}"
            why = f"the run at {finer.elements} elements, needed {needed}, failed: {failure}"
            return math.nan, f"none ({why})", levels
        levels = [*levels, (finer.elements, value)]
        estimate, rule = self.estimate_from_levels(scene, held, levels)
        runs = "; ".join(f"elements={n} gave {v:.12g}" for n, v in levels[1:])
        return estimate, f"Richardson: {runs}; {rule}", levels

    def coarser_levels(self, options: FemOptions) -> int:
        """Two coarser runs (N/2, N/4); one (N/2) below :data:`FINER_BELOW` elements, where the run at
        ``2N`` takes the N/4 run's place (:func:`~wavecontact.fem.error_estimate.estimate_with_finer`
        uses the two finest differences only)."""
        if options.nodes is None and options.elements < FINER_BELOW:
            return 1
        return self.error_levels

    def error_estimate_runs(self, scene: Scene, options: FemOptions) -> list:
        """The coarser runs, and below :data:`FINER_BELOW` elements or with a thermal bath the run at
        ``2N`` (four times the requested run's work)."""
        runs = super().error_estimate_runs(scene, options)
        if runs and self._finer_run(scene, options):
            runs.append(options.replace(elements=2 * options.elements, record_fields=False))
        return runs

    @staticmethod
    def _finer_run(scene: Scene, options: FemOptions) -> bool:
        """Whether the estimate also runs ``2N`` elements: below :data:`FINER_BELOW` elements, and with a
        thermal bath, whose collisions converge irregularly on the coarser meshes (several contact episodes at
        the ends' thermal speeds, the bath's fastest modes a few elements long: docs/error_estimates.md)."""
        return options.nodes is None and (options.elements < FINER_BELOW or scene.vibrations is not None)

    @staticmethod
    def _estimate_options(options: FemOptions, extra: dict) -> FemOptions:
        """The options of the coarser runs: the requested ones with ``scheme='auto'`` replaced by the
        contact scheme the requested run used (``extra['contact_scheme']``) where that is the force
        scheme or the massless-end interface."""
        used = extra.get("contact_scheme")
        if options.scheme == "auto" and used in ("force", "interface"):
            return options.replace(scheme=used)
        return options

    def coarser_options(self, options: FemOptions):
        """Half the elements (a user mesh ``nodes`` has no coarser twin: no estimate)."""
        if options.nodes is not None or options.elements < 2:
            return None
        return options.replace(elements=options.elements // 2, record_fields=False)

    def _contact_resolution(self, scene: Scene, options: FemOptions, thermal: bool = True) -> float:
        """``alpha V h / c`` on the shorter rod at ``options.elements`` (inf for hard and penalty contact,
        for user meshes and for scenes other than two rods); with a thermal bath ``V`` is the fastest
        approach of the ends, the rods' plus their vibrations' (:func:`wavecontact.bath.scene.end_speed`), unless
        not ``thermal``."""
        contact = scene.contact
        if not (contact.decay_rate > 0.0 and len(scene.rods) == 2 and options.nodes is None):
            return math.inf
        shorter = min(scene.rods, key=lambda rod: rod.length)
        travel = shorter.length / options.elements / shorter.wave_speed
        speed = abs(scene.velocities[0] - scene.velocities[1])
        if thermal and scene.vibrations is not None:
            speed += end_speed(scene.vibrations)
        return contact.decay_rate * speed * travel

    def _characteristic(self, scene: Scene, options: FemOptions) -> bool:
        """Whether the run uses the characteristic interface with the sub-step gap quadrature."""
        return ((options.order, options.mass) == (1, "lumped") and options.scheme in ("auto", "characteristic")
                and options.courant in (None, 1.0) and options.dt is None and options.gap_quadrature == "substeps"
                and scene.contact.decay_rate > 0.0)

    def _scheme_order(self, options: FemOptions) -> float:
        """Order in ``h`` of the runs the estimate compares: :data:`INTERFACE_ORDER` where they are held to
        the massless-end interface (``scheme='interface'``, as :meth:`_estimate_options` holds them where the
        requested run used it), else :meth:`expected_order` (the force scheme and the characteristic
        lattice where the contact is resolved)."""
        return INTERFACE_ORDER if options.scheme == "interface" else self.expected_order(options)

    def estimate_from_levels(self, scene: Scene, options: FemOptions, levels: list) -> tuple:
        """``(estimate, rule)`` by :func:`wavecontact.fem.error_estimate.estimate_from_levels`, or by
        :func:`~wavecontact.fem.error_estimate.estimate_with_finer` where a level is finer than the
        requested run.

        ``levels``: ``(elements, restitution)`` at N and N/2, then at N/4 (from :data:`FINER_BELOW`
        elements up, where it ran) or at 2N (below :data:`FINER_BELOW` elements).
        """
        requested = levels[0][0]
        finer = [level for level in levels if level[0] > requested]
        coarse = [level for level in levels if level[0] <= requested]
        arguments = (self._contact_resolution(scene, options), self.expected_order(options),
                     self._characteristic(scene, options), self._scheme_order(options), scene.vibrations is not None)
        if finer:
            return _estimate_with_finer(min(finer), coarse, *arguments)
        return _estimate_from_levels(coarse, *arguments)

    def rough_estimate(self, scene: Scene, options: FemOptions) -> str:
        """Advice where the estimate is an order of magnitude: P1 lumped on the characteristic lattice with
        ``alpha V dt > PLATEAU_ABOVE`` and both far-end echoes within one step (gamma near 1)."""
        x = self._contact_resolution(scene, options, thermal=False)  # the plateau was measured on cold collisions
        if self._characteristic(scene, options) and PLATEAU_ABOVE < x < math.inf:
            travel = [rod.length / rod.wave_speed for rod in scene.rods]
            if 2.0 * abs(travel[0] - travel[1]) < min(travel) / options.elements:
                return ("both far-end echoes return within one step and the contact is not resolved: the error has a "
                        "plateau the coarser runs do not see (docs/fem.md section 7); "
                        f"try elements={math.ceil(options.elements * x / PLATEAU_ABOVE)} or solver='delay'")
        return ""

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
        if scene.contact.decay_rate > 0.0:
            span += 100.0 / (scene.contact.decay_rate * speed)  # in from and out to where the force is negligible
        if options.max_time is not None:
            span = min(span, options.max_time)
        steps = span / dt
        runs = 2 if options.record_fields else 1  # fields are sampled in a second run
        return Cost(steps=steps, work=runs * steps * nodes,
                    memory=nodes * _BYTES_PER_NODE + steps * _BYTES_PER_STEP,
                    detail=f"{nodes:.3g} nodes, at least {steps:.3g} steps of dt = {dt:.3g}")


def _collide(scene: Scene, options: dict) -> CollisionFields:
    """One collision of two rods with the finite-element solver (options: :class:`FemOptions`).

    Returns
    -------
    CollisionFields
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
        "scheme": _scheme_name(setup, scene.contact.name, options),
        "contact_scheme": _SCHEME_NAMES[setup.scheme],
        "nodes_per_rod": [d.n_nodes for d in setup.rods],
    }
    if "fields" in out:
        extra["fields"] = out["fields"]
    return CollisionFields(
        restitution=restitution,
        time=time,
        relative_velocity=relative_velocity,
        contact_force=force,
        force_sampling="interval",  # force[i] is the mean over the step ending at time[i]
        energy_drift=energy_drift,
        momentum_drift=momentum_drift,
        work={
            "steps": out["steps"],
            "element_steps": out["steps"] * sum(elements),
            "elements": elements,
            "dt": setup.dt,
        },
        extra={**extra, "max_energy_drift": float(max_drift)},
    )


_SCHEME_NAMES = {kernels.SCHEME_CHARACTERISTIC: "characteristic", kernels.SCHEME_INTERFACE: "interface",
                 kernels.SCHEME_SPLITTING: "splitting", kernels.SCHEME_FORCE: "force"}


def _scheme_name(setup, law: str, options) -> str:
    contact = law + (" (elastic node impact)" if law == "hard" and not setup.plastic else "")
    base = f"P{options['order']} {options['mass']} mass, central differences, {contact} contact"
    if setup.scheme == kernels.SCHEME_CHARACTERISTIC:
        return base + " through the characteristic interface (incoming characteristics, exact gap equation)"
    if setup.scheme == kernels.SCHEME_INTERFACE:
        return base + " through the massless-end interface (exact gap equation)"
    if setup.scheme == kernels.SCHEME_FORCE:
        return base + " applied as a force at the end nodes (plain central differences, contact-resolving step)"
    return base + " through the impulse splitting (exact flow of the end-node pair)"


SOLVER = FemSolver()
