"""Set-up of a line scene for the multi-body time loop: meshes, sides, contacts and the step.

Layout on the line: body 0's left end at ``x = 0``, each next body after its
gap; a rigid body is a point (length 0); a left wall at ``-gap``, a right wall
at the last body's right end plus its gap.

Resolution: ``elements`` elements on the rod of the shortest wave travel time
(end to end); every segment of every rod gets elements of about the same
travel time ``h / c`` (at least one per segment).  Where all elements then
have one travel time (commensurate segments), P1 lumped runs at that step
(Courant number 1), where central differences are d'Alembert's exact lattice.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from skfem import Basis, BilinearForm, MeshLine

from ..bodies import PiecewiseRod, RigidBody, body_segments, pair_laws
from ..contact import LAW_EXPONENTIAL, Penalty
from ..errors import InvalidParameterError, UnsupportedSceneError
from ..scene import Rod
from .discretization import (
    _ELEMENTS,
    RodDiscretization,
    _left_to_right,
    assembled_discretization,
    discretize_rod,
)
from .explicit_step import prepare_mass
from .interleaved_step import LANE_TOLERANCE
from .multibody_kernel import (
    C_ALPHA,
    C_COL_A,
    C_COL_B,
    C_FIRST_A,
    C_FIRST_B,
    C_HARD,
    C_KIND_A,
    C_KIND_B,
    C_LAW,
    C_LEN_A,
    C_LEN_B,
    C_NEIGHBOUR_A,
    C_NEIGHBOUR_B,
    C_NODE_A,
    C_NODE_B,
    C_OFFSET,
    C_SLOT_A,
    C_SLOT_B,
    C_STIFFNESS,
    C_STRENGTH,
    C_THRESHOLD,
    C_W,
    CONTACT_FIELDS,
    HARD_ELASTIC,
    HARD_NONE,
    HARD_PLASTIC,
    SIDE_RIGID,
    SIDE_ROD,
    SIDE_WALL,
)
from .simulation import FORCE_COURANT, FORCE_PEAK, FORCE_RESOLUTION, POTENTIAL_TOLERANCE
from .stability import _reference_eigenvalue, check_time_step, largest_eigenvalue

__all__ = ["LineSetup", "build_line_setup", "rigid_contact_steps"]

# a hard impulse below this fraction of (end-node mass x velocity scale) is round-off, not a contact
IMPULSE_ROUNDOFF = 1e-10
# largest omega dt of the contact oscillation of a law acting on overlap only (penalty, Hertz): central differences
# on a spring that switches on and off pump energy where a step spans a good part of its period (omega dt = 1.56
# took a three-rod chain to 12 times its energy)
OVERLAP_RESOLUTION = 0.5
# fewest steps over the time scale pi / sqrt(k w) of a soft contact between two rigid sides (or a rigid body and a wall)
RIGID_CONTACT_STEPS = 50.0


def rigid_contact_steps(elements: int) -> float:
    """Steps over the time scale ``pi / sqrt(k w)`` of a soft contact between rigid sides at ``elements``.

    No rod takes part in such a contact, so ``elements`` alone would not refine it: it gets ``elements / 4``
    steps (200 at the default 800), at least ``RIGID_CONTACT_STEPS``; the error estimate's coarser runs halve
    this number with the elements (:func:`wavecontact.fem.multibody._estimate`), so Richardson sees the step.
    """
    return max(RIGID_CONTACT_STEPS, elements / 4.0)


@dataclass
class Side:
    kind: int  # SIDE_ROD, SIDE_RIGID, SIDE_WALL
    slot: int  # index among the rods or the rigid bodies
    node: int  # node of a rod
    position: float  # reference position on the line (length)
    column_first: int = 0
    column: np.ndarray | None = None  # M^-1 e_node from column_first on (1/mass)

    @property
    def inverse_mass(self) -> float:
        if self.kind == SIDE_WALL:
            return 0.0
        return float(self.column[self.node - self.column_first])


@dataclass
class LineSetup:
    """Everything the multi-body loop needs, built once per run."""

    scene: object
    rods: list  # RodDiscretization of each deformable body (in line order)
    body_kind: np.ndarray
    body_slot: np.ndarray
    rigid_masses: np.ndarray
    positions: np.ndarray  # reference left end of each body (length)
    contacts: np.ndarray  # (n, CONTACT_FIELDS)
    columns: np.ndarray
    contact_names: tuple
    laws: tuple  # the ContactLaw of each contact (a Penalty left to the solver: with its stiffness)
    u0: list
    v0: list
    dt: float
    stable_step: float
    lattice: bool  # P1 lumped at Courant number 1 on elements of one travel time
    period: float
    energy_scale: float
    speed_scale: float
    hard: bool  # some contact is hard
    walls: tuple  # (left present, right present)
    rigid_soft: bool = False  # some soft contact has no rod side (its step is not refined by the elements)


def _piecewise_discretization(body: PiecewiseRod, vertices: np.ndarray, order: int, mass_kind: str):
    """P1/P2 model of a rod of segments: ``E A(s)`` and ``rho A(s)`` per segment, linear in a taper."""
    segments = body.segments
    ends = np.cumsum([s.length for s in segments])
    starts = ends - np.array([s.length for s in segments])

    def profile(x, which):
        index = np.clip(np.searchsorted(ends, x, side="right"), 0, len(segments) - 1)
        out = np.empty_like(x)
        for k, s in enumerate(segments):
            here = index == k
            area = s.area_at(x[here] - starts[k])
            out[here] = area * (s.youngs_modulus if which == "stiffness" else s.density)
        return out

    @BilinearForm
    def stiffness_form(u, v, w):
        return profile(w.x[0], "stiffness") * u.grad[0] * v.grad[0]

    @BilinearForm
    def mass_form(u, v, w):
        return profile(w.x[0], "mass") * u * v

    mesh = MeshLine(vertices)
    basis = Basis(mesh, _ELEMENTS[order]())
    perm, inverse = _left_to_right(basis)
    stiffness = stiffness_form.assemble(basis).tocsr()[perm][:, perm].tocsr()
    consistent = mass_form.assemble(basis).tocsr()[perm][:, perm].tocsr()
    x = basis.doflocs[0][perm].copy()
    return assembled_discretization(body, order, mass_kind, basis, inverse, x, stiffness, consistent)


def _largest_eigenvalue(disc: RodDiscretization, segments, counts) -> float:
    """Largest eigenvalue of ``M^-1 K`` of one rod (1/time^2), by inertia bisection from the element bound.

    A uniform rod: :func:`wavecontact.fem.stability.largest_eigenvalue`.  Segments: the element bound of
    Irons and Fried, ``c^2 / h^2`` times the reference element's eigenvalue times the section ratio within
    the element (``K_e`` at most the largest section's, ``M_e`` at least the smallest's).
    """
    if isinstance(disc.rod, Rod):
        return largest_eigenvalue(disc)
    reference = _reference_eigenvalue(disc.order, disc.mass_kind)
    upper = 0.0
    for s, n in zip(segments, counts):
        h = s.length / n
        ratio = max(s.area, s.right_area) / min(s.area, s.right_area)
        upper = max(upper, reference * s.wave_speed**2 / h**2 * ratio)
    return largest_eigenvalue(disc, upper=upper * (1.0 + 1e-9))


def _mesh(body, travel: float) -> tuple:
    """Element end points of a rod (rod coordinate) with elements of about ``travel`` each, per segment."""
    segments = body_segments(body)
    counts = [max(1, round(s.travel_time / travel)) for s in segments]
    points, start = [np.zeros(1)], 0.0
    for s, n in zip(segments, counts):
        end = start + s.length
        points.append(np.linspace(start, end, n + 1)[1:])
        start = end
    vertices = np.concatenate(points)
    return vertices, segments, counts


def _end_section(body, right: bool) -> tuple:
    """``(E A / h-free impedance rho c A, E A)`` at one end of a rod: section and material of the end segment."""
    segments = body_segments(body)
    s = segments[-1] if right else segments[0]
    area = s.right_area if right else s.area
    return s.density * s.wave_speed * area, s.youngs_modulus * area


def _gap_where(function, level: float, scale: float) -> float:
    """The gap at which a decreasing ``function`` of the gap falls to ``level`` (bisection)."""
    hi = 0.0
    step = scale
    while function(hi) > level:
        hi += step
        step *= 2.0
    lo = -scale
    step = scale
    while function(lo) <= level:
        lo -= step
        step *= 2.0
        if step > 1e300:
            return -math.inf
    for _ in range(200):
        middle = 0.5 * (lo + hi)
        if middle in (lo, hi):
            break
        if function(middle) > level:
            lo = middle
        else:
            hi = middle
    return hi


def _stop_gap(law, energy: float, scale: float) -> float:
    """Gap (length) beyond which the law's potential is below POTENTIAL_TOLERANCE of the energy (0 for zero range)."""
    if law.hard or law.range == 0.0:
        return 0.0
    code, alpha, strength, _ = law.kernel_parameters()
    if code == LAW_EXPONENTIAL:  # the exponential law in closed form, as the two-rod solver
        return math.log(strength / (POTENTIAL_TOLERANCE * energy)) / alpha
    return _gap_where(lambda g: float(law.potential(g)), POTENTIAL_TOLERANCE * energy, max(law.range, scale))


