"""The explicit time loop of a scene of many bodies on a line (:mod:`wavecontact.fem.multibody`).

Central differences (leapfrog: velocities half a step behind the
displacements) for every body at once:

1. the soft contact forces (exponential, penalty, any law of
   :func:`wavecontact.contact_kernels.law_force`) at the current gaps;
2. each rod's free elastic step (:func:`~wavecontact.fem.explicit_step.step_flat`,
   the two-rod solver's per-rod step: P1/P2, lumped/consistent), each rigid
   body's free flight;
3. the soft forces as kicks spread along ``M^-1 e_end`` of each facing end
   (momentum is exchanged exactly);
4. the hard contacts as impulses with the same spread, solved by projected
   Gauss-Seidel so that every hard gap ends the step non-negative (a rod's end
   node sticks to what it meets: the *plastic* end-node rule, exact on the
   d'Alembert lattice, where the merged node is the characteristic junction of
   two impedances) or, between two rigid bodies or a rigid body and a wall,
   leaves with the reversed relative velocity (an elastic impact of exact point
   masses).

On the exact lattice (P1 lumped, every element crossed in one step) a hard
contact of two rod ends (or of a rod end and a wall) takes each end's free
motion over the step from its incoming characteristic (a massless end moves
at twice the incoming wave's rate, ``u_end + 2 d`` with ``d`` the incoming
wave's increment, kept by the recursion ``d = (u_neighbour^n - u_end^(n-1)) -
d_previous``), not from the half-mass node's leapfrog step: while the ends
are joined both give the characteristic junction, but only the former opens
the contact exactly when the incoming waves pull the ends apart (the leapfrog
end node carries the last step's contact impulse one step too long).  The
difference, the last step's impulse continued, is counted in the contact's
impulse.

Facing ends are *sides*: a rod node, a rigid body or a wall.  Each contact
keeps a record (impulse, steps in contact, first and last contact time, number
of intervals).  The loop stops once no contact has acted for ``period`` (the
longest vibration period) and no neighbours approach each other's centre of
mass (nor a wall).
"""

from __future__ import annotations

import math

from .._jit import kernel
from ..contact_kernels import law_force
from .explicit_step import MASS_CONDENSED, MASS_LUMPED, step_flat
from .interleaved_step import L_SHAPE, pack_nodes, step_condensed, step_tridiagonal, unpack_nodes
from .kernels import _leapfrog_p1

__all__ = ["CONTACT_FIELDS", "CONTROL_SIZE", "RECORD_FIELDS", "STATE_SIZE", "advance_line"]

SIDE_ROD = 0
SIDE_RIGID = 1
SIDE_WALL = 2
HARD_NONE = 0  # soft law: a force of the gap
HARD_PLASTIC = 1  # a rod's end node meets something: the gap closes to zero and stays closed while pressed
HARD_ELASTIC = 2  # two rigid sides: Newton's impact with restitution 1

# contact table columns
C_KIND_A, C_SLOT_A, C_NODE_A, C_KIND_B, C_SLOT_B, C_NODE_B = 0, 1, 2, 3, 4, 5
C_OFFSET = 6  # reference gap: gap = offset + u_b - u_a (length)
C_LAW, C_ALPHA, C_STRENGTH, C_STIFFNESS = 7, 8, 9, 10
C_THRESHOLD = 11  # force (soft) or impulse (hard) above which the contact counts as acting
C_HARD = 12
C_W = 13  # inverse mass the contact sees: (M^-1)_aa + (M^-1)_bb
C_COL_A, C_FIRST_A, C_LEN_A, C_COL_B, C_FIRST_B, C_LEN_B = 14, 15, 16, 17, 18, 19
C_LATTICE = 20  # 1: a hard contact of rod ends (or a rod end and a wall) on the exact lattice
C_NEIGHBOUR_A, C_NEIGHBOUR_B = 21, 22  # the node next to each rod end
CONTACT_FIELDS = 23

