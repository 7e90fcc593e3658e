"""Exponential collocation integrator for one contact pair (single collisions).

Between two rods touching at one pair of ends the only coupling is the scalar
contact force ``F(t)``.  Over a step of length ``h`` this integrator replaces
``F`` by the polynomial of degree ``s - 1`` through its values at the
Radau IIA nodes ``theta_1 h, ..., theta_s h`` (``theta_s = 1``) and integrates
every oscillator and both centres of mass *exactly* against that polynomial
(the integrals are ``phi`` functions of ``i omega h``, tabulated per step size).
The gap at the nodes is then an affine function of the ``s`` node forces, so
a step is an ``s``-dimensional implicit equation ``F_i = F(r_i(F))`` solved by
Newton, whatever the number of modes.  One step costs two passes over the
modes; the order is up to ``2 s - 1`` for smooth forces, and no step limit
comes from the highest mode (no kicks, hence no impulse resonance).

The step size is adapted from the difference between the node forces and the
previous step's polynomial extrapolated to the same times (an ``O(h^s)``
estimate), rounded down to a geometric ladder of sizes whose tables are filled
the first time they are used.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel
from .kernels import (
    LAW_EXPONENTIAL,
    STATUS_BUFFER_FULL,
    STATUS_NOT_FINITE,
    STATUS_RECORDS_FULL,
    STATUS_RUNNING,
    STATUS_SEPARATED,
    STATUS_STEP_UNDERFLOW,
    contact_response_from,
    exponential_response,
)

__all__ = ["CollocationTables", "radau_nodes", "run_collision"]


def radau_nodes(stages: int) -> np.ndarray:
    """Radau IIA nodes on (0, 1] (the last one is 1): zeros of ``P_s(2x-1) - P_{s-1}(2x-1)``."""
    if stages < 1:
        raise ValueError("stages must be at least 1")
    if stages == 1:
        return np.array([1.0])
    coefficients = np.zeros(stages + 1)
    coefficients[stages] = 1.0
    coefficients[stages - 1] = -1.0
    roots = np.polynomial.legendre.legroots(coefficients)
    nodes = np.sort(0.5 * (np.real(roots) + 1.0))
    nodes[-1] = 1.0
    return nodes


# largest growth of the step from one step to the next
GROW = 2.0
# node forces below FLOOR * force_scale are controlled relatively (see run_collision)
FLOOR = 1e-2
_TAYLOR_TERMS = 22  # |x| < 1: the series of phi_s(i x) to x^21 reaches round-off for every s >= 1


@kernel(internal=True, error_model="numpy")
def _phi(x, count, inverse_factorial, re, im):
    """``phi_0 .. phi_count`` at the imaginary point ``z = i x`` (real and imaginary parts).

    ``phi_0(z) = exp(z)``, ``phi_{k+1}(z) = (phi_k(z) - 1/k!) / z``; for ``|x| < 1`` the highest
    one from its Taylor series ``sum_n (i x)^n / (n + count)!`` (Horner in ``x^2``) and the
    others by the stable backward recurrence ``phi_k = i x phi_{k+1} + 1/k!``.
    ``inverse_factorial[n] = 1/n!`` for ``n < count + _TAYLOR_TERMS``.
    """
    if abs(x) < 1.0:
        y = -x * x
        sum_re = 0.0
        sum_im = 0.0
        for n in range(_TAYLOR_TERMS - 2, -1, -2):  # even powers: (i x)^n = (-x^2)^(n/2)
            sum_re = sum_re * y + inverse_factorial[n + count]
            sum_im = sum_im * y + inverse_factorial[n + 1 + count]
        re[count] = sum_re
        im[count] = x * sum_im
        for k in range(count - 1, -1, -1):
            re[k] = -x * im[k + 1] + inverse_factorial[k]
            im[k] = x * re[k + 1]
    else:
        re[0] = math.cos(x)
        im[0] = math.sin(x)
        for k in range(count):
            # (a + i b - 1/k!) / (i x) = b / x - i (a - 1/k!) / x
            re[k + 1] = im[k] / x
            im[k + 1] = -(re[k] - inverse_factorial[k]) / x


@kernel(internal=True, error_model="numpy")
def _fill_level(level, h, omega, coupling, inverse_mass_rigid, tables):
    """Tables of one ladder step ``h``: node rotations, exact polynomial-force integrals, gap response.

    ``tables`` is :meth:`CollocationTables.arrays` (``h_top`` and the ladder are not read here).
    """
    nodes, vinv, node_cos, node_sin, end_cos, end_sin, end_wsin, end_s, end_c, response, filled = tables[2:13]
    s = nodes.size
    re = np.empty(s + 1)
    im = np.empty(s + 1)
    factorials = np.empty(s)
    factorials[0] = 1.0
    for k in range(1, s):
        factorials[k] = factorials[k - 1] * k
    inverse_factorial = np.empty(s + _TAYLOR_TERMS + 1)
    inverse_factorial[0] = 1.0
    for n in range(1, inverse_factorial.size):
        inverse_factorial[n] = inverse_factorial[n - 1] / n
    g = np.empty((s, s))  # gap at node i per monomial coefficient k of the force (every entry set below)
    for i in range(s):
        for k in range(s):
            g[i, k] = inverse_mass_rigid * h * h * nodes[i] ** (k + 2) / ((k + 1) * (k + 2))
    for j in range(omega.size):
        w = omega[j]
        c2 = coupling[j] * coupling[j]
        for i in range(s):
            t = nodes[i] * h
            _phi(w * t, s, inverse_factorial, re, im)
            node_cos[level, i, j] = re[0]
            node_sin[level, i, j] = im[0] / w
            # int_0^t sin(w (t - tau)) / w (tau / h)^k d tau = k! theta^k t Im(phi_{k+1}(i w t)) / w
            power = 1.0
            for k in range(s):
                g[i, k] += c2 * factorials[k] * power * t * im[k + 1] / w
                power *= nodes[i]
            if i == s - 1:  # the last Radau node is the step's end
                end_cos[level, j] = re[0]
                end_sin[level, j] = im[0] / w
                end_wsin[level, j] = w * im[0]
                for k in range(s):
                    end_s[level, k, j] = factorials[k] * t * im[k + 1] / w
                    end_c[level, k, j] = factorials[k] * t * re[k + 1]
    # gap response to the node forces: r = r_free + (g vinv) F
    for i in range(s):
        for m in range(s):
            total = 0.0
            for k in range(s):
                total += g[i, k] * vinv[k, m]
            response[level, i, m] = total
    filled[level] = 1


@kernel(internal=True, error_model="numpy")
def _solve_small(matrix, rhs, out):
    """Gaussian elimination with partial pivoting (matrix and rhs are overwritten)."""
    n = rhs.size
    for col in range(n):
        pivot = col
        for row in range(col + 1, n):
            if abs(matrix[row, col]) > abs(matrix[pivot, col]):
                pivot = row
        if pivot != col:
            for k in range(n):
                tmp = matrix[col, k]
                matrix[col, k] = matrix[pivot, k]
                matrix[pivot, k] = tmp
            tmp = rhs[col]
            rhs[col] = rhs[pivot]
            rhs[pivot] = tmp
        d = matrix[col, col]
        for row in range(col + 1, n):
            factor = matrix[row, col] / d
            if factor != 0.0:
                for k in range(col, n):
                    matrix[row, k] -= factor * matrix[col, k]
                rhs[row] -= factor * rhs[col]
    for row in range(n - 1, -1, -1):
        total = rhs[row]
        for k in range(row + 1, n):
            total -= matrix[row, k] * out[k]
        out[row] = total / matrix[row, row]


@kernel(internal=True, error_model="numpy")
def _force(gap, law, alpha, strength, stiffness, compliance, guess_force):
    """Force and stiffness (-dF/dgap) at the modal gap; ``guess_force`` seeds the Lambert-W solve."""
    guess = math.nan
    if law == LAW_EXPONENTIAL and compliance > 0.0 and guess_force > 0.0:
        y = guess_force * alpha * compliance
        if y > 1e-6:
            guess = math.log(y)
    f, _, k, _ = contact_response_from(gap, law, alpha, strength, stiffness, compliance, guess)
    return f, k


@kernel(internal=True, error_model="numpy")
def _newton_forces(free_gap, response, contact_law, force_scale, forces, work, counters):
    """Newton on ``F_i = F(r_free,i + sum_m R_im F_m)`` in the forces (any law); True if converged.

    ``contact_law = (law, alpha, strength, stiffness, compliance)``, ``work = (residual, stiff, delta, matrix)``.
    """
    law, alpha, strength, stiffness, compliance = contact_law
    residual, stiff, delta, matrix = work
    s = forces.size
    for _ in range(60):
        counters[4] += 1
        biggest = 0.0
        for i in range(s):
            gap_i = free_gap[i]
            for m in range(s):
                gap_i += response[i, m] * forces[m]
            f_i, k_i = _force(gap_i, law, alpha, strength, stiffness, compliance, forces[i])
            if not (math.isfinite(f_i) and math.isfinite(k_i)):
                return False
            residual[i] = f_i - forces[i]
            stiff[i] = k_i
            biggest = max(biggest, abs(forces[i]), abs(f_i))
        for i in range(s):
            for m in range(s):
                matrix[i, m] = stiff[i] * response[i, m]
            matrix[i, i] += 1.0
        _solve_small(matrix, residual, delta)
        change = 0.0
        for i in range(s):
            forces[i] += delta[i]
            change = max(change, abs(delta[i]))
        if not math.isfinite(change):
            return False
        if change <= 1e-13 * (force_scale + biggest):
            return True
    return False


@kernel(internal=True, error_model="numpy")
def _newton_log_force(free_gap, response, predicted, alpha, strength, compliance, force_scale, forces,
                      work, counters, quick_newton):
    """Newton for the exponential law, possibly in series with a compliance ``C >= 0``, in ``v_i = log F_i``.

    The node equations ``v_i + alpha C exp(v_i) = log(alpha B) - alpha r_i`` with
    ``r_i = r_free,i + sum_m R_im exp(v_m)`` need one exponential per node and iteration (with
    ``C > 0`` a force-based Newton solves a Lambert-W equation inside every evaluation; with
    ``C = 0`` the logarithm keeps a stiff exponential from overflowing).
    ``work = (residual, delta, matrix, rhs)``.  ``quick_newton``: start from the force-free solution where the
    forces barely move the gaps, and stop after the update that leaves, by Newton's quadratic convergence,
    a change below the tolerance for the next one (saves the confirming iteration); None: start from
    ``predicted`` and stop after an update itself below the tolerance (numba compiles without the quick rules).
    """
    residual, delta, matrix, rhs = work
    s = forces.size
    v = residual  # reuse the work arrays: v in `residual`
    log_alpha_b = math.log(alpha * strength)
    for i in range(s):
        if predicted[i] > 1e-300:
            v[i] = math.log(predicted[i])
        else:
            # the scalar equation of node i alone, y exp(y) = alpha^2 B K exp(-alpha r_free) with
            # y = alpha K F and K its own compliance: u = log y from the Lambert-W asymptotics
            k_ii = compliance if compliance > 0.0 else max(response[i, i], 1e-300)
            x = log_alpha_b + math.log(alpha * k_ii) - alpha * free_gap[i]
            u = x if x < 0.0 else math.log1p(x)
            v[i] = u - math.log(alpha * k_ii)
    if quick_newton is not None:
        # where the forces barely move the gaps, the force-free solution v_i = log(alpha B) - alpha r_free,i is
        # within `weak` of the solution (an extrapolated light touch can be many e-folds off, and the capped
        # climb from below takes an iteration per two e-folds)
        largest = -math.inf
        reach = compliance
        for i in range(s):
            largest = max(largest, log_alpha_b - alpha * free_gap[i])
            row = 0.0
            for m in range(s):
                row += abs(response[i, m])
            reach = max(reach, compliance + row)
        if largest < 700.0 and alpha * reach * math.exp(largest) <= 1e-3:
            for i in range(s):
                v[i] = log_alpha_b - alpha * free_gap[i]
    last_update = math.inf  # the largest |change of v| of the iteration before
    for _ in range(60):
        counters[4] += 1
        biggest = 0.0
        for i in range(s):
            forces[i] = math.exp(v[i])
            biggest = max(biggest, forces[i])
        for i in range(s):
            gap_i = free_gap[i]
            for m in range(s):
                gap_i += response[i, m] * forces[m]
            y = forces[i] * alpha * compliance
            rhs[i] = -(v[i] + y - log_alpha_b + alpha * gap_i)
            for m in range(s):
                matrix[i, m] = alpha * response[i, m] * forces[m]
            matrix[i, i] += 1.0 + y
        _solve_small(matrix, rhs, delta)
        change = 0.0
        update = 0.0
        capped = False
        for i in range(s):
            step = min(delta[i], 2.0)  # a convex exponential: never overshoot upwards
            capped = capped or delta[i] > 2.0
            v[i] += step
            change = max(change, abs(step) * forces[i])
            update = max(update, abs(step))
        if not math.isfinite(change):
            return False
        if quick_newton is not None and 0.0 < last_update < math.inf and update <= 10.0 * last_update * last_update:
            # quadratic convergence seen (|dv_k| <= K |dv_{k-1}|^2 with K <= 10): the update just made leaves
            # an error of about the next one, K |dv_k|^2 of the forces
            remaining = update / (last_update * last_update) * update * update * biggest
            if remaining <= 1e-13 * (force_scale + biggest) and not capped:
                for i in range(s):
                    forces[i] = math.exp(v[i])
                return True
        last_update = update
        # a capped step is still climbing: its force may be tiny now, yet far too small for its gap (a node
        # driven deep into overlap within one step would otherwise pass with a negligible force)
        if change <= 1e-13 * (force_scale + biggest) and not capped:
            for i in range(s):
                forces[i] = math.exp(v[i])
            return True
    return False


@kernel(internal=True, error_model="numpy")
def _solve_hard(free_gap, response, predicted, tolerance, forces, active, matrix, rhs, counters):
    """Hard contact at the nodes: ``F_i >= 0``, ``r_i >= 0``, ``F_i r_i = 0`` (active-set iteration).

    ``r = r_free + R F`` with ``R`` the end response of the step; ``tolerance`` (length) is the
    overlap accepted at a node left free.  False if the active set does not settle.
    """
    s = forces.size
    for i in range(s):
        active[i] = predicted[i] > 0.0 or free_gap[i] < 0.0
    for _ in range(2 * s + 2):
        counters[4] += 1
        for i in range(s):
            for m in range(s):
                matrix[i, m] = response[i, m] if (active[i] and active[m]) else 0.0
            if active[i]:
                rhs[i] = -free_gap[i]
            else:
                matrix[i, i] = 1.0
                rhs[i] = 0.0
        _solve_small(matrix, rhs, forces)
        changed = False
        for i in range(s):
            if active[i] and forces[i] < 0.0:
                active[i] = False
                changed = True
        if not changed:
            for i in range(s):
                if not active[i]:
                    gap_i = free_gap[i]
                    for m in range(s):
                        gap_i += response[i, m] * forces[m]
                    if gap_i < -tolerance:
                        active[i] = True
                        changed = True
        if not changed:
            for i in range(s):
                forces[i] = max(forces[i], 0.0)
            return True
    return False


@kernel(internal=True, error_model="numpy")
def _history_at(t, records, count):
    """Impulse ``I(t) = int F`` and force ``F(t)`` at a past time ``t`` from the accepted steps.

    ``records[k] = (t0, h, I(t0), a_0 .. a_{s-1})``: step ``k`` began at ``t0``, lasted ``h`` and
    had the force ``sum_j a_j ((t - t0) / h)^j``.  Zero before the first step.
    """
    if count == 0 or t <= records[0, 0]:
        return 0.0, 0.0
    low = 0
    high = count - 1
    while low < high:  # last step that begins at or before t
        middle = (low + high + 1) // 2
        if records[middle, 0] <= t:
            low = middle
        else:
            high = middle - 1
    h = records[low, 1]
    x = min((t - records[low, 0]) / h, 1.0)
    s = records.shape[1] - 3
    impulse = 0.0
    force = 0.0
    for j in range(s - 1, -1, -1):
        impulse = impulse * x + records[low, 3 + j] / (j + 1)
        force = force * x + records[low, 3 + j]
    return records[low, 2] + h * x * impulse, force


@kernel(internal=True, error_model="numpy")
def _impulse_increment(a, span, records, count):
    """``I(a + span) - I(a)`` from the recorded step polynomials, summed from small pieces.

    Never the difference of two running totals: in a hard contact the gap is the small remainder of
    O(1) terms, and a round-off of 1e-16 in it divided by a step's compliance becomes a force error.
    """
    if count == 0 or span <= 0.0:
        return 0.0
    first = records[0, 0]
    if a + span <= first:
        return 0.0
    if a < first:
        span -= first - a
        a = first
    low = 0
    high = count - 1
    while low < high:  # last step that begins at or before a
        middle = (low + high + 1) // 2
        if records[middle, 0] <= a:
            low = middle
        else:
            high = middle - 1
    k = low
    s = records.shape[1] - 3
    x = (a - records[k, 0]) / records[k, 1]
    total = 0.0
    remaining = span
    while True:
        h = records[k, 1]
        room = (1.0 - x) * h
        last = remaining <= room or k == count - 1
        x_end = min(x + remaining / h, 1.0) if last else 1.0
        upper = 0.0
        lower = 0.0
        for j in range(s - 1, -1, -1):
            upper = upper * x_end + records[k, 3 + j] / (j + 1)
            lower = lower * x + records[k, 3 + j] / (j + 1)
        total += h * (x_end * upper - x * lower)
        if last:
            return total
        remaining -= room
        k += 1
        x = 0.0


@kernel(internal=True, error_model="numpy")
def _echo_increment(t0, offset, ends, records, count):
    """Change of the echo part of the end response over ``[t0, t0 + offset]``.

    ``sum_rods w sum_{n>=1} [I(t0 + offset - n T) - I(t0 - n T)]``, ``ends = (zeta, w_a, w_b, T_a,
    T_b, t_start, ...)``, ``w = 2 / Z`` (see :func:`run_collision`).
    """
    total = 0.0
    for rod in range(2):
        trip = ends[3 + rod]
        delayed = t0 - trip
        part = 0.0
        while delayed + offset > ends[5]:
            part += _impulse_increment(delayed, offset, records, count)
            delayed -= trip
        total += ends[1 + rod] * part
    return total


@kernel(internal=True, error_model="numpy")
def _echo_force(t, ends, records, count):
    """Echo part of the end velocity response at ``t``: ``sum_rods w sum_{n>=1} F(t - n T)``."""
    force = 0.0
    for rod in range(2):
        delayed = t - ends[3 + rod]
        while delayed > ends[5]:
            _, f_n = _history_at(delayed, records, count)
            force += ends[1 + rod] * f_n
            delayed -= ends[3 + rod]
    return force


def run_collision(modes, rigid, contact_law, control, tables, exact_ends, output, both_ends=False):
    """Integrate one collision of rod 0 (left) and rod 1 (right) until they separate for good.

    The arguments are tuples: ``modes = (q, v, omega, coupling)``, ``rigid = (X, U, mass, half)``,
    ``contact_law = (law, alpha, strength, stiffness, compliance)``, ``control = (contact_range, force_scale,
    tolerance, exponent_step, max_steps, quick_newton, onset_efolds)``, ``tables =`` :meth:`CollocationTables.arrays`
    ``(h_top, ladder_ratio, nodes, vinv, node_cos, ..., filled, free_rungs)``, ``exact_ends = (ends, free_q,
    free_v, records)``, ``output = (clock, counters, history)``; their entries are:

    Parameters
    ----------
    q, v, omega : float arrays (M,)
        Mass-normalised mode coordinates, velocities and frequencies of both rods.
    coupling : float array (M,)
        ``d gap / d q``: minus the right-end value for rod 0's modes, the
        left-end value for rod 1's.
    X, U, mass, half : float arrays (2,)
        Centres of mass, their velocities, masses, half lengths.
    compliance : float
        Residual compliance in series with the contact law (0 with exact ends).
    law, alpha, strength, stiffness : contact law (see ``kernels.contact_response``).
    contact_range, force_scale : float
        Gap beyond which the force is negligible; typical force.
    tolerance : float
        Accepted difference between predicted and solved node forces, relative to ``force_scale``.
    exponent_step : float
        Largest change of ``alpha_eff * gap`` per step where the force matters (exponential law).
    h_top, ladder_ratio : float
        Largest step; steps are ``h_top * ladder_ratio**-j``.
    nodes, vinv : arrays (s,), (s, s)
        Collocation nodes and the inverse Vandermonde matrix (node forces -> monomial coefficients).
    node_cos ... filled : tables filled on first use by ``_fill_level``.
    free_rungs : int
        Rungs of the ladder above the sampling step ``h_top * ladder_ratio**-free_rungs``: a step
        longer than that is taken only where a bound on the gap's fall over the step (from the kept
        modes' free motion, :func:`_free_fall`) proves that the
        force stays below ``exp(-30 + exponent_step)`` of ``force_scale`` throughout the step
        (exponential law, truncated ends; 0: every step at most the sampling step).
    ends : float array (11,)
        Exact end response of uniform rods (the end-response correction):
        ``(zeta, w_a, w_b, T_a, T_b, t_start, gap_0, rate_0, energy_0, tail_compliance, gap)`` with
        ``zeta = 1/Z_a + 1/Z_b`` (time/mass), ``w = 2/Z`` per rod, ``T = 2 l / c`` its round
        trip, ``t_start`` the time the force history begins, ``gap_0`` and ``rate_0`` the rigid
        gap and approach rate then, ``energy_0`` the total energy then and ``tail_compliance``
        the static compliance of the omitted modes (bounds their end excursion) and ``gap``
        the true gap now (updated in place).  The gap is ``gap_0 + rate_0 (t - t_start) +
        (kept modes' free motion) + zeta I(t) + sum_n w I(t - n T)`` with ``I = int F`` (every
        mode of a uniform rod, omitted ones included), advanced step by step by its increments;
        the kept modes are only driven by the force.  ``zeta = 0``: the gap of the kept modes
        and the rigid motion (plain or statically corrected truncation).
    free_q, free_v : float arrays (M,)
        The kept modes' free motion from the start (exact ends only; rotated in place).
    records : float array (K, 3 + s)
        Accepted steps ``(t0, h, I(t0), force coefficients)`` (exact ends only; the echoes
        are read from them).
    clock : float array (2,)
        Time; (unused second slot kept for symmetry with the splitting kernel).
    counters : int array (6,)
        Accepted steps, rejected steps, history length, filled levels, Newton iterations, records.
    history : float array (H, 3) or None
        ``(time, U1 - U0, force)`` at every collocation node of every step; H = 0 records nothing (None: nor
        does numba compile the recording).
    max_steps : int
        Return (status 0) after this many accepted steps.
    quick_newton : bool
        The ring's quicker rules (results differ in the last bits): Newton on the node forces
        (exponential law) starts from the force-free solution where the forces barely move the gaps and
        stops once its quadratic convergence puts the next change below the tolerance (one iteration
        earlier than waiting for that change); a step whose node forces are all below ``1e-30``
        of ``force_scale`` rotates the modes without their load.
    onset_efolds : float
        Exponential law: the step changes ``alpha_eff * gap`` by at most ``exponent_step`` once the force
        is within this many e-folds of ``force_scale`` (30: the single collisions), by that much more below.
    both_ends : bool
        Compile one kernel for calls with and without exact ends (for a caller that makes both, such as the
        modal solver's corrections); False compiles the kernel for this call's kind alone.
    """
    # which parts of the kernel this call runs: each one it does not is passed as None, and numba compiles
    # the kernel without it (a flag passed as True keeps both sides of its test, hence two flags for exact ends)
    ends, free_q, free_v, _ = exact_ends
    law, _, _, stiffness, compliance = contact_law
    exact = ends[0] > 0.0
    exponential = law == LAW_EXPONENTIAL
    hard = not exponential and stiffness == math.inf and compliance <= 0.0
    warm = np.count_nonzero(free_q) > 0 or np.count_nonzero(free_v) > 0  # a kept mode not at rest (`!= 0.0`)
    six_stages = tables[2].size == 6  # the collocation nodes
    quick_newton = control[5]
    clock, counters, history = output
    return _run_collision((modes, rigid, contact_law, control, tables), exact_ends, (clock, counters), history,
                          True if exact or both_ends else None, None if exact and not both_ends else True,
                          True if warm else None,
                          True if hard else None, None if exponential or hard else True,
                          True if tables[-1] > 0 and exponential and not exact else None,
                          None if six_stages else True, True if quick_newton else None)


@kernel(error_model="numpy")
def _run_collision(problem, exact_ends, output, history, exact, truncated, warm, hard, generic, free_steps,
                   other_stages, quick):
    """:func:`run_collision` with the parts a call does not run passed as None, so that numba compiles it without them.

    ``problem = (modes, rigid, contact_law, control, tables)``, ``output = (clock, counters)``, the other tuples
    and ``history`` as in :func:`run_collision` (history None: nothing recorded, nor compiled).  Flags, True or
    None: ``exact`` where the call may have exact ends (``ends[0] > 0``), ``truncated`` where it may have none
    (both True: one kernel for both, decided by ``ends[0]``); ``warm``: a kept mode does not start at rest
    (``free_q``, ``free_v`` not all zero); ``hard``: a hard contact without compliance (:func:`_solve_hard`),
    ``generic``: a law solved by :func:`_newton_forces` (both None: the exponential law,
    :func:`_newton_log_force`); ``free_steps``: steps above the sampling step where the force provably stays
    negligible (``free_rungs > 0``, exponential law, no exact ends); ``other_stages``: None for six
    collocation stages (their passes over the modes written out), True for any other number; ``quick``: True
    for ``quick_newton``, None without it.
    """
    modes, rigid, contact_law, control, tables = problem
    q, v, omega, coupling = modes
    X, U, mass, half = rigid
    law, alpha, strength, stiffness, compliance = contact_law
    contact_range, force_scale, tolerance, exponent_step, max_steps, _, onset_efolds = control
    h_top, ladder_ratio, nodes, vinv, node_cos, node_sin, end_cos, end_sin, end_wsin, end_s, end_c, response, \
        filled, free_rungs = tables
    ends, free_q, free_v, records = exact_ends
    clock, counters = output
    s = nodes.size
    n_levels = filled.size
    n_modes = q.size
    log_ratio = math.log(ladder_ratio)
    # the largest step that samples the gap finely enough; longer ones need _free_fall's proof
    h_sample = h_top * math.exp(-free_rungs * log_ratio)
    free_work = np.empty(n_modes if free_steps is not None else 0)
    amplitudes_now = False  # free_work holds the amplitudes of the modes' shares of the gap now
    forces_seen = 0.0  # largest node force since free_work was filled
    # the kept modes' gap at which the force (a compliance in series only lowers it) is exp(-30 + exponent_step)
    # of force_scale: a step over which the gap provably stays above it cannot miss a touch between its nodes
    free_gap_lowest = ((30.0 - exponent_step + math.log(alpha * strength / force_scale)) / alpha
                       if free_steps is not None else 0.0)
    inverse_mass_rigid = 1.0 / mass[0] + 1.0 / mass[1]
    recording = False
    if history is not None:
        recording = history.shape[0] > 0
    zeta = ends[0]
    exact_now = zeta > 0.0  # exact ends in this call (both flags True: decided here)

    free_gap = np.empty(s)
    forces = np.empty(s)
    predicted = np.empty(s)
    residual = np.empty(s)
    delta = np.empty(s)
    rhs = np.empty(s)
    matrix = np.empty((s, s))
    coefficients = np.empty(s)
    previous = np.empty(s)  # read only once a step was accepted (have_previous)
    if other_stages is not None:
        cq = np.empty(n_modes)
        cv = np.empty(n_modes)
    load_q = np.empty(n_modes)
    load_v = np.empty(n_modes)
    step_response = np.empty((s, s))
    if exact is not None:
        # exact ends: the gap responds to the step's force through the dashpot zeta alone (the echoes of
        # a step come back after it); integral of the node polynomial L_m from 0 to theta_i
        integral = np.empty((s, s))
        for i in range(s):
            for m in range(s):
                power = nodes[i]
                total = 0.0
                for k in range(s):
                    total += vinv[k, m] * power / (k + 1)
                    power *= nodes[i]
                integral[i, m] = total
    if hard is not None:
        active = np.empty(s, dtype=np.bool_)  # every entry set by _solve_hard before it is read
    if generic is not None:
        stiff = np.empty(s)
    # modes that start warm (a bath, initial fields) move the gap between the nodes faster than any
    # rate seen at a step boundary: the bound on their acceleration limits the step (_warm_step_limit)
    warm_accel = _free_acceleration_bound(coupling, omega, free_q, free_v) if warm is not None else 0.0
    # the gap's round-off: a hard contact's active set cannot settle below it (V T_long, see _solve_hard)
    gap_floor = 1e-12 * zeta * force_scale * max(ends[3], ends[4]) if exact is not None and exact_now else 0.0

    # state at the start (or where the last call stopped)
    sq = 0.0
    sv = 0.0
    for j in range(n_modes):
        sq += coupling[j] * q[j]
        sv += coupling[j] * v[j]
    rigid_gap = X[1] - half[1] - X[0] - half[0]
    rigid_rate = U[1] - U[0]
    impulse_total = 0.0
    if exact is not None and exact_now:
        n_rec = counters[5]
        if n_rec > 0:
            impulse_total, _ = _history_at(records[n_rec - 1, 0] + records[n_rec - 1, 1], records, n_rec)
        else:
            ends[10] = rigid_gap + sq  # no force yet: the kept modes' gap is the true one
        sq = ends[10] - rigid_gap
        sv = _exact_rate(clock[0], ends, coupling, free_v, warm, records, n_rec) - rigid_rate
    if exact is not None and exact_now and counters[5] > 0:
        _, force_now = _history_at(clock[0], records, counters[5])
        k_now = 0.0
    elif hard is not None:
        force_now = 0.0  # the first step's solve finds it (a start at zero gap may round to -1e-16)
        k_now = 0.0
    elif generic is None:  # the exponential law (hard contact: above), its response alone compiled
        force_now, _, k_now, _ = exponential_response(rigid_gap + sq, alpha, strength, compliance, math.nan)
    else:
        force_now, k_now = _force(rigid_gap + sq, law, alpha, strength, stiffness, compliance, 0.0)
    if not math.isfinite(force_now):
        return STATUS_NOT_FINITE
    if exact is not None and exact_now:
        sv += zeta * force_now
    have_previous = False
    h_previous = 1.0
    travel = (zeta * force_scale if exact is not None and exact_now else abs(rigid_rate)) * h_top  # the top step's length
    # first step from the contact's rate
    # (alpha is a rate per length for the exponential law only; the other laws carry a placeholder)
    approach = alpha * abs(rigid_rate + sv) if law == LAW_EXPONENTIAL else 0.0
    if exact is not None and exact_now:
        rate = approach + (zeta * k_now if math.isfinite(k_now) else 0.0)
    else:
        rate = approach + math.sqrt(max(k_now, 0.0) * inverse_mass_rigid)
    h_wanted = h_top if rate * h_top <= 0.1 else 0.1 / rate
    if warm is not None:
        h_wanted = min(h_wanted, _warm_step_limit(law, alpha, strength, force_scale, exponent_step,
                                                  ends[10] if exact is not None and exact_now else rigid_gap + sq,
                                                  rigid_rate + sv, force_now, warm_accel, travel))
    h_wanted = min(h_wanted, h_sample)
    if free_steps is not None:
        # the force provably negligible over a longer step: no need to feel the way in from the contact's rate
        _free_amplitudes(q, v, omega, coupling, free_work)
        amplitudes_now = True
        for trial in range(free_rungs):
            if filled[trial] == 0:
                _fill_level(trial, h_top * math.exp(-trial * log_ratio), omega, coupling, inverse_mass_rigid, tables)
                counters[3] += 1
            h_trial = h_top * math.exp(-trial * log_ratio)
            allowed = rigid_gap + sq - free_gap_lowest
            if _free_fall(h_trial, q, v, omega, coupling, free_work, end_cos[trial], end_sin[trial], rigid_rate,
                          allowed) <= allowed:
                h_wanted = max(h_wanted, h_trial)
                break
    level = max(0, int(math.ceil(math.log(h_top / h_wanted) / log_ratio - 1e-12)))  # noqa: RUF046
    steps_here = 0

    while True:
        if steps_here >= max_steps:
            return STATUS_RUNNING
        if history is not None and recording and counters[2] + s > history.shape[0]:
            return STATUS_BUFFER_FULL
        if exact is not None and exact_now and counters[5] >= records.shape[0]:
            return STATUS_RECORDS_FULL
        if level >= n_levels:
            return STATUS_STEP_UNDERFLOW
        h = h_top * math.exp(-level * log_ratio)
        if filled[level] == 0:
            _fill_level(level, h, omega, coupling, inverse_mass_rigid, tables)
            counters[3] += 1
        # free gap at the nodes (no force over the step) and its response to the node forces
        if exact is not None and exact_now:
            # increments from the gap now (small terms only, see _impulse_increment)
            kept_now = 0.0
            if warm is not None:
                for j in range(n_modes):
                    kept_now += coupling[j] * free_q[j]
            for i in range(s):
                offset = nodes[i] * h
                free_gap[i] = ends[10] - kept_now + ends[7] * offset + _echo_increment(clock[0], offset, ends,
                                                                                        records, counters[5])
                for m in range(s):
                    step_response[i, m] = zeta * h * integral[i, m]
            mode_q = free_q
            mode_v = free_v
        elif truncated is not None and not exact_now:
            for i in range(s):
                free_gap[i] = rigid_gap + rigid_rate * nodes[i] * h
                for m in range(s):
                    step_response[i, m] = response[level, i, m]
            mode_q = q
            mode_v = v
        if other_stages is None and (warm is not None or truncated is not None and not exact_now):
            # the six stages (the default) in one pass over the modes: six independent sums, each node's in its
            # order (the same arithmetic as the passes below)
            c0, c1, c2, c3, c4, c5 = (node_cos[level, 0], node_cos[level, 1], node_cos[level, 2], node_cos[level, 3],
                                      node_cos[level, 4], node_cos[level, 5])
            s0, s1, s2, s3, s4, s5 = (node_sin[level, 0], node_sin[level, 1], node_sin[level, 2], node_sin[level, 3],
                                      node_sin[level, 4], node_sin[level, 5])
            total0 = total1 = total2 = total3 = total4 = total5 = 0.0
            for j in range(n_modes):
                a = coupling[j] * mode_q[j]
                b = coupling[j] * mode_v[j]
                total0 += c0[j] * a + s0[j] * b
                total1 += c1[j] * a + s1[j] * b
                total2 += c2[j] * a + s2[j] * b
                total3 += c3[j] * a + s3[j] * b
                total4 += c4[j] * a + s4[j] * b
                total5 += c5[j] * a + s5[j] * b
            free_gap[0] += total0
            free_gap[1] += total1
            free_gap[2] += total2
            free_gap[3] += total3
            free_gap[4] += total4
            free_gap[5] += total5
        elif other_stages is not None and (warm is not None or truncated is not None and not exact_now):
            for j in range(n_modes):
                cq[j] = coupling[j] * mode_q[j]
                cv[j] = coupling[j] * mode_v[j]
            # three nodes per pass over the modes: independent sums instead of one long dependency
            # chain per node (each node's sum keeps its order, so the arithmetic is the same)
            for first in range(0, s, 3):
                i1 = min(first + 1, s - 1)
                i2 = min(first + 2, s - 1)
                c0 = node_cos[level, first]
                s0 = node_sin[level, first]
                c1 = node_cos[level, i1]
                s1 = node_sin[level, i1]
                c2 = node_cos[level, i2]
                s2 = node_sin[level, i2]
                total0 = 0.0
                total1 = 0.0
                total2 = 0.0
                for j in range(n_modes):
                    a = cq[j]
                    b = cv[j]
                    total0 += c0[j] * a + s0[j] * b
                    total1 += c1[j] * a + s1[j] * b
                    total2 += c2[j] * a + s2[j] * b
                free_gap[first] += total0
                if first + 1 < s:
                    free_gap[first + 1] += total1
                if first + 2 < s:
                    free_gap[first + 2] += total2
        # predictor: last step's polynomial continued
        for i in range(s):
            if have_previous:
                u = 1.0 + nodes[i] * h / h_previous
                value = 0.0
                for k in range(s - 1, -1, -1):
                    value = value * u + previous[k]
                predicted[i] = value
            else:
                predicted[i] = force_now
            forces[i] = max(predicted[i], 0.0)
        # the s node forces
        if hard is not None:
            converged = _solve_hard(free_gap, step_response, predicted, 1e-10 * zeta * h * force_scale, forces,
                                    active, matrix, delta, counters)
            if not converged and gap_floor > 1e-10 * zeta * h * force_scale:
                # at small steps the node gaps are round-off of O(V T) terms, and an overlap tolerance
                # relative to the step alone (V h) lies below it: the active set then cycles on noise
                converged = _solve_hard(free_gap, step_response, predicted, gap_floor, forces, active, matrix,
                                        delta, counters)
        elif generic is not None:
            converged = _newton_forces(free_gap, step_response, contact_law, force_scale, forces,
                                       (residual, stiff, delta, matrix), counters)
        else:  # the exponential law
            converged = _newton_log_force(free_gap, step_response, predicted, alpha, strength, compliance,
                                          force_scale, forces, (residual, delta, matrix, rhs), counters,
                                          quick)
        if not converged:
            level += 4
            continue
        # mixed test: absolute at forces above FLOOR * force_scale, relative below (a brief light touch
        # after the main contact must not be stepped over)
        error = 0.0
        for i in range(s):
            scale = FLOOR * force_scale + abs(forces[i]) + abs(predicted[i])
            error = max(error, abs(forces[i] - predicted[i]) / scale)
        error *= (FLOOR + 1.0) / tolerance
        if error > 1.0 and level < n_levels - 1:
            shrink = math.log(1.1 * error ** (1.0 / s)) / log_ratio
            level += max(1, int(math.ceil(shrink)))  # noqa: RUF046
            if hard is not None:
                # a jump of the hard contact's force never passes the test: take it at the smallest step
                level = min(level, n_levels - 1)
            counters[1] += 1
            continue
        # accept: monomial coefficients of the force polynomial in tau / h
        for k in range(s):
            total = 0.0
            for m in range(s):
                total += vinv[k, m] * forces[m]
            coefficients[k] = total
        negligible = quick is not None
        for k in range(s):
            negligible = negligible and abs(forces[k]) <= 1e-30 * force_scale
        # (quick rules) node forces below 1e-30 of the force scale move no mode by more than round-off: no load
        if other_stages is None and not negligible:
            # the six stages (the default) in one pass over the modes: the same sum for each mode, term by term
            # in the same order as the loop below, without reading and writing the loads six times
            a0, a1, a2, a3, a4, a5 = (coefficients[0], coefficients[1], coefficients[2], coefficients[3],
                                      coefficients[4], coefficients[5])
            sin0, sin1, sin2, sin3, sin4, sin5 = (end_s[level, 0], end_s[level, 1], end_s[level, 2], end_s[level, 3],
                                                  end_s[level, 4], end_s[level, 5])
            cos0, cos1, cos2, cos3, cos4, cos5 = (end_c[level, 0], end_c[level, 1], end_c[level, 2], end_c[level, 3],
                                                  end_c[level, 4], end_c[level, 5])
            for j in range(n_modes):
                load_q[j] = (0.0 + a0 * sin0[j] + a1 * sin1[j] + a2 * sin2[j] + a3 * sin3[j] + a4 * sin4[j]
                             + a5 * sin5[j])
                load_v[j] = (0.0 + a0 * cos0[j] + a1 * cos1[j] + a2 * cos2[j] + a3 * cos3[j] + a4 * cos4[j]
                             + a5 * cos5[j])
        else:
            for j in range(n_modes):
                load_q[j] = 0.0
                load_v[j] = 0.0
            if other_stages is not None:  # (six stages come here for negligible forces only: no load)
                for k in range(0 if negligible else s):
                    a_k = coefficients[k]
                    row_s = end_s[level, k]
                    row_c = end_c[level, k]
                    for j in range(n_modes):
                        load_q[j] += a_k * row_s[j]
                        load_v[j] += a_k * row_c[j]
        sq = 0.0
        sv = 0.0
        e_cos = end_cos[level]
        e_sin = end_sin[level]
        e_wsin = end_wsin[level]
        for j in range(n_modes):
            c = e_cos[j]
            qj = q[j]
            vj = v[j]
            qn = c * qj + e_sin[j] * vj + coupling[j] * load_q[j]
            vn = c * vj - e_wsin[j] * qj + coupling[j] * load_v[j]
            q[j] = qn
            v[j] = vn
            sq += coupling[j] * qn
            sv += coupling[j] * vn
        if exact is not None and exact_now and warm is not None:
            for j in range(n_modes):
                c = e_cos[j]
                qj = free_q[j]
                free_q[j] = c * qj + e_sin[j] * free_v[j]
                free_v[j] = c * free_v[j] - e_wsin[j] * qj
        impulse = 0.0
        moment = 0.0
        for k in range(s):
            impulse += coefficients[k] * h / (k + 1)
            moment += coefficients[k] * h * h / ((k + 1) * (k + 2))
        if exact is not None and exact_now:
            n_rec = counters[5]
            records[n_rec, 0] = clock[0]
            records[n_rec, 1] = h
            records[n_rec, 2] = impulse_total
            for k in range(s):
                records[n_rec, 3 + k] = coefficients[k]
            counters[5] = n_rec + 1
            impulse_total += impulse
        if history is not None and recording:
            # every node of the step: time, relative velocity of the centres of mass, force
            relative = U[1] - U[0]
            for i in range(s):
                partial = 0.0
                power = nodes[i]
                for k in range(s):
                    partial += coefficients[k] * h * power / (k + 1)
                    power *= nodes[i]
                n = counters[2]
                history[n, 0] = clock[0] + nodes[i] * h
                history[n, 1] = relative + inverse_mass_rigid * partial
                history[n, 2] = forces[i]
                counters[2] = n + 1
        X[0] += U[0] * h - moment / mass[0]
        X[1] += U[1] * h + moment / mass[1]
        U[0] -= impulse / mass[0]
        U[1] += impulse / mass[1]
        clock[0] += h
        for k in range(s):
            previous[k] = coefficients[k]
        h_previous = h
        have_previous = True
        force_now = forces[s - 1]
        if free_steps is not None:
            for i in range(s):
                forces_seen = max(forces_seen, forces[i])
        counters[0] += 1
        steps_here += 1
        rigid_gap = X[1] - half[1] - X[0] - half[0]
        rigid_rate = U[1] - U[0]
        if exact is not None and exact_now:
            # the true end motion (all modes) instead of the kept ones
            gap_end = free_gap[s - 1]
            for m in range(s):
                gap_end += step_response[s - 1, m] * forces[m]
            ends[10] = gap_end
            sq = gap_end - rigid_gap
            sv = _exact_rate(clock[0], ends, coupling, free_v, warm, records, counters[5]) - rigid_rate
            sv += zeta * force_now
        # separated for good: the pair opens and the ends' largest excursion cannot reach the force
        if rigid_rate > 0.0 and rigid_gap + sq > contact_range:
            reach = 0.0
            for j in range(n_modes):
                w = omega[j]
                reach += abs(coupling[j]) * math.sqrt(q[j] * q[j] + v[j] * v[j] / (w * w))
                if rigid_gap - reach <= contact_range:
                    break  # the sum of non-negative terms only grows: the test below fails either way
            if exact is not None and exact_now:
                reach += _omitted_reach(q, v, omega, U, mass, ends)
            if rigid_gap - reach > contact_range:
                return STATUS_SEPARATED
        # next step: from the error estimate, and (exponential law) at most `exponent_step` e-folds of
        # the force per step once it is within ~30 e-folds of the force scale: the absolute estimate
        # alone lets the onset of a stiff contact be crossed in one coarse step
        grow = GROW if error <= 1e-12 else min(GROW, 0.9 / error ** (1.0 / s))
        h_wanted = min(h_top, h * max(grow, 0.2))
        if law == LAW_EXPONENTIAL and force_now > 0.0:
            softening = 1.0 + alpha * compliance * force_now
            rate = alpha / softening * abs(rigid_rate + sv)
            room = exponent_step + max(0.0, -math.log(force_now / force_scale) - onset_efolds)
            if rate * h_wanted > room:
                h_wanted = room / rate
        if warm is not None:
            h_wanted = min(h_wanted, _warm_step_limit(law, alpha, strength, force_scale, exponent_step,
                                                      ends[10] if exact is not None and exact_now else rigid_gap + sq,
                                                      rigid_rate + sv, force_now, warm_accel, travel))
        if free_steps is not None and (h_wanted > h_sample or error <= 1e-12):
            # longer than the sampling step only where the force provably stays negligible: try twice this
            # step (the error estimate has nothing to say about a force of zero) and two rungs below it
            if forces_seen > 1e-30 * force_scale:
                forces_seen = 0.0  # the amplitudes changed by more than round-off since they were taken
                amplitudes_now = False
            if not amplitudes_now:
                _free_amplitudes(q, v, omega, coupling, free_work)
                amplitudes_now = True
            h_free = 0.0
            allowed = rigid_gap + sq - free_gap_lowest
            # the longest of twice this step and the rungs down to it whose fall stays within `allowed`; the
            # bound on the fall grows with the step, so try the shortest first: where it fails all fail
            trial = min(level, free_rungs - 1)
            while allowed > 0.0 and trial >= max(0, level - 2):
                if filled[trial] == 0:
                    _fill_level(trial, h_top * math.exp(-trial * log_ratio), omega, coupling, inverse_mass_rigid,
                                tables)
                    counters[3] += 1
                h_trial = h_top * math.exp(-trial * log_ratio)
                if _free_fall(h_trial, q, v, omega, coupling, free_work, end_cos[trial], end_sin[trial], rigid_rate,
                              allowed) > allowed:
                    break
                h_free = h_trial
                trial -= 1
            h_wanted = max(min(h_wanted, h_sample), h_free)
        elif h_wanted > h_sample:
            h_wanted = h_sample
        level = max(0, int(math.ceil(math.log(h_top / h_wanted) / log_ratio - 1e-9)))  # noqa: RUF046
        if hard is not None:
            level = min(level, n_levels - 1)


@kernel(internal=True, error_model="numpy")
def _free_acceleration_bound(coupling, omega, free_q, free_v):
    """Bound on ``|d^2/dt^2 sum_j c_j q_j(t)|`` of freely oscillating modes (their amplitudes are constant)."""
    bound = 0.0
    for j in range(omega.size):
        w = omega[j]
        bound += abs(coupling[j]) * w * math.sqrt(w * w * free_q[j] * free_q[j] + free_v[j] * free_v[j])
    return bound


@kernel(internal=True, error_model="numpy")
def _free_amplitudes(q, v, omega, coupling, amplitude):
    """``amplitude[j] = |c_j| A_j``, the amplitude of mode ``j``'s share ``c_j q_j`` of the gap (for :func:`_free_fall`)."""
    for j in range(q.size):
        w = omega[j]
        amplitude[j] = abs(coupling[j]) * math.sqrt(q[j] * q[j] + v[j] * v[j] / (w * w))


@kernel(internal=True, error_model="numpy")
def _free_fall(h, q, v, omega, coupling, amplitude, cos_h, sin_h, rigid_rate, allowed):
    """Bound on how far the gap falls within ``[0, h]`` while the modes move freely (no force).

    Each kept mode's share ``x_j(t) = c_j (q_j cos w_j t + v_j sin(w_j t) / w_j)`` is a sinusoid of amplitude
    ``|c_j| A_j`` (``amplitude``); ``cos_h = cos(w h)``, ``sin_h = sin(w h) / w`` (the step tables).  Where
    ``w_j h < pi`` it falls within the step by ``x_j(0) - min(x_j(0), x_j(h))``, or down to its trough,
    ``x_j(0) + |c_j| A_j``, if its slope turns from falling to rising inside; otherwise by at most the latter.
    The sum of these and the rigid gap's ``-rigid_rate h`` bounds the gap's fall (the largest of a sum is at
    most the sum of the largest).  Stops summing once ``allowed`` is exceeded.
    """
    fall = max(0.0, -rigid_rate * h)
    for j in range(q.size):
        c = coupling[j]
        now = c * q[j]
        w = omega[j]
        if w * h < math.pi:
            rate_now = c * v[j]
            later = c * (q[j] * cos_h[j] + v[j] * sin_h[j])
            rate_later = c * (v[j] * cos_h[j] - w * w * q[j] * sin_h[j])
            if rate_now < 0.0 and rate_later > 0.0:
                fall += now + amplitude[j]
            elif later < now:
                fall += now - later
        else:
            fall += now + amplitude[j]
        if fall > allowed:
            return fall
    return fall


@kernel(internal=True, error_model="numpy")
def _warm_step_limit(law, alpha, strength, force_scale, exponent_step, gap, rate, force, accel, travel):
    """Largest step over which warm modes cannot bring an unseen contact between the collocation nodes.

    Over a step ``h`` the gap falls at most ``|rate| h + accel h^2 / 2`` (``accel`` bounds the free
    modes' acceleration; the contact force only opens the gap).  Exponential law: that fall times
    ``alpha`` is at most ``exponent_step`` e-folds of the force, plus the e-folds by which the force
    is still below ``exp(-30) force_scale``.  Laws without range (penalty, hard): while the pair is
    open, the fall is at most the gap itself, or ``5e-4 exponent_step travel`` (``travel = V h_top``,
    the step ladder's own length) near touching, after which the error control takes over (a touch
    between the nodes can then go that deep unseen: the error estimate's finer run halves it).
    """
    speed = abs(rate)
    if law == LAW_EXPONENTIAL:
        distance = alpha * gap - math.log(alpha * strength / force_scale)  # -log(F / force_scale), no compliance
        room = exponent_step + max(0.0, distance - 30.0)
        scaled = alpha * speed
        return 2.0 * room / (scaled + math.sqrt(scaled * scaled + 2.0 * alpha * accel * room))
    if force > 0.0:
        return math.inf
    room = max(gap, 5e-4 * exponent_step * travel)
    return 2.0 * room / (speed + math.sqrt(speed * speed + 2.0 * accel * room))


@kernel(internal=True, error_model="numpy")
def _exact_rate(t, ends, coupling, free_v, warm, records, count):
    """True gap rate at the step boundary ``t`` with exact ends, less the step's own ``zeta F(t)``
    (``warm``: True with warm kept modes, else None)."""
    rate = ends[7] + _echo_force(t, ends, records, count)
    if warm is not None:
        for j in range(free_v.size):
            rate += coupling[j] * free_v[j]
    return rate


@kernel(internal=True, error_model="numpy")
def _omitted_reach(q, v, omega, U, mass, ends):
    """Bound on the omitted modes' end excursion: ``sqrt(2 C E_omitted)`` (Cauchy-Schwarz).

    ``E_omitted`` is what the total energy ``ends[8]`` leaves after the centres of mass and the kept
    modes (the omitted modes start at rest; the contact's energy is negligible where this is asked).
    """
    kept = 0.0
    for j in range(q.size):
        kept += 0.5 * (v[j] * v[j] + omega[j] * omega[j] * q[j] * q[j])
    translation = 0.5 * (mass[0] * U[0] * U[0] + mass[1] * U[1] * U[1])
    omitted = max(ends[8] - translation - kept, 0.0) + 1e-12 * ends[8]
    return math.sqrt(2.0 * ends[9] * omitted)


class CollocationTables:
    """Lazily filled step tables of :func:`run_collision` for one set of modes and couplings.

    Parameters
    ----------
    omega, coupling : float arrays (M,)
        Mode frequencies (rad/time) and gap couplings.
    inverse_mass_rigid : float
        ``1/m_0 + 1/m_1``.
    stages : int
        Radau IIA stages ``s`` (order up to ``2 s - 1``).
    h_top : float
        Largest step that samples the gap (time).
    ladder_ratio : float
        Ratio of consecutive step sizes.
    levels : int
        Number of step sizes up to ``h_top``.
    free_rungs : int
        Further rungs above ``h_top``, taken only where the force provably stays negligible over the
        step (see ``free_rungs`` of :func:`run_collision`); 0: none.
    """

    def __init__(self, omega, coupling, inverse_mass_rigid, stages, h_top, ladder_ratio=2.0**0.5, levels=60,
                 free_rungs=0):
        self.nodes = radau_nodes(stages)
        s = self.nodes.size
        self.vinv = np.linalg.inv(np.vander(self.nodes, s, increasing=True))
        m = omega.size
        self.free_rungs = int(free_rungs)
        levels += self.free_rungs
        self.h_top = float(h_top) * float(ladder_ratio) ** self.free_rungs
        self.ladder_ratio = float(ladder_ratio)
        self.node_cos = np.empty((levels, s, m))
        self.node_sin = np.empty((levels, s, m))
        self.end_cos = np.empty((levels, m))
        self.end_sin = np.empty((levels, m))
        self.end_wsin = np.empty((levels, m))
        self.end_s = np.empty((levels, s, m))
        self.end_c = np.empty((levels, s, m))
        self.response = np.empty((levels, s, s))
        self.filled = np.zeros(levels, dtype=np.int64)
        self.inverse_mass_rigid = float(inverse_mass_rigid)

    def arrays(self):
        return (self.h_top, self.ladder_ratio, self.nodes, self.vinv, self.node_cos, self.node_sin, self.end_cos,
                self.end_sin, self.end_wsin, self.end_s, self.end_c, self.response, self.filled, self.free_rungs)
