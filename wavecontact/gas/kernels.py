"""Event-driven kernels of the rod gas: an indexed binary heap of neighbour-pair collision times.

In one dimension only neighbours meet, so the gas has one event per
neighbour pair (N on a ring; N + 1 between walls, the walls counting as
fixed partners).  Each collision changes the velocities of two rods and
therefore the predicted times of at most three events; they are re-keyed in
the heap in ``O(log N)``.  Rods are advanced lazily: a rod's position,
velocity and bath temperature refer to its own clock ``local_time`` and are
brought forward only when it collides (free flight is exact).

Conventions (units: rod density, cross-section and wave speed 1, so a rod's
mass equals its length; energies in the unit of ``mass * velocity^2``):

* ring events ``k = 0..N-1`` are the pairs ``(k, k+1 mod N)``; the pair
  ``(N-1, 0)`` sees rod 0 shifted by the circumference;
* wall events ``k = 0..N``: ``k = 0`` is the left wall (at 0) with rod 0,
  ``k = N`` rod ``N-1`` with the right wall (at ``box``), the others the
  pairs ``(k-1, k)``;
* ``reach[k]`` is the centre distance at contact of event ``k``.

All functions take plain arrays and go through :func:`wavecontact._jit.kernel`.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel

__all__ = [
    "RULE_EXTERNAL",
    "RULE_FIXED",
    "RULE_TABLE",
    "STATUS_COLLAPSE",
    "STATUS_COOLED",
    "STATUS_DONE",
    "STATUS_NEED_DRAW",
    "STATUS_NO_EVENTS",
    "STATUS_TIME_LIMIT",
    "build_heap",
    "event_time",
    "run_events",
]

RULE_FIXED, RULE_TABLE, RULE_EXTERNAL = 0, 1, 2
STATUS_DONE, STATUS_TIME_LIMIT, STATUS_NEED_DRAW, STATUS_COLLAPSE, STATUS_NO_EVENTS, STATUS_COOLED = 0, 1, 2, 3, 4, 5

# indices into the float64 ``scalars`` array
T_NOW, KINETIC, LOST, DISSIPATED, MOMENTUM_ENERGY, ENERGY_FLOOR, KINETIC_CARRY, KINETIC_REFERENCE = range(8)
# indices into the int64 ``counters`` array
COLLISIONS, WALL_HITS, RATIO_CLAMPED, BATH_LIMITED = 0, 1, 2, 3


@kernel
def event_time(k, now, x, v, local_time, reach, ring, box):
    """Predicted time of event ``k`` seen from time ``now`` (``inf``: the partners separate)."""
    n = x.size
    if ring:
        i = k
        j = k + 1
        offset = 0.0
        if j == n:
            j = 0
            offset = box
    else:
        if k == 0:
            if v[0] >= 0.0:
                return math.inf
            gap = x[0] + v[0] * (now - local_time[0]) - reach[0]
            return now + max(gap, 0.0) / (-v[0])
        if k == n:
            if v[n - 1] <= 0.0:
                return math.inf
            gap = box - reach[n] - (x[n - 1] + v[n - 1] * (now - local_time[n - 1]))
            return now + max(gap, 0.0) / v[n - 1]
        i = k - 1
        j = k
        offset = 0.0
    approach = v[i] - v[j]
    if approach <= 0.0:
        return math.inf
    gap = (x[j] + v[j] * (now - local_time[j]) + offset) - (x[i] + v[i] * (now - local_time[i])) - reach[k]
    return now + max(gap, 0.0) / approach


@kernel
def _sift_up(heap, heap_time, slot, p):
    item = heap[p]
    t = heap_time[p]
    while p > 0:
        parent = (p - 1) >> 1
        other = heap[parent]
        tp = heap_time[parent]
        if tp < t or (tp == t and other < item):
            break
        heap[p] = other
        heap_time[p] = tp
        slot[other] = p
        p = parent
    heap[p] = item
    heap_time[p] = t
    slot[item] = p


@kernel
def _sift_down(heap, heap_time, slot, p):
    size = heap.size
    item = heap[p]
    t = heap_time[p]
    while True:
        child = 2 * p + 1
        if child >= size:
            break
        best = heap[child]
        tb = heap_time[child]
        right = child + 1
        if right < size:
            tr = heap_time[right]
            if tr < tb or (tr == tb and heap[right] < best):
                child = right
                best = heap[right]
                tb = tr
        if t < tb or (t == tb and item < best):
            break
        heap[p] = best
        heap_time[p] = tb
        slot[best] = p
        p = child
    heap[p] = item
    heap_time[p] = t
    slot[item] = p


@kernel
def _rekey(heap, heap_time, slot, k, t):
    p = slot[k]
    old = heap_time[p]
    heap_time[p] = t
    if t < old:
        _sift_up(heap, heap_time, slot, p)
    elif t > old:
        _sift_down(heap, heap_time, slot, p)


@kernel
def build_heap(key, heap, heap_time, slot):
    """Fill ``heap``/``heap_time``/``slot`` with a min-heap of the event times ``key`` (ties by event index).

    ``heap[p]`` is the event at heap position ``p``, ``heap_time[p]`` its
    time (kept beside it for locality) and ``slot[k]`` the position of event ``k``.
    """
    m = key.size
    for k in range(m):
        heap[k] = k
        heap_time[k] = key[k]
        slot[k] = k
    for p in range(m // 2 - 1, -1, -1):
        _sift_down(heap, heap_time, slot, p)


@kernel
def _advance(i, t, x, v, local_time, temperature, decay_rate, bath_modes, scalars):
    """Bring rod ``i`` to time ``t``: free flight, and its bath relaxing at ``decay_rate``."""
    dt = t - local_time[i]
    x[i] += v[i] * dt
    local_time[i] = t
    if decay_rate > 0.0 and dt > 0.0:
        cooled = temperature[i] * math.exp(-decay_rate * dt)
        scalars[DISSIPATED] += bath_modes * (temperature[i] - cooled)
        temperature[i] = cooled


@kernel
def _lookup(table_ratio, ratio, counters):
    """Lower grid index and weight of ``ratio``; beyond the grid it is held at the last point (counted)."""
    r = table_ratio.size
    if r == 1:
        return 0, 0.0
    if ratio >= table_ratio[r - 1]:
        if ratio > table_ratio[r - 1]:
            counters[RATIO_CLAMPED] += 1
        return r - 2, 1.0
    lo = 0
    hi = r - 1
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if table_ratio[mid] <= ratio:
            lo = mid
        else:
            hi = mid
    return lo, (ratio - table_ratio[lo]) / (table_ratio[lo + 1] - table_ratio[lo])


@kernel
def _table_draw(u, ig, wg, ir, wr, probability, uniform_levels, quantiles, share):
    """eps^2 at level ``u`` and the short rod's share, bilinear between the four corner quantile functions."""
    levels = probability.size
    lo = 0
    hi = levels - 1
    if uniform_levels:
        lo = min(int(u * hi), hi - 1)
        hi = lo + 1
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if probability[mid] <= u:
            lo = mid
        else:
            hi = mid
    wu = min(max((u - probability[lo]) / (probability[lo + 1] - probability[lo]), 0.0), 1.0)
    g1 = min(ig + 1, quantiles.shape[0] - 1)
    r1 = min(ir + 1, quantiles.shape[1] - 1)
    q00 = (1.0 - wu) * quantiles[ig, ir, lo] + wu * quantiles[ig, ir, lo + 1]
    q01 = (1.0 - wu) * quantiles[ig, r1, lo] + wu * quantiles[ig, r1, lo + 1]
    q10 = (1.0 - wu) * quantiles[g1, ir, lo] + wu * quantiles[g1, ir, lo + 1]
    q11 = (1.0 - wu) * quantiles[g1, r1, lo] + wu * quantiles[g1, r1, lo + 1]
    eps2 = (1.0 - wg) * ((1.0 - wr) * q00 + wr * q01) + wg * ((1.0 - wr) * q10 + wr * q11)
    s = (1.0 - wg) * ((1.0 - wr) * share[ig, ir] + wr * share[ig, r1]) + wg * (
        (1.0 - wr) * share[g1, ir] + wr * share[g1, r1]
    )
    return eps2, s


