"""Time loop of two rods in contact: plain-array numba kernels.

One step of central differences in leapfrog form (``v`` lives at half steps):

1. kick with the elastic forces ``v += dt M^-1 (-K u)`` and drift ``u += dt v``
   (one sweep over the nodes for P1 lumped);
2. contact, along the columns ``M^-1 e_end`` so that momentum is exchanged
   exactly: either the force of the gap at the start of the step as a kick
   (``SCHEME_FORCE``: plain central differences, where the contact is
   resolved) or the facing end nodes moved to the gap the contact law gives
   after the step (:mod:`.contact_flows`: interface schemes).

Elastic forces are evaluated as ``-sum_j K_ij (u_j - u_i)`` (rows of ``K``
sum to zero), so a rigid translation produces no force at all.

The exact lattice (P1 lumped, uniform interior, Courant number 1) has its own
loop, :func:`advance_lattice`: each rod is carried as d'Alembert's two waves
in circular buffers, so a step costs O(1) (end nodes and contact) and the
fields are rebuilt, O(N), only for the periodic checks and on return.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel
from .contact_flows import (
    LAW_EXPONENTIAL,
    contact_flow,
    contact_force,
    contact_potential,
    exponential_gap_linear,
    exponential_gap_quartic,
    interface_gap,
)

__all__ = [
    "STATUS_FAILED",
    "STATUS_RUNNING",
    "STATUS_SEPARATED",
    "advance",
    "elastic_acceleration",
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

# indices into the float state vector of `advance`
S_TIME = 0
S_MOMENTUM1 = 1
S_MOMENTUM2 = 2
S_LAST_IN_RANGE = 3
S_STEPS = 4
S_ENERGY0 = 5
S_MAX_DRIFT = 6
S_FAILED_ENERGY = 7
S_ENERGY_SCALE = 8
S_PREVIOUS_END1 = 9
S_PREVIOUS_END2 = 10
S_INCOMING = 11
S_INCOMING_EARLIER = 12  # incoming rate one step before S_INCOMING
STATE_SIZE = 13


@kernel(fastmath=False)
def _forces_p1(u, bands, out):
    """``out = -K u`` for a tridiagonal ``K`` (P1)."""
    n = u.size
    if n == 1:
        out[0] = 0.0
        return
    out[0] = -bands[1, 0] * (u[1] - u[0])
    for i in range(1, n - 1):
        out[i] = -bands[1, i - 1] * (u[i - 1] - u[i]) - bands[1, i] * (u[i + 1] - u[i])
    out[n - 1] = -bands[1, n - 2] * (u[n - 2] - u[n - 1])


@kernel
def _forces_banded(u, bands, out):
    """``out = -K u`` for a banded symmetric ``K`` (upper bands)."""
    width = bands.shape[0] - 1
    n = u.size
    for i in range(n):
        total = 0.0
        for d in range(1, width + 1):
            if i + d < n:
                total -= bands[d, i] * (u[i + d] - u[i])
            if i - d >= 0:
                total -= bands[d, i - d] * (u[i - d] - u[i])
        out[i] = total


@kernel
def _cholesky_solve(lower, x):
    """Solve ``L L^T x = b`` in place (``lower[d, j] = L[j + d, j]``)."""
    width = lower.shape[0] - 1
    n = x.size
    for i in range(n):
        value = x[i]
        for d in range(1, width + 1):
            if i - d >= 0:
                value -= lower[d, i - d] * x[i - d]
        x[i] = value / lower[0, i]
    for i in range(n - 1, -1, -1):
        value = x[i]
        for d in range(1, width + 1):
            if i + d < n:
                value -= lower[d, i] * x[i + d]
        x[i] = value / lower[0, i]


@kernel
def elastic_acceleration(u, bands, inverse_mass, cholesky, lumped, out):
    """``out = M^-1 (-K u)`` (acceleration, length/time^2)."""
    if bands.shape[0] == 2:
        _forces_p1(u, bands, out)
    else:
        _forces_banded(u, bands, out)
    if lumped:
        for i in range(u.size):
            out[i] *= inverse_mass[i]
    else:
        _cholesky_solve(cholesky, out)


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


@kernel
def _mean_displacement(u, weights):
    total = 0.0
    mass = 0.0
    for i in range(u.size):
        total += weights[i] * u[i]
        mass += weights[i]
    return total / mass


@kernel(fastmath=False)
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


@kernel
def _leapfrog_general(u, v, a, bands, inverse_mass, cholesky, lumped, dt):
    elastic_acceleration(u, bands, inverse_mass, cholesky, lumped, a)
    for i in range(u.size):
        velocity = v[i] + dt * a[i]
        v[i] = velocity
        u[i] += dt * velocity


@kernel
def _synchronize(u, v, a, sync, bands, inverse_mass, cholesky, lumped, dt):
    """Velocity at the time of ``u`` from the half-step velocity ``v``: ``v + dt/2 a(u)``."""
    elastic_acceleration(u, bands, inverse_mass, cholesky, lumped, a)
    for i in range(u.size):
        sync[i] = v[i] + 0.5 * dt * a[i]


@kernel
def _energy_check(
    kinetic1, strain1, kinetic2, strain2, potential, mass1, mass2, time, energy_tolerance, state, samples,
    energy_time, energy_kinetic, energy_strain, energy_contact, energy_internal1, energy_internal2,
):
    """Record one energy sample and watch the balance (the periodic check of both time loops).

    Returns ``(samples, internal1, internal2, within)``: the updated sample
    count, each rod's internal energy (total minus its translation), and
    False when the relative drift of the total is not finite or exceeds
    ``energy_tolerance`` (then ``state[S_FAILED_ENERGY]`` holds the total).
    """
    total = kinetic1 + strain1 + kinetic2 + strain2 + potential
    internal1 = kinetic1 + strain1 - 0.5 * state[S_MOMENTUM1] ** 2 / mass1
    internal2 = kinetic2 + strain2 - 0.5 * state[S_MOMENTUM2] ** 2 / mass2
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
def advance(
    u1, v1, a1, u2, v2, a2, sync1, sync2,
    bands1, bands2, inverse_mass1, inverse_mass2, cholesky1, cholesky2, lumped,
    mass_bands1, mass_bands2, weights1, weights2,
    column1, column2, m_inv, scheme,
    offset, law, alpha, strength, stiffness,
    dt, max_steps, r_stop, period, check_every, bound_factor1, bound_factor2,
    energy_tolerance, state,
    hist_time, hist_force, hist_vrel, hist_gap,
    energy_time, energy_kinetic, energy_strain, energy_contact, energy_internal1, energy_internal2,
):
    """Run up to ``max_steps`` steps; return ``(status, steps_done, energy_samples)``.

    On entry and exit ``u`` holds displacements at the current time and ``v``
    the velocities half a step earlier (leapfrog); ``a`` and ``sync`` are
    scratch arrays.  ``column1`` holds ``M1^-1 e_last`` for the last
    ``column1.size`` nodes of rod 1, ``column2`` holds ``M2^-1 e_0`` for the
    first nodes of rod 2.  The gap is ``offset + u2[0] - u1[-1]``.  ``state``
    (see ``S_*``) carries time, centre-of-mass momenta and run control between
    calls.  Histories get one entry per step (force = mean contact force over
    the step); energies one entry per ``check_every`` steps.  The run stops
    (status 1) once the rods are apart and provably stay apart: the end gap is
    bounded below by the centre-of-mass gap minus ``bound_factor *
    sqrt(internal energy)`` per rod, or it has stayed out of range for
    ``period`` (the longest free vibration period).
    """
    n1 = u1.size
    last = n1 - 1
    c1_start = n1 - column1.size
    mass1 = 0.0
    for i in range(n1):
        mass1 += weights1[i]
    mass2 = 0.0
    for i in range(u2.size):
        mass2 += weights2[i]
    samples = 0
    fast = lumped and bands1.shape[0] == 2 and bands2.shape[0] == 2
    for step in range(max_steps):
        r_now = offset + u2[0] - u1[last]
        if scheme == SCHEME_CHARACTERISTIC:
            # Incoming characteristics: the lattice gives their mean rate over [t - dt, t + dt];
            # the rate over [t, t + dt] follows by subtracting the one over [t - dt, t].
            end1 = state[S_PREVIOUS_END1]
            end2 = state[S_PREVIOUS_END2]
            mean_rate = ((u2[1] - end2) - (u1[last - 1] - end1)) / dt
            incoming = 2.0 * mean_rate - state[S_INCOMING]
            state[S_INCOMING] = incoming
            state[S_PREVIOUS_END1] = u1[last]
            state[S_PREVIOUS_END2] = u2[0]
        # 1. kick with the elastic forces and drift (central differences)
        if fast:
            _leapfrog_p1(u1, v1, bands1, inverse_mass1, dt)
            _leapfrog_p1(u2, v2, bands2, inverse_mass2, dt)
        else:
            _leapfrog_general(u1, v1, a1, bands1, inverse_mass1, cholesky1, lumped, dt)
            _leapfrog_general(u2, v2, a2, bands2, inverse_mass2, cholesky2, lumped, dt)
        # 2. contact: move the facing ends to the gap the contact law gives, spread along M^-1 e_end
        r_free = offset + u2[0] - u1[last]
        if scheme == SCHEME_CHARACTERISTIC:
            r_after = interface_gap(law, r_now, incoming, dt, 0.5 * m_inv * dt, alpha, strength, stiffness)
            shift = (r_after - r_free) / m_inv
            impulse = shift / dt
        elif scheme == SCHEME_FORCE:
            # plain central differences: the force at the start of the step, as a kick
            impulse = contact_force(law, r_now, alpha, strength, stiffness) * dt
            shift = impulse * dt
        elif scheme == SCHEME_INTERFACE:
            # massless-end approximation: the ends close at their current relative velocity
            w0 = v2[0] - v1[last]
            r_after = interface_gap(law, r_now, w0, dt, m_inv * dt, alpha, strength, stiffness)
            shift = (r_after - r_free) / m_inv
            impulse = shift / dt
        else:
            w0 = v2[0] - v1[last]
            r1, w1 = contact_flow(law, r_now, w0, dt, m_inv, alpha, strength, stiffness)
            impulse = (w1 - w0) / m_inv
            shift = (r1 - r_free) / m_inv
        if impulse != 0.0 or shift != 0.0:
            for k in range(column1.size):
                u1[c1_start + k] -= column1[k] * shift
                v1[c1_start + k] -= column1[k] * impulse
            for k in range(column2.size):
                u2[k] += column2[k] * shift
                v2[k] += column2[k] * impulse

        state[S_MOMENTUM1] -= impulse
        state[S_MOMENTUM2] += impulse
        time = state[S_TIME] + dt
        state[S_TIME] = time
        state[S_STEPS] += 1.0
        gap = offset + u2[0] - u1[last]
        vrel = state[S_MOMENTUM2] / mass2 - state[S_MOMENTUM1] / mass1
        hist_time[step] = time
        hist_force[step] = impulse / dt
        hist_vrel[step] = vrel
        hist_gap[step] = gap
        if gap <= r_stop or impulse != 0.0:
            state[S_LAST_IN_RANGE] = time
        if not (math.isfinite(gap) and math.isfinite(vrel)):
            state[S_FAILED_ENERGY] = math.nan
            return 2, step + 1, samples

        if (step + 1) % check_every == 0:
            _synchronize(u1, v1, a1, sync1, bands1, inverse_mass1, cholesky1, lumped, dt)
            _synchronize(u2, v2, a2, sync2, bands2, inverse_mass2, cholesky2, lumped, dt)
            kin1, str1, cor1 = rod_energies(u1, sync1, a1, bands1, mass_bands1, dt)
            kin2, str2, cor2 = rod_energies(u2, sync2, a2, bands2, mass_bands2, dt)
            pot = contact_potential(law, gap, alpha, strength, stiffness)
            samples, internal1, internal2, within = _energy_check(
                kin1 - cor1, str1, kin2 - cor2, str2, pot, mass1, mass2, time, energy_tolerance, state, samples,
                energy_time, energy_kinetic, energy_strain, energy_contact, energy_internal1, energy_internal2,
            )
            if not within:
                return 2, step + 1, samples
            if vrel > 0.0 and gap > r_stop:
                if time - state[S_LAST_IN_RANGE] >= period:
                    return 1, step + 1, samples
                spread = bound_factor1 * math.sqrt(max(internal1, 0.0)) + bound_factor2 * math.sqrt(
                    max(internal2, 0.0)
                )
                centre_gap = offset + _mean_displacement(u2, weights2) - _mean_displacement(u1, weights1)
                if centre_gap - spread > r_stop:
                    return 1, step + 1, samples
    return 0, max_steps, samples


@kernel
def _lattice_buffer_mask(n_nodes):
    """``mask`` of circular buffers of ``mask + 1`` (a power of two) >= ``n_nodes + 2`` entries."""
    size = 4
    while size < n_nodes + 2:
        size *= 2
    return size - 1


@kernel(fastmath=False)
def _lattice_split(current, previous, right_going, left_going, mask):
    """Write two time levels of one rod as ``u_i^n = F[i + n] + G[i - n]`` (``n = 0``: ``current``).

    ``left_going`` is ``F`` and ``right_going`` is ``G``, both circular
    (index ``k`` lives at ``k & mask``).  Level 0 fixes ``F[i] + G[i]`` and
    level -1 fixes ``F[i - 1] + G[i + 1]``; with the gauge ``F[-1] = F[0] = 0``
    the two recursions below give ``F[-1..N]`` and ``G[0..N+1]`` (``N`` the
    last node).  Both grow at most like the rigid displacement of the rod.
    """
    last = current.size - 1
    left_going[-1 & mask] = 0.0
    left_going[0] = 0.0
    right_going[0] = current[0]
    right_going[1] = previous[0]
    for i in range(1, last + 1):
        left_going[i & mask] = current[i] - right_going[i & mask]
        right_going[(i + 1) & mask] = previous[i] - left_going[(i - 1) & mask]


@kernel(fastmath=False)
def _lattice_fields(right_going, left_going, mask, n, ends, current, previous):
    """Both time levels ``n`` and ``n - 1`` of one rod from ``F`` and ``G`` (O(N)).

    The end nodes are taken from ``ends`` = (first now, first before, last
    now, last before): the lattice keeps them as they were computed.
    """
    last = current.size - 1
    for i in range(1, last):
        current[i] = left_going[(i + n) & mask] + right_going[(i - n) & mask]
        previous[i] = left_going[(i + n - 1) & mask] + right_going[(i - n + 1) & mask]
    current[0] = ends[0]
    previous[0] = ends[1]
    current[last] = ends[2]
    previous[last] = ends[3]


@kernel(fastmath=False)
def _lattice_ends(right_going, left_going, mask, n, last, ends, first_coefficient, last_coefficient):
    """Displacements of the two end nodes at level ``n + 1`` (general central difference).

    ``coefficient = dt^2 M^-1 K_(end, neighbour)``: ``u_new = 2 u - u_old - coefficient
    (u_neighbour - u)``.  The neighbours are interior nodes: ``F + G``.
    """
    second = left_going[(n + 1) & mask] + right_going[(1 - n) & mask]
    before_last = left_going[(last - 1 + n) & mask] + right_going[(last - 1 - n) & mask]
    first = 2.0 * ends[0] - ends[1] - first_coefficient * (second - ends[0])
    final = 2.0 * ends[2] - ends[3] - last_coefficient * (before_last - ends[2])
    return first, final


@kernel(fastmath=False)
def _lattice_enter(right_going, left_going, mask, n, last, ends, first, final):
    """Step one rod from level ``n`` to ``n + 1`` given its new end displacements: O(1).

    The interior at ``n + 1`` is already carried by ``F`` and ``G``; only the
    wave entering at each end is new: ``G[-(n + 1)]`` at node 0 and
    ``F[N + n + 1]`` at node ``N``.
    """
    right_going[(-n - 1) & mask] = first - left_going[(n + 1) & mask]
    left_going[(last + n + 1) & mask] = final - right_going[(last - n - 1) & mask]
    ends[1] = ends[0]
    ends[0] = first
    ends[3] = ends[2]
    ends[2] = final


@kernel
def _staggered_energies(current, previous, bands, masses, dt):
    """Kinetic energy of ``(current - previous)/dt`` and strain ``u_prev K u_cur / 2`` (P1).

    Their sum is the energy central differences conserve exactly for free rods.
    """
    n = current.size
    kinetic = 0.0
    strain = 0.0
    for i in range(n):
        velocity = (current[i] - previous[i]) / dt
        kinetic += 0.5 * masses[i] * velocity * velocity
    for e in range(n - 1):
        strain -= 0.5 * bands[1, e] * (previous[e + 1] - previous[e]) * (current[e + 1] - current[e])
    return kinetic, strain


@kernel
def advance_lattice(
    u1, w1, u2, w2,
    bands1, bands2, inverse_mass1, inverse_mass2, weights1, weights2, m_inv, substeps, centered, gauss,
    offset, law, alpha, strength, stiffness,
    dt, max_steps, r_stop, period, check_every, bound_factor1, bound_factor2,
    energy_tolerance, state,
    hist_time, hist_force, hist_vrel, hist_gap,
    energy_time, energy_kinetic, energy_strain, energy_contact, energy_internal1, energy_internal2,
):
    """The characteristic scheme on the exact lattice (P1 lumped, uniform interior, Courant 1).

    Same contract as :func:`advance`, except that the state is two time levels:
    ``u`` holds displacements at the current time and ``w`` one step earlier.

    Each rod is carried as d'Alembert's exact solution of the interior update
    ``u_i^{n+1} = u_{i-1}^n + u_{i+1}^n - u_i^{n-1}``: ``u_i^n = F[i + n] +
    G[i - n]`` with circular buffers ``F`` (left-going) and ``G``
    (right-going).  A step computes only the two end nodes of each rod
    (general central difference: their masses differ), applies the contact
    shift to the facing ends and stores the one new entry of ``F`` and of
    ``G`` that enters each rod there: O(1) work per step.  The full fields are
    rebuilt (O(N)) only for the energy and separation checks every
    ``check_every`` steps and for the hand-back in ``u``/``w`` on return.
    """
    n1 = u1.size
    n2 = u2.size
    last = n1 - 1
    last2 = n2 - 1
    mass1 = 0.0
    for i in range(n1):
        mass1 += weights1[i]
    mass2 = 0.0
    for i in range(n2):
        mass2 += weights2[i]
    mask1 = _lattice_buffer_mask(n1)
    mask2 = _lattice_buffer_mask(n2)
    f1 = np.empty(mask1 + 1)  # F, G of rod 1
    g1 = np.empty(mask1 + 1)
    f2 = np.empty(mask2 + 1)
    g2 = np.empty(mask2 + 1)
    _lattice_split(u1, w1, g1, f1, mask1)
    _lattice_split(u2, w2, g2, f2, mask2)
    # end nodes (first now, first before, last now, last before), kept as computed
    ends1 = np.array([u1[0], w1[0], u1[last], w1[last]])
    ends2 = np.array([u2[0], w2[0], u2[last2], w2[last2]])
    scale = dt * dt
    first1 = scale * inverse_mass1[0] * bands1[1, 0]
    final1 = scale * inverse_mass1[last] * bands1[1, last - 1]
    first2 = scale * inverse_mass2[0] * bands2[1, 0]
    final2 = scale * inverse_mass2[last2] * bands2[1, last2 - 1]
    samples = 0
    rates = np.zeros(5)
    status = 0
    done = max_steps
    n = 0  # time level of the current displacements, counted from the call
    for step in range(max_steps):
        r_now = offset + ends2[0] - ends1[2]
        # incoming characteristics: mean rate over [t - dt, t + dt], then the single step ahead;
        # u2[1] now - u2[0] before = F2[n + 1] - F2[n - 1], u1[N - 1] now - u1[N] before likewise in G1
        arriving2 = (f2[(n + 1) & mask2] + g2[(1 - n) & mask2]) - ends2[1]
        arriving1 = (f1[(last - 1 + n) & mask1] + g1[(last - 1 - n) & mask1]) - ends1[3]
        mean_rate = (arriving2 - arriving1) / dt
        incoming = 2.0 * mean_rate - state[S_INCOMING]
        varies = False
        if substeps > 1:
            if centered:
                # the interior carries the incoming waves of the next steps too: node j gives the
                # mean over [t + (j - 2) dt, t + j dt]; five step means centred on this step
                rates[0] = state[S_INCOMING_EARLIER]
                rates[1] = state[S_INCOMING]
                rates[2] = incoming
                for j in (2, 3):
                    later2 = (f2[(j + n) & mask2] + g2[(j - n) & mask2]) - (
                        f2[(j - 1 + n - 1) & mask2] + g2[(j - 1 - n + 1) & mask2]
                    )
                    later1 = (f1[(last - j + n) & mask1] + g1[(last - j - n) & mask1]) - (
                        f1[(last - j + 1 + n - 1) & mask1] + g1[(last - j + 1 - n + 1) & mask1]
                    )
                    later = (later2 - later1) / dt
                    rates[j + 1] = 2.0 * later - rates[j]
                variation = max(abs(rates[0] - incoming), abs(rates[1] - incoming), abs(rates[3] - incoming),
                                abs(rates[4] - incoming))
            else:
                variation = abs(incoming - state[S_INCOMING])
            varies = law == LAW_EXPONENTIAL and variation > (1e-13 if gauss else 1e-7) * abs(incoming)
        state[S_INCOMING_EARLIER] = state[S_INCOMING]
        state[S_INCOMING] = incoming
        start1, end1 = _lattice_ends(g1, f1, mask1, n, last, ends1, first1, final1)
        start2, end2 = _lattice_ends(g2, f2, mask2, n, last2, ends2, first2, final2)
        r_free = offset + start2 - end1
        if varies:
            # far apart the force cannot move the gap by a round-off amount within the step, and the
            # reconstruction of the incoming rate (waves still ringing in the rods) buys nothing
            closest = min(r_now, r_free)
            if alpha * closest > 40.0 and alpha * strength * math.exp(-alpha * closest) * m_inv * dt * dt < 1e-17 * closest:
                varies = False
        if varies:
            # the incoming rate varies within the step: reconstruct it and sub-step the gap equation
            if centered:
                r_after = exponential_gap_quartic(
                    r_now, rates, dt, 0.5 * m_inv * dt, alpha, strength, 0 if gauss else substeps
                )
            else:
                slope = (incoming - state[S_INCOMING_EARLIER]) / dt
                r_after = exponential_gap_linear(r_now, incoming, slope, dt, 0.5 * m_inv * dt, alpha, strength, substeps)
        else:
            r_after = interface_gap(law, r_now, incoming, dt, 0.5 * m_inv * dt, alpha, strength, stiffness)
        shift = (r_after - r_free) / m_inv
        impulse = shift / dt
        if shift != 0.0:
            end1 -= inverse_mass1[last] * shift
            start2 += inverse_mass2[0] * shift
        _lattice_enter(g1, f1, mask1, n, last, ends1, start1, end1)
        _lattice_enter(g2, f2, mask2, n, last2, ends2, start2, end2)
        n += 1

        state[S_MOMENTUM1] -= impulse
        state[S_MOMENTUM2] += impulse
        time = state[S_TIME] + dt
        state[S_TIME] = time
        state[S_STEPS] += 1.0
        gap = offset + ends2[0] - ends1[2]
        vrel = state[S_MOMENTUM2] / mass2 - state[S_MOMENTUM1] / mass1
        hist_time[step] = time
        hist_force[step] = impulse / dt
        hist_vrel[step] = vrel
        hist_gap[step] = gap
        if gap <= r_stop or impulse != 0.0:
            state[S_LAST_IN_RANGE] = time
        if not (math.isfinite(gap) and math.isfinite(vrel)):
            state[S_FAILED_ENERGY] = math.nan
            status = 2
            done = step + 1
            break

        if (step + 1) % check_every == 0:
            # the full fields, O(N): into u and w, which are handed back rebuilt on return anyway
            _lattice_fields(g1, f1, mask1, n, ends1, u1, w1)
            _lattice_fields(g2, f2, mask2, n, ends2, u2, w2)
            kin1, str1 = _staggered_energies(u1, w1, bands1, weights1, dt)
            kin2, str2 = _staggered_energies(u2, w2, bands2, weights2, dt)
            pot = contact_potential(law, gap, alpha, strength, stiffness)
            samples, internal1, internal2, within = _energy_check(
                kin1, str1, kin2, str2, pot, mass1, mass2, time, energy_tolerance, state, samples,
                energy_time, energy_kinetic, energy_strain, energy_contact, energy_internal1, energy_internal2,
            )
            if not within:
                status = 2
                done = step + 1
                break
            if vrel > 0.0 and gap > r_stop:
                finished = time - state[S_LAST_IN_RANGE] >= period
                if not finished:
                    spread = bound_factor1 * math.sqrt(max(internal1, 0.0)) + bound_factor2 * math.sqrt(
                        max(internal2, 0.0)
                    )
                    centre_gap = offset + _mean_displacement(u2, weights2) - _mean_displacement(u1, weights1)
                    finished = centre_gap - spread > r_stop
                if finished:
                    status = 1
                    done = step + 1
                    break
    # hand the current time level back in u, the previous one in w
    _lattice_fields(g1, f1, mask1, n, ends1, u1, w1)
    _lattice_fields(g2, f2, mask2, n, ends2, u2, w2)
    return status, done, samples