# characteristic state of the rod ends of lattice contacts (per contact)
E_PREVIOUS_A, E_INCOMING_A, E_PREVIOUS_B, E_INCOMING_B, E_FREE_A, E_FREE_B = 0, 1, 2, 3, 4, 5
END_FIELDS = 6

# records
R_IMPULSE, R_STEPS, R_FIRST, R_LAST, R_INTERVALS, R_ACTIVE = 0, 1, 2, 3, 4, 5
RECORD_FIELDS = 6

# control
K_DT, K_PERIOD, K_CHECK_EVERY, K_SPEED_TOLERANCE, K_ITERATIONS, K_LEFT_WALL, K_RIGHT_WALL = 0, 1, 2, 3, 4, 5, 6
K_RODS = 7  # rods in the lists (a scene of rigid bodies only passes one unused placeholder)
CONTROL_SIZE = 8

# state
S_TIME, S_STEPS, S_LAST_ACTIVE, S_MAX_ITERATIONS = 0, 1, 2, 3
STATE_SIZE = 4

STATUS_RUNNING = 0
STATUS_SEPARATED = 1
STATUS_FAILED = 2


@kernel
def _displacement(kind, slot, node, us, ru):
    if kind == SIDE_ROD:
        return us[slot][node]
    if kind == SIDE_RIGID:
        return ru[slot]
    return 0.0


@kernel
def _velocity(kind, slot, node, vs, rv):
    if kind == SIDE_ROD:
        return vs[slot][node]
    if kind == SIDE_RIGID:
        return rv[slot]
    return 0.0


@kernel
def _push(kind, slot, start, length, spread, stepped, rigid, kick, shift):
    """Add ``kick * M^-1 e_end`` to a side's velocities and ``shift * M^-1 e_end`` to its displacements.

    ``spread``: ``(columns, where)``, the ``M^-1 e_end`` entries and their positions in the arrays the loop
    steps, ``stepped``: those arrays ``(us, vs)``, ``rigid``: ``(ru, rv, rinv)`` (see :func:`advance_line`).
    """
    columns, where = spread
    ru, rv, rinv = rigid
    if kind == SIDE_ROD:
        u = stepped[0][slot]
        v = stepped[1][slot]
        for j in range(length):
            c = columns[start + j]
            k = where[start + j]
            v[k] += kick * c
            u[k] += shift * c
    elif kind == SIDE_RIGID:
        rv[slot] += kick * rinv[slot]
        ru[slot] += shift * rinv[slot]


@kernel
def _exchange(contacts, c, spread, stepped, rigid, impulse, dt):
    """Impulse ``impulse`` (>0 pushes the sides apart) over one step: kicks and the shift it makes (the
    tuples of :func:`_push`)."""
    _push(int(contacts[c, C_KIND_B]), int(contacts[c, C_SLOT_B]), int(contacts[c, C_COL_B]),
          int(contacts[c, C_LEN_B]), spread, stepped, rigid, impulse, impulse * dt)
    _push(int(contacts[c, C_KIND_A]), int(contacts[c, C_SLOT_A]), int(contacts[c, C_COL_A]),
          int(contacts[c, C_LEN_A]), spread, stepped, rigid, -impulse, -impulse * dt)


@kernel
def _gap(contacts, c, us, ru):
    return (contacts[c, C_OFFSET]
            + _displacement(int(contacts[c, C_KIND_B]), int(contacts[c, C_SLOT_B]), int(contacts[c, C_NODE_B]), us, ru)
            - _displacement(int(contacts[c, C_KIND_A]), int(contacts[c, C_SLOT_A]), int(contacts[c, C_NODE_A]), us, ru))


@kernel
def _closing_speed(contacts, c, vs, rv):
    return (_velocity(int(contacts[c, C_KIND_A]), int(contacts[c, C_SLOT_A]), int(contacts[c, C_NODE_A]), vs, rv)
            - _velocity(int(contacts[c, C_KIND_B]), int(contacts[c, C_SLOT_B]), int(contacts[c, C_NODE_B]), vs, rv))


