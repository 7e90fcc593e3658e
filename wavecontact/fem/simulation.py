"""Set up, run and summarize one finite-element collision of two rods on a line.

Layout on the line: rod 1 (left) ends at ``x = -gap/2``, rod 2 (right) starts
at ``x = +gap/2``; node coordinates ``x`` in the fields are these reference
positions, displacements ``u`` (rigid translation included) are added to them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..contact import LAW_EXPONENTIAL
from ..errors import InvalidParameterError, SolverFailure, UnsupportedSceneError, require_integer
from ..result import Outcome
from ..scene import Scene
from . import kernels, lattice, layout
from .discretization import RodDiscretization, matched_nodes, uniform_nodes
from .explicit_step import prepare_mass, rod_acceleration
from .interleaved_step import LANE_TOLERANCE
from .reuse import discretized_rods
from .schemes import choose_scheme, gap_treatment, wants_lattice_mesh
from .stability import banded_mass, check_time_step

__all__ = ["POTENTIAL_TOLERANCE", "FemSetup", "build_setup", "run_collision"]

# Contact energy, relative to the energy of the relative motion, below which the
# force counts as absent: the start gap and the end of the run are placed there.
POTENTIAL_TOLERANCE = 1e-16
_CHUNK = 1 << 15
_GAP_QUADRATURES = ("substeps", "gauss")
# plain central differences with the contact force ('force' scheme, resolved exponential contact):
FORCE_COURANT = 0.95  # fraction of the stable step including the contact stiffness
FORCE_PEAK = 2.0  # bound of the peak force in units of Z_eff V (the hard-contact plateau is 1)
FORCE_RESOLUTION = 1.0  # largest alpha V dt
_SCHEMES = {
    "characteristic": kernels.SCHEME_CHARACTERISTIC,
    "interface": kernels.SCHEME_INTERFACE,
    "splitting": kernels.SCHEME_SPLITTING,
    "force": kernels.SCHEME_FORCE,
}
_HARD_SCHEMES = ("plastic", "elastic")


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
    far_theta: tuple = (0.0, 0.0)  # unmeshed remainder beyond each rod's far end node, in elements
    plastic: bool = True  # the splitting scheme's hard node impact: perfectly plastic (else an elastic mirror)

    @property
    def characteristic(self) -> bool:
        return self.scheme == kernels.SCHEME_CHARACTERISTIC


def _law_parameters(scene: Scene, rods, hard_scheme: str):
    """``(code, alpha, strength, stiffness)`` of the scene's law; a penalty stiffness left to the
    solver becomes ``E A / h`` of the stiffer facing element."""
    law = scene.contact
    if law.hard and hard_scheme not in _HARD_SCHEMES:
        raise InvalidParameterError(f"hard_scheme must be one of {_HARD_SCHEMES}, got {hard_scheme!r}")
    code, alpha, strength, stiffness = law.kernel_parameters()
    if law.hard:
        return code, alpha, strength, 0.0
    if law.stiffness_from_solver:
        left, right = rods
        h1 = left.x[-1] - left.x[left.cells[-1, 0]]
        h2 = right.x[right.cells[0, 1]] - right.x[0]
        stiffness = max(
            left.rod.youngs_modulus * left.rod.area / h1, right.rod.youngs_modulus * right.rod.area / h2
        )
    return code, alpha, strength, float(stiffness)


def _check_elements(elements) -> int:
    elements = require_integer("elements", elements, allowed="an integer >= 1")
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
    approach_speed = abs(scene.velocities[0] - scene.velocities[1])
    far_theta = (0.0, 0.0)
    if nodes is None:
        elements = _check_elements(elements)
        shorter = left if left.length <= right.length else right
        travel = shorter.length / elements / shorter.wave_speed
        try:
            step_ratio = None if dt is None else float(dt) / travel
        except (TypeError, ValueError):
            step_ratio = math.nan  # refused with the step check below
        if wants_lattice_mesh(order, mass, step_ratio, courant, scheme):
            # matched: one travel time per element on both rods; the remainder of the long rod
            # (less than one element, at its far end) becomes a delay of the far-end echo
            vertices = (
                matched_nodes(left.length, travel * left.wave_speed, from_left=False),
                matched_nodes(right.length, travel * right.wave_speed, from_left=True),
            )
            far_theta = tuple(
                (rod.length - (v[-1] - v[0])) / (travel * rod.wave_speed) for rod, v in zip((left, right), vertices)
            )
            far_theta = tuple(theta if theta > 1e-9 else 0.0 for theta in far_theta)
            matched = True
        else:
            vertices = tuple(
                uniform_nodes(rod.length, max(1, round(rod.length / (travel * rod.wave_speed)))) for rod in (left, right)
            )
            matched = False
    else:
        if len(nodes) != 2:
            raise InvalidParameterError("nodes must be a pair (rod 1 vertices, rod 2 vertices)")
        vertices = tuple(nodes)
        matched = False
        travel = None
    remainder = ("left", "right") if matched else (None, None)
    # the meshes the solver builds itself are kept for the next solves (the error estimate's, a sweep's)
    rods, limit = discretized_rods((left, right), vertices, order, mass, remainder, reuse=nodes is None)
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
    exponential = law == LAW_EXPONENTIAL
    scheme, step = choose_scheme(
        scheme,
        exact_lattice=_is_exact_lattice(rods, step) and all(_uniform_interior(d, step) for d in rods),
        exponential=exponential,
        mesh_resolution=_end_travel_time(rods) * alpha * approach_speed,
        mesh_step=step,
        force_step=_force_step(rods, limit, law, alpha, approach_speed) if exponential else 0.0,
        user_step=dt is not None,
    )
    scheme_code = _SCHEMES[scheme]
    # Where the collision time 1/(alpha V) spans at least 1/10 of a step, the incoming rate is
    # reconstructed inside the step (the quartic with the step means of two steps before and two
    # after, which the interior nodes already carry) and the gap equation sub-stepped: holding the
    # rate constant was the dominant error during the release.  Where the contact is stiffer the
    # rate jumps from step to step and a reconstruction would overshoot, so it is held constant
    # (the hard limit stays exact).
    gap_substeps, centered = gap_treatment(
        scheme, exponential, alpha * approach_speed * step, min(d.n_nodes for d in rods)
    )
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
        if exponential and scheme_code == kernels.SCHEME_CHARACTERISTIC and gap_substeps == 1:
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
        gap_substeps=gap_substeps, centered=centered, gauss=gap_quadrature == "gauss", far_theta=far_theta,
        plastic=hard_scheme == "plastic",
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
        self.inverse_mass = [1.0 / d.lumped_mass for d in setup.rods]
        self.mass_solves = [prepare_mass(d) for d in setup.rods]
        self.mass_bands = [banded_mass(d) for d in setup.rods]
        column1 = left.inverse_mass_column(left.n_nodes - 1)
        column2 = right.inverse_mass_column(0)
        # a consistent mass spreads the contact over the whole rod, decaying geometrically from the end:
        # entries below LANE_TOLERANCE of the end's are left out (they change no velocity beyond rounding)
        start = int(np.flatnonzero(np.abs(column1) > LANE_TOLERANCE * abs(column1[-1]))[0])
        stop = int(np.flatnonzero(np.abs(column2) > LANE_TOLERANCE * abs(column2[0]))[-1]) + 1
        self.column1 = np.ascontiguousarray(column1[start:])
        self.column2 = np.ascontiguousarray(column2[:stop])
        self.m_inv = column1[-1] + column2[0]
        self.a = []
        for d, u, (kind, table) in zip(setup.rods, self.u, self.mass_solves):
            a = np.zeros(d.n_nodes)
            rod_acceleration(u, d.stiffness_bands, kind, table, a)
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
        self.state = np.zeros(layout.STATE_SIZE)
        self.state[layout.S_MOMENTUM1] = momenta[0]
        self.state[layout.S_MOMENTUM2] = momenta[1]
        self.state[layout.S_ENERGY0] = energy
        self.state[layout.S_ENERGY_SCALE] = scale
        self.state[layout.S_LAST_IN_RANGE] = 0.0
        # end positions one step before the start (central differences run backwards)
        dt = setup.dt
        self.state[layout.S_PREVIOUS_END1] = self.u[0][-1] - dt * self.v[0][-1] + 0.5 * dt * dt * self.a[0][-1]
        self.state[layout.S_PREVIOUS_END2] = self.u[1][0] - dt * self.v[1][0] + 0.5 * dt * dt * self.a[1][0]
        self.state[layout.S_INCOMING] = (self.v[1][0] - 0.5 * dt * self.a[1][0]) - (
            self.v[0][-1] - 0.5 * dt * self.a[0][-1]
        )
        self.state[layout.S_INCOMING_EARLIER] = self.state[layout.S_INCOMING]
        # the time loop keeps velocities half a step behind the displacements
        for v, a in zip(self.v, self.a):
            v -= 0.5 * dt * a
        self.sync = [np.zeros_like(v) for v in self.v]
        # the exact lattice runs on two time levels: u now, w = u one step earlier
        self.lattice = setup.scheme == kernels.SCHEME_CHARACTERISTIC
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
        self._pack_contact_and_control()
        if self.lattice:
            self._start_lattice()

    def _pack_contact_and_control(self):
        """The contact law and the run control as the kernels' plain arrays (:mod:`~wavecontact.fem.layout`)."""
        s = self.setup
        contact = np.zeros(layout.CONTACT_SIZE)
        contact[layout.C_LAW] = s.law
        contact[layout.C_ALPHA] = s.alpha
        contact[layout.C_STRENGTH] = s.strength
        contact[layout.C_STIFFNESS] = s.stiffness
        contact[layout.C_OFFSET] = s.gap
        contact[layout.C_R_STOP] = s.r_stop
        contact[layout.C_M_INV] = self.m_inv
        contact[layout.C_COMPLIANCE] = 0.5 * self.m_inv * s.dt
        self.contact = contact
        control = np.zeros(layout.CONTROL_SIZE)
        control[layout.K_DT] = s.dt
        control[layout.K_PERIOD] = self.period
        control[layout.K_CHECK_EVERY] = self.check_every
        control[layout.K_ENERGY_TOLERANCE] = self.watchdog_tolerance
        control[layout.K_SCHEME] = s.scheme
        control[layout.K_KIND1] = self.mass_solves[0][0]
        control[layout.K_KIND2] = self.mass_solves[1][0]
        control[layout.K_BOUND1] = self.bound[0]
        control[layout.K_BOUND2] = self.bound[1]
        control[layout.K_PLASTIC] = 1.0 if s.plastic else 0.0
        control[layout.K_SUBSTEPS] = s.gap_substeps
        control[layout.K_CENTERED] = float(s.centered)
        control[layout.K_GAUSS] = float(s.gauss)
        self.control = control

    def _start_lattice(self):
        """Split both rods into their waves and pack the lattice kernel's grouped arrays."""
        s = self.setup
        self.waves, self.rod_parameters = [], []
        for index, (disc, u, w, theta) in enumerate(zip(s.rods, self.u, self.w, s.far_theta)):
            mask = lattice.buffer_mask(disc.n_nodes)
            f, g = np.zeros(mask + 1), np.zeros(mask + 1)
            lattice.split_rod(u, w, f, g, mask)
            contact_node = disc.n_nodes - 1 if index == 0 else 0
            neighbour = contact_node - 1 if index == 0 else 1
            band = disc.stiffness_bands[1, min(contact_node, neighbour)]
            parameters = np.zeros(layout.ROD_SIZE)
            parameters[layout.R_MASK] = mask
            parameters[layout.R_FAR_THETA] = theta
            parameters[layout.R_CONTACT_COEFFICIENT] = s.dt * s.dt * band / disc.lumped_mass[contact_node]
            parameters[layout.R_CONTACT_INVERSE_MASS] = 1.0 / disc.lumped_mass[contact_node]
            parameters[layout.R_BOUND] = self.bound[index]
            self.waves.append((f, g, np.array([u[contact_node], w[contact_node]])))
            self.rod_parameters.append(parameters)

    def advance(self, max_steps: int):
        s = self.setup
        left, right = s.rods
        hist = tuple(np.empty(max_steps) for _ in range(4))
        n_energy = max_steps // self.check_every + 1
        energies = tuple(np.empty(n_energy) for _ in range(6))
        if self.lattice:
            status, done, samples = lattice.advance_lattice(
                (self.u[0], self.w[0], left.lumped_mass, left.stiffness_bands),
                (self.u[1], self.w[1], right.lumped_mass, right.stiffness_bands),
                self.rod_parameters[0], self.rod_parameters[1], self.waves[0], self.waves[1],
                self.contact, self.control, self.state, hist, energies,
                None if s.law == LAW_EXPONENTIAL else np.int64(s.law),
            )
            for v, u, w in zip(self.v, self.u, self.w):
                v[:] = (u - w) / s.dt
            return status, [h[:done] for h in hist], [e[:samples] for e in energies]
        status, done, samples = kernels.advance(
            (self.u[0], self.v[0], self.a[0], self.sync[0], left.stiffness_bands, self.mass_bands[0],
             left.lumped_mass),
            (self.u[1], self.v[1], self.a[1], self.sync[1], right.stiffness_bands, self.mass_bands[1],
             right.lumped_mass),
            (self.mass_solves[0][1], self.mass_solves[1][1]), (self.column1, self.column2),
            self.contact, self.control, self.state, hist, energies,
            None if s.scheme == kernels.SCHEME_FORCE else np.int64(s.scheme),
            None if s.scheme == kernels.SCHEME_FORCE or s.law == LAW_EXPONENTIAL else np.int64(s.law),
        )
        return status, [h[:done] for h in hist], [e[:samples] for e in energies]

    def momentum(self) -> float:
        """Total momentum of both rods now (mass * length/time), unmeshed remainders included.

        On the exact lattice a far node stands for half an element; the rest
        of the rod beyond it is in the waves (:func:`lattice.remainder_momentum`,
        at the half level of the velocities ``(u - w)/dt``).
        """
        if not self.lattice:
            return sum(float(d.lumped_mass @ v) for d, v in zip(self.setup.rods, self.v))
        total = 0.0
        level = int(self.state[layout.S_LEVEL])
        for index, (d, v, (f, g, _), parameters, theta) in enumerate(
            zip(self.setup.rods, self.v, self.waves, self.rod_parameters, self.setup.far_theta)
        ):
            far, inner = (0, 1) if index == 0 else (d.n_nodes - 1, d.n_nodes - 2)
            weights = d.lumped_mass.copy()
            weights[far] = 0.5 * d.rod.density * d.rod.area * abs(d.x[far] - d.x[inner])
            mask = int(parameters[layout.R_MASK])
            remainder = sum(
                lattice.remainder_momentum(f, g, mask, n, theta, far, d.rod.impedance) for n in (level, level - 1)
            )
            total += float(weights @ v) + 0.5 * remainder
        return total

    def synchronized_velocities(self):
        """Nodal velocities at the current time (the loop stores them half a step earlier)."""
        out = []
        for d, u, v, (kind, table) in zip(self.setup.rods, self.u, self.v, self.mass_solves):
            a = np.zeros_like(u)
            rod_acceleration(u, d.stiffness_bands, kind, table, a)
            out.append(v + 0.5 * self.setup.dt * a)
        return out

    def stresses(self):
        if not hasattr(self, "_recovery"):
            self._recovery = [d.stress_recovery() for d in self.setup.rods]
        return [matrix @ u for matrix, u in zip(self._recovery, self.u)]


def _failure_message(run: _Run, setup: FemSetup) -> str:
    time = run.state[layout.S_TIME]
    energy = run.state[layout.S_FAILED_ENERGY]
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
        if run.state[layout.S_STEPS] >= max_steps:
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
        "steps": int(run.state[layout.S_STEPS]),
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
        sample_times.append(run.state[layout.S_TIME])
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
