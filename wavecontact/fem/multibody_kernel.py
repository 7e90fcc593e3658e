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

Every body's arrays lie in one float array, the store (:mod:`.multibody_store`): a contact
side's end node, a rigid body or a wall is one index in it, a rod's arrays are views of it
made without a call or a reference count.

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
from .interleaved_step import pack_nodes, step_condensed, step_tridiagonal, unpack_nodes
from .kernels import _leapfrog_p1
from .multibody_store import (
    G_BAND_ROWS,
    G_BANDS,
    G_CHUNK_ROWS,
    G_FLAT_U,
    G_FLAT_V,
    G_KIND,
    G_NODES,
    G_SCRATCH,
    G_STEPPED_SIZE,
    G_STEPPED_U,
    G_STEPPED_V,
    G_TABLE,
    G_TABLE_COLS,
    G_TABLE_ROWS,
    G_WEIGHTS,
    block,
    borrowed,
    segment,
)

__all__ = ["CONTACT_FIELDS", "CONTROL_SIZE", "INDEX_FIELDS", "RECORD_FIELDS", "STATE_SIZE", "advance_line"]

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

# store indices of each contact's sides: the displacement of its end (a wall: an entry that stays 0) and how far
# from a displacement its velocity lies
I_U_A, I_SHIFT_A, I_U_B, I_SHIFT_B = 0, 1, 2, 3
INDEX_FIELDS = 4

# characteristic state of the rod ends of lattice contacts (per contact)
E_PREVIOUS_A, E_INCOMING_A, E_PREVIOUS_B, E_INCOMING_B, E_FREE_A, E_FREE_B = 0, 1, 2, 3, 4, 5
END_FIELDS = 6

# records
R_IMPULSE, R_STEPS, R_FIRST, R_LAST, R_INTERVALS, R_ACTIVE = 0, 1, 2, 3, 4, 5
RECORD_FIELDS = 6

# control
K_DT, K_PERIOD, K_CHECK_EVERY, K_SPEED_TOLERANCE, K_ITERATIONS, K_LEFT_WALL, K_RIGHT_WALL = 0, 1, 2, 3, 4, 5, 6
CONTROL_SIZE = 7

# state
S_TIME, S_STEPS, S_LAST_ACTIVE, S_MAX_ITERATIONS = 0, 1, 2, 3
STATE_SIZE = 4

STATUS_RUNNING = 0
STATUS_SEPARATED = 1
STATUS_FAILED = 2


@kernel(inline="always")
def _exchange(contacts, indices, c, columns, where, store, impulse, dt):
    """Impulse ``impulse`` (>0 pushes the sides apart) over one step: adds ``+-impulse M^-1 e_end`` to each
    side's velocities and ``+-impulse dt M^-1 e_end`` to its displacements.

    ``columns``: the ``M^-1 e_end`` entries of each side (a rigid body: one, its inverse mass; a wall: none),
    ``where``: the store indices of their displacements, ``indices``: how far from those the velocities lie.
    """
    kick, shift = impulse, impulse * dt
    start, to_velocity = int(contacts[c, C_COL_B]), indices[c, I_SHIFT_B]
    for j in range(int(contacts[c, C_LEN_B])):
        k = where[start + j]
        store[k + to_velocity] += kick * columns[start + j]
        store[k] += shift * columns[start + j]
    kick, shift = -impulse, -impulse * dt
    start, to_velocity = int(contacts[c, C_COL_A]), indices[c, I_SHIFT_A]
    for j in range(int(contacts[c, C_LEN_A])):
        k = where[start + j]
        store[k + to_velocity] += kick * columns[start + j]
        store[k] += shift * columns[start + j]


@kernel(inline="always")
def _gap(contacts, indices, c, store):
    return contacts[c, C_OFFSET] + store[indices[c, I_U_B]] - store[indices[c, I_U_A]]


@kernel(inline="always")
def _closing_speed(indices, c, store):
    return store[indices[c, I_U_A] + indices[c, I_SHIFT_A]] - store[indices[c, I_U_B] + indices[c, I_SHIFT_B]]


