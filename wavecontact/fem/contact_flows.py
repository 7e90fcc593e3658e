"""The FE contact step: the law's flow and gap solutions (:mod:`wavecontact.contact_kernels`) as the
FE kernels use them, and the exponential gap equation with a varying incoming rate.

The time step is split (impulse / RESPA style, see docs/fem.md): a half kick
with the elastic forces, then the flow of ``kinetic + contact`` energy over a
whole step, then another half kick.  In the middle part every node drifts
freely except that the two facing end nodes also feel the contact force,
which depends only on their gap ``r``.  Because the contact force acts along
``M1^-1 e_end`` on one rod and ``M2^-1 e_end`` on the other, the gap obeys a
one-dimensional two-body equation

    r'' = m_inv * F(r),    m_inv = (M1^-1)_ee + (M2^-1)_ee,

solved for each law by :func:`wavecontact.contact_kernels.law_flow`.  The rest
of the mesh follows from the two integrals of the force over the step: the
impulse ``I = (r1' - r0') / m_inv`` and ``J = (r1 - r0 - r0' dt) / m_inv``.
The massless-end schemes solve ``r' = g + C F(r)`` instead
(:func:`wavecontact.contact_kernels.law_gap`).

A hard law is one law code; whether the splitting scheme treats its node
impact as perfectly plastic or as an elastic mirror is the scheme's flag
``plastic``, not a law.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel
from ..contact import LAW_EXPONENTIAL, LAW_HARD, LAW_PENALTY
from ..contact_kernels import (
    exponential_flow,
    exponential_gap,
    hard_elastic_flow,
    hard_gap,
    hard_plastic_update,
    law_flow,
    law_force,
    law_gap,
    law_potential,
    penalty_flow,
    penalty_gap,
)

__all__ = [
    "LAW_EXPONENTIAL",
    "LAW_HARD",
    "LAW_PENALTY",
    "contact_flow",
    "contact_force",
    "contact_potential",
    "exponential_flow",
    "exponential_gap",
    "exponential_gap_linear",
    "exponential_gap_quartic",
    "hard_elastic_flow",
    "hard_gap",
    "hard_plastic_update",
    "interface_gap",
    "penalty_flow",
    "penalty_gap",
    "pruned_flow",
    "pruned_gap",
]

# the exponential force and energy count as infinite beyond this exponent (a massive overlap)
_EXPONENT_LIMIT = 700.0


@kernel(internal=True)
def contact_flow(law, plastic, r, w, dt, m_inv, alpha, strength, stiffness):
    """The splitting scheme's flow of the end-node pair: :func:`~wavecontact.contact_kernels.law_flow`."""
    return law_flow(law, plastic, r, w, dt, m_inv, alpha, strength, stiffness)


@kernel(internal=True)
def contact_force(law, r, alpha, strength, stiffness):
    """Contact force at gap ``r`` (force, pushing the ends apart); zero for hard contact."""
    if law == LAW_HARD:
        return 0.0
    if law == LAW_EXPONENTIAL and -alpha * r > _EXPONENT_LIMIT:
        return math.inf
    return law_force(law, alpha, strength, stiffness, r)


@kernel
def contact_potential(law, r, alpha, strength, stiffness):
    """Contact energy at gap ``r`` (energy); zero for hard contact."""
    if law == LAW_HARD:
        return 0.0
    if law == LAW_EXPONENTIAL and -alpha * r > _EXPONENT_LIMIT:
        return math.inf
    return law_potential(law, alpha, strength, stiffness, r)


@kernel(internal=True)
def interface_gap(law, r, g, duration, compliance, alpha, strength, stiffness):
    """The massless-end gap after ``duration``: :func:`~wavecontact.contact_kernels.law_gap`."""
    return law_gap(law, r, g, duration, compliance, alpha, strength, stiffness)


@kernel(internal=True)
def pruned_flow(general_law, plastic, r, w, dt, m_inv, alpha, strength, stiffness):
    """The splitting scheme's flow: the exponential law's when ``general_law`` is None (numba then prunes
    the other laws and compiles none of them), else :func:`contact_flow` of the law ``general_law``."""
    if general_law is None:
        return exponential_flow(r, w, dt, m_inv, alpha, strength)
    return contact_flow(general_law, plastic, r, w, dt, m_inv, alpha, strength, stiffness)


