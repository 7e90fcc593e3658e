"""The delay equation of two rods for a contact law acting on overlap only (method of steps, RK4).

Two cold rods approach at ``V``; every impulse ``I(t)`` the contact gave comes
back from each far end after every round trip ``T_i``, so the gap is

    r(t) = R0 - V t + I(t) / Z_s + sum_i (2 / Z_i) sum_{n>=1} I(t - n T_i)

(docs/theory.md).  Nothing in it depends on the force law: ``I' = F(r)``
closes it for any law.  In the units of the exponential equation (time
``tau = t Z_s / mu``, ``Gamma_i = T_i Z_s / mu``, weights ``beta_i = 2 Z_s / Z_i``)
with the velocity increase ``W = I / (mu V)`` and the gap in units of
``lambda = V mu / Z_s``,

    rho(tau) = a - tau + W(tau) + sum_i beta_i sum_{n>=1} W(tau - n Gamma_i),
    W'(tau) = F(lambda rho) / (Z_s V),        epsilon = W(inf) - 1.

On a step ``h <= Gamma_min / 2`` every delayed value lies in the computed past,
so the equation is an ordinary scalar one there: classical Runge-Kutta, with
the delayed ``W`` from the cubic Hermite interpolant of the stored ``W`` and
``W'``.  The law enters only through
:func:`wavecontact.contact_kernels.law_force`.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel
from ..contact_kernels import law_force

__all__ = ["STATUS_MAX_STEPS", "STATUS_NOT_FINITE", "STATUS_OK", "integrate_overlap_delay"]

STATUS_OK = 0
STATUS_MAX_STEPS = 1
STATUS_NOT_FINITE = 2


@kernel
def _delayed(s, h, w, d):
    """``W(s)`` from the stored grid (``W = 0`` for ``s <= 0``): cubic Hermite on the cell of ``s``."""
    if s <= 0.0:
        return 0.0
    x = s / h
    i = int(x)
    theta = x - i
    if theta == 0.0:
        return w[i]
    t2 = theta * theta
    t3 = t2 * theta
    return ((2.0 * t3 - 3.0 * t2 + 1.0) * w[i] + (t3 - 2.0 * t2 + theta) * h * d[i]
            + (-2.0 * t3 + 3.0 * t2) * w[i + 1] + (t3 - t2) * h * d[i + 1])


@kernel
def _memory(t, h, w, d, delays, weights):
    """``sum_i beta_i sum_{n>=1} W(t - n Gamma_i)``."""
    total = 0.0
    for i in range(delays.size):
        partial = 0.0
        n = 1
        while t - n * delays[i] > 0.0:
            partial += _delayed(t - n * delays[i], h, w, d)
            n += 1
        total += weights[i] * partial
    return total


@kernel
def _rate(rho, law, alpha, strength, stiffness, length_unit, force_unit):
    """``W' = F(lambda rho) / (Z_s V)``."""
    return law_force(law, alpha, strength, stiffness, length_unit * rho) / force_unit


@kernel
def integrate_overlap_delay(law, alpha, strength, stiffness, length_unit, force_unit, a0, delays, weights,
                            h, settle, max_steps):
    """Integrate the delay equation above on the uniform grid ``tau_k = k h``.

    Parameters
    ----------
    law, alpha, strength, stiffness : contact law (``ContactLaw.kernel_parameters``)
    length_unit, force_unit : float
        ``lambda = V mu / Z_s`` (length) and ``Z_s V`` (force).
    a0 : float
        Start gap in units of ``lambda`` (>= 0: the force acts on overlap only).
    delays, weights : float arrays (2,)
        ``Gamma_i`` and ``beta_i``.
    h : float
        Step, at most ``min(delays) / 2``.
    settle : float
        The run ends once the force has been zero for this long after the contact.
    max_steps : int

    Returns
    -------
    w, d : float arrays
        ``W`` and ``W'`` at ``tau_k = k h``, ``k = 0 .. steps``.
    status : int
        ``STATUS_*``.
    """
    w = np.zeros(max_steps + 1)
    d = np.zeros(max_steps + 1)
    d[0] = _rate(a0, law, alpha, strength, stiffness, length_unit, force_unit)
    touched = d[0] > 0.0
    free_since = 0.0
    status = STATUS_MAX_STEPS
    k = 0
    while k < max_steps:
        t = k * h
        wk = w[k]
        m_mid = _memory(t + 0.5 * h, h, w, d, delays, weights)
        m_end = _memory(t + h, h, w, d, delays, weights)
        base = a0 - t
        k1 = d[k]
        k2 = _rate(base - 0.5 * h + wk + 0.5 * h * k1 + m_mid, law, alpha, strength, stiffness, length_unit,
                   force_unit)
        k3 = _rate(base - 0.5 * h + wk + 0.5 * h * k2 + m_mid, law, alpha, strength, stiffness, length_unit,
                   force_unit)
        k4 = _rate(base - h + wk + h * k3 + m_end, law, alpha, strength, stiffness, length_unit, force_unit)
        w1 = wk + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        d1 = _rate(base - h + w1 + m_end, law, alpha, strength, stiffness, length_unit, force_unit)
        if not (math.isfinite(w1) and math.isfinite(d1)):
            status = STATUS_NOT_FINITE
            break
        k += 1
        w[k] = w1
        d[k] = d1
        if d1 > 0.0 or k2 > 0.0 or k3 > 0.0 or k4 > 0.0:
            touched = True
            free_since = k * h
        elif touched and k * h - free_since >= settle:
            status = STATUS_OK
            break
    return w[:k + 1], d[:k + 1], status