@kernel(inline="always")
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
def _apart(body_kind, body_slot, store, layout, rv, control):
    """True if no neighbours approach each other's centre of mass, nor a wall."""
    n = body_kind.size
    tolerance = control[K_SPEED_TOLERANCE]
    previous = 0.0
    for i in range(n):
        slot = int(body_slot[i])
        if int(body_kind[i]) == SIDE_RIGID:
            speed = rv[slot]
        else:
            w = segment(store, layout[slot, G_WEIGHTS], layout[slot, G_NODES])
            v = segment(store, layout[slot, G_FLAT_V], layout[slot, G_NODES])
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
def _free_end(store, end, neighbour, ends, c, previous, incoming, free):
    """Free motion of a rod end over the coming step from its incoming characteristic (see the module docstring).

    ``end``, ``neighbour``: store indices of the displacements of the end node and the node next to it.
    """
    now = store[end]
    d = (store[neighbour] - ends[c, previous]) - ends[c, incoming]
    ends[c, previous] = now
    ends[c, incoming] = d
    ends[c, free] = now + 2.0 * d


@kernel
def _to_free_end(store, end, to_velocity, value, dt):
    """Move a rod end (its displacement at store index ``end``, its velocity ``to_velocity`` further) to its
    characteristic free position; return the shift (length)."""
    shift = value - store[end]
    store[end] = value
    store[end + to_velocity] += shift / dt
    return shift


@kernel
def _node_arrays(store, layout, b):
    """Rod ``b``'s flat displacements and velocities and the arrays the loop steps: views of the store."""
    n, size = layout[b, G_NODES], layout[b, G_STEPPED_SIZE]
    return (segment(store, layout[b, G_FLAT_U], n), segment(store, layout[b, G_FLAT_V], n),
            segment(store, layout[b, G_STEPPED_U], size), segment(store, layout[b, G_STEPPED_V], size))


@kernel
def _flat(store, layout):
    """Copy the rods that run in the interleaved layout back to their flat arrays."""
    for b in range(layout.shape[0]):
        rows = layout[b, G_CHUNK_ROWS]
        if rows:
            flat_u, flat_v, u, v = _node_arrays(store, layout, b)
            unpack_nodes(u, flat_u, rows, layout[b, G_BAND_ROWS] - 1)
            unpack_nodes(v, flat_v, rows, layout[b, G_BAND_ROWS] - 1)