@kernel
def _recount_kinetic(v, mass, ring, scalars):
    """Recompute the kinetic energy from the velocities (O(N)).

    The running sum of the collision losses carries an error of about 1e-16
    of the energy it started from, so once the energy has decayed a
    millionfold it is recounted: each decay by 10^6 costs one pass over the rods.
    """
    kinetic = 0.0
    momentum = 0.0
    total = 0.0
    for i in range(v.size):
        kinetic += 0.5 * mass[i] * v[i] * v[i]
        momentum += mass[i] * v[i]
        total += mass[i]
    scalars[KINETIC] = kinetic
    scalars[KINETIC_CARRY] = 0.0
    scalars[MOMENTUM_ENERGY] = momentum * momentum / (2.0 * total) if ring else 0.0
    scalars[KINETIC_REFERENCE] = kinetic


@kernel
def run_events(
    x, v, local_time, temperature, mass, reach, pair_gamma_index, pair_gamma_weight, left_is_short,
    heap, heap_time, slot, ring, box,
    rule, restitution_squared, table_ratio, probability, uniform_levels, quantiles, share, bath_modes, decay_rate,
    uniforms, pending, max_collisions, time_limit,
    window, collapse_factor, scalars, counters,
):
    """Process events until ``max_collisions`` rod-rod collisions, a stop condition, or a needed draw.

    Parameters
    ----------
    x, v, local_time, temperature, mass : ndarray, shape (N,)
        Rod centres at their own clocks, velocities, clocks, bath
        temperatures (energy per bath mode) and masses; updated in place.
    reach : ndarray
        Centre distance at contact of each event.
    pair_gamma_index, pair_gamma_weight : ndarray
        Per event, the lower gamma-grid index and weight of the pair's
        length ratio (table rule).
    left_is_short : ndarray of bool
        Per event, whether the left rod of the pair is the shorter one.
    heap, heap_time, slot : ndarray
        The indexed heap of event times (see :func:`build_heap`; updated in place).
    ring : bool
        Periodic ring (True) or box with elastic walls (False).
    box : float
        Circumference or box length.
    rule : int
        :data:`RULE_FIXED`, :data:`RULE_TABLE` or :data:`RULE_EXTERNAL`.
    restitution_squared : float
        eps^2 of the fixed rule.
    table_ratio, probability, quantiles, share : ndarray
        The restitution table's arrays (:meth:`RestitutionTable.arrays`).
    uniform_levels : bool
        Whether ``probability`` is ``linspace(0, 1, P)`` exactly (then the
        level is found by one multiplication instead of a search).
    bath_modes : float
        Modes per rod: a bath at temperature T holds ``bath_modes * T``.
    decay_rate : float
        ``1 / tau_diss`` (0: no bath dissipation).
    uniforms : ndarray
        Levels in [0, 1), one per collision of the table rule.
    pending : ndarray, shape (3,)
        ``(flag, eps2, share)`` supplied by the caller for the external rule.
    max_collisions : int
        Rod-rod collisions to process in this call.
    time_limit : float
        Stop before any event later than this.
    window : ndarray, shape (2 W,)
        Times of the last ``2 W`` collisions (ring buffer; ``2 W`` a power of two).
    collapse_factor : float
        Collapse when the last ``W`` collisions took less than
        ``collapse_factor`` times the time the ``W`` before them took.
    scalars, counters : ndarray
        Running clock and energies, and counters (see the module constants).
        The run stops (``STATUS_COOLED``) once the kinetic energy in the
        centre-of-mass frame falls below ``scalars[ENERGY_FLOOR]``.

    Returns
    -------
    status : int
        One of the ``STATUS_*`` constants.
    event : int
        The event awaiting an external draw (``STATUS_NEED_DRAW``), else -1.
    done : int
        Rod-rod collisions processed in this call.
    """
    n = x.size
    events = heap.size
    done = 0
    while done < max_collisions:
        k = heap[0]
        t = heap_time[0]
        if t == math.inf:
            # on a ring this means all velocities are equal: the gas has merged into one block. If the
            # collisions before were accelerating, that is the end of a collapse lost in the rounding.
            count = counters[COLLISIONS]
            size = window.size
            half = (min(count, size) - 1) // 2
            if ring and half >= 2:
                last = window[(count - 1) & (size - 1)]
                middle = window[(count - half - 1) & (size - 1)]
                if last - middle < middle - window[(count - 2 * half - 1) & (size - 1)]:
                    return STATUS_COLLAPSE, -1, done
            return STATUS_NO_EVENTS, -1, done
        if t > time_limit:
            return STATUS_TIME_LIMIT, -1, done
        if not ring and (k == 0 or k == n):
            rod = 0 if k == 0 else n - 1
            _advance(rod, t, x, v, local_time, temperature, decay_rate, bath_modes, scalars)
            v[rod] = -v[rod]
            scalars[T_NOW] = t
            counters[WALL_HITS] += 1
            _rekey(heap, heap_time, slot, k, math.inf)
            neighbour = 1 if k == 0 else n - 1  # the rod's other event (a pair, or the far wall if N = 1)
            _rekey(heap, heap_time, slot, neighbour, event_time(neighbour, t, x, v, local_time, reach, ring, box))
            continue
        if ring:
            i = k
            j = k + 1 if k + 1 < n else 0
        else:
            i = k - 1
            j = k
        if rule == RULE_EXTERNAL and pending[0] == 0.0:
            return STATUS_NEED_DRAW, k, done
        _advance(i, t, x, v, local_time, temperature, decay_rate, bath_modes, scalars)
        _advance(j, t, x, v, local_time, temperature, decay_rate, bath_modes, scalars)
        mi = mass[i]
        mj = mass[j]
        total = mi + mj
        approach = v[i] - v[j]
        reduced = mi * mj / total
        e_tr = 0.5 * reduced * approach * approach
        if left_is_short[k]:
            short = i
            long = j
        else:
            short = j
            long = i
        if rule == RULE_FIXED:
            eps2 = restitution_squared
            s = 0.0
        elif rule == RULE_TABLE:
            pair_temperature = 0.5 * (temperature[i] + temperature[j])
            ratio = pair_temperature / e_tr if e_tr > 0.0 else math.inf
            ir, wr = _lookup(table_ratio, ratio, counters)
            eps2, s = _table_draw(uniforms[done], pair_gamma_index[k], pair_gamma_weight[k], ir, wr,
                                  probability, uniform_levels, quantiles, share)
        else:
            eps2 = pending[1]
            s = pending[2]
            pending[0] = 0.0
        lost = (1.0 - eps2) * e_tr
        if rule != RULE_FIXED and lost < 0.0:
            # energy returned from the baths cannot exceed what they hold
            floor = 0.0
            if s > 0.0:
                floor = -bath_modes * temperature[short] / s
            if s < 1.0:
                other = -bath_modes * temperature[long] / (1.0 - s)
                if s <= 0.0 or other > floor:
                    floor = other
            if lost < floor:
                lost = floor
                eps2 = 1.0 - lost / e_tr
                counters[BATH_LIMITED] += 1
        if rule == RULE_FIXED:
            scalars[LOST] += lost
        else:
            temperature[short] += s * lost / bath_modes
            temperature[long] += (1.0 - s) * lost / bath_modes
        # compensated (Kahan) sum: the kinetic energy stays accurate relative to itself while it decays
        # by many orders of magnitude (plain sums would keep an error of 1e-16 of the initial energy)
        change = -lost - scalars[KINETIC_CARRY]
        kinetic = scalars[KINETIC] + change
        scalars[KINETIC_CARRY] = (kinetic - scalars[KINETIC]) - change
        scalars[KINETIC] = kinetic
        centre = (mi * v[i] + mj * v[j]) / total
        after = math.sqrt(eps2) * approach
        v[i] = centre - mj / total * after
        v[j] = centre + mi / total * after
        scalars[T_NOW] = t
        counters[COLLISIONS] += 1
        done += 1
        _rekey(heap, heap_time, slot, k, math.inf)
        before = k - 1
        after_k = k + 1
        if ring:
            if before < 0:
                before = events - 1
            if after_k == events:
                after_k = 0
        if before >= 0 and before != k:
            _rekey(heap, heap_time, slot, before, event_time(before, t, x, v, local_time, reach, ring, box))
        if after_k < events and after_k != k and after_k != before:
            _rekey(heap, heap_time, slot, after_k, event_time(after_k, t, x, v, local_time, reach, ring, box))
        # inelastic collapse: the collisions accelerate geometrically (infinitely many in a finite time).
        # Compare the time taken by the last half of the window with the half before it; in floating
        # point a collapsing cluster ends after a few dozen collisions with exactly equal velocities,
        # which the half-window of 8..16 collisions still sees.
        if scalars[KINETIC] < 1e-6 * scalars[KINETIC_REFERENCE]:
            _recount_kinetic(v, mass, ring, scalars)
        count = counters[COLLISIONS]
        size = window.size  # a power of two: positions by masking instead of a division
        mask = size - 1
        window[(count - 1) & mask] = t
        cooled = scalars[ENERGY_FLOOR] > 0.0 and scalars[KINETIC] - scalars[MOMENTUM_ENERGY] < scalars[ENERGY_FLOOR]
        if count >= size or cooled:
            # inelastic collapse: the collisions accelerate geometrically (infinitely many in a finite
            # time).  Compare the time taken by the last half of the window with the half before it;
            # in floating point a collapsing cluster ends after a few dozen collisions with exactly
            # equal velocities, which a half-window of 16 collisions still sees.  When the energy
            # floor is reached earlier (a small system whose whole thermal energy is the collapsing
            # motion), the same test on the shorter history tells collapse from cooling.
            half = (min(count, size) - 1) // 2  # window[(c - 1) & mask] holds the time of collision c
            if half >= 2:
                middle = window[(count - half - 1) & mask]
                if t - middle < collapse_factor * (middle - window[(count - 2 * half - 1) & mask]):
                    return STATUS_COLLAPSE, k, done
            if cooled:
                return STATUS_COOLED, k, done
    return STATUS_DONE, -1, done


def empty_table():
    """Placeholder table arrays for rules that use none (one grid point, two levels)."""
    return (np.zeros(1), np.array([0.0, 1.0]), np.ones((1, 1, 2)), np.zeros((1, 1)))
