"""Set up, run and summarize one finite-element collision of two rods on a line.

Layout on the line: rod 1 (left) ends at ``x = -gap/2``, rod 2 (right) starts
at ``x = +gap/2``; node coordinates ``x`` in the fields are these reference
positions, displacements ``u`` (rigid translation included) are added to them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..contact import Exponential, Hard, Penalty
from ..errors import InvalidParameterError, SolverFailure, UnsupportedSceneError
from ..result import Outcome
from ..scene import Scene
from . import kernels
from .contact_flows import LAW_EXPONENTIAL, LAW_HARD_ELASTIC, LAW_HARD_PLASTIC, LAW_PENALTY
from .discretization import RodDiscretization, discretize_rod, matched_nodes
from .stability import banded_mass, check_time_step, stable_step

__all__ = ["POTENTIAL_TOLERANCE", "FemSetup", "build_setup", "run_collision"]

# Contact energy, relative to the energy of the relative motion, below which the
# force counts as absent: the start gap and the end of the run are placed there.
POTENTIAL_TOLERANCE = 1e-16
_CHUNK = 1 << 15
# sub-steps of the gap equation with a linearly varying incoming rate, where the contact is resolved
_GAP_SUBSTEPS = 8  # linear reconstruction (rods of fewer than 5 nodes)
_QUARTIC_SUBSTEPS = 32  # quartic reconstruction, gap_quadrature='substeps'
_GAP_QUADRATURES = ("substeps", "gauss")
_RESOLVED = 10.0  # alpha V dt at or below which the incoming rate is reconstructed
# plain central differences with the contact force ('force' scheme, resolved exponential contact):
FORCE_COURANT = 0.95  # fraction of the stable step including the contact stiffness
FORCE_PEAK = 2.0  # bound of the peak force in units of Z_eff V (the hard-contact plateau is 1)
FORCE_RESOLUTION = 1.0  # largest alpha V dt
FORCE_MAX_COST = 4.0  # largest ratio of the mesh's step to the contact-resolving step
FORCE_MESH_RESOLUTION = 1.0  # largest alpha V h / c of the facing end elements
_SCHEMES = {
    "characteristic": kernels.SCHEME_CHARACTERISTIC,
    "interface": kernels.SCHEME_INTERFACE,
    "splitting": kernels.SCHEME_SPLITTING,
    "force": kernels.SCHEME_FORCE,
}
_HARD_SCHEMES = {"plastic": LAW_HARD_PLASTIC, "elastic": LAW_HARD_ELASTIC}


@dataclass
class FemSetup:
    """Everything the time loop needs, built once per solve."""

    rods: tuple  # (RodDiscretization, RodDiscretization)
    dt: float
    stable_step: float
    law: int
    alpha: float
    strength: float
    stiffness: float
    gap: float
    r_stop: float
    u0: tuple
    v0: tuple
    matched: bool
    scheme: int
    gap_substeps: int = 1
    centered: bool = False
    gauss: bool = False

    @property
    def characteristic(self) -> bool:
        return self.scheme == kernels.SCHEME_CHARACTERISTIC


def _law_parameters(scene: Scene, rods, hard_scheme: str):
    law = scene.contact
    if isinstance(law, Exponential):
        return law.kernel_parameters()
    if isinstance(law, Penalty):
        if law.stiffness is not None:
            k = law.stiffness
        else:  # E A / h of the stiffer facing element
            left, right = rods
            h1 = left.x[-1] - left.x[left.cells[-1, 0]]
            h2 = right.x[right.cells[0, 1]] - right.x[0]
            k = max(
                left.rod.youngs_modulus * left.rod.area / h1, right.rod.youngs_modulus * right.rod.area / h2
            )
        return LAW_PENALTY, 0.0, 0.0, float(k)
    if isinstance(law, Hard):
        if hard_scheme not in _HARD_SCHEMES:
            raise InvalidParameterError(
                f"hard_scheme must be one of {tuple(_HARD_SCHEMES)}, got {hard_scheme!r}"
            )
        return _HARD_SCHEMES[hard_scheme], 0.0, 0.0, 0.0
    raise UnsupportedSceneError(f"the fem solver does not know the contact law {type(law).__name__}")


def _check_elements(elements) -> int:
    if isinstance(elements, bool) or not isinstance(elements, (int, np.integer)):
        raise InvalidParameterError(f"elements must be an integer >= 1, got {elements!r}")
    if not 1 <= elements <= 10**6:
        raise InvalidParameterError(f"elements must lie in [1, 1e6], got {elements}")
    return int(elements)


def build_setup(
    scene: Scene,
    elements: int = 800,
    order: int = 1,
    mass: str = "lumped",
    nodes=None,
    dt=None,
    courant=None,
    hard_scheme: str = "plastic",
    scheme: str = "auto",
    gap_quadrature: str = "substeps",
) -> FemSetup:
    """Discretize the scene's two rods and choose the step, the gap and the stop gap.

    Parameters
    ----------
    scene : Scene
        Two rods on a line (rod 0 left, rod 1 right).
    elements : int
        Elements on the shorter rod; the other rod gets elements of the same
        wave travel time ``h / c``; the piece shorter than one element left
        at its far end is carried as a point mass on the far end node.
    order : {1, 2}
        Lagrange order.
    mass : {'lumped', 'consistent'}
    nodes : pair of arrays or None
        Element end points of each rod (rod coordinate, 0 to its length);
        overrides ``elements``.
    dt : float or None
        Time step; ``None`` = the default below.  Refused above the stable step.
    courant : float or None
        Fraction of the stable step used when ``dt`` is None.  Default: 1 for
        P1 lumped on matched meshes (the step equals the element travel time,
        where central differences are exact), 0.95 otherwise.
    hard_scheme : {'plastic', 'elastic'}
        End-node impact rule of hard contact in the 'splitting' scheme (see docs/fem.md).
    scheme : {'auto', 'characteristic', 'force', 'interface', 'splitting'}
        Contact treatment.  'auto': 'characteristic' on P1 lumped matched meshes
        stepped at the element travel time (exact lattice, second order); else,
        for an exponential law that the facing elements resolve
        (``alpha V h / c <= FORCE_MESH_RESOLUTION``), 'force' (plain central
        differences with the contact force at the end nodes, second order) at
        the smaller of the mesh's step and the contact-resolving step of
        :func:`_force_step` (at most ``FORCE_MAX_COST`` times smaller); else
        'interface' (massless-end gap equation, first order, stable for any
        stiffness).  With a user ``dt``, 'force' is chosen only if ``dt`` is
        within the contact-resolving step.  'splitting' (the impulse/RESPA
        splitting with the exact flow of the end-node pair) is kept for
        comparison: it loses stability for stiff contact (kappa >~ 1e4).
    gap_quadrature : {'substeps', 'gauss'}
        Characteristic scheme with resolved contact: how the gap equation is
        integrated over a step with the quartic reconstruction of the incoming
        rate.  'substeps': 32 sub-steps with constant rate (second order in the
        sub-step; skipped where the force or the rate's variation is negligible).
        'gauss': the linear equation for ``exp(alpha r)`` solved with a 16-point
        Gauss-Legendre integral, wherever the rate varies at all (round-off
        accurate; where the rate is constant while the force acts the whole
        collision is then exact to round-off, e.g. gamma = 0.6, kappa = 20).
    """
    if scene.is_ring or len(scene.rods) != 2:
        raise UnsupportedSceneError("the fem solver handles two rods on a line")
    if order not in (1, 2) or isinstance(order, bool):
        raise InvalidParameterError(f"order must be 1 or 2, got {order!r}")
    if mass not in ("lumped", "consistent"):
        raise InvalidParameterError(f"mass must be 'lumped' or 'consistent', got {mass!r}")
    if gap_quadrature not in _GAP_QUADRATURES:
        raise InvalidParameterError(f"gap_quadrature must be one of {_GAP_QUADRATURES}, got {gap_quadrature!r}")
    left, right = scene.rods
    if nodes is None:
        elements = _check_elements(elements)
        shorter = left if left.length <= right.length else right
        travel = shorter.length / elements / shorter.wave_speed
        vertices = (
            matched_nodes(left.length, travel * left.wave_speed, from_left=False),
            matched_nodes(right.length, travel * right.wave_speed, from_left=True),
        )
        matched = True
    else:
        if len(nodes) != 2:
            raise InvalidParameterError("nodes must be a pair (rod 1 vertices, rod 2 vertices)")
        vertices = tuple(nodes)
        matched = False
        travel = None
    remainder = ("left", "right") if matched else (None, None)
    lump = not (matched and _contact_unresolved(scene, travel))
    rods = (
        discretize_rod(left, vertices[0], order, mass, remainder[0], lump),
        discretize_rod(right, vertices[1], order, mass, remainder[1], lump),
    )
    limit = stable_step(rods)
    if dt is None:
        if courant is None:
            exact = matched and order == 1 and mass == "lumped"
            step = travel if exact and travel <= limit * (1 + 1e-9) else 0.95 * limit
        else:
            if not (isinstance(courant, (int, float)) and 0.0 < courant <= 1.0):
                raise InvalidParameterError(f"courant must lie in (0, 1], got {courant!r}")
            step = courant * limit
    else:
        step = check_time_step(dt, limit)
    law, alpha, strength, stiffness = _law_parameters(scene, rods, hard_scheme)
    if scheme not in ("auto",) + tuple(_SCHEMES):
        raise InvalidParameterError(
            f"scheme must be one of 'auto', {', '.join(map(repr, _SCHEMES))}, got {scheme!r}"
        )
    exact = _is_exact_lattice(rods, step)
    if scheme == "characteristic" and not exact:
        raise InvalidParameterError(
            "scheme='characteristic' needs order=1, mass='lumped' and dt equal to the travel time h/c "
            "of the elements at both facing ends (the default matched mesh with dt=None)"
        )
    approach_speed = abs(scene.velocities[0] - scene.velocities[1])
    force_step = _force_step(rods, limit, law, alpha, approach_speed) if law == LAW_EXPONENTIAL else 0.0
    if scheme == "force":
        if law != LAW_EXPONENTIAL:
            raise InvalidParameterError("scheme='force' needs the exponential contact law")
        if dt is None:
            step = min(step, force_step)
    if scheme == "auto":
        if exact:
            scheme = "characteristic"
        elif law == LAW_EXPONENTIAL and _end_travel_time(rods) * alpha * approach_speed > FORCE_MESH_RESOLUTION:
            scheme = "interface"  # the mesh does not resolve the force's rise
        elif step <= force_step:
            scheme = "force"
        elif dt is None and FORCE_MAX_COST * force_step >= step:
            # the contact is resolved by a step at most FORCE_MAX_COST times smaller than the mesh's
            scheme, step = "force", force_step
        else:
            scheme = "interface"
    scheme_code = _SCHEMES[scheme]
    # Where the collision time 1/(alpha V) spans at least 1/10 of a step, the incoming rate is
    # reconstructed inside the step (the quartic with the step means of two steps before and two
    # after, which the interior nodes already carry) and the gap equation sub-stepped: holding the
    # rate constant was the dominant error during the release.  Where the contact is stiffer the
    # rate jumps from step to step and a reconstruction would overshoot, so it is held constant
    # (the hard limit stays exact).
    resolved = law == LAW_EXPONENTIAL and alpha * approach_speed * step <= _RESOLVED
    # the quartic reconstruction reads the incoming waves three nodes into each rod
    centered = resolved and min(d.n_nodes for d in rods) >= 5
    gap_substeps = (_QUARTIC_SUBSTEPS if centered else _GAP_SUBSTEPS) if resolved else 1
    u0, v0 = [], []
    for index, (disc, speed) in enumerate(zip(rods, scene.velocities)):
        u = np.zeros(disc.n_nodes)
        v = np.full(disc.n_nodes, float(speed))
        for values, fields in ((u, scene.initial_displacement), (v, scene.initial_velocity)):
            if fields is not None and fields[index] is not None:
                added = np.asarray(fields[index](disc.x.copy()), dtype=float)
                if added.shape != disc.x.shape or not np.all(np.isfinite(added)):
                    raise InvalidParameterError(
                        f"initial field of rod {index} must return finite values of shape {disc.x.shape}"
                    )
                values += added
        u0.append(u)
        v0.append(v)

    masses = [d.rod.mass for d in rods]
    reduced = masses[0] * masses[1] / (masses[0] + masses[1])
    momenta = [float(d.lumped_mass @ v) for d, v in zip(rods, v0)]
    approach = momenta[0] / masses[0] - momenta[1] / masses[1]
    if approach <= 0.0:
        raise InvalidParameterError(
            "the rods do not approach each other (v_left - v_right must be > 0 for a collision)"
        )
    relative_energy = 0.5 * reduced * approach**2
    internal = sum(float(np.sum(d.energy(u, v))) for d, u, v in zip(rods, u0, v0)) - sum(
        p * p / (2 * m) for p, m in zip(momenta, masses)
    )
    energy_scale = relative_energy + internal
    if law == LAW_EXPONENTIAL:
        if energy_scale <= 0.0:
            raise InvalidParameterError("the rods carry no energy of relative or internal motion")
        r_stop = math.log(strength / (POTENTIAL_TOLERANCE * energy_scale)) / alpha
    else:
        r_stop = 0.0
    if scene.gaps is not None:
        gap = float(scene.gaps[0])
    else:
        gap = max(r_stop, 0.0)
        if law == LAW_EXPONENTIAL and scheme_code == kernels.SCHEME_CHARACTERISTIC and gap_substeps == 1:
            # Unresolved contact: the force switches on within a small part of a step.  The
            # lattice sees a step only through its mean, so a collision starting inside a step
            # would end (when the reflected waves return) up to a step early.  Start where the
            # closing ends reach the plateau gap r* (r' = -V + F(r*) / Z_eff = 0) at a step boundary.
            compliance = 1.0 / left.impedance + 1.0 / right.impedance
            plateau = math.log(compliance * alpha * strength / approach) / alpha
            steps_to_contact = max(1, math.ceil((gap - plateau) / (approach * step)))
            gap = plateau + steps_to_contact * approach * step
    return FemSetup(
        rods=rods, dt=step, stable_step=limit, law=law, alpha=alpha, strength=strength, stiffness=stiffness,
        gap=gap, r_stop=r_stop, u0=tuple(u0), v0=tuple(v0), matched=matched, scheme=scheme_code,
        gap_substeps=gap_substeps, centered=centered, gauss=gap_quadrature == "gauss",
    )


def _end_travel_time(rods) -> float:
    """Longest wave travel time ``h / c`` of the two elements at the contact (time)."""
    left, right = rods
    h1 = left.x[-1] - left.x[left.cells[-1, 0]]
    h2 = right.x[right.cells[0, 1]] - right.x[0]
    return max(h1 / left.rod.wave_speed, h2 / right.rod.wave_speed)


def _force_step(rods, limit: float, law: int, alpha: float, approach: float) -> float:
    """Largest step at which plain central differences resolve the exponential contact.

    Two bounds: stability of the end nodes on the contact's stiffness (its
    largest value ``alpha F_max``, ``F_max = FORCE_PEAK Z_eff V``, added to the
    elastic ``lambda_max``) and resolution of the collision time,
    ``alpha V dt <= FORCE_RESOLUTION``.
    """
    left, right = rods
    m_inv = left.inverse_mass_column(left.n_nodes - 1)[-1] + right.inverse_mass_column(0)[0]
    impedance = 1.0 / (1.0 / left.rod.impedance + 1.0 / right.rod.impedance)
    contact_stiffness = alpha * FORCE_PEAK * impedance * approach
    lambda_max = (2.0 / limit) ** 2
    stable = FORCE_COURANT * 2.0 / math.sqrt(lambda_max + m_inv * contact_stiffness)
    return min(stable, FORCE_RESOLUTION / (alpha * approach))


def _contact_unresolved(scene: Scene, step: float) -> bool:
    """Hard contact, or an exponential law whose collision time is below 1/20 of the step.

    Then the remainder of a matched mesh (less than one element at the far end
    of the long rod) is left out of the model instead of being lumped there:
    a heavier far node reflects an initial compression blip that reaches the
    contact while the ends graze (docs/fem.md), which matters only when the
    contact is stiff; the missing length shifts the far-end echo by less than
    2 h / c, which matters only when it is soft.  Masses used for epsilon stay exact.
    """
    law = scene.contact
    if isinstance(law, Hard):
        return True
    if isinstance(law, Exponential):
        approach = abs(scene.velocities[0] - scene.velocities[1])
        return law.alpha * approach * step > 20.0
    return False


def _uniform_interior(disc: RodDiscretization, dt: float) -> bool:
    """True if every interior node has ``dt^2 k / m = 1`` on both sides (d'Alembert's lattice)."""
    if disc.order != 1 or disc.mass_kind != "lumped" or disc.n_nodes < 3:
        return False
    k = -disc.stiffness_bands[1, :-1]
    inverse = 1.0 / disc.lumped_mass[1:-1]
    left = dt * dt * k[:-1] * inverse
    right = dt * dt * k[1:] * inverse
    return bool(np.all(np.abs(left - 1.0) < 1e-9) and np.all(np.abs(right - 1.0) < 1e-9))


def _is_exact_lattice(rods, dt: float) -> bool:
    """P1 lumped with the facing end elements (and their neighbours) crossed by a wave in exactly dt."""
    left, right = rods
    if left.order != 1 or left.mass_kind != "lumped":
        return False
    for disc, ends in ((left, (-1, -2, -3)), (right, (0, 1, 2))):
        if disc.n_nodes < 3:
            return False
        x = disc.x
        sizes = (abs(x[ends[1]] - x[ends[0]]), abs(x[ends[2]] - x[ends[1]]))
        travel = disc.rod.length / disc.rod.wave_speed  # scale for the comparison
        for size in sizes:
            if abs(size / disc.rod.wave_speed - dt) > 1e-12 * travel:
                return False
    return True


class _Run:
    """Mutable state of one time integration (used for the main run and the field replay)."""

    def __init__(self, setup: FemSetup, energy_tolerance: float):
        self.setup = setup
        left, right = setup.rods
        self.u = [u.copy() for u in setup.u0]
        self.v = [v.copy() for v in setup.v0]
        self.lumped = left.mass_kind == "lumped"
        self.inverse_mass = [1.0 / d.lumped_mass for d in setup.rods]
        self.cholesky = [
            d.mass_cholesky if d.mass_cholesky is not None else np.zeros((1, 1)) for d in setup.rods
        ]
        self.mass_bands = [banded_mass(d) for d in setup.rods]
        column1 = left.inverse_mass_column(left.n_nodes - 1)
        column2 = right.inverse_mass_column(0)
        start = int(np.flatnonzero(column1)[0])
        stop = int(np.flatnonzero(column2)[-1]) + 1
        self.column1 = np.ascontiguousarray(column1[start:])
        self.column2 = np.ascontiguousarray(column2[:stop])
        self.m_inv = column1[-1] + column2[0]
        self.a = []
        for d, u, inv, chol in zip(setup.rods, self.u, self.inverse_mass, self.cholesky):
            a = np.zeros(d.n_nodes)
            kernels.elastic_acceleration(u, d.stiffness_bands, inv, chol, self.lumped, a)
            self.a.append(a)
        masses = [float(d.lumped_mass.sum()) for d in setup.rods]
        self.masses = masses
        momenta = [float(d.lumped_mass @ v) for d, v in zip(setup.rods, self.v)]
        energy = 0.0
        for d, u, v, a, mb in zip(setup.rods, self.u, self.v, self.a, self.mass_bands):
            kinetic, strain, correction = kernels.rod_energies(u, v, a, d.stiffness_bands, mb, setup.dt)
            energy += kinetic + strain - correction
        from .contact_flows import contact_potential

        energy += contact_potential(setup.law, setup.gap, setup.alpha, setup.strength, setup.stiffness)
        total_mass = sum(masses)
        scale = energy - sum(momenta) ** 2 / (2 * total_mass)
        self.state = np.zeros(kernels.STATE_SIZE)
        self.state[kernels.S_MOMENTUM1] = momenta[0]
        self.state[kernels.S_MOMENTUM2] = momenta[1]
        self.state[kernels.S_ENERGY0] = energy
        self.state[kernels.S_ENERGY_SCALE] = scale
        self.state[kernels.S_LAST_IN_RANGE] = 0.0
        # end positions one step before the start (central differences run backwards)
        dt = setup.dt
        self.state[kernels.S_PREVIOUS_END1] = self.u[0][-1] - dt * self.v[0][-1] + 0.5 * dt * dt * self.a[0][-1]
        self.state[kernels.S_PREVIOUS_END2] = self.u[1][0] - dt * self.v[1][0] + 0.5 * dt * dt * self.a[1][0]
        self.state[kernels.S_INCOMING] = (self.v[1][0] - 0.5 * dt * self.a[1][0]) - (
            self.v[0][-1] - 0.5 * dt * self.a[0][-1]
        )
        self.state[kernels.S_INCOMING_EARLIER] = self.state[kernels.S_INCOMING]
        # the time loop keeps velocities half a step behind the displacements
        for v, a in zip(self.v, self.a):
            v -= 0.5 * dt * a
        self.sync = [np.zeros_like(v) for v in self.v]
        # the exact lattice runs on two time levels: u now, w = u one step earlier
        self.lattice = setup.scheme == kernels.SCHEME_CHARACTERISTIC and all(
            _uniform_interior(d, dt) for d in setup.rods
        )
        if self.lattice:
            self.w = [u - dt * v for u, v in zip(self.u, self.v)]
        self.energy0 = energy
        self.energy_scale = scale
        self.momentum0 = sum(momenta)
        self.approach = momenta[0] / masses[0] - momenta[1] / masses[1]
        reduced = masses[0] * masses[1] / total_mass
        self.momentum_scale = reduced * self.approach
        self.period = 1.05 * max(2 * d.rod.length / d.rod.wave_speed for d in setup.rods)
        shortest = min(2 * d.rod.length / d.rod.wave_speed for d in setup.rods)
        self.check_every = max(1, int(0.05 * shortest / setup.dt))
        self.bound = [1.1 * math.sqrt(2 * d.rod.length / (3 * d.rod.youngs_modulus * d.rod.area)) for d in setup.rods]
        self.energy_tolerance = energy_tolerance
        # The massless-end interface ignores the inertia of the two end nodes: while they are in
        # contact the discrete energy can miss up to their relative kinetic energy at twice the
        # approach speed (O(h), returned on release). A blow-up exceeds this bound at once.
        massless_ends = setup.scheme in (kernels.SCHEME_CHARACTERISTIC, kernels.SCHEME_INTERFACE)
        self.energy_allowance = 2.0 * self.approach**2 / self.m_inv / scale if massless_ends else 0.0
        self.watchdog_tolerance = energy_tolerance + self.energy_allowance

    def advance(self, max_steps: int):
        s = self.setup
        left, right = s.rods
        hist = [np.empty(max_steps) for _ in range(4)]
        n_energy = max_steps // self.check_every + 1
        energies = [np.empty(n_energy) for _ in range(6)]
        if self.lattice:
            status, done, samples = kernels.advance_lattice(
                self.u[0], self.w[0], self.u[1], self.w[1],
                left.stiffness_bands, right.stiffness_bands, self.inverse_mass[0], self.inverse_mass[1],
                left.lumped_mass, right.lumped_mass, self.m_inv, s.gap_substeps, s.centered, s.gauss,
                s.gap, s.law, s.alpha, s.strength, s.stiffness,
                s.dt, max_steps, s.r_stop, self.period, self.check_every, self.bound[0], self.bound[1],
                self.watchdog_tolerance, self.state,
                hist[0], hist[1], hist[2], hist[3], *energies,
            )
            for v, u, w in zip(self.v, self.u, self.w):
                v[:] = (u - w) / s.dt
            return status, [h[:done] for h in hist], [e[:samples] for e in energies]
        status, done, samples = kernels.advance(
            self.u[0], self.v[0], self.a[0], self.u[1], self.v[1], self.a[1], self.sync[0], self.sync[1],
            left.stiffness_bands, right.stiffness_bands, self.inverse_mass[0], self.inverse_mass[1],
            self.cholesky[0], self.cholesky[1], self.lumped,
            self.mass_bands[0], self.mass_bands[1], left.lumped_mass, right.lumped_mass,
            self.column1, self.column2, self.m_inv, s.scheme,
            s.gap, s.law, s.alpha, s.strength, s.stiffness,
            s.dt, max_steps, s.r_stop, self.period, self.check_every, self.bound[0], self.bound[1],
            self.watchdog_tolerance, self.state,
            hist[0], hist[1], hist[2], hist[3], *energies,
        )
        return status, [h[:done] for h in hist], [e[:samples] for e in energies]

    def synchronized_velocities(self):
        """Nodal velocities at the current time (the loop stores them half a step earlier)."""
        out = []
        for d, u, v, inv, chol in zip(self.setup.rods, self.u, self.v, self.inverse_mass, self.cholesky):
            a = np.zeros_like(u)
            kernels.elastic_acceleration(u, d.stiffness_bands, inv, chol, self.lumped, a)
            out.append(v + 0.5 * self.setup.dt * a)
        return out

    def stresses(self):
        if not hasattr(self, "_recovery"):
            self._recovery = [d.stress_recovery() for d in self.setup.rods]
        return [matrix @ u for matrix, u in zip(self._recovery, self.u)]


def _failure_message(run: _Run, setup: FemSetup) -> str:
    time = run.state[kernels.S_TIME]
    energy = run.state[kernels.S_FAILED_ENERGY]
    drift = abs(energy - run.energy0) / run.energy_scale if math.isfinite(energy) else math.inf
    elements = [d.n_elements for d in setup.rods]
    if setup.scheme == kernels.SCHEME_SPLITTING:
        advice = "use scheme='auto' (the splitting scheme is unstable for stiff contact)"
    elif min(elements) < 10:
        advice = f"use more elements (got {elements}; at least 10 on the shorter rod)"
    else:
        advice = "use more elements, a smaller dt, or order=1 with mass='lumped' (exact lattice)"
    return (
        f"energy balance violated at t = {time:.6g}: relative energy error {drift:.3g} exceeds "
        f"energy_tolerance = {run.energy_tolerance:g}"
        + (f" (+ {run.energy_allowance:.2g} for the end nodes' inertia)" if run.energy_allowance else "")
        + f"; {advice}"
    )


def run_collision(setup: FemSetup, energy_tolerance: float = 0.05, max_time=None, record_fields=False,
                  field_samples: int = 300) -> dict:
    """Integrate until the rods have separated; return histories and diagnostics."""
    run = _Run(setup, energy_tolerance)
    if max_time is None:
        # generous cap: approach, a departure as slow as epsilon = 0.05, fifty vibration periods
        max_time = 21.0 * setup.gap / run.approach + 50.0 * run.period
    max_steps = math.ceil(max_time / setup.dt)
    pieces_hist, pieces_energy = [], []
    status = kernels.STATUS_RUNNING
    while status == kernels.STATUS_RUNNING:
        if run.state[kernels.S_STEPS] >= max_steps:
            raise SolverFailure(
                f"the rods did not separate within t = {max_time:.4g}; the contact may keep "
                f"re-engaging (check the scene's velocities) or the run needs max_time",
                Outcome.TIME_LIMIT,
            )
        status, hist, energies = run.advance(_CHUNK)
        pieces_hist.append(hist)
        pieces_energy.append(energies)
    if status == kernels.STATUS_FAILED:
        raise SolverFailure(_failure_message(run, setup), Outcome.ENERGY_DRIFT)
    hist = [np.concatenate([p[i] for p in pieces_hist]) for i in range(4)]
    energies = [np.concatenate([p[i] for p in pieces_energy]) for i in range(6)]
    out = {
        "run": run,
        "time": hist[0],
        "contact_force": hist[1],
        "relative_velocity": hist[2],
        "gap": hist[3],
        "energy_time": energies[0],
        "kinetic": energies[1],
        "strain": energies[2],
        "contact": energies[3],
        "internal": (energies[4], energies[5]),
        "steps": int(run.state[kernels.S_STEPS]),
    }
    if record_fields:
        out["fields"] = _replay_fields(setup, energy_tolerance, hist[0], hist[1], field_samples)
    return out


def _replay_fields(setup: FemSetup, energy_tolerance, times, force, samples: int) -> dict:
    """Run again from the start and sample u, v and stress over the collision window."""
    active = np.flatnonzero(force > 1e-3 * max(force.max(), 1e-300))
    if active.size == 0:
        first, last = 0, times.size - 1
    else:
        first, last = active[0], active[-1]
    span = max(last - first, 1)
    begin = max(0, first - span // 10)
    end = min(times.size - 1, last + span // 4)
    steps = np.unique(np.linspace(begin, end, samples).round().astype(int))
    run = _Run(setup, energy_tolerance)
    sample_times = []
    records = [{"displacement": [], "velocity": [], "stress": []} for _ in range(2)]
    done = -1  # index of the last completed step (history index)
    for target in steps:
        if target > done:
            status, _, _ = run.advance(int(target - done))
            done = target
            if status == kernels.STATUS_FAILED:
                raise SolverFailure(_failure_message(run, setup), Outcome.ENERGY_DRIFT)
        sample_times.append(run.state[kernels.S_TIME])
        for record, u, v, stress in zip(records, run.u, run.synchronized_velocities(), run.stresses()):
            record["displacement"].append(u.copy())
            record["velocity"].append(v.copy())
            record["stress"].append(stress)
    left, _right = setup.rods
    offsets = (-0.5 * setup.gap - left.rod.length, 0.5 * setup.gap)
    rods = []
    for disc, record, offset in zip(setup.rods, records, offsets):
        rods.append(
            {
                "x": disc.x + offset,
                "displacement": np.array(record["displacement"]),
                "velocity": np.array(record["velocity"]),
                "stress": np.array(record["stress"]),
                "cells": disc.cells.copy(),
            }
        )
    return {"time": np.array(sample_times), "rods": rods}
