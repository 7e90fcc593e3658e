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

__all__ = ["ENDS_SIZE", "end_parameters", "forced_energy"]

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


def _force_at(times, starts, records):
    """Force of the recorded step polynomials at ``times`` (zero outside the record)."""
    index = np.searchsorted(starts, times, side="right") - 1
    inside = (index >= 0) & (times <= starts[-1] + records[-1, 1])
    index = np.clip(index, 0, starts.size - 1)
    x = np.clip((times - starts[index]) / records[index, 1], 0.0, 1.0)
    force = np.zeros_like(times)
    for j in range(records.shape[1] - 1, 2, -1):  # Horner, one coefficient column gathered at a time
        force = force * x + records[:, j].take(index)
    return np.where(inside, force, 0.0)


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
    if records.shape[0] == 0:
        return 0.0
    points = max(points, records.shape[1] - 3)
    nodes, weights = _gauss_legendre(points)
    starts = records[:, 0]
    bounds = np.append(starts, starts[-1] + records[-1, 1])
    trip = 2.0 * rod.length / rod.wave_speed
    lags = int((bounds[-1] - bounds[0]) // trip)
    # every lag's quadrature points first, then the force at all of them (and at the shifted ones) in one
    # evaluation: elementwise, the same numbers as one evaluation per lag
    pieces = []  # (weight of the lag, quadrature weights, times, shift)
    for n in range(lags + 1):
        shift = n * trip
        edges = np.union1d(bounds, bounds[(bounds - shift > bounds[0]) & (bounds - shift < bounds[-1])] - shift)
        edges = edges[edges <= bounds[-1] - shift]
        if edges.size < 2:
            continue
        left, width = edges[:-1], np.diff(edges)
        times = (left[:, None] + width[:, None] * 0.5 * (nodes + 1.0)).ravel()
        pieces.append((1.0 if n == 0 else 2.0, (width[:, None] * 0.5 * weights).ravel(), times, shift))
    if not pieces:
        return 0.0
    sizes = [times.size for _, _, times, _ in pieces]
    force = _force_at(np.concatenate([times for _, _, times, _ in pieces]
                                     + [times + shift for _, _, times, shift in pieces]), starts, records)
    at, later = 0, sum(sizes)  # offsets of a lag's points and of its shifted points in ``force``
    total = 0.0
    for (factor, quadrature, _, _), size in zip(pieces, sizes):
        product = force[at:at + size] * force[later + at:later + at + size]
        total += factor * float(np.sum(quadrature * product))
        at += size
    return total / rod.impedance