def _stiffness_bound(law, energy: float, force_cap: float, scale: float) -> float:
    """Largest contact stiffness ``dF/d(overlap)`` (force/length) the run can meet: at the gap where the
    potential reaches the whole energy or the force reaches ``force_cap``, whichever comes first."""
    at_energy = _gap_where(lambda g: float(law.potential(g)), energy, max(law.range, scale))
    gap = at_energy
    if math.isfinite(force_cap):
        gap = max(gap, _gap_where(lambda g: float(law.force(g)), force_cap, max(law.range, scale)))
    delta = 1e-6 * max(abs(gap), law.range, scale)
    return max(float(law.force(gap - delta) - law.force(gap + delta)) / (2.0 * delta), 0.0)


def build_line_setup(scene, elements: int = 800, order: int = 1, mass: str = "lumped", dt=None, courant=None,
                     max_time=None, contact_steps=None) -> LineSetup:
    """Discretize every body of a line scene and choose the step (see the module docstring).

    ``contact_steps``: steps over the time scale ``pi / sqrt(k w)`` (``k`` the law's largest stiffness the
    energy allows, ``w`` the sum of the inverse masses) of each soft contact between two rigid sides
    (default :func:`rigid_contact_steps` of ``elements``); contacts with a rod side are resolved by its mesh.
    """
    del max_time
    if contact_steps is None:
        contact_steps = rigid_contact_steps(elements)
    if order not in (1, 2) or isinstance(order, bool):
        raise InvalidParameterError(f"order must be 1 or 2, got {order!r}")
    if mass not in ("lumped", "consistent"):
        raise InvalidParameterError(f"mass must be 'lumped' or 'consistent', got {mass!r}")
    if scene.is_ring:
        raise UnsupportedSceneError("the fem multi-body loop takes scenes on a line")
    bodies = scene.rods
    deformable = [b for b in bodies if not isinstance(b, RigidBody)]
    velocities = np.array(scene.velocities, dtype=float)
    walls = scene.walls or (None, None)
    wall_speeds = [0.0] * sum(w is not None for w in walls)
    speeds = np.concatenate([velocities, wall_speeds])
    speed_scale = float(speeds.max() - speeds.min())
    if speed_scale <= 0.0 and scene.is_cold:
        raise InvalidParameterError("no body moves relative to another (or to a wall): nothing collides")
    # meshes
    travel = None
    if deformable:
        travel = min(sum(s.travel_time for s in body_segments(b)) for b in deformable) / elements
    rods, body_kind, body_slot, rigid_masses, meshes = [], [], [], [], []
    for body in bodies:
        if isinstance(body, RigidBody):
            body_kind.append(SIDE_RIGID)
            body_slot.append(len(rigid_masses))
            rigid_masses.append(body.mass)
            continue
        vertices, segments, counts = _mesh(body, travel)
        if isinstance(body, Rod):
            disc = discretize_rod(body, vertices, order, mass)
        else:
            disc = _piecewise_discretization(body, vertices, order, mass)
        body_kind.append(SIDE_ROD)
        body_slot.append(len(rods))
        rods.append(disc)
        meshes.append((segments, counts))
    # initial state
    u0, v0 = [], []
    for index, body in enumerate(bodies):
        if body_kind[index] != SIDE_ROD:
            continue
        disc = rods[body_slot[index]]
        u = np.zeros(disc.n_nodes)
        v = np.full(disc.n_nodes, velocities[index])
        for values, fields in ((u, scene.initial_displacement), (v, scene.initial_velocity)):
            if fields is not None and fields[index] is not None:
                added = np.asarray(fields[index](disc.x.copy()), dtype=float)
                if added.shape != disc.x.shape or not np.all(np.isfinite(added)):
                    raise InvalidParameterError(
                        f"initial field of body {index} must return finite values of shape {disc.x.shape}")
                values += added
        u0.append(u)
        v0.append(v)
    masses = np.array([b.mass if isinstance(b, RigidBody) else float(rods[body_slot[i]].lumped_mass.sum())
                       for i, b in enumerate(bodies)])
    energy = 0.5 * float(np.sum([masses[i] * velocities[i] ** 2 for i in range(len(bodies))
                                 if body_kind[i] == SIDE_RIGID]))
    momentum = sum(masses[i] * velocities[i] for i in range(len(bodies)) if body_kind[i] == SIDE_RIGID)
    for disc, u, v in zip(rods, u0, v0):
        kinetic, strain = disc.energy(u, v)
        energy += kinetic + strain
        momentum += float(disc.lumped_mass @ v)
    if not any(w is not None for w in walls):
        energy -= momentum**2 / (2.0 * masses.sum())
    if not energy > 0.0:
        raise InvalidParameterError("the bodies carry no energy of relative or internal motion: nothing collides")
    # the time step
    lam = 0.0
    for disc, (segments, counts) in zip(rods, meshes):
        lam = max(lam, _largest_eigenvalue(disc, segments, counts))
    limit = 2.0 / math.sqrt(lam) if lam > 0.0 else math.inf
    element_travel = []
    for segments, counts in meshes:
        element_travel.extend(s.travel_time / n for s, n in zip(segments, counts))
    one_travel = bool(element_travel) and (max(element_travel) - min(element_travel)) <= 1e-9 * min(element_travel)
    length_scale = sum(b.length for b in bodies) or 1.0
    # sides and contacts
    positions, x = [], 0.0
    laws = list(pair_laws(scene))
    gaps = list(scene.gaps) if scene.gaps is not None else [None] * len(laws)

    def side(index, right):
        kind, slot = body_kind[index], body_slot[index]
        if kind == SIDE_RIGID:
            return Side(SIDE_RIGID, slot, 0, 0.0, 0, np.array([1.0 / rigid_masses[slot]]))
        disc = rods[slot]
        node = disc.n_nodes - 1 if right else 0
        column = disc.inverse_mass_column(node)
        significant = np.flatnonzero(np.abs(column) > LANE_TOLERANCE * abs(column[node]))
        first, last = int(significant[0]), int(significant[-1]) + 1
        return Side(SIDE_ROD, slot, node, 0.0, first, np.ascontiguousarray(column[first:last]))

    def facing_impedance(s, index, right):
        if s.kind != SIDE_ROD:
            return math.inf
        return _end_section(bodies[index], right)[0]

    pairs = []
    for i in range(len(bodies) - 1):
        pairs.append((side(i, True), side(i + 1, False), laws[i], gaps[i], f"{i}-{i + 1}", (i, True), (i + 1, False)))
    if walls[0] is not None:
        pairs.append((Side(SIDE_WALL, 0, 0, 0.0), side(0, False), walls[0].contact, walls[0].gap, "left wall",
                      None, (0, False)))
    if walls[1] is not None:
        last = len(bodies) - 1
        pairs.append((side(last, True), Side(SIDE_WALL, 0, 0, 0.0), walls[1].contact, walls[1].gap, "right wall",
                      (last, True), None))
    resolved_laws, stop_gaps, start_gaps = [], [], []
    for a, b, law, gap, name, end_a, end_b in pairs:
        if law.stiffness_from_solver:
            stiffnesses = [_end_section(bodies[e[0]], e[1])[1] / _end_element(rods[body_slot[e[0]]], e[1])
                           for e in (end_a, end_b) if e is not None and body_kind[e[0]] == SIDE_ROD]
            if not stiffnesses:
                raise InvalidParameterError(f"contact {name}: Penalty() between rigid sides needs a stiffness")
            law = Penalty(max(stiffnesses))
        resolved_laws.append(law)
        stop = _stop_gap(law, energy, 1e-6 * length_scale)
        stop_gaps.append(stop)
        start_gaps.append(max(stop, 0.0) if gap is None else float(gap))
    # positions along the line
    for i, body in enumerate(bodies):
        positions.append(x)
        x += body.length + (start_gaps[i] if i < len(bodies) - 1 else 0.0)
    positions = np.array(positions)
    left_wall = -start_gaps[len(bodies) - 1] if walls[0] is not None else 0.0
    right_wall = positions[-1] + bodies[-1].length + start_gaps[-1] if walls[1] is not None else 0.0
    # the step
    soft_limit, resolution = math.inf, math.inf
    rigid_soft = False
    columns, rows = [], []
    hard_any = False
    for k, ((a, b, _, _, name, end_a, end_b), law) in enumerate(zip(pairs, resolved_laws)):
        code, alpha, strength, stiffness = law.kernel_parameters()
        w = a.inverse_mass + b.inverse_mass
        if law.hard:
            hard_any = True
        else:
            impedances = [facing_impedance(s, e[0], e[1]) for s, e in ((a, end_a), (b, end_b)) if e is not None]
            admittance = sum(1.0 / z for z in impedances)
            z_eff = 1.0 / admittance if admittance > 0.0 else math.inf  # rigid sides and walls: no admittance
            if len(impedances) == 1 and impedances[0] == math.inf:
                z_eff = math.inf
            # the two-rod bound of the peak force, FORCE_PEAK Z_eff V, holds between two free rods; a wall or a
            # rigid body can press harder (a three-body scene with a wall overflowed the exponential at alpha V h = 10):
            # there only the energy bound (the potential at most the whole energy) holds
            free_rods = math.isfinite(z_eff) and not any(walls) and not rigid_masses
            cap = FORCE_PEAK * z_eff * speed_scale if free_rods else math.inf
            k_contact = _stiffness_bound(law, energy, cap, 1e-6 * length_scale)
            soft_limit = min(soft_limit, FORCE_COURANT * 2.0 / math.sqrt(lam + k_contact * w))
            if law.range > 0.0:  # alpha V dt <= FORCE_RESOLUTION, as the two-rod force scheme
                resolution = min(resolution, FORCE_RESOLUTION / (law.range**-1 * max(speed_scale, 1e-300)))
            elif k_contact > 0.0:  # a law acting on overlap only switches on and off: resolve its oscillation
                resolution = min(resolution, OVERLAP_RESOLUTION / math.sqrt(k_contact * w))
            if a.kind != SIDE_ROD and b.kind != SIDE_ROD and k_contact > 0.0:  # no mesh resolves it: its own steps
                rigid_soft = True
                resolution = min(resolution, math.pi / math.sqrt(k_contact * w) / contact_steps)
        row = np.zeros(CONTACT_FIELDS)
        for s, prefix in ((a, "A"), (b, "B")):
            kind_col, slot_col, node_col = (C_KIND_A, C_SLOT_A, C_NODE_A) if prefix == "A" else (C_KIND_B, C_SLOT_B,
                                                                                              C_NODE_B)
            col_col, first_col, len_col = (C_COL_A, C_FIRST_A, C_LEN_A) if prefix == "A" else (C_COL_B, C_FIRST_B,
                                                                                            C_LEN_B)
            row[kind_col], row[slot_col], row[node_col] = s.kind, s.slot, s.node
            if s.kind == SIDE_ROD:
                row[C_NEIGHBOUR_A if prefix == "A" else C_NEIGHBOUR_B] = s.node - 1 if s.node > 0 else 1
            if s.kind != SIDE_WALL:
                row[col_col] = sum(c.size for c in columns)
                row[first_col] = s.column_first
                row[len_col] = s.column.size
                columns.append(s.column)
        ref_a = left_wall if a.kind == SIDE_WALL else positions[end_a[0]] + bodies[end_a[0]].length
        ref_b = right_wall if b.kind == SIDE_WALL else positions[end_b[0]]
        row[C_OFFSET] = ref_b - ref_a
        row[C_LAW], row[C_ALPHA], row[C_STRENGTH], row[C_STIFFNESS] = code, alpha, strength, stiffness
        if law.hard:
            rigid_pair = a.kind != SIDE_ROD and b.kind != SIDE_ROD
            row[C_HARD] = HARD_ELASTIC if rigid_pair else HARD_PLASTIC
            row[C_THRESHOLD] = IMPULSE_ROUNDOFF * speed_scale / w
        else:
            row[C_HARD] = HARD_NONE
            row[C_THRESHOLD] = float(law.force(stop_gaps[k])) if law.range > 0.0 else 0.0
        row[C_W] = w
        rows.append(row)
    contacts = np.array(rows).reshape(len(rows), CONTACT_FIELDS)
    columns = np.concatenate(columns) if columns else np.zeros(1)
    # step: the lattice where it applies, else a fraction of the stable step, within the soft contacts' limits
    lattice = False
    if dt is None:
        if courant is None:
            exact = order == 1 and mass == "lumped" and one_travel and math.isfinite(limit)
            step = element_travel[0] if exact and element_travel[0] <= limit * (1 + 1e-9) else 0.95 * limit
            lattice = exact and step == element_travel[0] and not math.isfinite(soft_limit)
        else:
            if not (isinstance(courant, (int, float)) and 0.0 < courant <= 1.0):
                raise InvalidParameterError(f"courant must lie in (0, 1], got {courant!r}")
            step = courant * limit
        step = min(step, soft_limit, resolution)
        if not math.isfinite(step):  # rigid bodies with hard contact only: resolve the approach
            step = length_scale / speed_scale / elements
    else:
        step = check_time_step(dt, limit)  # a soft contact stiffer than its bound shows in the energy check
    round_trips = [2.0 * sum(s.travel_time for s in body_segments(b)) for b in deformable]
    period = max(1.05 * max(round_trips, default=0.0), 2.0 * step)
    return LineSetup(scene=scene, rods=rods, body_kind=np.array(body_kind, dtype=np.int64),
                     body_slot=np.array(body_slot, dtype=np.int64), rigid_masses=np.array(rigid_masses, dtype=float),
                     positions=positions, contacts=contacts, columns=columns,
                     contact_names=tuple(p[4] for p in pairs), laws=tuple(resolved_laws), u0=u0, v0=v0, dt=float(step),
                     stable_step=limit, lattice=lattice, period=period, energy_scale=energy, speed_scale=speed_scale,
                     hard=hard_any, walls=(walls[0] is not None, walls[1] is not None), rigid_soft=rigid_soft)


def _end_element(disc: RodDiscretization, right: bool) -> float:
    """Length of the end element of a rod (length)."""
    cell = disc.cells[-1] if right else disc.cells[0]
    return float(disc.x[cell[1]] - disc.x[cell[0]])


def mass_solves(setup: LineSetup) -> list:
    """``(kind, table)`` of each rod's mass solve (:func:`~wavecontact.fem.explicit_step.prepare_mass`)."""
    return [prepare_mass(d) for d in setup.rods]
