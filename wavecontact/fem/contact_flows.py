"""Exact motion of the two facing end nodes under the contact force alone.

The time step is split (impulse / RESPA style, see docs/fem.md): a half kick
with the elastic forces, then the flow of ``kinetic + contact`` energy over a
whole step, then another half kick.  In the middle part every node drifts
freely except that the two facing end nodes also feel the contact force,
which depends only on their gap ``r``.  Because the contact force acts along
``M1^-1 e_end`` on one rod and ``M2^-1 e_end`` on the other, the gap obeys a
one-dimensional two-body equation

    r'' = m_inv * F(r),    m_inv = (M1^-1)_ee + (M2^-1)_ee,

which is solved here in closed form for each law.  The rest of the mesh
follows from the two integrals of the force over the step: the impulse
``I = (r1' - r0') / m_inv`` and ``J = (r1 - r0 - r0' dt) / m_inv``.

All functions return the gap and its rate after ``dt``: ``(r1, w1)``.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel
from ..contact import LAW_EXPONENTIAL, LAW_HARD, LAW_PENALTY

__all__ = [
    "LAW_EXPONENTIAL",
    "LAW_HARD_ELASTIC",
    "LAW_HARD_PLASTIC",
    "LAW_PENALTY",
    "contact_flow",
    "contact_force",
    "contact_potential",
    "exponential_flow",
    "hard_elastic_flow",
    "hard_plastic_update",
    "penalty_flow",
]

LAW_HARD_ELASTIC = LAW_HARD  # the splitting scheme's end-node impact rules for a hard law
LAW_HARD_PLASTIC = LAW_HARD + 1

_LN2 = math.log(2.0)


@kernel
def exponential_flow(r, w, dt, m_inv, alpha, strength):
    """Exact flow of ``r'' = m_inv alpha B exp(-alpha r)`` over ``dt``.

    With ``P = m_inv B exp(-alpha r)`` the energy ``w^2/2 + P`` is conserved,
    ``w_inf = sqrt(w^2 + 2P)``, and ``w(t) = w_inf tanh(s)`` with
    ``s' = alpha w_inf / 2``; ``r`` follows from ``ln cosh s``.  Logarithms
    keep it exact far from contact (``P`` may underflow) and for any
    ``alpha dt``: the flow never limits the step.
    """
    log_p = math.log(m_inv * strength) - alpha * r
    if log_p < -700.0 or (w != 0.0 and log_p + _LN2 < 2.0 * math.log(abs(w)) - 80.0):
        return r + w * dt, w  # the force changes nothing at double precision
    two_p = 2.0 * math.exp(log_p)
    speed = math.sqrt(w * w + two_p)
    s0 = math.log(speed + abs(w)) - 0.5 * (log_p + _LN2)
    if w < 0.0:
        s0 = -s0
    s1 = s0 + 0.5 * alpha * speed * dt
    a0 = abs(s0)
    a1 = abs(s1)
    change = (a1 - a0) + math.log1p(math.exp(-2.0 * a1)) - math.log1p(math.exp(-2.0 * a0))
    return r + (2.0 / alpha) * change, speed * math.tanh(s1)


@kernel
def penalty_flow(r, w, dt, m_inv, stiffness):
    """Exact flow of ``r'' = -m_inv k min(r, 0)``: drift, half a harmonic swing, drift."""
    omega = math.sqrt(m_inv * stiffness)
    remaining = dt
    for _ in range(3):
        if r > 0.0 or (r == 0.0 and w >= 0.0):
            if w >= 0.0:
                return r + w * remaining, w
            hit = r / (-w)
            if hit >= remaining:
                return r + w * remaining, w
            remaining -= hit
            r = 0.0
        # inside the overlap: r = A sin(omega t + phase), phase in [-pi, 0]
        amplitude = math.sqrt(r * r + (w / omega) ** 2)
        phase = math.atan2(r, w / omega)
        if phase > 0.0:
            phase = -math.pi
        exit_time = -phase / omega
        if remaining <= exit_time:
            angle = omega * remaining + phase
            return amplitude * math.sin(angle), amplitude * omega * math.cos(angle)
        remaining -= exit_time
        r = 0.0
        w = amplitude * omega
    return r + w * remaining, w


@kernel
def hard_elastic_flow(r, w, dt):
    """Exact flow of two point masses with a hard core: drift, mirror at ``r = 0``."""
    r1 = r + w * dt
    if r1 < 0.0:
        return -r1, -w
    return r1, w


@kernel
def hard_plastic_update(r, w, dt):
    """Forward-increment constraint: if the drift would overlap, end the step at ``r = 0``.

    The two end nodes then move together for this step (a momentum-conserving,
    perfectly plastic node impact), which is the exact interface condition of
    the continuum while it is in compression.
    """
    r1 = r + w * dt
    if r1 < 0.0:
        return 0.0, -r / dt
    return r1, w


@kernel
def contact_flow(law, r, w, dt, m_inv, alpha, strength, stiffness):
    """Dispatch on the law code (``LAW_*``)."""
    if law == LAW_EXPONENTIAL:
        return exponential_flow(r, w, dt, m_inv, alpha, strength)
    if law == LAW_PENALTY:
        return penalty_flow(r, w, dt, m_inv, stiffness)
    if law == LAW_HARD_ELASTIC:
        return hard_elastic_flow(r, w, dt)
    return hard_plastic_update(r, w, dt)


@kernel
def contact_force(law, r, alpha, strength, stiffness):
    """Contact force at gap ``r`` (force, pushing the ends apart); zero for hard contact."""
    if law == LAW_EXPONENTIAL:
        exponent = -alpha * r
        if exponent > 700.0:
            return math.inf
        return alpha * strength * math.exp(exponent)
    if law == LAW_PENALTY:
        if r < 0.0:
            return -stiffness * r
        return 0.0
    return 0.0


@kernel
def contact_potential(law, r, alpha, strength, stiffness):
    """Contact energy at gap ``r`` (energy); zero for hard contact."""
    if law == LAW_EXPONENTIAL:
        exponent = -alpha * r
        if exponent > 700.0:
            return math.inf
        return strength * math.exp(exponent)
    if law == LAW_PENALTY:
        if r < 0.0:
            return 0.5 * stiffness * r * r
        return 0.0
    return 0.0


# --- massless interface: first-order gap equation of the characteristic scheme -------------
#
# On a P1 lumped mesh stepped at exactly the element travel time (Courant number 1),
# central differences are the method of characteristics.  The end node then moves by
# the incoming wave plus F / Z (Z = rho c A), so over a double step 2 dt the gap obeys
#
#     r' = g + F(r) / Z_eff,     1 / Z_eff = 1/Z1 + 1/Z2,
#
# with g fixed by the incoming characteristics.  These functions return the gap after
# time T for each law (exactly), from which the impulse of the contact follows.


@kernel
def _log_expm1_over(z):
    """``log(expm1(z) / z)`` without overflow or cancellation."""
    if abs(z) < 1e-8:
        return 0.5 * z
    if z > 0.0:
        return z + math.log1p(-math.exp(-z)) - math.log(z)
    return math.log(-math.expm1(z)) - math.log(-z)


@kernel
def exponential_gap(r, g, duration, compliance, alpha, strength):
    """Solve ``r' = g + compliance * alpha B exp(-alpha r)`` exactly over ``duration``.

    ``y = exp(alpha r)`` obeys the linear equation ``y' = alpha (g y + c)``
    (``c = compliance alpha B``), solved in logarithms: no step limit for any alpha.
    """
    coefficient = compliance * alpha * strength
    z = alpha * g * duration
    first = alpha * r + z
    second = math.log(coefficient * alpha * duration) + _log_expm1_over(z)
    top = max(first, second)
    return (top + math.log(math.exp(first - top) + math.exp(second - top))) / alpha


@kernel
def penalty_gap(r, g, duration, compliance, stiffness):
    """Solve ``r' = g - compliance k min(r, 0)`` exactly over ``duration``."""
    rate = compliance * stiffness
    remaining = duration
    for _ in range(3):
        if r > 0.0 or (r == 0.0 and g >= 0.0):
            if g >= 0.0:
                return r + g * remaining
            hit = r / (-g)
            if hit >= remaining:
                return r + g * remaining
            remaining -= hit
            r = 0.0
        target = g / rate  # the overlap relaxes towards r* = g / rate
        if target < 0.0 or r == target:
            return target + (r - target) * math.exp(-rate * remaining)
        exit_time = math.log((target - r) / target) / rate
        if exit_time >= remaining:
            return target + (r - target) * math.exp(-rate * remaining)
        remaining -= exit_time
        r = 0.0
    return r + g * remaining


@kernel
def hard_gap(r, g, duration):
    """Hard contact of massless ends: the gap closes at rate ``g`` and stays at 0."""
    return max(r + g * duration, 0.0)


@kernel
def interface_gap(law, r, g, duration, compliance, alpha, strength, stiffness):
    """Dispatch of the first-order gap solutions on the law code."""
    if law == LAW_EXPONENTIAL:
        return exponential_gap(r, g, duration, compliance, alpha, strength)
    if law == LAW_PENALTY:
        return penalty_gap(r, g, duration, compliance, stiffness)
    return hard_gap(r, g, duration)


@kernel
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


@kernel
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


@kernel
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


@kernel
def _antiderivative(c0, c1, c2, c3, c4, x):
    """``int_{-1/2}^{x} sum_k c_k s^k ds`` (Horner: no powers)."""
    a = -0.5
    at_x = x * (c0 + x * (c1 / 2.0 + x * (c2 / 3.0 + x * (c3 / 4.0 + x * (c4 / 5.0)))))
    at_a = a * (c0 + a * (c1 / 2.0 + a * (c2 / 3.0 + a * (c3 / 4.0 + a * (c4 / 5.0)))))
    return at_x - at_a
