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

import numpy as np

from .._jit import NUMBA_ENABLED, kernel
from ..contact_kernels import law_force
from .explicit_step import MASS_CONDENSED, MASS_LUMPED, step_flat
from .interleaved_step import pack_nodes, step_condensed, step_tridiagonal, unpack_nodes
from .kernels import _leapfrog_p1

__all__ = ["CONTACT_FIELDS", "CONTROL_SIZE", "INDEX_FIELDS", "RECORD_FIELDS", "ROD_FIELDS", "STATE_SIZE", "advance_line"]

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

# rod layout: where each rod's arrays lie in the store (offsets in doubles) and their shapes
G_NODES = 0  # nodes n
G_FLAT_U, G_FLAT_V, G_SCRATCH, G_WEIGHTS = 1, 2, 3, 4  # n each: displacements, velocities, scratch, lumped masses
G_BANDS, G_BAND_ROWS = 5, 6  # stiffness bands, (rows, n)
G_TABLE, G_TABLE_ROWS, G_TABLE_COLS = 7, 8, 9  # the mass solve's table
G_STEPPED_U, G_STEPPED_V, G_STEPPED_SIZE = 10, 11, 12  # the arrays the loop steps (the flat ones or table rows)
G_KIND = 13  # mass-solve kind
G_CHUNK_ROWS = 14  # rows per chunk of the interleaved layout (0: flat layout)
ROD_FIELDS = 15

STATUS_RUNNING = 0
STATUS_SEPARATED = 1
STATUS_FAILED = 2


def _store_views():
    """:func:`_segment` and :func:`_block` for compiled kernels: views made from the store's data pointer."""
    from numba import carray
    from numba.core import types
    from numba.extending import intrinsic

    @intrinsic
    def address(typingctx, array, offset):
        signature = types.CPointer(array.dtype)(array, types.int64)

        def codegen(context, builder, sig, args):
            data = context.make_array(sig.args[0])(context, builder, args[0]).data
            return builder.gep(data, [args[1]])

        return signature, codegen

    @kernel(inline="always")
    def segment(store, offset, size):
        return carray(address(store, offset), (size,))

    @kernel(inline="always")
    def block(store, offset, rows, cols):
        return carray(address(store, offset), (rows, cols))

    @kernel(inline="always")
    def borrowed(array):
        return carray(address(array, np.int64(0)), array.shape)

    return segment, block, borrowed


def _segment_python(store, offset, size):
    return store[offset:offset + size]


def _block_python(store, offset, rows, cols):
    return store[offset:offset + rows * cols].reshape(rows, cols)


def _borrowed_python(array):
    return array


if NUMBA_ENABLED:
    _segment, _block, _borrowed = _store_views()
else:
    _segment, _block, _borrowed = _segment_python, _block_python, _borrowed_python
_segment.__doc__ = """``store[offset:offset + size]`` inside a compiled kernel, without a reference count or a call.

Every rod's arrays lie in one float array, the *store*, at the offsets of the rod layout (``G_*`` columns):
a lookup in a list of arrays per rod calls a helper of numba's typed list and counts a reference (about 12 ns
measured, some thirty lookups a step), a view made here is an address computation.  Like
:func:`~wavecontact._jit.row_view` it holds the data pointer only: valid while ``store`` is alive, never
returned.  Without numba it is the slice.
"""
_block.__doc__ = """``store[offset:offset + rows * cols].reshape(rows, cols)`` inside a compiled kernel (see :func:`_segment`)."""
_borrowed.__doc__ = """A C-contiguous array as a view that counts no references, inside a compiled kernel (see :func:`_segment`).

numba counts a reference (an atomic increment and decrement) for every array argument of a compiled call it
does not inline, on entry and on every tuple it unpacks: the loop's helpers, called a few times per contact
and step, took some ten such pairs each (on the 3-rod chain, about 0.15 us of its 0.55 us fixed cost per
step).  Handed views made here, each is a test of a null pointer.  Valid while ``array`` is alive (the
loop's arguments are, for the whole call); never returned.  Without numba it is ``array``.
"""