@kernel(internal=True)
def pruned_gap(general_law, r, g, duration, compliance, alpha, strength, stiffness):
    """The massless-end gap after ``duration``: the exponential law's solution when ``general_law`` is None
    (numba then prunes the other laws and compiles none of them), else :func:`interface_gap` of the law
    ``general_law``."""
    if general_law is None:
        return exponential_gap(r, g, duration, compliance, alpha, strength)
    return interface_gap(general_law, r, g, duration, compliance, alpha, strength, stiffness)


@kernel(internal=True)
def exponential_gap_linear(r, rate, slope, duration, compliance, alpha, strength, substeps):
    """``r' = rate + slope (t - duration/2) + compliance alpha B exp(-alpha r)`` over ``duration``.

    The closing rate varies linearly within the step (mean ``rate``); each of
    ``substeps`` sub-steps uses the exact constant-rate solution at its midpoint rate.
    """
    lowest = r + min(0.0, rate - 0.5 * abs(slope) * duration) * duration
    coefficient = compliance * alpha * strength
    if alpha * lowest - math.log(coefficient * duration) > 14.0:
        # the force moves the gap by less than 1e-6 over the step: the variation of the rate
        # within the step cannot matter, one exact constant-rate solution is enough
        return exponential_gap(r, rate, duration, compliance, alpha, strength)
    h = duration / substeps
    for k in range(substeps):
        middle = (k + 0.5) * h - 0.5 * duration
        r = exponential_gap(r, rate + slope * middle, h, compliance, alpha, strength)
    return r


# Gauss-Legendre rule on [-1, 1] for the integral in the linear gap equation (exact to degree 31)
_GAUSS_NODES, _GAUSS_WEIGHTS = np.polynomial.legendre.leggauss(16)


@kernel(internal=True)
def exponential_gap_quartic(r, rates, duration, compliance, alpha, strength, substeps):
    """Gap equation with the closing rate reconstructed from five consecutive step means.

    ``rates`` = mean closing rates over the steps ``-2 .. 2`` around this one
    (index 2 is this step).  The rate inside the step is the quartic ``q(t)``
    whose means over those five steps equal ``rates`` (fourth-order accurate
    for a smooth rate, centred: it uses the incoming waves of the next two
    steps too).  ``y = exp(alpha r)`` obeys the linear ``y' = alpha (q y + c)``,
    so ``y(T) = exp(alpha Q(T)) (y(0) + alpha c int_0^T exp(-alpha Q(s)) ds)``
    with ``Q = int q``.  ``substeps = 0``: the integral is taken with 16-point
    Gauss-Legendre (in logarithms: no overflow), accurate to round-off for the
    steps where the reconstruction is used.  ``substeps > 0``: the step is cut
    into that many sub-steps, each solved exactly with the quartic's mean rate
    over it (second order in the sub-step), and the reconstruction is skipped
    where the force moves the gap by less than 1e-6 over the step.
    """
    m2, m1, q0, p1, p2 = rates[0], rates[1], rates[2], rates[3], rates[4]
    # coefficients of s^k, s = (t - mid-step) / duration in [-1/2, 1/2]
    c0 = (9.0 * (m2 + p2) - 116.0 * (m1 + p1) + 2134.0 * q0) / 1920.0
    c1 = (5.0 * (m2 - p2) - 34.0 * (m1 - p1)) / 48.0
    c2 = (-(m2 + p2) + 12.0 * (m1 + p1) - 22.0 * q0) / 16.0
    c3 = (-(m2 - p2) + 2.0 * (m1 - p1)) / 12.0
    c4 = ((m2 + p2) - 4.0 * (m1 + p1) + 6.0 * q0) / 24.0
    spread = 0.5 * abs(c1) + 0.25 * abs(c2) + 0.125 * abs(c3) + 0.0625 * abs(c4) + abs(c0 - q0)
    lowest = r + min(0.0, q0 - spread) * duration
    coefficient = compliance * alpha * strength
    negligible = 14.0 if substeps > 0 else 30.0
    if alpha * lowest - math.log(coefficient * duration) > negligible:
        # the force moves the gap by less than exp(-negligible) over the step: its shape cannot matter
        return exponential_gap(r, q0, duration, compliance, alpha, strength)
    if substeps > 0:
        r_end = _quartic_substeps_linear(r, c0, c1, c2, c3, c4, duration, coefficient, alpha, substeps)
        if math.isfinite(r_end):
            return r_end
        h = 1.0 / substeps  # out of the linear form's range: the same sub-steps in logarithms
        for k in range(substeps):
            a = -0.5 + k * h
            mean = (_antiderivative(c0, c1, c2, c3, c4, a + h) - _antiderivative(c0, c1, c2, c3, c4, a)) / h
            r = exponential_gap(r, mean, h * duration, compliance, alpha, strength)
        return r
    # alpha Q(s) at the Gauss nodes (Q from the start of the step), then log of the integral
    n = _GAUSS_NODES.size
    exponents = np.empty(n)
    top = -math.inf
    for i in range(n):
        x = 0.5 * _GAUSS_NODES[i]
        exponents[i] = -alpha * duration * _antiderivative(c0, c1, c2, c3, c4, x)
        top = max(top, exponents[i])
    total = 0.0
    for i in range(n):
        total += _GAUSS_WEIGHTS[i] * math.exp(exponents[i] - top)
    log_integral = top + math.log(0.5 * duration * total)
    first = alpha * r
    second = math.log(alpha * coefficient) + log_integral
    high = max(first, second)
    log_y = high + math.log(math.exp(first - high) + math.exp(second - high))
    return (alpha * duration * _antiderivative(c0, c1, c2, c3, c4, 0.5) + log_y) / alpha


