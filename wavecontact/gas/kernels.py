"""Event-driven kernels of the rod gas: a tournament tree of neighbour-pair collision times.

In one dimension only neighbours meet, so the gas has one event per
neighbour pair (N on a ring; N + 1 between walls, the walls counting as
fixed partners).  Each collision changes the velocities of two rods and
therefore the predicted times of at most three events, and these three are
neighbours: they sit on neighbouring leaves of a tournament tree with four
children per node (each node holding the earliest of its children, the
root the next event), so their paths to the root join after a level or two
and one path of ``log4 N`` levels is re-evaluated per collision.  (An indexed
binary heap would re-key the three events separately, each with its own
sift of unpredictable branches.)  Rods are advanced lazily: a rod's position,
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
    "RULE_LAW",
    "RULE_TABLE",
    "STATUS_COLLAPSE",
    "STATUS_COOLED",
    "STATUS_DONE",
    "STATUS_FROZEN",
    "STATUS_NEED_DRAW",
    "STATUS_NO_EVENTS",
    "STATUS_OFF_TABLE",
    "STATUS_TIME_LIMIT",
    "build_tree",
    "collapse_cluster",
    "empty_soft_law",
    "event_time",
    "event_times",
    "resolve_cluster",
    "run_events",
    "tree_size",
]

RULE_FIXED, RULE_TABLE, RULE_EXTERNAL, RULE_LAW = 0, 1, 2, 3
STATUS_DONE, STATUS_TIME_LIMIT, STATUS_NEED_DRAW, STATUS_COLLAPSE, STATUS_NO_EVENTS, STATUS_COOLED = 0, 1, 2, 3, 4, 5
STATUS_OFF_TABLE = 6  # a pair met at a temperature ratio outside the table: the run stops (never clipped)
STATUS_FROZEN = 7  # the collisions accelerate, but only because relative velocities are lost in the rounding
# the collisions accelerated: the caller looks for the cluster (collapse_cluster, compiled only for runs that get
# here) and resumes on a false alarm; _FROZEN: without a cluster the pair's relative velocity is lost in the
# rounding; _MERGED: a ring with no events left (its velocities equal), the largest cluster decides
STATUS_CLUSTER, STATUS_CLUSTER_FROZEN, STATUS_CLUSTER_MERGED = 8, 9, 10
# indices into the float64 ``collapse`` array of :func:`run_events` (the collapse detector's parameters)
COLLAPSE_FACTOR, COLLAPSE_GAP, COLLAPSE_RODS, FROZEN_SPEED, FROZEN_POSITION, COLLAPSE_CLOCK = range(6)
COLLAPSE_PARAMETERS = 6

# indices into the float64 ``scalars`` array
T_NOW, KINETIC, LOST, DISSIPATED, MOMENTUM_ENERGY, ENERGY_FLOOR, KINETIC_CARRY, KINETIC_REFERENCE = range(8)
# indices into the int64 ``counters`` array (OFF_TABLE: for the law rule, the draws below its last row;
# SOFTER: law rule with a contact stiffness, the draws softer than the soft law's softest row; FLOORED: the
# draws whose soft-corrected eps^2 came out negative and was set to 0)
COLLISIONS, WALL_HITS, OFF_TABLE, BATH_LIMITED, SOFTER, FLOORED = 0, 1, 2, 3, 4, 5
COUNTERS = 6


@kernel(inline="always")
def _pair_time(now, xi, vi, ti, xj, vj, tj, offset, reach):
    """Predicted contact time of rods ``i`` (left) and ``j`` (right), each given by its centre ``x``, velocity
    ``v`` and clock ``t`` (``offset``: the circumference when ``j`` sits across the ring's seam)."""
    gap = (xj + vj * (now - tj) + offset) - (xi + vi * (now - ti)) - reach
    return _closing_time(now, gap, vi - vj)


@kernel(inline="always")
def _closing_time(now, gap, approach):
    """Contact time of a pair at distance ``gap`` (beyond contact) at time ``now`` closing in at ``approach``."""
    # whether the pair closes in is random from one call to the next: selects instead of a branch
    closing = approach > 0.0
    when = now + max(gap, 0.0) / (approach if closing else 1.0)
    return when if closing else math.inf


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
    return _pair_time(now, x[i], v[i], local_time[i], x[j], v[j], local_time[j], offset, reach[k])


@kernel
def event_times(now, x, v, local_time, reach, ring, box, out):
    """Fill ``out[k]`` with :func:`event_time` of every event ``k`` (the set-up of a run, one call)."""
    for k in range(out.size):
        out[k] = event_time(k, now, x, v, local_time, reach, ring, box)


def tree_size(events):
    """Length of the tree arrays for ``events`` events: twice the power of four at or above ``events`` (and 16)."""
    leaves = 16  # at least two levels below the root (:func:`_pull_triple` updates two levels unconditionally)
    while leaves < events:
        leaves *= 4
    return 2 * leaves


@kernel(inline="always")
def _pull(tree_time, tree_event, p):
    """Node ``p`` takes the earliest of its four children (ties: the leftmost, which holds the lowest events);
    returns its new ``(time, event)``.  Written as two pairs and their final (selects, no branches)."""
    c = p << 2
    t0 = tree_time[c]
    t1 = tree_time[c + 1]
    t2 = tree_time[c + 2]
    t3 = tree_time[c + 3]
    e0 = tree_event[c]
    e1 = tree_event[c + 1]
    e2 = tree_event[c + 2]
    e3 = tree_event[c + 3]
    ea = e1 if t1 < t0 else e0
    ta = min(t0, t1)
    eb = e3 if t3 < t2 else e2
    tb = min(t2, t3)
    e = eb if tb < ta else ea
    t = min(ta, tb)
    tree_time[p] = t
    tree_event[p] = e
    return t, e


@kernel(inline="always")
def _climb(tree_time, tree_event, p):
    """Re-evaluate the ancestors of node ``p`` (whose own entry is right); returns the root ``(time, event)``."""
    return _climb_from(tree_time, tree_event, p, tree_time[p], tree_event[p])


@kernel(inline="always")
def _climb_from(tree_time, tree_event, p, t, e):
    """Re-evaluate the ancestors of node ``p``, which holds ``(t, e)``, carrying the winner in registers.

    Each level first finds the earliest of the other three children of
    ``p``'s parent (sibling subtrees that did not change, so their loads and
    comparisons need not wait for the carried winner), then compares that
    one with the carried winner: the chain of dependent steps from the
    leaves to the root is one comparison per level, ``log4 M`` of them.  Comparisons order by ``(time, event)``, which is the tie rule of
    the tree (ties to the lower event); they are written as selects
    (conditional moves), not branches that the processor would mispredict.
    Returns the root's ``(time, event)``, so that the next collision need not read it back from memory.
    """
    while p > 1:
        # the siblings of p: its partner in its pair, and the other pair of the group of four (indices
        # computed rather than the carried child masked: a mask on p's position became a branch on it)
        partner = p ^ 1
        pair = (p & ~3) | ((p & 2) ^ 2)
        partner_time = tree_time[partner]
        partner_event = tree_event[partner]
        pair_time = tree_time[pair]
        pair_event = tree_event[pair]
        pair_time_1 = tree_time[pair + 1]
        pair_event_1 = tree_event[pair + 1]
        pair_event = pair_event_1 if pair_time_1 < pair_time else pair_event  # ties: the lower (left) event
        pair_time = min(pair_time, pair_time_1)
        take = (pair_time < partner_time) | ((pair_time == partner_time) & (pair_event < partner_event))
        sibling_event = pair_event if take else partner_event
        sibling_time = min(partner_time, pair_time)
        take = (sibling_time < t) | ((sibling_time == t) & (sibling_event < e))
        e = sibling_event if take else e
        t = min(t, sibling_time)
        p >>= 2
        tree_time[p] = t
        tree_event[p] = e
    return t, e


@kernel(inline="always")
def _pull_range(tree_time, tree_event, lo, hi):
    """Recompute every ancestor of the leaves of events ``lo..hi`` (their times already set), up to the root;
    returns the root's ``(time, event)``."""
    leaves = tree_time.size >> 1
    return _pull_nodes(tree_time, tree_event, lo + leaves, hi + leaves)


@kernel(inline="always")
def _pull_nodes(tree_time, tree_event, lo, hi):
    """Recompute every ancestor of the nodes ``lo..hi`` of one level (themselves right), up to the root."""
    while lo != hi:
        lo >>= 2
        hi >>= 2
        for p in range(lo, hi + 1):
            _pull(tree_time, tree_event, p)
    return _climb(tree_time, tree_event, lo)


@kernel(inline="always")
def _pull_triple(tree_time, tree_event, leaf):
    """Recompute the ancestors of the leaves ``leaf - 1`` to ``leaf + 1`` (their times already set), up to the
    root; returns the root's ``(time, event)``.

    Their parents are one node or two neighbours, and so are the grandparents
    (two only when the triple straddles a boundary of 16 leaves): the two
    lowest levels update both nodes unconditionally (the same node twice when
    they coincide), then the winner is carried up in registers.  No branch
    depends on where the triple lies, except the rare straddle.
    """
    lo = (leaf - 1) >> 2
    hi = (leaf + 1) >> 2
    _pull(tree_time, tree_event, lo)
    _pull(tree_time, tree_event, hi)
    lo >>= 2
    hi >>= 2
    _pull(tree_time, tree_event, lo)
    t, e = _pull(tree_time, tree_event, hi)
    if lo != hi:
        _pull_span(tree_time, tree_event, np.int64(lo), np.int64(hi))
        return tree_time[1], tree_event[1]
    return _climb_from(tree_time, tree_event, lo, t, e)


@kernel
def _pull_span(tree_time, tree_event, lo, hi):
    """:func:`_pull_nodes` called rather than inlined (nodes ``lo..hi`` of one level, int64), for the rarer
    updates: events at a wall or the ring's seam, a triple straddling two grandparents.

    Each inlined copy of the climb to the root made the event loop's compilation longer by about 0.7 s
    (seven copies: 12.5 s of compile CPU for the loop and its callees, 6.7 s with these calls; on a ring
    of 2000 rods and 2e6 collisions no slower)."""
    _pull_nodes(tree_time, tree_event, lo, hi)


@kernel
def build_tree(key, tree_time, tree_event):
    """Fill a tournament tree of the event times ``key``: the root holds the earliest (ties: the lowest event).

    Every node has four children.  The arrays have length ``2 M``
    (:func:`tree_size`, ``M`` a power of four); leaf ``M + k`` holds the time
    of event ``k`` (``inf`` for the padding beyond ``key.size``), node ``p``
    the earliest of nodes ``4 p`` to ``4 p + 3`` (time in ``tree_time``,
    event in ``tree_event``).  Node 1 is the root; the levels are the index
    ranges ``[4^l, 2 4^l)``, and the indices between them (and 0) are unused
    (``inf``, event -1).  The siblings of a node are the aligned group of four
    entries around it (one 32-byte block).  Changing the times of a few
    neighbouring events re-evaluates their common path to the root once
    (:func:`_pull_range`), ``log4 M`` levels: half the depth of a binary tree,
    for a few more comparisons per level that do not wait for each other.
    """
    leaves = tree_time.size >> 1
    for p in range(leaves):
        tree_time[p] = math.inf
        tree_event[p] = -1
    for k in range(leaves):
        tree_time[leaves + k] = key[k] if k < key.size else math.inf
        tree_event[leaves + k] = k
    level = leaves
    while level > 1:
        level >>= 2
        for p in range(level, 2 * level):
            _pull(tree_time, tree_event, p)


@kernel(inline="always")
def _advance(i, t, x, v, local_time):
    """Bring rod ``i`` to time ``t`` (free flight); returns the time it flew and its new centre.

    Branch-free, so that numba's reference counts of the arrays cancel when
    it is inlined; the bath's relaxation is :func:`_relax_bath`, called only
    when there is damping.
    """
    dt = t - local_time[i]
    moved = x[i] + v[i] * dt
    x[i] = moved
    local_time[i] = t
    return dt, moved


@kernel
def _relax_bath(i, dt, temperature, decay_rate, bath_modes, scalars):
    """Rod ``i``'s bath relaxing at ``decay_rate`` for a time ``dt`` (its energy counted as dissipated)."""
    if dt > 0.0:
        cooled = temperature[i] * math.exp(-decay_rate * dt)
        scalars[DISSIPATED] += bath_modes * (temperature[i] - cooled)
        temperature[i] = cooled


@kernel
def _bracket(grid, value):
    """Largest ``i`` in ``0`` to ``grid.size - 2`` with ``grid[i] <= value`` (0 if none), for an ascending ``grid``.

    A binary search whose steps are selects rather than branches (the
    outcome of each comparison is random from one collision to the next, so
    a branch would be mispredicted half of the time).
    """
    base = 0
    n = grid.size - 1
    while n > 1:
        half = n >> 1
        base = base + half if grid[base + half] <= value else base
        n -= half
    return base


@kernel
def _lookup(table_ratio, ratio):
    """Lower grid index and weight of ``ratio``; index -1 when it lies outside the grid (refused)."""
    r = table_ratio.size
    if not (table_ratio[0] <= ratio <= table_ratio[r - 1]):
        return -1, 0.0
    if r == 1:
        return 0, 0.0
    if ratio == table_ratio[r - 1]:
        return r - 2, 1.0
    lo = _bracket(table_ratio, ratio)
    return lo, (ratio - table_ratio[lo]) / (table_ratio[lo + 1] - table_ratio[lo])


@kernel
def _table_draw(u, ig, wg, ir, wr, i_s, ws, probability, uniform_levels, quantiles, share, per_level):
    """eps^2 at level ``u`` and the short rod's share (``share[..., 0]``) or, ``per_level``, its gain at level
    ``u`` (``share`` holds one value per level), trilinear between the eight corner quantile functions of the
    ``(gamma, ratio, short-rod share)`` grid (arrays of shape ``(G, R, S, P)``; ``S = 1``: no share axis)."""
    if uniform_levels:
        top = probability.size - 1
        lo = min(int(u * top), top - 1)
    else:
        lo = _bracket(probability, u)
    wu = min(max((u - probability[lo]) / (probability[lo + 1] - probability[lo]), 0.0), 1.0)
    g1 = min(ig + 1, quantiles.shape[0] - 1)
    r1 = min(ir + 1, quantiles.shape[1] - 1)
    s1 = min(i_s + 1, quantiles.shape[2] - 1)
    eps2 = (1.0 - ws) * _bilinear(quantiles, ig, g1, wg, ir, r1, wr, i_s, lo, wu) + ws * _bilinear(
        quantiles, ig, g1, wg, ir, r1, wr, s1, lo, wu)
    if per_level:
        gain = (1.0 - ws) * _bilinear(share, ig, g1, wg, ir, r1, wr, i_s, lo, wu) + ws * _bilinear(
            share, ig, g1, wg, ir, r1, wr, s1, lo, wu)
    else:  # one share per grid point (a restitution table: no share axis, S = 1)
        gain = (1.0 - wg) * ((1.0 - wr) * share[ig, ir, 0, 0] + wr * share[ig, r1, 0, 0]) + wg * (
            (1.0 - wr) * share[g1, ir, 0, 0] + wr * share[g1, r1, 0, 0])
    return eps2, gain


@kernel
def _bilinear(array, ig, g1, wg, ir, r1, wr, c, lo, wu):
    """``array[:, :, c]`` linear in the level (``lo``, ``wu``) and bilinear in the first two axes."""
    q00 = (1.0 - wu) * array[ig, ir, c, lo] + wu * array[ig, ir, c, lo + 1]
    q01 = (1.0 - wu) * array[ig, r1, c, lo] + wu * array[ig, r1, c, lo + 1]
    q10 = (1.0 - wu) * array[g1, ir, c, lo] + wu * array[g1, ir, c, lo + 1]
    q11 = (1.0 - wu) * array[g1, r1, c, lo] + wu * array[g1, r1, c, lo + 1]
    return (1.0 - wg) * ((1.0 - wr) * q00 + wr * q01) + wg * ((1.0 - wr) * q10 + wr * q11)


@kernel
def _law_point(log_x, short_share, log_x_grid, share_grid):
    """``(below, ix, wx, i_s, ws)``: grid cell of a pair in a collision law; below its last row (``below``)
    that row's law is used."""
    below = log_x < log_x_grid[0]
    ix, wx = 0, 0.0
    if not below:
        ix, wx = _lookup(log_x_grid, log_x)
    i_s, ws = 0, 0.0
    if share_grid.size > 1:
        i_s, ws = _lookup(share_grid, short_share)
    return below, ix, wx, i_s, ws


@kernel
def _soft_draw(u, gamma, kappa, log_x, short_share, eps2_hard, gain_hard, soft):
    """The hard-core draw plus the soft law's correction at this collision's ``kappa`` (same level ``u``).

    ``soft``: the soft law's ``(kappa, gamma, log_x, share, probability, d_eps2, d_gain)``
    (:meth:`VibrationLaw.soft_arrays`); ``d_eps2``, ``d_gain``: per kappa row, the soft law minus the hard-core law on the soft law's
    grid (:func:`wavecontact.gas.collision_law.soft_corrections`), interpolated linearly in
    ``z = ln(kappa)/kappa`` between the rows and, above the stiffest, between it and zero (the hard core);
    below the softest row that row's correction.  Returns ``(eps2, gain, softer, below, floored)``:
    ``softer`` when ``kappa`` lies below the softest row, ``below`` when the pair lies below the soft law's
    last ``x`` row, ``floored`` when the corrected ``eps2`` came out negative and was set to 0.
    """
    soft_kappa, soft_gamma, soft_log_x, soft_share, soft_probability, soft_d_eps2, soft_d_gain = soft
    rows = soft_kappa.size
    ig, wg = _lookup(soft_gamma, gamma)
    below, ix, wx, i_s, ws = _law_point(log_x, short_share, soft_log_x, soft_share)
    # the level by a branch-free search (soft draws are a minority; no exactness test); np.bool_ and np.int64 here
    # and below: literal arguments would compile the callee once more for them alone
    uniform = np.bool_(False)
    softer = False
    if kappa <= soft_kappa[0]:
        r = 0
        weight_hi = 0.0
        weight_lo = 1.0
        softer = kappa < soft_kappa[0]
    else:
        z = math.log(kappa) / kappa
        z_last = math.log(soft_kappa[rows - 1]) / soft_kappa[rows - 1]
        if z <= z_last:
            r = rows - 1
            weight_lo = z / z_last
            weight_hi = 0.0
        else:
            r = _bracket(soft_kappa, kappa)
            z_lo = math.log(soft_kappa[r]) / soft_kappa[r]
            z_hi = math.log(soft_kappa[r + 1]) / soft_kappa[r + 1]
            weight_hi = (z_lo - z) / (z_lo - z_hi)
            weight_lo = 1.0 - weight_hi
    d_eps, d_gain = _table_draw(u, ig, wg, ix, wx, i_s, ws, soft_probability, uniform, soft_d_eps2[r],
                                soft_d_gain[r], np.bool_(True))
    d_eps *= weight_lo
    d_gain *= weight_lo
    if weight_hi > 0.0:
        e1, g1 = _table_draw(u, ig, wg, ix, wx, i_s, ws, soft_probability, uniform, soft_d_eps2[r + 1],
                             soft_d_gain[r + 1], np.bool_(True))
        d_eps += weight_hi * e1
        d_gain += weight_hi * g1
    eps2 = eps2_hard + d_eps
    floored = eps2 < 0.0
    return max(eps2, 0.0), gain_hard + d_gain, softer, below, floored


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
def _event_gap(e, now, x, v, local_time, reach, ring, box):
    """Distance beyond contact of the partners of event ``e`` at time ``now`` (a wall counts as a partner)."""
    n = x.size
    if not ring and e == 0:
        return x[0] + v[0] * (now - local_time[0]) - reach[0]
    if not ring and e == n:
        return box - reach[n] - (x[n - 1] + v[n - 1] * (now - local_time[n - 1]))
    i, j, offset = (e, e + 1, 0.0) if ring else (e - 1, e, 0.0)
    if j == n:
        j = 0
        offset = box
    return (x[j] + v[j] * (now - local_time[j]) + offset) - (x[i] + v[i] * (now - local_time[i])) - reach[e]


@kernel
def collapse_cluster(k, now, x, v, local_time, reach, ring, box, gap_floor):
    """The cluster of event ``k``: ``(first, last, members)``, the events ``first`` to ``last`` (cyclic on a ring)
    next to each other whose gaps at time ``now`` all lie below ``gap_floor``, and the bodies they join
    (rods, and a wall that takes part).  ``members`` is 0 when the gap of ``k`` itself does not lie below
    the floor.  ``k < 0``: the largest such cluster anywhere (``O(N)``; ties: the first found).

    Only called when the collisions accelerate, so its cost (the cluster's size) does not enter the loop.
    """
    events = reach.size
    n = x.size
    if k >= 0:
        if not _event_gap(k, now, x, v, local_time, reach, ring, box) < gap_floor:
            return k, k, 0
        first = k
        last = k
        pairs = 1
        while pairs < events:
            e = first - 1
            if e < 0:
                if not ring:
                    break
                e = events - 1
            if not _event_gap(e, now, x, v, local_time, reach, ring, box) < gap_floor:
                break
            first = e
            pairs += 1
        while pairs < events:
            e = last + 1
            if e == events:
                if not ring:
                    break
                e = 0
            if not _event_gap(e, now, x, v, local_time, reach, ring, box) < gap_floor:
                break
            last = e
            pairs += 1
        return first, last, (n if ring and pairs == events else pairs + 1)
    # the largest cluster: scan once around the ring from an event outside every cluster
    start = -1
    for e in range(events):
        if not _event_gap(e, now, x, v, local_time, reach, ring, box) < gap_floor:
            start = e
            break
    if start < 0:
        return 0, events - 1, (n if ring else events + 1)
    best_first, best_last, best = -1, -1, 0
    run = 0
    first = -1
    for m in range(1, events + 1):
        e = (start + m) % events
        if not ring and e == 0:
            run = 0  # the box does not close: no cluster across its two walls
        if _event_gap(e, now, x, v, local_time, reach, ring, box) < gap_floor:
            if run == 0:
                first = e
            run += 1
            if run > best:
                best, best_first, best_last = run, first, e
        else:
            run = 0
    return best_first, best_last, (best + 1 if best > 0 else 0)


def resolve_cluster(status, k, x, v, local_time, reach, ring, box, collapse, scalars):
    """The status a :data:`STATUS_CLUSTER`, :data:`STATUS_CLUSTER_FROZEN` or :data:`STATUS_CLUSTER_MERGED` of
    :func:`run_events` stands for, from the cluster of event ``k`` (:func:`collapse_cluster`, at the clock
    ``scalars[T_NOW]``): :data:`STATUS_COLLAPSE`, :data:`STATUS_FROZEN`, :data:`STATUS_COOLED`, or
    :data:`STATUS_DONE` for a false alarm (call :func:`run_events` again: it resumes where it returned).
    Any other status is returned as it is.

    The decisions are the ones the event loop made inline before (the same comparisons of the same numbers):
    a cluster of at least ``collapse[COLLAPSE_RODS]`` bodies is a collapse; else the pair's relative velocity
    lost in the rounding (``_FROZEN``) is a frozen gas; else a run below its energy floor has cooled.  On a
    ring whose velocities all rounded to equal (``_MERGED``) the largest cluster is a collapse if its rods'
    positions resolve the gap floor, else the gas froze.
    """
    if status not in (STATUS_CLUSTER, STATUS_CLUSTER_FROZEN, STATUS_CLUSTER_MERGED):
        return status
    now = scalars[T_NOW]
    first, last, members = collapse_cluster(np.int64(k), now, x, v, local_time, reach, ring, box,
                                            collapse[COLLAPSE_GAP])
    if status == STATUS_CLUSTER_MERGED:
        if members >= collapse[COLLAPSE_RODS]:
            # the positions must resolve the floor (a rod far out on its unwrapped path cannot)
            n = x.size
            rods = np.arange(first, last + 1 if last >= first else last + 1 + n) % n
            rounding = float(np.max(np.abs(x[rods] + v[rods] * (now - local_time[rods]))))
            if rounding * collapse[FROZEN_POSITION] < collapse[COLLAPSE_GAP]:
                return STATUS_COLLAPSE
        return STATUS_FROZEN
    if members >= collapse[COLLAPSE_RODS]:
        return STATUS_COLLAPSE
    if status == STATUS_CLUSTER_FROZEN:
        return STATUS_FROZEN
    if scalars[ENERGY_FLOOR] > 0.0 and scalars[KINETIC] - scalars[MOMENTUM_ENERGY] < scalars[ENERGY_FLOOR]:
        return STATUS_COOLED
    return STATUS_DONE


@kernel
def _accelerating(window, count, factor, clock):
    """Whether the last half of the window of collision times took less than ``factor`` times its first half
    and no more than ``clock`` times the time itself (the clock's rounding; ``inf``: no such condition), on
    the history there is (at least 2 collisions per half)."""
    size = window.size
    mask = size - 1
    half = (min(count, size) - 1) // 2  # window[(c - 1) & mask] holds the time of collision c
    if half < 2:
        return False
    last = window[(count - 1) & mask]
    middle = window[(count - half - 1) & mask]
    return last - middle < factor * (middle - window[(count - 2 * half - 1) & mask]) and (
        last - middle <= clock * abs(last))


@kernel
def run_events(rods, pairs, tree, ring, box, rule, table, soft, draws, stop, monitor):
    """Process events until ``max_collisions`` rod-rod collisions, a stop condition, or a needed draw.

    Parameters
    ----------
    rods : tuple of 5 ndarray, shape (N,)
        ``(x, v, local_time, temperature, mass)``: rod centres at their own clocks (length), velocities
        (length/time), clocks (time), bath temperatures (energy per bath mode) and masses; updated in place.
    pairs : tuple of 5 ndarray, one entry per event
        ``(reach, gamma, gamma_index, gamma_weight, left_is_short)``: centre distance at contact (length);
        the pair's length ratio and its lower gamma-grid index and weight (table and law rules); whether
        the left rod of the pair is the shorter one.
    tree : tuple of 2 ndarray
        ``(tree_time, tree_event)``: the tournament tree of event times (see :func:`build_tree`; updated in
        place).
    ring : bool
        Periodic ring (True) or box with elastic walls (False).
    box : float
        Circumference or box length.
    rule : tuple
        ``(code, restitution_squared, bath_modes, decay_rate, stiffness, uniform_levels)``:
        :data:`RULE_FIXED`, :data:`RULE_TABLE`, :data:`RULE_EXTERNAL` or :data:`RULE_LAW`; eps^2 of the
        fixed rule; modes per rod (a bath at temperature T holds ``bath_modes * T``); ``1 / tau_diss``
        (0: no bath dissipation); for :data:`RULE_LAW` the contact's ``alpha`` (inverse length), each
        collision having ``kappa = alpha V l`` with ``V`` the approach speed and ``l = 2 l_i l_j / (l_i +
        l_j)`` (``= 2 mu``: masses equal lengths), 0: hard core (``soft`` is not used); whether
        ``probability`` is ``linspace(0, 1, P)`` exactly (then the level is found by one multiplication
        instead of a search).
    table : tuple of 5 ndarray
        ``(ratio, share_grid, probability, quantiles, share)``: the restitution table's arrays
        (:meth:`RestitutionTable.arrays`, ``quantiles`` as ``(G, R, 1, P)``, ``share`` as ``(G, R, 1, 1)``),
        or for :data:`RULE_LAW` the hard-core collision law's (:meth:`CollisionLaw.kernel_arrays`:
        ``log10 x`` grid, short-rod-share grid, levels, eps^2 quantiles and short-rod gains per level,
        ``(G, X, S, P)``).
    soft : tuple of 7 ndarray, or None
        ``(kappa, gamma, log_x, share, probability, quantiles, gains)``: the soft (finite-kappa) collision
        law, its kappa rows, grids, levels, and its corrections to the hard-core law, arrays
        ``(K, G, X, S, P)`` (:meth:`VibrationLaw.soft_arrays`).  None without a contact stiffness: numba
        then compiles a specialisation without the soft law's draw (one for every hard-core rule).
    draws : tuple of 2 ndarray
        ``(uniforms, pending)``: levels in [0, 1), one per collision of the table and law rules; ``(flag,
        eps2, share)`` supplied by the caller for the external rule (shape (3,)).
    stop : tuple
        ``(max_collisions, time_limit)``: rod-rod collisions to process in this call; stop before any
        event later than this time.
    monitor : tuple of 4 ndarray
        ``(window, collapse, scalars, counters)``.  ``window``, shape (2 W,): times of the last ``2 W``
        collisions (ring buffer; ``2 W`` a power of two).  ``collapse``, shape (6,): the collapse
        detector (indices ``COLLAPSE_*``, ``FROZEN_*``).  When the last ``W`` collisions took less than
        ``collapse[COLLAPSE_FACTOR]`` times the time the ``W`` before them took and no more than
        ``collapse[COLLAPSE_CLOCK]`` times the clock (the collisions accelerated until their count
        diverged at the clock's rounding), the run stops as frozen if the pair's relative velocity was at
        most ``collapse[FROZEN_SPEED]`` times the larger of its two speeds, or if
        ``collapse[FROZEN_POSITION]`` times its centres' magnitude (their rounding) reaches
        ``collapse[COLLAPSE_GAP]`` (the relative motion is lost in the rounding); else it returns
        :data:`STATUS_CLUSTER` (or :data:`STATUS_CLUSTER_FROZEN`, :data:`STATUS_CLUSTER_MERGED`) and
        :func:`resolve_cluster` decides: collapsed if the colliding pair's cluster (:func:`collapse_cluster`)
        joins at least ``collapse[COLLAPSE_RODS]`` bodies by gaps below ``collapse[COLLAPSE_GAP]`` (a length);
        else the run goes on (a false alarm: call again).
        ``collapse[COLLAPSE_FACTOR] = 0`` switches the detector off.  ``scalars``, ``counters``: running
        clock and energies, and counters (see the module constants).  The run stops (``STATUS_COOLED``)
        once the kinetic energy in the centre-of-mass frame falls below ``scalars[ENERGY_FLOOR]``.

    Returns
    -------
    status : int
        One of the ``STATUS_*`` constants (``STATUS_CLUSTER*``: pass it to :func:`resolve_cluster`).
    event : int
        The event awaiting an external draw (``STATUS_NEED_DRAW``) or refused
        by the table (``STATUS_OFF_TABLE``), else -1.
    done : int
        Rod-rod collisions processed in this call.
    """
    x, v, local_time, temperature, mass = rods
    reach, pair_gamma, pair_gamma_index, pair_gamma_weight, left_is_short = pairs
    tree_time, tree_event = tree
    code, restitution_squared, bath_modes, decay_rate, stiffness, uniform_levels = rule
    table_ratio, share_grid, probability, quantiles, share = table
    uniforms, pending = draws
    max_collisions, time_limit = stop
    window, collapse, scalars, counters = monitor
    n = x.size
    events = reach.size
    leaves = tree_time.size >> 1
    done = 0
    k = tree_event[1]
    t = tree_time[1]
    # interior events, whose two neighbouring events are pairs of rods next to the collision's (no seam, no wall)
    first_interior, last_interior = (1, n - 3) if ring else (2, n - 2)
    # the running sums in registers (written through to the arrays at every collision, read from here)
    kinetic = scalars[KINETIC]
    carry = scalars[KINETIC_CARRY]
    reference = scalars[KINETIC_REFERENCE]
    momentum_energy = scalars[MOMENTUM_ENERGY]
    energy_floor = scalars[ENERGY_FLOOR]
    lost_total = scalars[LOST]
    count = counters[COLLISIONS]
    while done < max_collisions:
        if t == math.inf:
            # on a ring this means all velocities are equal: the gas has merged into one block. If the
            # collisions before were accelerating, that is the end of a collapse lost in the rounding.
            # A collapse may end so (its cluster's velocities rounded to equal before 16 collisions fell within
            # the clock's rounding): a collapse if a cluster of touching rods is left, else the gas froze.
            count = counters[COLLISIONS]
            if ring and collapse[COLLAPSE_FACTOR] > 0.0 and _accelerating(window, count, 1.0, math.inf):
                return STATUS_CLUSTER_MERGED, -1, done  # collapsed or frozen: the caller's cluster search decides
            return STATUS_NO_EVENTS, -1, done
        if t > time_limit:
            return STATUS_TIME_LIMIT, -1, done
        if not ring and (k == 0 or k == n):
            rod = 0 if k == 0 else n - 1
            dt, _ = _advance(rod, t, x, v, local_time)
            if decay_rate > 0.0:
                _relax_bath(rod, dt, temperature, decay_rate, bath_modes, scalars)
            v[rod] = -v[rod]
            scalars[T_NOW] = t
            counters[WALL_HITS] += 1
            neighbour = 1 if k == 0 else n - 1  # the rod's other event (a pair, or the far wall if N = 1)
            tree_time[leaves + k] = math.inf
            tree_time[leaves + neighbour] = event_time(neighbour, t, x, v, local_time, reach, ring, box)
            _pull_span(tree_time, tree_event, leaves + min(k, neighbour), leaves + max(k, neighbour))
            k = tree_event[1]
            t = tree_time[1]
            continue
        if ring:
            i = k
            j = k + 1 if k + 1 < n else 0
        else:
            i = k - 1
            j = k
        if code == RULE_EXTERNAL and pending[0] == 0.0:
            return STATUS_NEED_DRAW, k, done
        dt_i, x_i = _advance(i, t, x, v, local_time)
        dt_j, x_j = _advance(j, t, x, v, local_time)
        if decay_rate > 0.0:
            _relax_bath(i, dt_i, temperature, decay_rate, bath_modes, scalars)
            _relax_bath(j, dt_j, temperature, decay_rate, bath_modes, scalars)
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
        if code == RULE_FIXED:
            eps2 = restitution_squared
            s = 0.0
        elif code == RULE_TABLE:
            pair_temperature = 0.5 * (temperature[i] + temperature[j])
            ratio = pair_temperature / e_tr if e_tr > 0.0 else math.inf
            ir, wr = _lookup(table_ratio, ratio)
            if ir < 0:
                counters[OFF_TABLE] += 1
                return STATUS_OFF_TABLE, k, done
            eps2, s = _table_draw(uniforms[done], pair_gamma_index[k], pair_gamma_weight[k], ir, wr, np.int64(0), 0.0,
                                  probability, uniform_levels, quantiles, share, np.bool_(False))
        elif code == RULE_LAW:
            # the law in x = E_tr / (E_tr + T_pair) and s = T_short / (T_short + T_long): every pair lies in
            # (0, 1] x [0, 1]; below the last x row that row's law is used (counted); the gain comes in units of
            # E_tr + T_pair
            t_sum = temperature[short] + temperature[long]
            scale = e_tr + 0.5 * t_sum
            log_x = math.log10(e_tr / scale)
            short_share = temperature[short] / t_sum if t_sum > 0.0 else 0.5
            below, ir, wr, i_s, ws = _law_point(log_x, short_share, table_ratio, share_grid)
            eps2, s = _table_draw(uniforms[done], pair_gamma_index[k], pair_gamma_weight[k], ir, wr, i_s, ws,
                                  probability, uniform_levels, quantiles, share, np.bool_(True))
            if soft is not None:  # None (no contact stiffness): numba prunes the soft law's branch at compile time
                kappa = stiffness * approach * 2.0 * reduced  # alpha V l with l = 2 mu (rods of unit density)
                eps2, s, softer, below_soft, floored = _soft_draw(
                    uniforms[done], pair_gamma[k], kappa, log_x, short_share, eps2, s, soft)
                below = below or below_soft
                if softer:
                    counters[SOFTER] += 1
                if floored:
                    counters[FLOORED] += 1
            if below:
                counters[OFF_TABLE] += 1
            s *= scale
        else:
            eps2 = pending[1]
            s = pending[2]
            pending[0] = 0.0
        lost = (1.0 - eps2) * e_tr
        if code == RULE_LAW:
            # s: the short rod's gain, lost - s the long rod's. A bath cannot give more than it holds: the
            # deficit goes to the other bath, and if that one cannot give it either, eps^2 is reduced
            gain_short = s
            gain_long = lost - s
            capped = False
            if bath_modes * temperature[short] + gain_short < 0.0:
                gain_short = -bath_modes * temperature[short]
                gain_long = lost - gain_short
                capped = True
            if bath_modes * temperature[long] + gain_long < 0.0:
                gain_long = -bath_modes * temperature[long]
                gain_short = lost - gain_long
                capped = True
                if bath_modes * temperature[short] + gain_short < 0.0:
                    gain_short = -bath_modes * temperature[short]
                    lost = gain_short + gain_long
                    eps2 = 1.0 - lost / e_tr
            if capped:
                counters[BATH_LIMITED] += 1  # once per draw, so that bath_limited / collisions is a fraction
            temperature[short] = max(temperature[short] + gain_short / bath_modes, 0.0)
            temperature[long] = max(temperature[long] + gain_long / bath_modes, 0.0)
        elif code != RULE_FIXED and lost < 0.0:
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
        elif code != RULE_FIXED and (s < 0.0 or s > 1.0):
            # a per-collision split may take energy from one bath while filling the other
            ceiling = bath_modes * temperature[short] / -s if s < 0.0 else bath_modes * temperature[long] / (s - 1.0)
            if lost > ceiling:
                lost = ceiling
                eps2 = 1.0 - lost / e_tr
                counters[BATH_LIMITED] += 1
        if code == RULE_FIXED:
            lost_total += lost
            scalars[LOST] = lost_total
        elif code != RULE_LAW:
            temperature[short] += s * lost / bath_modes
            temperature[long] += (1.0 - s) * lost / bath_modes
            # a bath emptied by the cap above can end a rounding error below zero: it is empty
            temperature[short] = max(temperature[short], 0.0)
            temperature[long] = max(temperature[long], 0.0)
        # compensated (Kahan) sum: the kinetic energy stays accurate relative to itself while it decays
        # by many orders of magnitude (plain sums would keep an error of 1e-16 of the initial energy)
        change = -lost - carry
        updated = kinetic + change
        carry = (updated - kinetic) - change
        kinetic = updated
        scalars[KINETIC_CARRY] = carry
        scalars[KINETIC] = kinetic
        centre = (mi * v[i] + mj * v[j]) / total
        after = math.sqrt(eps2) * approach
        vi = centre - mj / total * after
        vj = centre + mi / total * after
        v[i] = vi
        v[j] = vj
        scalars[T_NOW] = t
        count += 1
        counters[COLLISIONS] = count
        done += 1
        if first_interior <= k <= last_interior:
            # the usual case: the two new predictions from the centres and velocities still in registers, and
            # one shared path to the root.  Rods i and j are at time t, so event_time's term ``x + v (t - t)``
            # is ``x`` (up to the sign of a zero, which the subtraction of ``reach > 0`` removes): the gaps
            # come out bit for bit as event_time's, but do not wait for the new velocities
            gap_before = x_i - (x[i - 1] + v[i - 1] * (t - local_time[i - 1])) - reach[k - 1]
            gap_after = (x[j + 1] + v[j + 1] * (t - local_time[j + 1])) - x_j - reach[k + 1]
            t_before = _closing_time(t, gap_before, v[i - 1] - vi)
            t_after = _closing_time(t, gap_after, vj - v[j + 1])
            tree_time[leaves + k - 1] = t_before
            tree_time[leaves + k] = math.inf
            tree_time[leaves + k + 1] = t_after
            t_next, k_next = _pull_triple(tree_time, tree_event, leaves + k)
        else:
            tree_time[leaves + k] = math.inf
            before = k - 1
            after_k = k + 1
            if ring:
                if before < 0:
                    before = events - 1
                if after_k == events:
                    after_k = 0
            has_before = before >= 0 and before != k
            has_after = after_k < events and after_k != k and after_k != before
            if has_before:
                tree_time[leaves + before] = event_time(before, t, x, v, local_time, reach, ring, box)
            if has_after:
                tree_time[leaves + after_k] = event_time(after_k, t, x, v, local_time, reach, ring, box)
            # the paths to the root by calls (_pull_span), not inlined: these events are a few of the N
            if before == k - 1 and after_k == k + 1:
                _pull_span(tree_time, tree_event, leaves + before, leaves + after_k)  # one shared path to the root
            else:  # the ring's seam (or fewer than three events): separate paths
                _pull_span(tree_time, tree_event, leaves + k, leaves + k)
                if has_before:
                    _pull_span(tree_time, tree_event, leaves + before, leaves + before)
                if has_after:
                    _pull_span(tree_time, tree_event, leaves + after_k, leaves + after_k)
            t_next = tree_time[1]
            k_next = tree_event[1]
        # inelastic collapse: the collisions accelerate geometrically (infinitely many in a finite time).
        # Compare the time taken by the last half of the window with the half before it; in floating
        # point a collapsing cluster ends after a few dozen collisions with exactly equal velocities,
        # which the half-window of 8..16 collisions still sees.
        if kinetic < 1e-6 * reference:
            _recount_kinetic(v, mass, ring, scalars)
            kinetic = scalars[KINETIC]
            carry = scalars[KINETIC_CARRY]
            momentum_energy = scalars[MOMENTUM_ENERGY]
            reference = scalars[KINETIC_REFERENCE]
        size = window.size  # a power of two: positions by masking instead of a division
        mask = size - 1
        window[(count - 1) & mask] = t
        cooled = energy_floor > 0.0 and kinetic - momentum_energy < energy_floor
        if count >= size or cooled:
            # inelastic collapse: the collisions accelerate geometrically (infinitely many in a finite
            # time).  Compare the time taken by the last half of the window with the half before it;
            # in floating point a collapsing cluster ends after a few dozen collisions with exactly
            # equal velocities, which a half-window of 16 collisions still sees.  When the energy
            # floor is reached earlier (a small system whose whole thermal energy is the collapsing
            # motion), the same test on the shorter history tells collapse from cooling.
            # A false alarm (no cluster, velocities resolved) goes on: the test fires again at the next collision.
            if _accelerating(window, count, collapse[COLLAPSE_FACTOR], collapse[COLLAPSE_CLOCK]):
                # Positions whose rounding reaches the gap floor (after a drift at the rounding of the
                # centre-of-mass velocity over a very long time) cannot show a cluster: frozen.  Else a cluster
                # is a collapse, and without one a pair whose relative velocity is a few thousand ulps of its
                # speed has lost it in the rounding: frozen too.
                if max(abs(x_i), abs(x_j)) * collapse[FROZEN_POSITION] >= collapse[COLLAPSE_GAP]:
                    return STATUS_FROZEN, k, done
                # the cluster of k is the caller's to find (resolve_cluster): collapse_cluster then compiles only
                # for runs that get here, and the loop resumes from the same state on a false alarm
                if abs(approach) <= collapse[FROZEN_SPEED] * max(abs(vi), abs(vj)):
                    return STATUS_CLUSTER_FROZEN, k, done
                return STATUS_CLUSTER, k, done
            if cooled:
                return STATUS_COOLED, k, done
        k = k_next
        t = t_next
    return STATUS_DONE, -1, done


def _read_only(arrays):
    """``arrays`` made read-only, as the collision laws' arrays are: a placeholder of the same numba types as
    the arrays it stands beside compiles no second copy of the kernels that read both."""
    for array in arrays:
        array.setflags(write=False)
    return arrays


def empty_table():
    """Placeholder ``(ratio, share grid, levels, quantiles, share)`` for rules that use none (one point, two levels;
    read-only)."""
    return _read_only((np.zeros(1), np.array([0.5]), np.array([0.0, 1.0]), np.ones((1, 1, 1, 2)),
                       np.zeros((1, 1, 1, 1))))


def empty_soft_law():
    """Placeholder soft-law arrays ``(kappa, gamma, log_x, share, levels, quantiles, gains)`` (stiffness 0;
    read-only)."""
    return _read_only((np.array([10.0]), np.array([1.0]), np.zeros(1), np.array([0.5]), np.array([0.0, 1.0]),
                       np.ones((1, 1, 1, 1, 2)), np.zeros((1, 1, 1, 1, 2))))