@kernel(inline="always")
def _rod_u(store, layout, slot):
    """Array the loop steps for the displacements of rod ``slot``."""
    return _segment(store, layout[slot, G_STEPPED_U], layout[slot, G_STEPPED_SIZE])


@kernel(inline="always")
def _rod_v(store, layout, slot):
    """Array the loop steps for the velocities of rod ``slot``."""
    return _segment(store, layout[slot, G_STEPPED_V], layout[slot, G_STEPPED_SIZE])



@kernel(inline="always")
def _push(store, columns, where, start, length, to_velocity, kick, shift):
    """Add ``kick * M^-1 e_end`` to a side's velocities and ``shift * M^-1 e_end`` to its displacements.

    ``columns[start:start + length]``: the ``M^-1 e_end`` entries, ``where``: the store indices of their
    displacements, ``to_velocity``: how far from those the velocities lie (a rigid body: one entry, its
    inverse mass; a wall: none).
    """
    for j in range(length):
        c = columns[start + j]
        k = where[start + j]
        store[k + to_velocity] += kick * c
        store[k] += shift * c


@kernel(inline="always")
def _exchange(contacts, indices, c, columns, where, store, impulse, dt):
    """Impulse ``impulse`` (>0 pushes the sides apart) over one step: kicks and the shift it makes."""
    _push(store, columns, where, int(contacts[c, C_COL_B]), int(contacts[c, C_LEN_B]), indices[c, I_SHIFT_B],
          impulse, impulse * dt)
    _push(store, columns, where, int(contacts[c, C_COL_A]), int(contacts[c, C_LEN_A]), indices[c, I_SHIFT_A],
          -impulse, -impulse * dt)


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
            w = _segment(store, layout[slot, G_WEIGHTS], layout[slot, G_NODES])
            v = _segment(store, layout[slot, G_FLAT_V], layout[slot, G_NODES])
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
def _flat(store, layout):
    """Copy the rods that run in the interleaved layout back to their flat arrays."""
    for b in range(layout.shape[0]):
        rows = layout[b, G_CHUNK_ROWS]
        if rows:
            n = layout[b, G_NODES]
            order = layout[b, G_BAND_ROWS] - 1
            unpack_nodes(_rod_u(store, layout, b), _segment(store, layout[b, G_FLAT_U], n), rows, order)
            unpack_nodes(_rod_v(store, layout, b), _segment(store, layout[b, G_FLAT_V], n), rows, order)