@kernel(internal=True)
def _quartic_substeps_linear(r, c0, c1, c2, c3, c4, duration, coefficient, alpha, substeps):
    """The sub-steps of :func:`exponential_gap_quartic` on ``Y = exp(alpha (r - r_0))``.

    Over a sub-step of length ``tau`` with constant rate ``q`` the exact
    solution (that of :func:`exponential_gap`) is linear in ``Y``:
    ``Y <- exp(z) Y + K expm1(z) / z`` with ``z = alpha q tau`` and ``K =
    coefficient alpha tau exp(-alpha r_0)``; both terms are positive, so the
    chain is accurate to a few ulps per sub-step and needs one ``expm1`` each
    instead of the logarithmic form's six transcendentals.  Returns NaN where
    ``K`` or ``Y`` would leave the floating-point range (the caller then uses
    the logarithmic form).
    """
    h = 1.0 / substeps
    tau = h * duration
    exponent = math.log(coefficient * alpha * tau) - alpha * r
    if exponent > 600.0:
        return math.nan
    scaled = math.exp(exponent)
    y = 1.0
    lower = _antiderivative(c0, c1, c2, c3, c4, -0.5)
    for k in range(substeps):
        upper = _antiderivative(c0, c1, c2, c3, c4, -0.5 + (k + 1) * h)
        z = alpha * tau * ((upper - lower) / h)
        lower = upper
        growth = math.expm1(z)
        y = y + growth * y + scaled * (growth / z if z != 0.0 else 1.0)
    if not (0.0 < y < 1e300):
        return math.nan
    return r + math.log(y) / alpha


@kernel(internal=True)
def _antiderivative(c0, c1, c2, c3, c4, x):
    """``int_{-1/2}^{x} sum_k c_k s^k ds`` (Horner: no powers)."""
    a = -0.5
    at_x = x * (c0 + x * (c1 / 2.0 + x * (c2 / 3.0 + x * (c3 / 4.0 + x * (c4 / 5.0)))))
    at_a = a * (c0 + a * (c1 / 2.0 + a * (c2 / 3.0 + a * (c3 / 4.0 + a * (c4 / 5.0)))))
    return at_x - at_a