@kernel
def advance_line(rods, rigid, line, links, control, state, max_steps):
    """Run up to ``max_steps`` steps; return ``(status, steps done)``.

    The arrays come in four tuples: ``rods = (store, layout)``, ``rigid = (ru, rv)``, ``line =
    (body_kind, body_slot)`` and ``links = (contacts, columns, where, records, values, targets, ends,
    indices)``.

    Parameters
    ----------
    store : float array
        Every body's arrays (:func:`~wavecontact.fem.multibody_store.build_store`): per rod the
        displacements now (length) and velocities half a step earlier (length/time), node by node, a
        scratch array, the lumped masses, the stiffness bands and the mass solve of
        :func:`~wavecontact.fem.explicit_step.prepare_mass`; the rigid bodies' displacements and
        velocities; an entry that stays 0.  The loop steps the flat arrays, or for a consistent mass in the
        interleaved layout (:mod:`~wavecontact.fem.interleaved_step`) the rows of its table (packed on
        entry, unpacked to the flat arrays for the checks and on return).
    layout : int array (n_rods, ROD_FIELDS)
        Per rod, the ``G_*`` columns of :mod:`~wavecontact.fem.multibody_store`: where its arrays lie in
        ``store``, their shapes, its mass-solve kind.
    ru, rv : arrays, one entry per rigid body
        Displacement and velocity (views of ``store``).
    body_kind, body_slot : arrays, one entry per body in order along the line
        :data:`SIDE_ROD` or :data:`SIDE_RIGID` and the index in the rod layout or the rigid arrays.
    contacts : array (n_contacts, CONTACT_FIELDS)
        The ``C_*`` columns (rod nodes as positions in the arrays the loop steps); ``columns`` holds the
        ``M^-1 e_end`` entries they point to (a rigid body: its inverse mass), ``where`` the store indices
        of their displacements.
    indices : int array (n_contacts, INDEX_FIELDS)
        The ``I_*`` columns: each side's end displacement as a store index, and how far from a
        displacement its velocity lies.
    records : array (n_contacts, RECORD_FIELDS)
        Accumulated ``R_*`` records.
    values, targets : arrays (n_contacts,)
        Scratch: this step's force or impulse per contact, and the hard contacts' target gaps.
    control, state : arrays
        ``K_*`` and ``S_*`` entries.
    """
    store = borrowed(rods[0])  # a view that counts no references, for the calls of the lattice's helpers
    layout = rods[1]
    ru, rv = rigid
    body_kind, body_slot = line
    contacts, columns, where, records, values, targets, links_ends, indices = links
    ends = borrowed(links_ends)
    dt = control[K_DT]
    period = control[K_PERIOD]
    check_every = int(control[K_CHECK_EVERY])
    iterations = int(control[K_ITERATIONS])
    n_contacts = contacts.shape[0]
    n_rigid = ru.size
    hard_any = False
    lattice_any = False
    for c in range(n_contacts):
        hard_any = hard_any or contacts[c, C_HARD] != HARD_NONE
        lattice_any = lattice_any or contacts[c, C_LATTICE] != 0.0
    for b in range(layout.shape[0]):
        rows = layout[b, G_CHUNK_ROWS]
        if rows:
            flat_u, flat_v, u, v = _node_arrays(store, layout, b)
            pack_nodes(flat_u, u, rows, layout[b, G_BAND_ROWS] - 1)
            pack_nodes(flat_v, v, rows, layout[b, G_BAND_ROWS] - 1)
    for step in range(max_steps):
        time = state[S_TIME]
        # 1. soft forces at the current gaps
        for c in range(n_contacts):
            if contacts[c, C_HARD] == HARD_NONE:
                gap = _gap(contacts, indices, c, store)
                values[c] = law_force(int(contacts[c, C_LAW]), contacts[c, C_ALPHA], contacts[c, C_STRENGTH],
                                      contacts[c, C_STIFFNESS], gap)
        # characteristic free motion of the rod ends of lattice contacts, from the state now
        if lattice_any:
            for c in range(n_contacts):
                if contacts[c, C_LATTICE] != 0.0:
                    if int(contacts[c, C_KIND_A]) == SIDE_ROD:
                        end = indices[c, I_U_A]
                        _free_end(store, end, end + int(contacts[c, C_NEIGHBOUR_A]) - int(contacts[c, C_NODE_A]), ends,
                                  c, E_PREVIOUS_A, E_INCOMING_A, E_FREE_A)
                    if int(contacts[c, C_KIND_B]) == SIDE_ROD:
                        end = indices[c, I_U_B]
                        _free_end(store, end, end + int(contacts[c, C_NEIGHBOUR_B]) - int(contacts[c, C_NODE_B]), ends,
                                  c, E_PREVIOUS_B, E_INCOMING_B, E_FREE_B)
        # 2. free elastic step of every rod, free flight of every rigid body
        for b in range(layout.shape[0]):
            n = layout[b, G_NODES]
            u = segment(store, layout[b, G_STEPPED_U], layout[b, G_STEPPED_SIZE])
            v = segment(store, layout[b, G_STEPPED_V], layout[b, G_STEPPED_SIZE])
            kind = layout[b, G_KIND]
            band_rows = layout[b, G_BAND_ROWS]
            table_rows = layout[b, G_TABLE_ROWS]
            table_cols = layout[b, G_TABLE_COLS]
            bands = block(store, layout[b, G_BANDS], band_rows, n)
            if kind == MASS_LUMPED and band_rows == 2:
                _leapfrog_p1(u, v, bands,
                             segment(store, layout[b, G_TABLE], table_cols), dt)
            elif layout[b, G_CHUNK_ROWS] > 0:
                table = block(store, layout[b, G_TABLE], table_rows, table_cols)
                if kind == MASS_CONDENSED:
                    step_condensed(table, dt)
                else:
                    step_tridiagonal(table, dt)
            else:
                step_flat(u, v,
                          segment(store, layout[b, G_SCRATCH], n), bands, kind,
                          block(store, layout[b, G_TABLE], table_rows, table_cols), dt)
        for r in range(n_rigid):
            ru[r] += dt * rv[r]
        # 3. soft forces as kicks
        acting_any = False
        for c in range(n_contacts):
            if contacts[c, C_HARD] == HARD_NONE:
                force = values[c]
                if force != 0.0:
                    _exchange(contacts, indices, c, columns, where, store, force * dt, dt)
                acting = force > contacts[c, C_THRESHOLD]
                acting_any = acting_any or acting
                _record(records, c, force * dt, acting, time)
        # 4. hard contacts: impulses that leave every hard gap non-negative (projected Gauss-Seidel)
        if hard_any:
            for c in range(n_contacts):
                if contacts[c, C_HARD] != HARD_NONE:
                    values[c] = 0.0
            # the lattice contacts' rod ends to their characteristic free motion (the last impulse continued)
            for c in range(n_contacts):
                if contacts[c, C_LATTICE] != 0.0:
                    continued = 0.0
                    sides = 0.0
                    if int(contacts[c, C_KIND_A]) == SIDE_ROD:
                        node = int(contacts[c, C_NODE_A])
                        shift = _to_free_end(store, indices[c, I_U_A], indices[c, I_SHIFT_A], ends[c, E_FREE_A], dt)
                        inverse = columns[int(contacts[c, C_COL_A]) + node - int(contacts[c, C_FIRST_A])]
                        continued -= shift / (dt * inverse)
                        sides += 1.0
                    if int(contacts[c, C_KIND_B]) == SIDE_ROD:
                        node = int(contacts[c, C_NODE_B])
                        shift = _to_free_end(store, indices[c, I_U_B], indices[c, I_SHIFT_B], ends[c, E_FREE_B], dt)
                        inverse = columns[int(contacts[c, C_COL_B]) + node - int(contacts[c, C_FIRST_B])]
                        continued += shift / (dt * inverse)
                        sides += 1.0
                    records[c, R_IMPULSE] += continued / sides
            for c in range(n_contacts):
                if contacts[c, C_HARD] != HARD_NONE:
                    targets[c] = 0.0
                    if contacts[c, C_HARD] == HARD_ELASTIC:
                        gap = _gap(contacts, indices, c, store)
                        closing = _closing_speed(indices, c, store)
                        if gap < 0.0 and closing > 0.0:
                            targets[c] = gap + 2.0 * dt * closing  # leave with the reversed relative velocity
            for sweep in range(iterations):
                moved = False
                for c in range(n_contacts):
                    if contacts[c, C_HARD] == HARD_NONE:
                        continue
                    gap = _gap(contacts, indices, c, store)
                    wanted = values[c] + (targets[c] - gap) / (dt * contacts[c, C_W])
                    wanted = max(wanted, 0.0)
                    change = wanted - values[c]
                    if change != 0.0:
                        _exchange(contacts, indices, c, columns, where, store, change, dt)
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
                if not math.isfinite(_gap(contacts, indices, c, store)):
                    _flat(store, layout)
                    return STATUS_FAILED, step + 1
            if time - state[S_LAST_ACTIVE] >= period:
                _flat(store, layout)
                if _apart(body_kind, body_slot, store, layout, rv, control):
                    return STATUS_SEPARATED, step + 1
    _flat(store, layout)
    return STATUS_RUNNING, max_steps
