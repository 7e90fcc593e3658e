"""Compiled kernels of the modal integrator (plain arrays in, plain arrays out).

The system: rods with centre-of-mass positions ``X`` and velocities ``U``,
mass-normalised mode coordinates ``q`` with velocities ``v`` and frequencies
``omega``, and end values ``left``/``right`` of each mode; contact pairs
``k`` join the right end of rod ``pair_a[k]`` to the left end of rod
``pair_b[k]`` (``pair_offset[k]`` adds the ring circumference for the pair
that faces across the ring's seam).

Integrator (:func:`run_episode`): while every pair is provably out of range
of its force, the linear free motion is applied in closed form over the whole
stretch (oscillators rotated in phase space, centres of mass moved
ballistically).  Otherwise a Strang splitting is taken: half kick by the
contact forces, exact rotation of all oscillators over the step, half kick.
The step comes from the contact alone (never from the highest mode), from
the rate ``alpha_eff |dr/dt|`` at which the force changes, weighted by the
force's size so that the toe of the exponential costs few steps, and from the
linearised contact frequency.  Steps are rounded down to a geometric ladder
whose rotation coefficients are tabulated once.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel
from ..contact import LAW_EXPONENTIAL, LAW_PENALTY
from ..contact_kernels import contact_response, exponential_response  # noqa: F401 (the modal kernels' names)
from ..contact_kernels import law_response as contact_response_from

TOE_MARGIN = 5.0

LAW_LINEAR = LAW_PENALTY  # a spring on overlap; hard contact is its infinite stiffness

STATUS_RUNNING = 0  # max_steps reached: call again
STATUS_SEPARATED = 1  # the episode's pair separated for good
STATUS_FREE_FOREVER = 2  # no pair will ever meet again (line)
STATUS_BUFFER_FULL = 3  # history buffer full: grow it and call again
STATUS_RECORDS_FULL = 4  # step records (collocation with exact ends) full: grow them and call again
STATUS_STEP_UNDERFLOW = -1
STATUS_NOT_FINITE = -2

@kernel(internal=True, error_model="numpy")
def free_flight(q, v, omega, X, U, duration):
    """Advance the force-free motion exactly by ``duration`` (in place)."""
    for j in range(q.size):
        w = omega[j]
        c = math.cos(w * duration)
        s = math.sin(w * duration)
        qj = q[j]
        q[j] = c * qj + s * v[j] / w
        v[j] = -w * s * qj + c * v[j]
    for i in range(X.size):
        X[i] += U[i] * duration

@kernel(error_model="numpy")
def end_sums(q, v, left, right, rod_first, sums):
    """Per rod: modal displacement and velocity of the left and right end.

    ``sums[i] = (sum left q, sum right q, sum left v, sum right v)`` for rod ``i``.
    """
    for i in range(rod_first.size - 1):
        sl = 0.0
        sr = 0.0
        vl = 0.0
        vr = 0.0
        for j in range(rod_first[i], rod_first[i + 1]):
            sl += left[j] * q[j]
            sr += right[j] * q[j]
            vl += left[j] * v[j]
            vr += right[j] * v[j]
        sums[i, 0] = sl
        sums[i, 1] = sr
        sums[i, 2] = vl
        sums[i, 3] = vr

@kernel(internal=True, error_model="numpy")
def _kick_deferred(U, mass, pair_a, pair_b, force, h, rod_products, sums, pending):
    """Kick by the pair forces over ``h`` without touching the mode velocities.

    The centres of mass and the end-velocity sums are updated at once (the
    sums through ``rod_products`` = per rod ``(sum left^2, sum left right,
    sum right^2)``); the end impulses are added to ``pending`` and reach the
    mode velocities in the next :func:`_rotate` or :func:`_flush` (one pass
    over the modes per step instead of three).
    """
    for k in range(pair_a.size):
        f = force[k] * h
        if f != 0.0:
            a = pair_a[k]
            b = pair_b[k]
            U[a] -= f / mass[a]
            U[b] += f / mass[b]
            pending[a, 1] -= f
            pending[b, 0] += f
            sums[a, 2] -= rod_products[a, 1] * f
            sums[a, 3] -= rod_products[a, 2] * f
            sums[b, 2] += rod_products[b, 0] * f
            sums[b, 3] += rod_products[b, 1] * f


@kernel(internal=True, error_model="numpy")
def _flush(v, left, right, rod_first, pending):
    """Apply the pending end impulses to the mode velocities."""
    for i in range(rod_first.size - 1):
        pl = pending[i, 0]
        pr = pending[i, 1]
        if pl == 0.0 and pr == 0.0:
            continue
        pending[i, 0] = 0.0
        pending[i, 1] = 0.0
        for j in range(rod_first[i], rod_first[i + 1]):
            v[j] += left[j] * pl + right[j] * pr


@kernel(internal=True, error_model="numpy")
def _pair_state(X, U, half, sums, pair_a, pair_b, pair_offset, gap, gap_rate):
    """Modal gap and gap rate of every pair from the centres of mass and the end sums."""
    for k in range(pair_a.size):
        a = pair_a[k]
        b = pair_b[k]
        gap[k] = (X[b] - half[b] + pair_offset[k] + sums[b, 0]) - (X[a] + half[a] + sums[a, 1])
        gap_rate[k] = (U[b] + sums[b, 2]) - (U[a] + sums[a, 3])


@kernel(internal=True, error_model="numpy")
def _bounds(modes, inverse_omega, bodies, pairs, bounds, amp_left, amp_right):
    """Rigorous bounds on the modal end motion under free flight.

    ``modes``, ``bodies`` and ``pairs`` as in :func:`run_episode`; ``bounds = (rigid_gap, rigid_rate, reach,
    speed_bound, accel_bound)`` (filled): ``reach[k]`` bounds |modal displacement| of the pair's two ends,
    ``speed_bound[k]`` bounds |d gap / dt| and ``accel_bound[k]`` bounds |d^2 gap / dt^2|.
    """
    q, v, omega, left, right, rod_first = modes
    X, U, _, half = bodies
    pair_a, pair_b, pair_offset = pairs[0], pairs[1], pairs[2]
    rigid_gap, rigid_rate, reach, speed_bound, accel_bound = bounds
    for i in range(rod_first.size - 1):
        al = 0.0
        ar = 0.0
        sl = 0.0
        sr = 0.0
        cl = 0.0
        cr = 0.0
        for j in range(rod_first[i], rod_first[i + 1]):
            w = omega[j]
            # amplitude times frequency: sqrt of twice the mode's energy
            amp_w = math.sqrt(w * w * q[j] * q[j] + v[j] * v[j])
            amp = amp_w * inverse_omega[j]
            al += abs(left[j]) * amp
            ar += abs(right[j]) * amp
            sl += abs(left[j]) * amp_w
            sr += abs(right[j]) * amp_w
            cl += abs(left[j]) * amp_w * w
            cr += abs(right[j]) * amp_w * w
        amp_left[i, 0] = al
        amp_left[i, 1] = sl
        amp_left[i, 2] = cl
        amp_right[i, 0] = ar
        amp_right[i, 1] = sr
        amp_right[i, 2] = cr
    for k in range(pair_a.size):
        a = pair_a[k]
        b = pair_b[k]
        rigid_gap[k] = (X[b] - half[b] + pair_offset[k]) - (X[a] + half[a])
        rigid_rate[k] = U[b] - U[a]
        reach[k] = amp_right[a, 0] + amp_left[b, 0]
        speed_bound[k] = abs(rigid_rate[k]) + amp_right[a, 1] + amp_left[b, 1]
        accel_bound[k] = amp_right[a, 2] + amp_left[b, 2]

@kernel(internal=True, error_model="numpy")
def _rotate(q, v, left, right, rod_first, cos_row, sin_over_omega_row, omega_sin_row, sums, pending):
    """Apply the pending end impulses to the mode velocities, rotate every oscillator exactly over
    one ladder step, and recompute the end sums (one pass over the modes)."""
    for i in range(rod_first.size - 1):
        sl = 0.0
        sr = 0.0
        vl = 0.0
        vr = 0.0
        pl = pending[i, 0]
        pr = pending[i, 1]
        pending[i, 0] = 0.0
        pending[i, 1] = 0.0
        for j in range(rod_first[i], rod_first[i + 1]):
            c = cos_row[j]
            qj = q[j]
            vj = v[j] + left[j] * pl + right[j] * pr
            qn = c * qj + sin_over_omega_row[j] * vj
            vn = c * vj - omega_sin_row[j] * qj
            q[j] = qn
            v[j] = vn
            sl += left[j] * qn
            sr += right[j] * qn
            vl += left[j] * vn
            vr += right[j] * vn
        sums[i, 0] = sl
        sums[i, 1] = sr
        sums[i, 2] = vl
        sums[i, 3] = vr


@kernel(internal=True, error_model="numpy")
def _update_forces(gap, law, alpha, strength, stiffness, pair_compliance, force, keff, aeff, generic_law):
    """Force, stiffness and softened alpha of every pair; False if a force is not finite (``generic_law``:
    ``generic`` of :func:`~wavecontact.contact_kernels.law_response`)."""
    finite = True
    for k in range(gap.size):
        guess = math.nan
        if law == LAW_EXPONENTIAL and pair_compliance[k] > 0.0:
            previous = alpha / aeff[k] - 1.0  # aeff = alpha / (1 + y): last step's y
            if previous > 1e-6:
                guess = math.log(previous)
        f, _, kk, soft = contact_response_from(gap[k], law, alpha, strength, stiffness, pair_compliance[k], guess,
                                               generic_law)
        if not math.isfinite(f):
            finite = False
        force[k] = f
        keff[k] = kk
        aeff[k] = alpha / soft
    return finite


@kernel(error_model="numpy")
def run_episode(modes, bodies, pairs, contact_law, control, tables, output, history, max_steps, generic_law):
    """Integrate until the current collision (episode) is over.

    All arrays are modified in place where they hold state.  The arguments are tuples:
    ``modes = (q, v, omega, left, right, rod_first)``, ``bodies = (X, U, mass, half)``,
    ``pairs = (pair_a, pair_b, pair_offset, pair_compliance, pair_inverse_mass)``,
    ``contact_law = (law, alpha, strength, stiffness, contact_range)``, ``control = (step_accuracy,
    step_reach, force_scale, dt_top, ladder_ratio, sub_index, sub_weight)``, ``tables = (cos_table,
    sin_table, omega_sin_table)``, ``output = (clock, episode, counters)``; their entries are:

    Parameters
    ----------
    q, v : float arrays (M,)
        Mass-normalised mode coordinates and velocities.
    omega, left, right : float arrays (M,)
        Frequencies and end values of the modes, rod after rod.
    rod_first : uint64 array (n_rods + 1,)
        Modes of rod ``i`` are ``rod_first[i]:rod_first[i + 1]``.
    X, U, mass, half : float arrays (n_rods,)
        Centre-of-mass positions and velocities, masses, half lengths.
    pair_a, pair_b, pair_offset, pair_compliance, pair_inverse_mass : arrays (K,)
        Contact pairs (right end of a, left end of b), offset added to b's
        position, residual compliance, inverse effective end mass.
    law, alpha, strength, stiffness : int and floats
        The contact law (see :func:`contact_response`).
    contact_range : float
        Gap beyond which the force is negligible (length).
    step_accuracy, step_reach : float
        ``eta`` of the step control and the largest change of ``alpha * gap``
        allowed in one step while the force is small.
    force_scale : float
        Force against which "small" is measured.
    dt_top, ladder_ratio : float
        Largest step; the ladder is ``dt_top * ladder_ratio**-j``.
    sub_index, sub_weight : int and float arrays (S,)
        The step's Strang substeps: table to use and fraction of the step
        (``[0], [1.0]`` for order 2; the triple jump for order 4).
    cos_table, sin_table, omega_sin_table : float arrays (F, J, M)
        ``cos(omega f dt_j)``, ``sin(omega f dt_j) / omega``, ``omega sin(omega f dt_j)``
        for each distinct substep fraction ``f``; ``tables`` None: no step is taken (the free flight to
        where a pair may be in range, then status 0, as with ``max_steps = 0``), and numba compiles the
        kernel without the stepping (and, with ``history`` None, without the contact law: the start's
        force is then not checked, the first step's kernel does).
    clock : float array (2,)
        Current time; time at which the current episode began.
    episode : int array (1,)
        Pair of the collision under way, -1 before it starts.
    counters : int array (4,)
        Steps, free-flight skips, history length, history capacity use flag.
    history : float array (H, 3) or None
        Records ``(time, rigid gap rate, force)`` of the episode's pair; None (or H = 0)
        records nothing (None: numba compiles the kernel without the recording).
    max_steps : int
        Return after this many steps (status 0).
    generic_law : True or None
        None for a law of ``CLOSED_FORM_CODES`` (numba compiles without the generic solve, see
        :func:`~wavecontact.contact_kernels.law_response`), True for any law.

    Returns
    -------
    int
        A status code (STATUS_*).
    """
    q, v, omega, left, right, rod_first = modes
    X, U, mass, half = bodies
    pair_a, pair_b, pair_offset, pair_compliance, pair_inverse_mass = pairs
    law, alpha, strength, stiffness, contact_range = contact_law
    step_accuracy, step_reach, force_scale, dt_top, ladder_ratio, sub_index, sub_weight = control
    clock, episode, counters = output
    n_rods = X.size
    n_pairs = pair_a.size
    inverse_omega = np.empty(omega.size)
    for j in range(omega.size):
        inverse_omega[j] = 1.0 / omega[j]
    sums = np.empty((n_rods, 4))
    amp_left = np.empty((n_rods, 3))
    amp_right = np.empty((n_rods, 3))
    gap = np.empty(n_pairs)
    gap_rate = np.empty(n_pairs)
    force = np.empty(n_pairs)
    aeff = np.empty(n_pairs)
    for k in range(n_pairs):
        aeff[k] = alpha
    keff = np.empty(n_pairs)
    rigid_gap = np.empty(n_pairs)
    rigid_rate = np.empty(n_pairs)
    reach = np.empty(n_pairs)
    speed_bound = np.empty(n_pairs)
    accel_bound = np.empty(n_pairs)
    bounds = (rigid_gap, rigid_rate, reach, speed_bound, accel_bound)
    recording = False
    if history is not None:
        recording = history.shape[0] > 0
    steps_here = 0
    skip_tolerance = 1e-6 * contact_range + 1e-12 * half[0]
    pending = np.empty((n_rods, 2))
    for i in range(n_rods):
        pending[i, 0] = 0.0
        pending[i, 1] = 0.0
    if tables is not None:  # the stepping's constants (a free flight alone needs none)
        # farthest a composed step strays from its start, in units of the step (1.35 for the triple jump):
        # the rigorous free-flight and toe limits must hold for every substep's end point
        excursion = 0.0
        partial = 0.0
        for sub in range(sub_weight.size):
            partial += sub_weight[sub]
            excursion = max(excursion, abs(partial))
        omega_max = 0.0
        for j in range(omega.size):
            omega_max = max(omega_max, omega[j])
        log_ratio = math.log(ladder_ratio)
        # alpha * gap at which alpha B exp(-alpha gap) = force_scale (accuracy / reach)^2
        significant_exponent = 0.0
        if law == LAW_EXPONENTIAL:
            significant_exponent = (math.log(alpha * strength / force_scale) + 2.0 * math.log(step_reach / step_accuracy)
                                    + TOE_MARGIN)
        rod_products = np.empty((n_rods, 3))
        for i in range(n_rods):
            left_left = 0.0
            left_right = 0.0
            right_right = 0.0
            for j in range(rod_first[i], rod_first[i + 1]):
                left_left += left[j] * left[j]
                left_right += left[j] * right[j]
                right_right += right[j] * right[j]
            rod_products[i, 0] = left_left
            rod_products[i, 1] = left_right
            rod_products[i, 2] = right_right

    end_sums(q, v, left, right, rod_first, sums)
    _pair_state(X, U, half, sums, pair_a, pair_b, pair_offset, gap, gap_rate)
    # the forces are read by the steps and the history alone: a free flight without them (tables and history
    # None) compiles without the contact law (nor checks that the force at the start is finite)
    if (tables is not None or history is not None) and not _update_forces(gap, law, alpha, strength, stiffness,
                                                                          pair_compliance, force, keff, aeff,
                                                                          generic_law):
        return STATUS_NOT_FINITE

    while True:
        # every return below leaves the mode velocities complete (pending impulses applied)
        all_far = True
        for k in range(n_pairs):
            if gap[k] <= contact_range:
                all_far = False
        dt_free = 0.0
        candidate = -1
        if all_far:
            _flush(v, left, right, rod_first, pending)
            _bounds(modes, inverse_omega, bodies, pairs, bounds, amp_left, amp_right)
            ep = episode[0]
            if ep >= 0 and rigid_rate[ep] > 0.0 and rigid_gap[ep] - reach[ep] > contact_range:
                return STATUS_SEPARATED
            provably_free = True
            skip = math.inf
            closest_margin = math.inf
            for k in range(n_pairs):
                # land a little short of the bound so that the next pass steps instead of skipping again
                margin = rigid_gap[k] - reach[k] - contact_range
                if margin <= skip_tolerance:
                    provably_free = False
                    # the collision about to be resolved is the pair that cannot be proven free
                    # (not a pair that has just separated and is still close)
                    if margin < closest_margin and rigid_rate[k] <= 0.0:
                        closest_margin = margin
                        candidate = k
                elif rigid_rate[k] < 0.0:
                    skip = min(skip, (margin - 0.5 * skip_tolerance) / (-rigid_rate[k]))
            if provably_free:
                if skip == math.inf:
                    return STATUS_FREE_FOREVER
                free_flight(q, v, omega, X, U, skip)
                clock[0] += skip
                counters[1] += 1
                end_sums(q, v, left, right, rod_first, sums)
                _pair_state(X, U, half, sums, pair_a, pair_b, pair_offset, gap, gap_rate)
                if tables is not None or history is not None:
                    _update_forces(gap, law, alpha, strength, stiffness, pair_compliance, force, keff, aeff,
                                   generic_law)
                if history is not None and recording and episode[0] >= 0:
                    n = counters[2]
                    if n < history.shape[0]:
                        history[n, 0] = clock[0]
                        history[n, 1] = rigid_rate[episode[0]]
                        history[n, 2] = force[episode[0]]
                        counters[2] = n + 1
                continue
            if tables is not None:
                dt_free = math.inf
                for k in range(n_pairs):
                    dt_free = min(dt_free, (gap[k] - contact_range) / speed_bound[k])
        if episode[0] < 0:
            # the collision begins with the closest pair whose centres of mass close in and that
            # cannot be proven free (out of range) or is within reach of the force; a pair that is
            # opening (it has just separated, or another pair pushes it apart) only keeps the
            # integrator stepping, whatever its ends' vibration does to its gap
            best = -1
            if all_far:
                best = candidate
            else:
                for k in range(n_pairs):
                    closing = U[pair_b[k]] - U[pair_a[k]] <= 0.0
                    if closing and gap[k] <= contact_range and (best < 0 or gap[k] < gap[best]):
                        best = k
            if best >= 0:
                episode[0] = best
                clock[1] = clock[0]
        if tables is None or steps_here >= max_steps:
            _flush(v, left, right, rod_first, pending)
            return STATUS_RUNNING
        cos_table, sin_table, omega_sin_table = tables
        n_levels = cos_table.shape[1]
        if history is not None and recording and counters[2] >= history.shape[0]:
            _flush(v, left, right, rod_first, pending)
            return STATUS_BUFFER_FULL

        # step size from the contact alone
        rate = 0.0
        bounds_ready = all_far
        for k in range(n_pairs):
            r_k = 0.0
            if law == LAW_EXPONENTIAL:
                # distance (in alpha * gap) to where the force becomes significant for the step control
                excess = alpha * gap[k] - significant_exponent
                excess = max(excess, 0.0)
                weight = math.sqrt(force[k] / force_scale) / step_accuracy
                toe = 1.0 / (step_reach + excess)
                if weight >= toe:
                    # the force matters: resolve its rate of change, and keep every kept mode's
                    # phase advance per step below one radian (kicks at omega dt near pi resonate)
                    r_k = max(aeff[k] * abs(gap_rate[k]) * weight, omega_max)
                else:
                    # small force: limit the change of alpha * gap per step by a bound on the gap
                    # speed over the step (the momentary rate may vanish at a turning point)
                    if not bounds_ready:
                        _flush(v, left, right, rod_first, pending)
                        _bounds(modes, inverse_omega, bodies, pairs, bounds, amp_left, amp_right)
                        bounds_ready = True
                    # largest dt with alpha_eff (|dr/dt| dt + accel_bound dt^2 / 2) <= reach + excess:
                    # the momentary rate plus a rigorous bound on how fast it can change
                    room = step_reach + excess
                    ar = aeff[k] * abs(gap_rate[k])
                    r_k = excursion * (ar + math.sqrt(ar * ar + 2.0 * aeff[k] * accel_bound[k] * room)) / (2.0 * room)
            osc = math.sqrt(max(keff[k], 0.0) * pair_inverse_mass[k]) / step_accuracy
            if law == LAW_LINEAR:
                # the stiffness it will have once touching
                if stiffness == math.inf:
                    series = 1.0 / pair_compliance[k]
                else:
                    series = 1.0 / (1.0 / stiffness + pair_compliance[k])
                osc = math.sqrt(series * pair_inverse_mass[k]) / step_accuracy
            r_k = max(r_k, osc)
            rate = max(rate, r_k)
        dt = dt_top if rate * dt_top <= 1.0 else 1.0 / rate
        if all_far and dt_free / excursion > dt:
            dt = min(dt_free / excursion, dt_top)
        level = int(math.ceil(math.log(dt_top / dt) / log_ratio - 1e-12))  # noqa: RUF046 (numba)
        level = max(level, 0)
        if level >= n_levels:
            _flush(v, left, right, rod_first, pending)
            return STATUS_STEP_UNDERFLOW
        dt = dt_top * math.exp(-level * log_ratio)
        # one step = a composition of Strang substeps (one for order 2, the triple jump for order 4)
        for sub in range(sub_index.size):
            kind = sub_index[sub]
            dt_sub = sub_weight[sub] * dt
            h = 0.5 * dt_sub
            _kick_deferred(U, mass, pair_a, pair_b, force, h, rod_products, sums, pending)
            _rotate(q, v, left, right, rod_first, cos_table[kind, level], sin_table[kind, level],
                    omega_sin_table[kind, level], sums, pending)
            for i in range(n_rods):
                X[i] += U[i] * dt_sub
            clock[0] += dt_sub
            _pair_state(X, U, half, sums, pair_a, pair_b, pair_offset, gap, gap_rate)
            if not _update_forces(gap, law, alpha, strength, stiffness, pair_compliance, force, keff, aeff, generic_law):
                _flush(v, left, right, rod_first, pending)
                return STATUS_NOT_FINITE
            _kick_deferred(U, mass, pair_a, pair_b, force, h, rod_products, sums, pending)
            _pair_state(X, U, half, sums, pair_a, pair_b, pair_offset, gap, gap_rate)
        counters[0] += 1
        steps_here += 1
        if history is not None and recording and episode[0] >= 0:  # only the episode's own pair is recorded
            n = counters[2]
            ep = episode[0]
            history[n, 0] = clock[0]
            history[n, 1] = U[pair_b[ep]] - U[pair_a[ep]]
            history[n, 2] = force[ep]
            counters[2] = n + 1

@kernel(error_model="numpy")
def rotation_tables(omega, dt_top, ladder_ratio, levels, fractions):
    """Rotation coefficients of every substep fraction ``f`` on every ladder rung.

    ``cos(omega f dt_j)``, ``sin(omega f dt_j) / omega`` and ``omega sin(omega f dt_j)``
    for ``dt_j = dt_top * ladder_ratio**-j``; arrays of shape (F, levels, M).
    """
    shape = (fractions.size, levels, omega.size)
    cos_table = np.empty(shape)
    sin_table = np.empty(shape)
    omega_sin_table = np.empty(shape)
    for f in range(fractions.size):
        for lev in range(levels):
            dt = fractions[f] * dt_top * ladder_ratio ** (-lev)
            for j in range(omega.size):
                sine = math.sin(omega[j] * dt)
                cos_table[f, lev, j] = math.cos(omega[j] * dt)
                sin_table[f, lev, j] = sine / omega[j]
                omega_sin_table[f, lev, j] = omega[j] * sine
    return cos_table, sin_table, omega_sin_table


def composition(order):
    """Substeps of one step: ``(fractions, sub_index, sub_weight)`` for order 2 or 4.

    Order 4 is the symmetric triple jump ``S(w1 h) S(w0 h) S(w1 h)`` with
    ``w1 = 1 / (2 - 2^(1/3))``, ``w0 = 1 - 2 w1`` (Yoshida 1990).
    """
    if order == 2:
        return np.array([1.0]), np.array([0], dtype=np.int64), np.array([1.0])
    if order == 4:
        w1 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
        w0 = 1.0 - 2.0 * w1
        return np.array([w1, w0]), np.array([0, 1, 0], dtype=np.int64), np.array([w1, w0, w1])
    raise ValueError(f"order must be 2 or 4, got {order!r}")