@kernel
def advance_line(rods, rigid, line, links, control, state, max_steps):
    """Run up to ``max_steps`` steps; return ``(status, steps done)``.

    The arrays come in four tuples: ``rods = (store, layout)``, ``rigid = (ru, rv)``, ``line =
    (body_kind, body_slot)`` and ``links = (contacts, columns, where, records, values, targets, ends,
    indices)``.

    Parameters
    ----------
    store : float array
        Every rod's arrays, one after the other (each starting on a 64-byte boundary when ``store`` does):
        displacements now (length) and velocities half a step earlier (length/time), node by node; the
        arrays the loop steps (those themselves, or for a consistent mass in the interleaved layout
        (:mod:`~wavecontact.fem.interleaved_step`) the rows of its table, packed on entry and unpacked to
        the flat arrays for the checks and on return); a scratch array, the stiffness bands, the mass solve
        of :func:`~wavecontact.fem.explicit_step.prepare_mass` and the lumped masses.
    layout : int array (n_rods, ROD_FIELDS)
        Per rod, the ``G_*`` columns: where its arrays lie in ``store``, their shapes, its mass-solve kind.
    ru, rv : arrays, one entry per rigid body
        Displacement and velocity (views of ``store``).
    body_kind, body_slot : arrays, one entry per body in order along the line
        :data:`SIDE_ROD` or :data:`SIDE_RIGID` and the index in the rod layout or the rigid arrays.
    contacts : array (n_contacts, CONTACT_FIELDS)
        The ``C_*`` columns (rod nodes as positions in the arrays the loop steps); ``columns`` holds the
        ``M^-1 e_end`` entries they point to, ``where`` their positions in those arrays.
    records : array (n_contacts, RECORD_FIELDS)
        Accumulated ``R_*`` records.
    values, targets : arrays (n_contacts,)
        Scratch: this step's force or impulse per contact, and the hard contacts' target gaps.
    control, state : arrays
        ``K_*`` and ``S_*`` entries.
    """
    # views that count no references, for the helpers' calls (see _borrowed)
    store = _borrowed(rods[0])
    layout = _borrowed(rods[1])
    ru, rv = _borrowed(rigid[0]), _borrowed(rigid[1])
    body_kind, body_slot = _borrowed(line[0]), _borrowed(line[1])
    contacts, columns, where = _borrowed(links[0]), _borrowed(links[1]), _borrowed(links[2])
    records, values, targets, ends = _borrowed(links[3]), _borrowed(links[4]), _borrowed(links[5]), _borrowed(links[6])
    indices = _borrowed(links[7])
    control = _borrowed(control)
    state = _borrowed(state)
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
            n = layout[b, G_NODES]
            order = layout[b, G_BAND_ROWS] - 1
            pack_nodes(_segment(store, layout[b, G_FLAT_U], n), _rod_u(store, layout, b), rows, order)
            pack_nodes(_segment(store, layout[b, G_FLAT_V], n), _rod_v(store, layout, b), rows, order)
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
                        _free_end(_rod_u(store, layout, int(contacts[c, C_SLOT_A])), int(contacts[c, C_NODE_A]),
                                  int(contacts[c, C_NEIGHBOUR_A]), ends, c, E_PREVIOUS_A, E_INCOMING_A, E_FREE_A)
                    if int(contacts[c, C_KIND_B]) == SIDE_ROD:
                        _free_end(_rod_u(store, layout, int(contacts[c, C_SLOT_B])), int(contacts[c, C_NODE_B]),
                                  int(contacts[c, C_NEIGHBOUR_B]), ends, c, E_PREVIOUS_B, E_INCOMING_B, E_FREE_B)
        # 2. free elastic step of every rod, free flight of every rigid body
        for b in range(layout.shape[0]):
            n = layout[b, G_NODES]
            kind = layout[b, G_KIND]
            band_rows = layout[b, G_BAND_ROWS]
            table_rows = layout[b, G_TABLE_ROWS]
            table_cols = layout[b, G_TABLE_COLS]
            bands = _block(store, layout[b, G_BANDS], band_rows, n)
            if kind == MASS_LUMPED and band_rows == 2:
                _leapfrog_p1(_rod_u(store, layout, b), _rod_v(store, layout, b), bands,
                             _segment(store, layout[b, G_TABLE], table_cols), dt)
            elif layout[b, G_CHUNK_ROWS] > 0:
                table = _block(store, layout[b, G_TABLE], table_rows, table_cols)
                if kind == MASS_CONDENSED:
                    step_condensed(table, dt)
                else:
                    step_tridiagonal(table, dt)
            else:
                step_flat(_rod_u(store, layout, b), _rod_v(store, layout, b),
                          _segment(store, layout[b, G_SCRATCH], n), bands, kind,
                          _block(store, layout[b, G_TABLE], table_rows, table_cols), dt)
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
                        slot = int(contacts[c, C_SLOT_A])
                        node = int(contacts[c, C_NODE_A])
                        shift = _to_free_end(_rod_u(store, layout, slot), _rod_v(store, layout, slot), node,
                                             ends[c, E_FREE_A], dt)
                        inverse = columns[int(contacts[c, C_COL_A]) + node - int(contacts[c, C_FIRST_A])]
                        continued -= shift / (dt * inverse)
                        sides += 1.0
                    if int(contacts[c, C_KIND_B]) == SIDE_ROD:
                        slot = int(contacts[c, C_SLOT_B])
                        node = int(contacts[c, C_NODE_B])
                        shift = _to_free_end(_rod_u(store, layout, slot), _rod_v(store, layout, slot), node,
                                             ends[c, E_FREE_B], dt)
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
