"""A straightforward event-driven loop in plain Python (``heapq``), written independently of the kernels.

It is what open-source Python granular-gas codes do: a heap of predicted
collisions ``(time, i, j, stamp_i, stamp_j)``, stale entries recognised by
the rods' collision counters and skipped when popped.  Only the ring and the
fixed restitution are covered.  It serves as the reference the kernels are
tested against and as the baseline of ``benchmarks/bench_gas.py``.
"""

from __future__ import annotations

import heapq

__all__ = ["heapq_ring_gas"]


def heapq_ring_gas(lengths, positions, velocities, circumference, restitution, collisions):
    """Run ``collisions`` collisions of a ring gas with a fixed restitution.

    Parameters
    ----------
    lengths, positions, velocities : sequence of float
        Rod lengths (= masses), centres (ascending) and velocities.
    circumference : float
        Ring length.
    restitution : float
        Coefficient of restitution in [0, 1].
    collisions : int
        Collisions to perform.

    Returns
    -------
    (list, list, float, list)
        Final positions (at the final time, not wrapped), velocities, the
        final time, and the sequence of colliding left-rod indices.
    """
    n = len(lengths)
    x = [float(p) for p in positions]
    v = [float(u) for u in velocities]
    m = [float(l) for l in lengths]
    clock = [0.0] * n
    stamp = [0] * n
    now = 0.0
    heap = []

    def predict(i):
        j = (i + 1) % n
        if v[i] <= v[j]:
            return
        shift = circumference if j == 0 else 0.0
        xi = x[i] + v[i] * (now - clock[i])
        xj = x[j] + v[j] * (now - clock[j]) + shift
        gap = max(xj - xi - 0.5 * (m[i] + m[j]), 0.0)
        heapq.heappush(heap, (now + gap / (v[i] - v[j]), i, stamp[i], stamp[j]))

    for i in range(n):
        predict(i)
    order = []
    while len(order) < collisions and heap:
        t, i, si, sj = heapq.heappop(heap)
        j = (i + 1) % n
        if si != stamp[i] or sj != stamp[j]:
            continue  # one of the rods collided since this prediction
        now = t
        for r in (i, j):
            x[r] += v[r] * (now - clock[r])
            clock[r] = now
        total = m[i] + m[j]
        centre = (m[i] * v[i] + m[j] * v[j]) / total
        relative = v[i] - v[j]
        v[i] = centre - m[j] / total * restitution * relative
        v[j] = centre + m[i] / total * restitution * relative
        stamp[i] += 1
        stamp[j] += 1
        order.append(i)
        for r in ((i - 1) % n, i, j):
            predict(r)
    final = [x[r] + v[r] * (now - clock[r]) for r in range(n)]
    return final, v, now, order

