"""The exact end response of a free uniform rod, used to correct the truncated modal expansion.

A uniform rod (impedance ``Z = rho c A``, round trip ``T = 2 l / c``) pushed at one end by a force
``F(t)`` that begins at rest moves that end with the velocity

    v(t) = (1 / Z) [F(t) + 2 sum_{n >= 1} F(t - n T)]

(the pulse enters, runs to the free far end and back, and every return doubles at the free end).
This is the sum of the rigid motion and of *all* free-free modes, which is why the delay equation
is exact.  The collocation integrator (:func:`wavecontact.modal.collocation.run_collision`) uses
it for the gap of two rods and lets the kept modes ride along, driven by the same force; this
module holds the parameters it needs and the energy the force leaves in the omitted modes.
"""

from __future__ import annotations

import functools

import numpy as np

from .._jit import kernel

__all__ = ["ENDS_SIZE", "end_parameters", "forced_energies", "forced_energy"]

# (zeta, w_a, w_b, T_a, T_b, t_start, gap_0, rate_0, energy_0, tail_compliance, gap now)
ENDS_SIZE = 11


def end_parameters(rod_a, rod_b, t_start, gap_0, rate_0, energy_0, tail_compliance) -> np.ndarray:
    """The ``ends`` array of :func:`~wavecontact.modal.collocation.run_collision`.

    Parameters
    ----------
    rod_a, rod_b : Rod
        The left rod (pushed at its right end) and the right rod (pushed at its left end).
    t_start : float
        Time at which the force history begins (time).
    gap_0, rate_0 : float
        Rigid gap (length) and its rate (length/time) at ``t_start``.
    energy_0 : float
        Total energy at ``t_start`` (energy; the omitted modes at rest).
    tail_compliance : float
        Static end compliance of the omitted modes of both rods (length/force).
    """
    z_a, z_b = rod_a.impedance, rod_b.impedance
    return np.array([
        1.0 / z_a + 1.0 / z_b, 2.0 / z_a, 2.0 / z_b,
        2.0 * rod_a.length / rod_a.wave_speed, 2.0 * rod_b.length / rod_b.wave_speed,
        t_start, gap_0, rate_0, energy_0, tail_compliance, gap_0,
    ], dtype=float)


@functools.lru_cache(maxsize=8)
def _gauss_legendre(points: int) -> tuple:
    """Nodes and weights of the ``points``-point Gauss-Legendre rule on [-1, 1] (read-only arrays)."""
    nodes, weights = np.polynomial.legendre.leggauss(points)
    nodes.flags.writeable = weights.flags.writeable = False
    return nodes, weights


