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
loop, :func:`wavecontact.fem.lattice.advance_lattice`.
"""

from __future__ import annotations

import math

from .._jit import kernel
from .contact_flows import (
    contact_flow,
    contact_force,
    contact_potential,
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
S_LEVEL = 13  # time level of the exact lattice's waves, counted from the start of the run
STATE_SIZE = 14


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