@kernel
def _record(records, c, impulse, acting, time):
    records[c, R_IMPULSE] += impulse
    if acting:
        if records[c, R_ACTIVE] == 0.0:
            records[c, R_INTERVALS] += 1.0
            if records[c, R_FIRST] < 0.0:
                records[c, R_FIRST] = time
        records[c, R_ACTIVE] = 1.0
        records[c, R_LAST] = time
        records[c, R_STEPS] += 1.0
    else:
        records[c, R_ACTIVE] = 0.0


@kernel
def _apart(body_kind, body_slot, weights, vs, rv, control):
    """True if no neighbours approach each other's centre of mass, nor a wall."""
    n = body_kind.size
    tolerance = control[K_SPEED_TOLERANCE]
    previous = 0.0
    for i in range(n):
        slot = int(body_slot[i])
        if int(body_kind[i]) == SIDE_RIGID:
            speed = rv[slot]
        else:
            w = weights[slot]
            v = vs[slot]
            momentum = 0.0
            mass = 0.0
            for j in range(v.size):
                momentum += w[j] * v[j]
                mass += w[j]
            speed = momentum / mass
        if i == 0:
            if control[K_LEFT_WALL] > 0.0 and speed < -tolerance:
                return False
        elif previous - speed > tolerance:
            return False
        previous = speed
    return not (control[K_RIGHT_WALL] > 0.0 and previous > tolerance)


@kernel
def _free_end(u, end, neighbour, ends, c, previous, incoming, free):
    """Free motion of a rod end over the coming step from its incoming characteristic (see the module docstring)."""
    now = u[end]
    d = (u[neighbour] - ends[c, previous]) - ends[c, incoming]
    ends[c, previous] = now
    ends[c, incoming] = d
    ends[c, free] = now + 2.0 * d


@kernel
def _to_free_end(u, v, end, value, dt):
    """Move a rod end to its characteristic free position; return the shift (length)."""
    shift = value - u[end]
    u[end] = value
    v[end] += shift / dt
    return shift


@kernel
def _flat(flat_u, flat_v, us, vs, tables, bands, n_rods):
    """Copy the rods that run in the interleaved layout back to their flat arrays."""
    for b in range(n_rods):
        rows = int(tables[b][L_SHAPE, 0])
        if rows:
            unpack_nodes(us[b], flat_u[b], rows, bands[b].shape[0] - 1)
            unpack_nodes(vs[b], flat_v[b], rows, bands[b].shape[0] - 1)


