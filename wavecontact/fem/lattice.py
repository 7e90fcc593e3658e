"""The exact lattice: P1 lumped rods at Courant number 1 carried as d'Alembert's two waves.

On a uniform P1 lumped mesh stepped at the element travel time ``dt = h/c``
the interior update ``u_i^{n+1} = u_{i-1}^n + u_{i+1}^n - u_i^{n-1}`` has the
exact general solution ``u_i^n = F[i + n] + G[i - n]``: ``F`` moves left,
``G`` right, both integer-indexed.  Each rod is held as ``F`` and ``G`` in
two circular buffers (``mask + 1`` entries, a power of two), so a step only
writes the two entries that enter the rod at its ends: O(1) work per step.

Ends (docs/fem.md section 4):

* the **contact end** (last node of rod 1, node 0 of rod 2) is a half-mass
  node stepped by the general central difference plus the contact shift;
* the **far end** is a free end at ``theta`` elements beyond the last node
  (``0 <= theta < 1``: the unmeshed remainder of a matched mesh).  A free end
  reflects ``f(L + s) = g(L - s) + const``; on the lattice that is the
  recursion ``F[m] = F[m - 1] + g(2L - m) - g(2L - m + 1)`` (at node 0:
  ``G[k] = G[k + 1] + f(-2 theta - k) - f(-2 theta - k - 1)``), with ``g``,
  ``f`` between integer indices interpolated linearly.  For ``theta = 0`` it
  is the half-mass mirror ``u_N^{n+1} = 2 u_{N-1}^n - u_N^{n-1}``; otherwise
  the echo returns ``2 theta`` steps later, exactly as from the true end.
  Linear interpolation is exact for waves whose displacement is linear
  between lattice points (every front made on the lattice, e.g. a hard
  impact's) and second order for smooth waves.

The state of one rod is the tuple ``(f, g, contact)`` of arrays plus the
shared level ``n`` (``state[S_LEVEL]``); it persists between calls, because
the part of a wave inside the unmeshed remainder is not in the node values.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel
from .contact_flows import (
    LAW_EXPONENTIAL,
    contact_potential,
    exponential_gap_linear,
    exponential_gap_quartic,
    pruned_gap,
)
from .kernels import (
    STATUS_FAILED,
    STATUS_RUNNING,
    STATUS_SEPARATED,
    _energy_check,
    _mean_displacement,
)
from .layout import (
    C_COMPLIANCE,
    K_CENTERED,
    K_GAUSS,
    K_SUBSTEPS,
    R_BOUND,
    R_CONTACT_COEFFICIENT,
    R_CONTACT_INVERSE_MASS,
    R_FAR_THETA,
    R_MASK,
    S_FAILED_ENERGY,
    S_INCOMING,
    S_INCOMING_EARLIER,
    S_LAST_IN_RANGE,
    S_LEVEL,
    S_MOMENTUM1,
    S_MOMENTUM2,
    S_STEPS,
    S_TIME,
    read_contact,
    read_run_control,
)

__all__ = [
    "advance_lattice",
    "buffer_mask",
    "far_end_weights",
    "split_rod",
]

# relative tolerance for "the incoming rate is constant" in the one-jump reconstruction
_JUMP_FLAT = 1e-6


def buffer_mask(n_nodes: int) -> int:
    """``mask`` of circular buffers of ``mask + 1`` (a power of two) >= ``n_nodes + 8`` entries.

    A step reads ``F[n - 3 .. N + n + 1]`` and ``G[-(n + 1) .. N - n + 3]``.
    """
    size = 8
    while size < n_nodes + 8:
        size *= 2
    return size - 1


@kernel(fastmath=False, internal=True)
def far_end_weights(theta):
    """``(shift, weight)`` of the interpolation ``x -> (1 - weight) B[k + shift] + weight B[k + shift + 1]``.

    For the far end at node ``N`` (rod 2) the reflected entry needs ``g`` at
    ``N - n - 1 + 2 theta``: ``shift = floor(2 theta - 1)``, ``weight`` its
    fractional part.  Rod 1's far end (node 0) needs ``f`` at ``n + 1 - 2
    theta``: the same numbers with ``1 - 2 theta``.  Returned for ``2 theta - 1``;
    the kernel mirrors them for node 0.
    """
    s = 2.0 * theta - 1.0
    shift = math.floor(s)
    return shift, s - shift


@kernel(fastmath=False)
def split_rod(current, previous, f, g, mask):
    """Write two time levels of one rod as ``u_i^n = F[i + n] + G[i - n]`` (``n = 0``: ``current``).

    Level 0 fixes ``F[i] + G[i]``, level -1 fixes ``F[i - 1] + G[i + 1]``; the
    recursions from ``F[-1] = F[0] = 0`` give ``F[-1..N]`` and ``G[0..N+1]``.
    The two checkerboard sub-lattices (``i + n`` even, odd) are independent,
    so a constant may be added to ``F`` and taken from ``G`` on the odd
    entries without changing any node: it is chosen so that ``F`` is smooth
    across the two (exact for a rigid motion and any linear wave), which the
    interpolation at a far end with a remainder needs.  ``F[-2]`` and
    ``G[N+2]`` (waves inside an unmeshed remainder) are extrapolated linearly.
    """
    last = current.size - 1
    f[-1 & mask] = 0.0
    f[0] = 0.0
    g[0] = current[0]
    g[1] = previous[0]
    for i in range(1, last + 1):
        f[i & mask] = current[i] - g[i & mask]
        g[(i + 1) & mask] = previous[i] - f[(i - 1) & mask]
    offset = 0.0
    count = 0
    for i in range(1, last, 2):
        offset += 0.5 * (f[(i - 1) & mask] + f[(i + 1) & mask]) - f[i & mask]
        count += 1
    if count > 0:
        offset /= count
    for i in range(-1, last + 1, 2):
        f[i & mask] += offset
    for i in range(1, last + 2, 2):
        g[i & mask] -= offset
    for k in (-2, -3):
        f[k & mask] = 2.0 * f[(k + 1) & mask] - f[(k + 2) & mask]
    for k in (last + 2, last + 3):
        g[k & mask] = 2.0 * g[(k - 1) & mask] - g[(k - 2) & mask]


@kernel(fastmath=False, internal=True)
def _node(f, g, mask, n, i):
    return f[(i + n) & mask] + g[(i - n) & mask]


@kernel(fastmath=False, internal=True)
def _rebuild(f, g, mask, n, contact, contact_node, current, previous):
    """Both time levels ``n`` and ``n - 1`` of one rod from its waves (O(N)).

    The contact end node is taken from ``contact`` = (now, before), as the
    lattice computed it.
    """
    for i in range(current.size):
        current[i] = f[(i + n) & mask] + g[(i - n) & mask]
        previous[i] = f[(i + n - 1) & mask] + g[(i - n + 1) & mask]
    current[contact_node] = contact[0]
    previous[contact_node] = contact[1]


@kernel(fastmath=False, internal=True)
def _eno(left, a, b, right, weight):
    """Value at ``weight`` in ``[0, 1]`` between samples ``a`` and ``b`` (neighbours ``left``, ``right``).

    Quadratic through the smoother of the stencils (left, a, b) and (a, b,
    right) (essentially non-oscillatory): exact where the samples are linear
    on either side of a kink at ``a`` or ``b`` (a front made on the lattice),
    third-order accurate for a smooth wave.
    """
    first = left - 2.0 * a + b
    second = a - 2.0 * b + right
    curvature = first if abs(first) <= abs(second) else second
    return a + weight * (b - a) + 0.5 * weight * (weight - 1.0) * curvature


@kernel(fastmath=False, internal=True)
def _reflect_at_last(f, g, mask, n, last, shift, weight):
    """New entry ``F[N + n + 1]`` of a free end ``theta`` beyond node ``N`` (``shift``, ``weight``: see above)."""
    base = last - n + shift
    g_1 = g[(base - 1) & mask]
    g0 = g[base & mask]
    g1 = g[(base + 1) & mask]
    g2 = g[(base + 2) & mask]
    g3 = g[(base + 3) & mask]
    arriving = _eno(g_1, g0, g1, g2, weight)  # g(N - n - 1 + 2 theta)
    before = _eno(g0, g1, g2, g3, weight)  # g(N - n + 2 theta)
    f[(last + n + 1) & mask] = f[(last + n) & mask] + arriving - before


@kernel(fastmath=False, internal=True)
def _reflect_at_first(f, g, mask, n, shift, weight):
    """New entry ``G[-(n + 1)]`` of a free end ``theta`` before node 0 (mirror image of the above)."""
    base = n - shift - 2  # f(n + 1 - 2 theta) lies between F[base + 2] and F[base + 1], weight from the former
    f_1 = f[(base - 1) & mask]
    f0 = f[base & mask]
    f1 = f[(base + 1) & mask]
    f2 = f[(base + 2) & mask]
    f3 = f[(base + 3) & mask]
    arriving = _eno(f3, f2, f1, f0, weight)  # f(n + 1 - 2 theta)
    before = _eno(f2, f1, f0, f_1, weight)  # f(n - 2 theta)
    g[(-n - 1) & mask] = g[(-n) & mask] + arriving - before


@kernel(fastmath=False)
def remainder_momentum(f, g, mask, n, theta, last, impedance):
    """Momentum (mass * length/time) of the unmeshed remainder beyond a far end node.

    The waves inside it are the ones that left the last node during the
    past ``2 theta`` steps (and will come back): with ``u = f(x + ct) +
    g(x - ct)`` and the free end's reflection, ``rho A int u_t dx`` over the
    remainder is ``Z [g(N - n) - g(N - n + 2 theta)]`` at node ``N`` and
    ``Z [f(n) - f(n - 2 theta)]`` at node 0 (``Z = rho c A``).  ``last``: the
    far node (``N``, or 0 for a rod whose far end is its first node).
    """
    if theta == 0.0:
        return 0.0
    shift, weight = far_end_weights(theta)
    if last > 0:
        base = last - n + shift + 1  # g(N - n + 2 theta) lies between G[base] and G[base + 1]
        return impedance * (g[(last - n) & mask] - _eno(g[(base - 1) & mask], g[base & mask], g[(base + 1) & mask],
                                                      g[(base + 2) & mask], weight))
    base = n - shift - 2  # f(n - 2 theta) between F[base + 1] and F[base], weight from the former
    return impedance * (f[n & mask] - _eno(f[(base + 2) & mask], f[(base + 1) & mask], f[base & mask],
                                           f[(base - 1) & mask], weight))


@kernel(fastmath=False, internal=True)
def _contact_end_value(contact, neighbour, coefficient):
    """General central difference of a contact end node: ``2 u - u_old - coefficient (u_nb - u)``."""
    return 2.0 * contact[0] - contact[1] - coefficient * (neighbour - contact[0])


@kernel(fastmath=False, internal=True)
def _one_jump_gap(general_law, r, rates, dt, compliance, alpha, strength, stiffness):
    """Gap after a step whose incoming rate jumps once, or NaN if the step means do not show one jump.

    A front that reaches the contact between lattice times (an echo from a
    far end with a remainder) makes the step mean a blend of the rates
    before and after it.  If the two steps before share one rate ``q_b``,
    the two after share ``q_a``, and this step's mean lies strictly between,
    the rate is ``q_b`` for the fraction ``(mean - q_a)/(q_b - q_a)`` of the
    step and ``q_a`` after; the gap equation is solved exactly on each part
    (a release inside the step then gives the exact impulse).  ``general_law``: as in
    :func:`~wavecontact.fem.contact_flows.pruned_gap`.
    """
    before = rates[1]
    after = rates[3]
    mean = rates[2]
    scale = abs(before) + abs(after)
    flat = _JUMP_FLAT * scale
    if abs(rates[0] - before) > flat or abs(rates[4] - after) > flat or abs(after - before) <= 1e3 * flat:
        return math.nan
    fraction = (mean - after) / (before - after)
    if not (1e-12 < fraction < 1.0 - 1e-12):
        return math.nan
    middle = pruned_gap(general_law, r, before, fraction * dt, compliance, alpha, strength, stiffness)
    return pruned_gap(general_law, middle, after, (1.0 - fraction) * dt, compliance, alpha, strength, stiffness)


@kernel(fastmath=False, internal=True)
def _later_rate(f1, g1, mask1, last1, f2, g2, mask2, n, j, dt):
    """Mean incoming closing rate over ``[t + (j - 2) dt, t + j dt]`` read at node ``j`` from the contact."""
    later2 = (f2[(j + n) & mask2] + g2[(j - n) & mask2]) - (f2[(j - 1 + n - 1) & mask2] + g2[(j - 1 - n + 1) & mask2])
    later1 = (f1[(last1 - j + n) & mask1] + g1[(last1 - j - n) & mask1]) - (
        f1[(last1 - j + 1 + n - 1) & mask1] + g1[(last1 - j + 1 - n + 1) & mask1]
    )
    return (later2 - later1) / dt


@kernel
def advance_lattice(rod1, rod2, parameters1, parameters2, waves1, waves2, contact, control, state, history, energies,
                    general_law):
    """Run up to ``history[0].size`` steps of the characteristic scheme on the exact lattice.

    Parameters
    ----------
    rod1, rod2 : tuple of arrays
        ``(u, w, weights, bands)``: displacements now and one step earlier
        (length; written on return), nodal masses (mass; the far node
        includes the remainder) and the stiffness bands (force/length).
    parameters1, parameters2 : ndarray
        ``R_*`` entries of each rod.
    waves1, waves2 : tuple of arrays
        ``(f, g, contact)``: the rod's waves (length) and its contact end
        node (now, before); made by :func:`split_rod` once per run and
        carried from call to call.
    contact, control : ndarray
        ``C_*`` and ``K_*`` entries.
    state : ndarray
        ``S_*`` entries (time, momenta, level, run control), carried between calls.
    history : tuple of 4 arrays
        Per step: time, mean contact force over the step, relative velocity
        of the centres of mass, gap.  Their size is the number of steps asked.
    energies : tuple of 6 arrays
        Per check: time, kinetic, strain, contact energy, internal energy of each rod.
    general_law : None or np.int64
        None for the exponential law (the law of ``contact``; its gap equation is then solved
        directly and numba compiles no other law's), else the law's code (the gap equation of
        :func:`~wavecontact.fem.contact_flows.interface_gap`).

    Returns
    -------
    status, steps_done, energy_samples
    """
    u1, w1, weights1, bands1 = rod1
    u2, w2, weights2, bands2 = rod2
    f1, g1, contact1 = waves1
    f2, g2, contact2 = waves2
    hist_time, hist_force, hist_vrel, hist_gap = history
    max_steps = hist_time.size
    last1 = u1.size - 1
    last2 = u2.size - 1
    mask1 = int(parameters1[R_MASK])
    mask2 = int(parameters2[R_MASK])
    shift1, weight1 = far_end_weights(parameters1[R_FAR_THETA])
    shift2, weight2 = far_end_weights(parameters2[R_FAR_THETA])
    mirror1 = parameters1[R_FAR_THETA] == 0.0  # the far end on the last node: the half-mass mirror
    mirror2 = parameters2[R_FAR_THETA] == 0.0
    coefficient1 = parameters1[R_CONTACT_COEFFICIENT]
    coefficient2 = parameters2[R_CONTACT_COEFFICIENT]
    law, alpha, strength, stiffness, offset, r_stop, m_inv = read_contact(contact)
    compliance = contact[C_COMPLIANCE]
    dt, period, check_every, energy_tolerance = read_run_control(control)
    substeps = int(control[K_SUBSTEPS])
    centered = control[K_CENTERED] != 0.0
    gauss = control[K_GAUSS] != 0.0
    mass1 = 0.0
    for i in range(u1.size):
        mass1 += weights1[i]
    mass2 = 0.0
    for i in range(u2.size):
        mass2 += weights2[i]
    samples = np.int64(0)  # np.int64: a literal argument would compile a callee once more for it alone
    rates = np.zeros(5)
    status = STATUS_RUNNING
    done = max_steps
    n = int(state[S_LEVEL])
    for step in range(max_steps):
        r_now = offset + contact2[0] - contact1[0]
        # incoming characteristics: mean rate over [t - dt, t + dt], then the single step ahead
        arriving2 = _node(f2, g2, mask2, n, np.int64(1)) - contact2[1]
        arriving1 = _node(f1, g1, mask1, n, last1 - 1) - contact1[1]
        incoming = 2.0 * (arriving2 - arriving1) / dt - state[S_INCOMING]
        rates[0] = state[S_INCOMING_EARLIER]
        rates[1] = state[S_INCOMING]
        rates[2] = incoming
        if centered:
            # the interior carries the incoming waves of the next two steps too
            for j in (2, 3):
                rates[j + 1] = 2.0 * _later_rate(f1, g1, mask1, last1, f2, g2, mask2, n, j, dt) - rates[j]
        varies = False
        if substeps > 1:
            if centered:
                variation = max(abs(rates[0] - incoming), abs(rates[1] - incoming), abs(rates[3] - incoming),
                                abs(rates[4] - incoming))
            else:
                variation = abs(incoming - state[S_INCOMING])
            varies = law == LAW_EXPONENTIAL and variation > (1e-13 if gauss else 1e-7) * abs(incoming)
        state[S_INCOMING_EARLIER] = state[S_INCOMING]
        state[S_INCOMING] = incoming
        end1 = _contact_end_value(contact1, _node(f1, g1, mask1, n, last1 - 1), coefficient1)
        start2 = _contact_end_value(contact2, _node(f2, g2, mask2, n, np.int64(1)), coefficient2)
        r_free = offset + start2 - end1
        if varies:
            # far apart the force cannot move the gap by a round-off amount within the step
            closest = min(r_now, r_free)
            if alpha * closest > 40.0 and alpha * strength * math.exp(-alpha * closest) * m_inv * dt * dt < 1e-17 * closest:
                varies = False
        r_after = math.nan
        if varies:
            # the incoming rate varies within the step: reconstruct it and sub-step the gap equation
            if centered:
                r_after = exponential_gap_quartic(r_now, rates, dt, compliance, alpha, strength, 0 if gauss else substeps)
            else:
                slope = (incoming - rates[1]) / dt
                r_after = exponential_gap_linear(r_now, incoming, slope, dt, compliance, alpha, strength, substeps)
        elif centered:
            r_after = _one_jump_gap(general_law, r_now, rates, dt, compliance, alpha, strength, stiffness)
        if math.isnan(r_after):
            r_after = pruned_gap(general_law, r_now, incoming, dt, compliance, alpha, strength, stiffness)
        shift = (r_after - r_free) / m_inv
        impulse = shift / dt
        if shift != 0.0:
            end1 -= parameters1[R_CONTACT_INVERSE_MASS] * shift
            start2 += parameters2[R_CONTACT_INVERSE_MASS] * shift
        # the waves entering each rod: at the contact end from the new end value, at the far end by reflection
        f1[(last1 + n + 1) & mask1] = end1 - g1[(last1 - n - 1) & mask1]
        if mirror1:
            far = 2.0 * _node(f1, g1, mask1, n, np.int64(1)) - _node(f1, g1, mask1, n - 1, np.int64(0))
            g1[(-n - 1) & mask1] = far - f1[(n + 1) & mask1]
        else:
            _reflect_at_first(f1, g1, mask1, n, shift1, weight1)
        g2[(-n - 1) & mask2] = start2 - f2[(n + 1) & mask2]
        if mirror2:
            far = 2.0 * _node(f2, g2, mask2, n, last2 - 1) - _node(f2, g2, mask2, n - 1, last2)
            f2[(last2 + n + 1) & mask2] = far - g2[(last2 - n - 1) & mask2]
        else:
            _reflect_at_last(f2, g2, mask2, n, last2, shift2, weight2)
        contact1[1] = contact1[0]
        contact1[0] = end1
        contact2[1] = contact2[0]
        contact2[0] = start2
        n += 1
        state[S_LEVEL] = n

        state[S_MOMENTUM1] -= impulse
        state[S_MOMENTUM2] += impulse
        time = state[S_TIME] + dt
        state[S_TIME] = time
        state[S_STEPS] += 1.0
        gap = offset + contact2[0] - contact1[0]
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
            _rebuild(f1, g1, mask1, n, contact1, last1, u1, w1)
            _rebuild(f2, g2, mask2, n, contact2, np.int64(0), u2, w2)
            kin1, str1 = _staggered_energies(u1, w1, bands1, weights1, dt)
            kin2, str2 = _staggered_energies(u2, w2, bands2, weights2, dt)
            pot = contact_potential(law, gap, alpha, strength, stiffness)
            samples, internal1, internal2, within = _energy_check(
                kin1, str1, kin2, str2, pot, mass1, mass2, time, energy_tolerance, state, samples, energies,
            )
            if not within:
                status = STATUS_FAILED
                done = step + 1
                break
            if vrel > 0.0 and gap > r_stop:
                finished = time - state[S_LAST_IN_RANGE] >= period
                if not finished:
                    spread = parameters1[R_BOUND] * math.sqrt(max(internal1, 0.0)) + parameters2[R_BOUND] * math.sqrt(
                        max(internal2, 0.0)
                    )
                    centre_gap = offset + _mean_displacement(u2, weights2) - _mean_displacement(u1, weights1)
                    finished = centre_gap - spread > r_stop
                if finished:
                    status = STATUS_SEPARATED
                    done = step + 1
                    break
    _rebuild(f1, g1, mask1, n, contact1, last1, u1, w1)
    _rebuild(f2, g2, mask2, n, contact2, np.int64(0), u2, w2)
    return status, done, samples


@kernel(internal=True)
def _staggered_energies(current, previous, bands, masses, dt):
    """Kinetic energy of ``(current - previous)/dt`` and strain ``u_prev K u_cur / 2`` (P1).

    Their sum is the energy central differences conserve exactly for free rods
    (the part of a rod inside an unmeshed remainder is not counted).
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
