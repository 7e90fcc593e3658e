"""Time loop of two rods in contact: plain-array numba kernels.

One step of central differences in leapfrog form (``v`` lives at half steps):

1. kick with the elastic forces ``v += dt M^-1 (-K u)`` and drift ``u += dt v``
   (one sweep over the nodes for P1 lumped);
2. contact, along the columns ``M^-1 e_end`` so that momentum is exchanged
   exactly: either the force of the gap at the start of the step as a kick
   (``SCHEME_FORCE``: plain central differences, where the contact is
   resolved) or the facing end nodes moved to the gap the contact law gives
   after the step (:mod:`.contact_flows`: interface schemes).  A rod in the
   interleaved layout (:mod:`.interleaved_step`) takes the force scheme's
   force in step 1 instead, on its mass solve's right-hand side, which spreads
   it as ``M^-1 e_end`` (the same to rounding, without a pass over the nodes
   near the end, each on its own cache line in that layout).

Elastic forces are evaluated as ``-sum_j K_ij (u_j - u_i)`` (rows of ``K``
sum to zero), so a rigid translation produces no force at all.

The exact lattice (P1 lumped, uniform interior, Courant number 1) has its own
loop, :func:`wavecontact.fem.lattice.advance_lattice`.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel
from .contact_flows import (
    contact_force,
    contact_potential,
    pruned_flow,
    pruned_gap,
)
from .explicit_step import MASS_CONDENSED, MASS_LUMPED, T_CHAIN_INVERSE, elastic_acceleration, step_flat
from .interleaved_step import (
    L_SHAPE,
    L_U,
    L_V,
    node_position,
    pack_nodes,
    step_condensed_loaded,
    step_tridiagonal_loaded,
    unpack_nodes,
)
from .layout import (
    K_BOUND1,
    K_BOUND2,
    K_KIND1,
    K_KIND2,
    K_PLASTIC,
    S_ENERGY0,
    S_ENERGY_SCALE,
    S_FAILED_ENERGY,
    S_LAST_IN_RANGE,
    S_MAX_DRIFT,
    S_MOMENTUM1,
    S_MOMENTUM2,
    S_STEPS,
    S_TIME,
    read_contact,
    read_run_control,
)

__all__ = [
    "STATUS_FAILED",
    "STATUS_RUNNING",
    "STATUS_SEPARATED",
    "advance",
    "rod_energies",
]

STATUS_RUNNING = 0
# contact treatments (docs/fem.md)
SCHEME_CHARACTERISTIC = 0  # exact lattice: incoming characteristics + first-order gap equation
SCHEME_INTERFACE = 1  # any mesh: massless-end gap equation with the end nodes' velocities
SCHEME_SPLITTING = 2  # any mesh: impulse splitting with the exact two-body flow of the end nodes
SCHEME_FORCE = 3  # any mesh, resolved contact: plain central differences, force at the end nodes
STATUS_SEPARATED = 1
STATUS_FAILED = 2



@kernel
def rod_energies(u, v, a, bands, mass_bands, dt):
    """Kinetic and strain energy of one rod; ``mass_bands`` in the layout of ``bands``.

    Also returns the leapfrog correction ``dt^2/8 a.M a``: central differences
    conserve ``kinetic + strain - dt^2/8 a.M a`` exactly for free rods (the
    kinetic energy of the half-step velocities), not ``kinetic + strain``.
    """
    n = u.size
    width = bands.shape[0] - 1
    mwidth = mass_bands.shape[0] - 1
    kinetic = 0.0
    strain = 0.0
    correction = 0.0
    for i in range(n):
        kinetic += 0.5 * mass_bands[0, i] * v[i] * v[i]
        correction += 0.5 * mass_bands[0, i] * a[i] * a[i]
        for d in range(1, mwidth + 1):
            if i + d < n:
                kinetic += mass_bands[d, i] * v[i] * v[i + d]
                correction += mass_bands[d, i] * a[i] * a[i + d]
        for d in range(1, width + 1):
            if i + d < n:
                diff = u[i + d] - u[i]
                strain -= 0.5 * bands[d, i] * diff * diff
    return kinetic, strain, 0.25 * dt * dt * correction


@kernel(internal=True)
def _mean_displacement(u, weights):
    total = 0.0
    mass = 0.0
    for i in range(u.size):
        total += weights[i] * u[i]
        mass += weights[i]
    return total / mass


@kernel(fastmath=False, internal=True)
def _leapfrog_p1(u, v, bands, inverse_mass, dt):
    """P1 lumped fast path of one step in a single sweep: ``v += dt M^-1 (-K u)``, ``u += dt v``.

    Each node's displacement is overwritten right after its own acceleration
    is known; the old value is kept in ``previous`` for the next node.
    """
    n = u.size
    if n == 1:
        u[0] += dt * v[0]
        return
    previous = u[0]
    v[0] += dt * (-bands[1, 0] * (u[1] - previous) * inverse_mass[0])
    u[0] = previous + dt * v[0]
    for i in range(1, n - 1):
        current = u[i]
        force = -bands[1, i - 1] * (previous - current) - bands[1, i] * (u[i + 1] - current)
        velocity = v[i] + dt * force * inverse_mass[i]
        v[i] = velocity
        u[i] = current + dt * velocity
        previous = current
    current = u[n - 1]
    v[n - 1] += dt * (-bands[1, n - 2] * (previous - current) * inverse_mass[n - 1])
    u[n - 1] = current + dt * v[n - 1]


@kernel(fastmath=False, inline="always")
def _synchronize(u, v, a, sync, bands, kind, table, dt):
    """Velocity at the time of ``u`` from the half-step velocity ``v``: ``v + dt/2 a(u)``."""
    elastic_acceleration(u, bands, kind, table, a)
    for i in range(u.size):
        sync[i] = v[i] + 0.5 * dt * a[i]


@kernel(internal=True)
def _energy_check(kinetic1, strain1, kinetic2, strain2, potential, mass1, mass2, time, energy_tolerance, state,
                  samples, energies):
    """Record one energy sample and watch the balance (the periodic check of both time loops).

    ``energies``: the 6 sample arrays of the loops (time, kinetic, strain and contact energy, internal
    energy of each rod).

    Returns ``(samples, internal1, internal2, within)``: the updated sample
    count, each rod's internal energy (total minus its translation), and
    False when the relative drift of the total is not finite or exceeds
    ``energy_tolerance`` (then ``state[S_FAILED_ENERGY]`` holds the total).
    """
    total = kinetic1 + strain1 + kinetic2 + strain2 + potential
    internal1 = kinetic1 + strain1 - 0.5 * state[S_MOMENTUM1] ** 2 / mass1
    internal2 = kinetic2 + strain2 - 0.5 * state[S_MOMENTUM2] ** 2 / mass2
    energy_time, energy_kinetic, energy_strain, energy_contact, energy_internal1, energy_internal2 = energies
    if samples < energy_time.size:
        energy_time[samples] = time
        energy_kinetic[samples] = kinetic1 + kinetic2
        energy_strain[samples] = strain1 + strain2
        energy_contact[samples] = potential
        energy_internal1[samples] = internal1
        energy_internal2[samples] = internal2
        samples += 1
    drift = abs(total - state[S_ENERGY0]) / state[S_ENERGY_SCALE]
    if not math.isfinite(drift) or drift > energy_tolerance:
        state[S_FAILED_ENERGY] = total
        return samples, internal1, internal2, False
    state[S_MAX_DRIFT] = max(state[S_MAX_DRIFT], drift)
    return samples, internal1, internal2, True




@kernel
def advance(rod1, rod2, tables, columns, contact, control, state, history, energies, end_scheme, general_law):
    """Run up to ``history[0].size`` steps of central differences with the contact; return ``(status, steps, samples)``.

    Parameters
    ----------
    rod1, rod2 : tuple of arrays
        ``(u, v, a, sync, bands, mass_bands, weights)``: displacements now
        (length) and velocities half a step earlier (leapfrog; length/time),
        two scratch arrays, the stiffness bands, the mass in the same banded
        layout and the lumped masses (weights of momentum and centre of mass).
    tables : tuple of 2 arrays
        Mass solves of :func:`~wavecontact.fem.explicit_step.prepare_mass`
        (their kinds in ``control``).
    columns : tuple of 2 arrays
        ``M1^-1 e_last`` on the last ``columns[0].size`` nodes of rod 1 and
        ``M2^-1 e_0`` on the first nodes of rod 2 (1/mass): how the contact
        acts, so that momentum is exchanged exactly (not used for a rod in
        the interleaved layout under the force scheme: its solve spreads the
        force).
    contact : ndarray
        Law, its parameters, reference gap (``gap = offset + u2[0] - u1[-1]``),
        stop gap and ``m_inv`` (:mod:`~wavecontact.fem.layout` ``C_*``).
    control : ndarray
        ``K_*`` entries (:mod:`~wavecontact.fem.layout`).
    state : ndarray
        ``S_*`` entries carried between calls (time, momenta, run control).
    history : tuple of 4 arrays
        Per step: time, mean contact force over the step, relative velocity
        of the centres of mass, gap; their size is the number of steps asked.
    energies : tuple of 6 arrays
        Per check (every ``check_every`` steps): time, kinetic, strain and
        contact energy, internal energy of each rod.
    end_scheme : None or np.int64
        The contact scheme: None for the force scheme (``SCHEME_FORCE``), else
        ``SCHEME_SPLITTING`` or ``SCHEME_INTERFACE`` (the end nodes moved to the
        gap of the contact's exact solution).  numba prunes the branches of a
        None argument before typing, so a force-scheme run compiles neither
        scheme's flows and gaps (the README's FE commands run no other scheme).
    general_law : None or np.int64
        For the two other schemes: None for the exponential law (the law of
        ``contact``; its flow and gap are then called directly and numba
        compiles no other law's), else the law's code.  None under the force
        scheme, which reads the law from ``contact`` (one specialisation for
        every law).

    The run stops (status 1) once the rods are apart and provably stay apart:
    the end gap is bounded below by the centre-of-mass gap minus ``bound *
    sqrt(internal energy)`` per rod, or it has stayed out of range for
    ``period`` (the longest free vibration period).
    """
    u1, v1, a1, sync1, bands1, mass_bands1, weights1 = rod1
    u2, v2, a2, sync2, bands2, mass_bands2, weights2 = rod2
    table1, table2 = tables
    column1, column2 = columns
    hist_time, hist_force, hist_vrel, hist_gap = history
    law, alpha, strength, stiffness, offset, r_stop, m_inv = read_contact(contact)
    dt, period, check_every, energy_tolerance = read_run_control(control)
    plastic = control[K_PLASTIC] != 0.0
    kind1 = int(control[K_KIND1])
    kind2 = int(control[K_KIND2])
    max_steps = hist_time.size
    n1 = u1.size
    last = n1 - 1
    c1_start = n1 - column1.size
    mass1 = 0.0
    for i in range(n1):
        mass1 += weights1[i]
    mass2 = 0.0
    for i in range(u2.size):
        mass2 += weights2[i]
    samples = np.int64(0)  # np.int64: a literal argument would compile a callee once more for it alone
    # large consistent masses run in the interleaved layout (interleaved_step.py): U, V below are then the
    # packed copies in their tables, the flat u, v are refreshed for the energy checks and at the end
    rows1 = int(table1[L_SHAPE, 0])
    rows2 = int(table2[L_SHAPE, 0])
    order1 = bands1.shape[0] - 1
    order2 = bands2.shape[0] - 1
    U1, V1 = _layout(u1, v1, table1, rows1, order1)
    U2, V2 = _layout(u2, v2, table2, rows2, order2)
    end1 = node_position(last, rows1, order1) if rows1 else last
    start2 = node_position(np.int64(0), rows2, order2) if rows2 else 0
    where1 = np.empty(column1.size, np.int64)
    for k in range(column1.size):
        where1[k] = node_position(c1_start + k, rows1, order1) if rows1 else c1_start + k
    where2 = np.empty(column2.size, np.int64)
    for k in range(column2.size):
        where2[k] = node_position(k, rows2, order2) if rows2 else k
    fast = kind1 == MASS_LUMPED and kind2 == MASS_LUMPED and bands1.shape[0] == 2 and bands2.shape[0] == 2
    # the force scheme's contact force on a rod in the interleaved layout enters its mass solve's right-hand side
    # (scaled by the end's inverse pivot), which spreads it as M^-1 e_end: no column added over the end's nodes
    loaded1 = rows1 > 0 and end_scheme is None
    loaded2 = rows2 > 0 and end_scheme is None
    scale1 = table1[T_CHAIN_INVERSE, last // order1] if loaded1 else 0.0
    scale2 = table2[T_CHAIN_INVERSE, 0] if loaded2 else 0.0
    status = STATUS_RUNNING
    done = max_steps
    for step in range(max_steps):
        r_now = offset + U2[start2] - U1[end1]
        force = 0.0
        if end_scheme is None:
            force = contact_force(law, r_now, alpha, strength, stiffness)
        # 1. kick with the elastic forces (and the force scheme's contact force on loaded rods) and drift
        if fast:
            _leapfrog_p1(u1, v1, bands1, table1[0], dt)
            _leapfrog_p1(u2, v2, bands2, table2[0], dt)
        else:
            _step(u1, v1, a1, bands1, kind1, table1, rows1, dt, end1 if loaded1 else -1, -force * scale1)
            _step(u2, v2, a2, bands2, kind2, table2, rows2, dt, start2 if loaded2 else -1, force * scale2)
        # 2. contact, spread along M^-1 e_end
        r_free = offset + U2[start2] - U1[end1]
        if end_scheme is None:
            # plain central differences (the force scheme): the force at the start of the step, as a kick
            impulse = force * dt
            shift = impulse * dt
        elif end_scheme == SCHEME_SPLITTING:
            w0 = V2[start2] - V1[end1]
            r1, w1 = pruned_flow(general_law, plastic, r_now, w0, dt, m_inv, alpha, strength, stiffness)
            impulse = (w1 - w0) / m_inv
            shift = (r1 - r_free) / m_inv
        else:
            # massless-end interface: the ends close at their current relative velocity
            w0 = V2[start2] - V1[end1]
            r_after = pruned_gap(general_law, r_now, w0, dt, m_inv * dt, alpha, strength, stiffness)
            shift = (r_after - r_free) / m_inv
            impulse = shift / dt
        if (impulse != 0.0 or shift != 0.0) and not loaded1:
            for k in range(column1.size):
                U1[where1[k]] -= column1[k] * shift
                V1[where1[k]] -= column1[k] * impulse
        if (impulse != 0.0 or shift != 0.0) and not loaded2:
            for k in range(column2.size):
                U2[where2[k]] += column2[k] * shift
                V2[where2[k]] += column2[k] * impulse

        state[S_MOMENTUM1] -= impulse
        state[S_MOMENTUM2] += impulse
        time = state[S_TIME] + dt
        state[S_TIME] = time
        state[S_STEPS] += 1.0
        gap = offset + U2[start2] - U1[end1]
        vrel = state[S_MOMENTUM2] / mass2 - state[S_MOMENTUM1] / mass1
        hist_time[step] = time
        hist_force[step] = impulse / dt
        hist_vrel[step] = vrel
        hist_gap[step] = gap
        if gap <= r_stop or impulse != 0.0:
            state[S_LAST_IN_RANGE] = time
        if not (math.isfinite(gap) and math.isfinite(vrel)):
            state[S_FAILED_ENERGY] = math.nan
            status = STATUS_FAILED
            done = step + 1
            break

        if (step + 1) % check_every == 0:
            _to_flat(u1, v1, table1, rows1, order1, u2, v2, table2, rows2, order2)
            _synchronize(u1, v1, a1, sync1, bands1, kind1, table1, dt)
            _synchronize(u2, v2, a2, sync2, bands2, kind2, table2, dt)
            kin1, str1, cor1 = rod_energies(u1, sync1, a1, bands1, mass_bands1, dt)
            kin2, str2, cor2 = rod_energies(u2, sync2, a2, bands2, mass_bands2, dt)
            pot = contact_potential(law, gap, alpha, strength, stiffness)
            samples, internal1, internal2, within = _energy_check(
                kin1 - cor1, str1, kin2 - cor2, str2, pot, mass1, mass2, time, energy_tolerance, state, samples,
                energies,
            )
            if not within:
                status = STATUS_FAILED
                done = step + 1
                break
            if vrel > 0.0 and gap > r_stop:
                if time - state[S_LAST_IN_RANGE] >= period:
                    status = STATUS_SEPARATED
                    done = step + 1
                    break
                spread = control[K_BOUND1] * math.sqrt(max(internal1, 0.0)) + control[K_BOUND2] * math.sqrt(
                    max(internal2, 0.0)
                )
                centre_gap = offset + _mean_displacement(u2, weights2) - _mean_displacement(u1, weights1)
                if centre_gap - spread > r_stop:
                    status = STATUS_SEPARATED
                    done = step + 1
                    break
    # one exit: the flat arrays refreshed once (after a check they already are; copying again changes nothing)
    _to_flat(u1, v1, table1, rows1, order1, u2, v2, table2, rows2, order2)
    return status, done, samples


@kernel(inline="always")
def _step(u, v, a, bands, kind, table, rows, dt, where, load):
    """One rod's elastic step in its layout (``rows`` > 0: the interleaved one, on the table's copy, with
    ``load`` on its scaled right-hand side at ``where``, an end node's position; -1: none)."""
    if rows == 0:
        step_flat(u, v, a, bands, kind, table, dt)
    elif kind == MASS_CONDENSED:
        step_condensed_loaded(table, dt, where, load)
    else:
        step_tridiagonal_loaded(table, dt, where, load)


@kernel(inline="always")
def _layout(u, v, table, rows, order):
    """The arrays the time loop steps: ``u, v`` themselves, or (``rows`` > 0) their interleaved copies."""
    if rows == 0:
        return u, v
    pack_nodes(u, table[L_U], rows, order)
    pack_nodes(v, table[L_V], rows, order)
    return table[L_U], table[L_V]


@kernel(inline="always")
def _to_flat(u1, v1, table1, rows1, order1, u2, v2, table2, rows2, order2):
    """Copy the interleaved state of the rods that run in that layout back to their flat arrays."""
    if rows1:
        unpack_nodes(table1[L_U], u1, rows1, order1)
        unpack_nodes(table1[L_V], v1, rows1, order1)
    if rows2:
        unpack_nodes(table2[L_U], u2, rows2, order2)
        unpack_nodes(table2[L_V], v2, rows2, order2)