@kernel
def advance_line(rods, rigid, line, links, control, state, max_steps):
    """Run up to ``max_steps`` steps; return ``(status, steps done)``.

    The arrays come in four tuples: ``rods = (flat_u, flat_v, us, vs, scratch, bands, kinds, tables,
    weights)``, ``rigid = (ru, rv, rinv)``, ``line = (body_kind, body_slot)`` and ``links = (contacts,
    columns, where, records, values, targets, ends)``.

    Parameters
    ----------
    flat_u, flat_v : lists of arrays, one per rod
        Displacements now (length) and velocities half a step earlier (length/time), node by node.
    us, vs : lists of arrays, one per rod
        The arrays the loop steps: ``flat_u, flat_v`` themselves, or for a consistent mass in the
        interleaved layout (:mod:`~wavecontact.fem.interleaved_step`) the rows of its table, packed on
        entry and unpacked to ``flat_u, flat_v`` for the checks and on return.
    scratch, bands, tables, weights : lists of arrays, one per rod
        A scratch array, the stiffness bands, the mass solve of
        :func:`~wavecontact.fem.explicit_step.prepare_mass` and the lumped masses.
    kinds : int array
        Mass-solve kind of each rod.
    ru, rv, rinv : arrays, one entry per rigid body
        Displacement, velocity and inverse mass.
    body_kind, body_slot : arrays, one entry per body in order along the line
        :data:`SIDE_ROD` or :data:`SIDE_RIGID` and the index in the rod or rigid lists.
    contacts : array (n_contacts, CONTACT_FIELDS)
        The ``C_*`` columns (rod nodes as positions in ``us``); ``columns`` holds the ``M^-1 e_end``
        entries they point to, ``where`` their positions in ``us``.
    records : array (n_contacts, RECORD_FIELDS)
        Accumulated ``R_*`` records.
    values, targets : arrays (n_contacts,)
        Scratch: this step's force or impulse per contact, and the hard contacts' target gaps.
    control, state : arrays
        ``K_*`` and ``S_*`` entries.
    """
    flat_u, flat_v, us, vs, scratch, bands, kinds, tables, weights = rods
    ru, rv = rigid[0], rigid[1]
    body_kind, body_slot = line
    contacts, columns, where, records, values, targets, ends = links
    stepped = (us, vs)
    spread = (columns, where)
    dt = control[K_DT]
    period = control[K_PERIOD]
    check_every = int(control[K_CHECK_EVERY])
    iterations = int(control[K_ITERATIONS])
    n_contacts = contacts.shape[0]
    n_rods = int(control[K_RODS])
    n_rigid = ru.size
    for b in range(n_rods):
        rows = int(tables[b][L_SHAPE, 0])
        if rows:
            pack_nodes(flat_u[b], us[b], rows, bands[b].shape[0] - 1)
            pack_nodes(flat_v[b], vs[b], rows, bands[b].shape[0] - 1)
    for step in range(max_steps):
        time = state[S_TIME]
        # 1. soft forces at the current gaps
        for c in range(n_contacts):
            if contacts[c, C_HARD] == HARD_NONE:
                gap = _gap(contacts, c, us, ru)
                values[c] = law_force(int(contacts[c, C_LAW]), contacts[c, C_ALPHA], contacts[c, C_STRENGTH],
                                      contacts[c, C_STIFFNESS], gap)
        # characteristic free motion of the rod ends of lattice contacts, from the state now
        for c in range(n_contacts):
            if contacts[c, C_LATTICE] != 0.0:
                if int(contacts[c, C_KIND_A]) == SIDE_ROD:
                    _free_end(us[int(contacts[c, C_SLOT_A])], int(contacts[c, C_NODE_A]),
                              int(contacts[c, C_NEIGHBOUR_A]), ends, c, E_PREVIOUS_A, E_INCOMING_A, E_FREE_A)
                if int(contacts[c, C_KIND_B]) == SIDE_ROD:
                    _free_end(us[int(contacts[c, C_SLOT_B])], int(contacts[c, C_NODE_B]),
                              int(contacts[c, C_NEIGHBOUR_B]), ends, c, E_PREVIOUS_B, E_INCOMING_B, E_FREE_B)
        # 2. free elastic step of every rod, free flight of every rigid body
        for b in range(n_rods):
            table = tables[b]
            if kinds[b] == MASS_LUMPED and bands[b].shape[0] == 2:
                _leapfrog_p1(us[b], vs[b], bands[b], table[0], dt)
            elif table[L_SHAPE, 0] > 0.0:
                if kinds[b] == MASS_CONDENSED:
                    step_condensed(table, dt)
                else:
                    step_tridiagonal(table, dt)
            else:
                step_flat(us[b], vs[b], scratch[b], bands[b], kinds[b], table, dt)
        for r in range(n_rigid):
            ru[r] += dt * rv[r]
        # 3. soft forces as kicks
        acting_any = False
        for c in range(n_contacts):
            if contacts[c, C_HARD] == HARD_NONE:
                force = values[c]
                if force != 0.0:
                    _exchange(contacts, c, spread, stepped, rigid, force * dt, dt)
                acting = force > contacts[c, C_THRESHOLD]
                acting_any = acting_any or acting
                _record(records, c, force * dt, acting, time)
        # 4. hard contacts: impulses that leave every hard gap non-negative (projected Gauss-Seidel)
        hard_any = False
        for c in range(n_contacts):
            if contacts[c, C_HARD] != HARD_NONE:
                hard_any = True
                values[c] = 0.0
        # the lattice contacts' rod ends to their characteristic free motion (the last impulse continued)
        for c in range(n_contacts):
            continued = 0.0
            if contacts[c, C_LATTICE] != 0.0:
                sides = 0.0
                if int(contacts[c, C_KIND_A]) == SIDE_ROD:
                    slot = int(contacts[c, C_SLOT_A])
                    node = int(contacts[c, C_NODE_A])
                    shift = _to_free_end(us[slot], vs[slot], node, ends[c, E_FREE_A], dt)
                    inverse = columns[int(contacts[c, C_COL_A]) + node - int(contacts[c, C_FIRST_A])]
                    continued -= shift / (dt * inverse)
                    sides += 1.0
                if int(contacts[c, C_KIND_B]) == SIDE_ROD:
                    slot = int(contacts[c, C_SLOT_B])
                    node = int(contacts[c, C_NODE_B])
                    shift = _to_free_end(us[slot], vs[slot], node, ends[c, E_FREE_B], dt)
                    inverse = columns[int(contacts[c, C_COL_B]) + node - int(contacts[c, C_FIRST_B])]
                    continued += shift / (dt * inverse)
                    sides += 1.0
                continued /= sides
            targets[c] = continued  # kept here until the records below
        if hard_any:
            for c in range(n_contacts):
                if contacts[c, C_HARD] != HARD_NONE:
                    records[c, R_IMPULSE] += targets[c]
                    targets[c] = 0.0
                    if contacts[c, C_HARD] == HARD_ELASTIC:
                        gap = _gap(contacts, c, us, ru)
                        closing = _closing_speed(contacts, c, vs, rv)
                        if gap < 0.0 and closing > 0.0:
                            targets[c] = gap + 2.0 * dt * closing  # leave with the reversed relative velocity
            for sweep in range(iterations):
                moved = False
                for c in range(n_contacts):
                    if contacts[c, C_HARD] == HARD_NONE:
                        continue
                    gap = _gap(contacts, c, us, ru)
                    wanted = values[c] + (targets[c] - gap) / (dt * contacts[c, C_W])
                    wanted = max(wanted, 0.0)
                    change = wanted - values[c]
                    if change != 0.0:
                        _exchange(contacts, c, spread, stepped, rigid, change, dt)
                        values[c] = wanted
                        # converged once no impulse changes by more than round-off (1e-12 of speed / W)
                        moved = moved or abs(change) > 0.01 * contacts[c, C_THRESHOLD]
                state[S_MAX_ITERATIONS] = max(state[S_MAX_ITERATIONS], sweep + 1.0)
                if not moved:
                    break
            for c in range(n_contacts):
                if contacts[c, C_HARD] != HARD_NONE:
                    acting = values[c] > contacts[c, C_THRESHOLD]
                    acting_any = acting_any or acting
                    _record(records, c, values[c], acting, time)
        time += dt
        state[S_TIME] = time
        state[S_STEPS] += 1.0
        if acting_any:
            state[S_LAST_ACTIVE] = time
        if (step + 1) % check_every == 0:
            for c in range(n_contacts):
                if not math.isfinite(_gap(contacts, c, us, ru)):
                    _flat(flat_u, flat_v, us, vs, tables, bands, n_rods)
                    return STATUS_FAILED, step + 1
            if time - state[S_LAST_ACTIVE] >= period:
                _flat(flat_u, flat_v, us, vs, tables, bands, n_rods)
                if _apart(body_kind, body_slot, weights, flat_v, rv, control):
                    return STATUS_SEPARATED, step + 1
    _flat(flat_u, flat_v, us, vs, tables, bands, n_rods)
    return STATUS_RUNNING, max_steps