@kernel(error_model="numpy")
def _autocorrelation_sum(records, trip, first_lag, lags, nodes, weights, total):
    """``total`` plus ``R(0)`` (if ``first_lag`` is 0) plus ``2 sum_{n=max(1, first_lag)}^{lags} R(n T)`` of the
    recorded force, the lags added to ``total`` in turn (see :func:`forced_energy`).

    Each lag is integrated over the union of the step boundaries and the shifted ones, Gauss-Legendre on
    every piece; the terms of a lag are summed in numpy's pairwise order (fewer than 8 terms in turn, up
    to 128 in eight interleaved partial sums, a longer run split in halves, the first a multiple of 8,
    walked here with an explicit stack), so the value is the same, bit for bit, as the same sums written
    with numpy's ``union1d`` and ``sum``.  One function (its helpers written out inside it): each compiled
    function costs its own second or so on an empty cache.
    """
    count = records.shape[0]
    columns = records.shape[1]
    points = nodes.size
    bounds = np.empty(count + 1)
    for k in range(count):
        bounds[k] = records[k, 0]
    bounds[count] = records[count - 1, 0] + records[count - 1, 1]
    first, end = bounds[0], bounds[count]
    edges = np.empty(2 * (count + 1))
    terms = np.empty(edges.size * points)
    task_start = np.empty(128, dtype=np.int64)
    task_count = np.empty(128, dtype=np.int64)  # -1: add the two sums on top of the value stack
    sums = np.empty(64)
    steps = np.empty(2, dtype=np.int64)
    forces = np.empty(2)
    for n in range(first_lag, lags + 1):
        shift = n * trip
        # the sorted union (equal values once) of the bounds and of the shifted bounds inside (first, end),
        # kept up to end - shift
        size = 0
        i = 0
        j = 0
        while j <= count and not (bounds[j] - shift > first):
            j += 1
        while i <= count or (j <= count and bounds[j] - shift < end):
            take_shifted = j <= count and bounds[j] - shift < end and (i > count or bounds[j] - shift < bounds[i])
            value = bounds[j] - shift if take_shifted else bounds[i]
            if take_shifted:
                j += 1
            else:
                if j <= count and bounds[j] - shift == value:
                    j += 1  # the same value in both lists
                i += 1
            if value > end - shift:
                break
            if size == 0 or value != edges[size - 1]:
                edges[size] = value
                size += 1
        if size < 2:
            continue
        used = 0
        # last step that begins at or before t and t + shift (numpy's searchsorted, right, - 1)
        steps[0] = 0
        steps[1] = 0
        for piece in range(size - 1):
            left = edges[piece]
            half = (edges[piece + 1] - left) * 0.5
            for m in range(points):
                t = left + half * (nodes[m] + 1.0)
                # the force at t and (other lags) at t + shift: zero outside the record, else the step's
                # polynomial (Horner); lag 0 needs t alone (t + 0.0 is t)
                for which in range(1 if n == 0 else 2):
                    at = t if which == 0 else t + shift
                    step = steps[which]
                    while step + 1 < count and records[step + 1, 0] <= at:
                        step += 1
                    while step > 0 and records[step, 0] > at:
                        step -= 1
                    steps[which] = step
                    value = 0.0
                    if records[step, 0] <= at <= end:
                        x = min(max((at - records[step, 0]) / records[step, 1], 0.0), 1.0)
                        for c in range(columns - 1, 2, -1):
                            value = value * x + records[step, c]
                    forces[which] = value
                now = forces[0]
                later = now if n == 0 else forces[1]
                terms[used] = half * weights[m] * (now * later)
                used += 1
        # numpy's pairwise sum of terms[:used]
        tasks = 1
        task_start[0] = 0
        task_count[0] = used
        held = 0
        while tasks > 0:
            tasks -= 1
            start, length = task_start[tasks], task_count[tasks]
            if length < 0:
                held -= 1
                sums[held - 1] = sums[held - 1] + sums[held]
            elif length > 128:
                middle = length // 2
                middle -= middle % 8
                # popped in reverse: the first half, the second, then their sum
                task_start[tasks], task_count[tasks] = 0, -1
                task_start[tasks + 1], task_count[tasks + 1] = start + middle, length - middle
                task_start[tasks + 2], task_count[tasks + 2] = start, middle
                tasks += 3
            elif length < 8:
                block = 0.0
                for k in range(length):
                    block += terms[start + k]
                sums[held] = block
                held += 1
            else:
                r0, r1, r2, r3 = terms[start], terms[start + 1], terms[start + 2], terms[start + 3]
                r4, r5, r6, r7 = terms[start + 4], terms[start + 5], terms[start + 6], terms[start + 7]
                k = 8
                while k < length - length % 8:
                    r0 += terms[start + k]
                    r1 += terms[start + k + 1]
                    r2 += terms[start + k + 2]
                    r3 += terms[start + k + 3]
                    r4 += terms[start + k + 4]
                    r5 += terms[start + k + 5]
                    r6 += terms[start + k + 6]
                    r7 += terms[start + k + 7]
                    k += 8
                block = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
                while k < length:
                    block += terms[start + k]
                    k += 1
                sums[held] = block
                held += 1
        total += (1.0 if n == 0 else 2.0) * (0.0 + sums[0])
    return total


def forced_energy(records, rod, points=6) -> float:
    """Energy (rigid motion and all modes) that the recorded force puts into ``rod`` from rest.

    ``int F v dt = (1 / Z) [R(0) + 2 sum_n R(n T)]`` with the force's autocorrelation
    ``R(tau) = int F(t) F(t + tau) dt``.  The force is a polynomial of degree ``s - 1`` on each
    recorded step ``records[k] = (t0, h, I(t0), a_0 .. a_{s-1})``; each lag is integrated between
    the union of the step boundaries and the shifted ones, where the product is one polynomial of
    degree ``2 s - 2``, by Gauss-Legendre with ``points >= s`` nodes: exact up to round-off.

    Parameters
    ----------
    records : float array (K, 3 + s)
        The accepted steps of :func:`~wavecontact.modal.collocation.run_collision`.
    rod : Rod
        A uniform rod.

    Returns
    -------
    float
        Energy (energy units); subtract ``I^2 / (2 m)`` for the vibration alone.
    """
    return forced_energies(records, (rod,), points)[0]


def forced_energies(records, rods, points=6) -> list:
    """:func:`forced_energy` of each rod in ``rods`` pushed by the same recorded force (the lag-0 term, the
    same for every rod, computed once; the same values, bit for bit)."""
    if records.shape[0] == 0:
        return [0.0 for _ in rods]
    points = max(points, records.shape[1] - 3)
    nodes, weights = _gauss_legendre(points)
    records = np.ascontiguousarray(records, dtype=float)
    end = records[-1, 0] + records[-1, 1]
    zero_lag = _autocorrelation_sum(records, 1.0, 0, 0, nodes, weights, 0.0)
    energies = []
    for rod in rods:
        trip = 2.0 * rod.length / rod.wave_speed
        lags = int((end - records[0, 0]) // trip)
        energies.append(_autocorrelation_sum(records, trip, 1, lags, nodes, weights, zero_lag) / rod.impedance)
    return energies
