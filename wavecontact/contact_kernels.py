"""The contact laws inside compiled kernels: one dispatch on the codes of :mod:`wavecontact.contact`.

A kernel never sees a law object, only ``(code, alpha, strength, stiffness)``
from :meth:`wavecontact.contact.ContactLaw.kernel_parameters`.  This module is
the one place where those numbers become physics; the FE, modal and delay
kernels call it and hold no law of their own:

* :func:`law_force`, :func:`law_potential`, :func:`law_stiffness`: ``F(r)``,
  ``V(r)`` and ``-dF/dr`` at the gap ``r`` (the tests hold them to the Python
  methods of the law objects);
* :func:`law_response`: the gap solve with a compliance in series (the modal
  solver's omitted modes): ``r - C F(r) = gap``;
* :func:`law_flow`: the two-body flow ``r'' = m_inv F(r)`` over a step (the FE
  impulse splitting);
* :func:`law_gap`: the massless-end gap equation ``r' = g + C F(r)`` over a
  step (the FE characteristic and interface schemes).

The exponential, penalty and hard laws have closed forms for the last three.
Any other code is served by the generic solutions :func:`series_response`,
:func:`overlap_flow` and :func:`overlap_gap`, built on ``law_force`` and
``law_stiffness`` alone, for laws that act on overlap only (``F = 0`` for
``r >= 0``) with a force that grows with the overlap: a new law of that kind
is one branch in each of the first three functions.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import kernel
from .contact import LAW_EXPONENTIAL, LAW_HARD, LAW_HERTZ, LAW_PENALTY

__all__ = [
    "exponential_response",
    "law_flow",
    "law_force",
    "law_gap",
    "law_potential",
    "law_response",
    "law_stiffness",
    "overlap_flow",
    "overlap_gap",
    "series_response",
]

_LN2 = math.log(2.0)


#: Codes whose flow and gap solve have closed forms; any other law goes through the generic solutions,
#: whose sub-step error no solver's estimate includes yet (the modal splitting refuses those laws).
CLOSED_FORM_CODES = (LAW_EXPONENTIAL, LAW_PENALTY, LAW_HARD)

@kernel(internal=True)
def law_force(code, alpha, strength, stiffness, gap):
    """Repulsive force (>= 0) at end-to-end gap ``gap`` (force units; ``inf`` for a hard overlap)."""
    if code == LAW_EXPONENTIAL:
        return alpha * strength * math.exp(-alpha * gap)
    if code == LAW_PENALTY or code == LAW_HARD:
        if gap >= 0.0:
            return 0.0
        return stiffness * -gap
    if code == LAW_HERTZ:
        if gap >= 0.0:
            return 0.0
        return stiffness * -gap * math.sqrt(-gap)
    return math.nan


@kernel(internal=True)
def law_potential(code, alpha, strength, stiffness, gap):
    """Interaction energy at gap ``gap`` (energy units), zero far apart (``inf`` for a hard overlap)."""
    if code == LAW_EXPONENTIAL:
        return strength * math.exp(-alpha * gap)
    if code == LAW_PENALTY or code == LAW_HARD:
        if gap >= 0.0:
            return 0.0
        return 0.5 * stiffness * gap * gap
    if code == LAW_HERTZ:
        if gap >= 0.0:
            return 0.0
        return 0.4 * stiffness * gap * gap * math.sqrt(-gap)
    return math.nan


@kernel(internal=True)
def law_stiffness(code, alpha, strength, stiffness, gap):
    """``-dF/dgap`` (force/length, >= 0) at gap ``gap``; ``inf`` inside a hard overlap."""
    if code == LAW_EXPONENTIAL:
        return alpha * alpha * strength * math.exp(-alpha * gap)
    if code == LAW_PENALTY or code == LAW_HARD:
        if gap >= 0.0:
            return 0.0
        return stiffness
    if code == LAW_HERTZ:
        if gap >= 0.0:
            return 0.0
        return 1.5 * stiffness * math.sqrt(-gap)
    return math.nan


# --- the gap solve with a compliance in series (modal solver) ---------------------------------------


@kernel(error_model="numpy")
def contact_response(gap, law, alpha, strength, stiffness, compliance):
    """See :func:`law_response`; starts the inner solve from scratch."""
    return law_response(gap, law, alpha, strength, stiffness, compliance, math.nan)


@kernel(error_model="numpy")
def exponential_response(gap, alpha, strength, compliance, guess):
    """:func:`law_response` of the exponential law ``F = alpha B exp(-alpha r)``, on its own (a caller that
    knows its law compiles only this branch).  ``guess`` as there."""
    x = alpha * gap
    if compliance <= 0.0:
        if x < -700.0:
            return math.inf, math.inf, math.inf, 1.0
        energy = strength * math.exp(-x)
        return alpha * energy, energy, alpha * alpha * energy, 1.0
    # r - C alpha B exp(-alpha r) = gap  <=>  y exp(y) = beta exp(-x), y = alpha (r - gap)
    log_z = math.log(alpha * alpha * strength * compliance) - x
    if log_z < -30.0:
        z = math.exp(log_z)
        y = z * (1.0 - z)
    else:
        # Newton on u + exp(u) = log_z (u = log y): convex, increasing, started right of the root
        if math.isnan(guess):
            u = log_z if log_z < 0.0 else math.log1p(log_z)
        else:
            u = guess  # the previous step's root: Newton then needs two or three iterations
        for _ in range(60):
            eu = math.exp(u)
            du = (u + eu - log_z) / (1.0 + eu)
            u -= du
            if abs(du) < 1e-8 * (1.0 + abs(u)):
                # quadratic convergence: one more step reaches round-off
                eu = math.exp(u)
                u -= (u + eu - log_z) / (1.0 + eu)
                break
        y = math.exp(u)
    scale = 1.0 / (alpha * compliance)
    force = y * scale
    energy = (y + 0.5 * y * y) * scale / alpha
    return force, energy, alpha * force / (1.0 + y), 1.0 + y


@kernel(error_model="numpy")
def law_response(gap, law, alpha, strength, stiffness, compliance, guess, generic=True):
    """Force, interaction energy and stiffness of one pair at the modal gap ``gap``.

    With ``compliance > 0`` the contact acts through a massless spring of that
    compliance (the omitted modes, statically): the true gap ``r`` solves
    ``r - compliance * F(r) = gap``, the returned force is ``F(r)``, the energy
    includes the spring's, and the stiffness is ``dF/dgap``.

    ``guess`` (``nan``: none) starts the inner Newton solve for
    ``log(alpha (r - gap))``.  ``generic`` None promises a law of :data:`CLOSED_FORM_CODES`, and numba
    compiles the function without the generic solve (:func:`series_response`); True: any law.

    Returns
    -------
    force, energy, stiffness, softening : float
        ``softening = 1 + compliance * dF/dr`` (1 without compliance).
    """
    if law == LAW_EXPONENTIAL:
        return exponential_response(gap, alpha, strength, compliance, guess)
    if generic is not None and law != LAW_PENALTY and law != LAW_HARD:
        return series_response(gap, law, alpha, strength, stiffness, compliance)
    # linear spring on overlap (penalty; hard = infinite stiffness, then only the compliance)
    if gap >= 0.0:
        return 0.0, 0.0, 0.0, 1.0
    if stiffness == math.inf:
        if compliance <= 0.0:
            # overlap of a hard contact without compliance (round-off: exact ends keep the gap at 0);
            # the force is unbounded, the constraint stores no energy
            return math.inf, 0.0, math.inf, 1.0
        series = 1.0 / compliance
    else:
        series = 1.0 / (1.0 / stiffness + compliance)
    return -series * gap, 0.5 * series * gap * gap, series, 1.0


@kernel(error_model="numpy")
def series_response(gap, law, alpha, strength, stiffness, compliance):
    """:func:`law_response` of a law acting on overlap only, by Newton on ``r - C F(r) = gap``.

    ``h(r) = r - C F(r)`` increases; started at ``r = gap`` (left of the root, as
    ``F >= 0``) Newton's iterates increase monotonically to the root for a
    force convex in ``r`` (as ``K (-r)^p`` with ``p >= 1``).
    """
    force = law_force(law, alpha, strength, stiffness, gap)
    if compliance <= 0.0 or force == 0.0:
        k = law_stiffness(law, alpha, strength, stiffness, gap)
        return force, law_potential(law, alpha, strength, stiffness, gap), k, 1.0
    r = gap
    k = law_stiffness(law, alpha, strength, stiffness, r)
    for _ in range(200):
        step = (r - compliance * force - gap) / (1.0 + compliance * k)
        r -= step
        force = law_force(law, alpha, strength, stiffness, r)
        k = law_stiffness(law, alpha, strength, stiffness, r)
        if abs(step) <= 1e-15 * abs(r):
            break
    softening = 1.0 + compliance * k
    energy = law_potential(law, alpha, strength, stiffness, r) + 0.5 * compliance * force * force
    return force, energy, k / softening, softening


# --- the two-body flow r'' = m_inv F(r) over a step (FE impulse splitting) --------------------------


@kernel(internal=True)
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


@kernel(internal=True)
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


@kernel(internal=True)
def hard_elastic_flow(r, w, dt):
    """Exact flow of two point masses with a hard core: drift, mirror at ``r = 0``."""
    r1 = r + w * dt
    if r1 < 0.0:
        return -r1, -w
    return r1, w


@kernel(internal=True)
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

# --- massless interface: first-order gap equation r' = g + C F(r) (FE characteristic scheme) --------
#
# On a P1 lumped mesh stepped at exactly the element travel time (Courant number 1),
# central differences are the method of characteristics.  The end node then moves by
# the incoming wave plus F / Z (Z = rho c A), so over a double step 2 dt the gap obeys
#
#     r' = g + F(r) / Z_eff,     1 / Z_eff = 1/Z1 + 1/Z2,
#
# with g fixed by the incoming characteristics.  These functions return the gap after
# time T for each law, from which the impulse of the contact follows.


@kernel(internal=True)
def _log_expm1_over(z):
    """``log(expm1(z) / z)`` without overflow or cancellation."""
    if abs(z) < 1e-8:
        return 0.5 * z
    if z > 0.0:
        return z + math.log1p(-math.exp(-z)) - math.log(z)
    return math.log(-math.expm1(z)) - math.log(-z)


@kernel(internal=True)
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


@kernel(internal=True)
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


@kernel(internal=True)
def hard_gap(r, g, duration):
    """Hard contact of massless ends: the gap closes at rate ``g`` and stays at 0."""
    return max(r + g * duration, 0.0)


# --- generic solutions for laws acting on overlap only ---------------------------------------------

# RK4 sub-steps per time scale of the motion (error about (1/200)^4 = 6e-10 of the scale)
_SUBSTEPS_PER_SCALE = 200.0
_MAX_SUBSTEPS = 1_000_000
# the first sub-step and the one in which the ends part are taken again in this many parts (the force has
# a kink at touching)
_EXIT_SPLIT = 64.0


@kernel(internal=True)
def _deepest_overlap(law, alpha, strength, stiffness, level, potential):
    """Overlap ``x > 0`` at which ``V(-x)`` (``potential``) or ``F(-x)`` reaches ``level`` (bisection)."""
    hi = 1.0
    for _ in range(2100):
        if potential:
            value = law_potential(law, alpha, strength, stiffness, -hi)
        else:
            value = law_force(law, alpha, strength, stiffness, -hi)
        if value >= level:
            break
        hi *= 2.0
    lo = 0.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        if potential:
            value = law_potential(law, alpha, strength, stiffness, -mid)
        else:
            value = law_force(law, alpha, strength, stiffness, -mid)
        if value >= level:
            hi = mid
        else:
            lo = mid
    return hi


@kernel(internal=True)
def _hermite(theta, p0, p1, m0, m1):
    """Cubic Hermite interpolant on [0, 1] with values ``p0, p1`` and slopes ``m0, m1`` (per unit theta)."""
    t2 = theta * theta
    t3 = t2 * theta
    return (2.0 * t3 - 3.0 * t2 + 1.0) * p0 + (t3 - 2.0 * t2 + theta) * m0 + (-2.0 * t3 + 3.0 * t2) * p1 + (t3 - t2) * m1


@kernel(internal=True)
def _hermite_root(p0, p1, m0, m1):
    """A root in (0, 1] of :func:`_hermite` with ``p0 <= 0 < p1`` (bisection)."""
    lo = 0.0
    hi = 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if _hermite(mid, p0, p1, m0, m1) > 0.0:
            hi = mid
        else:
            lo = mid
    return hi


@kernel(internal=True)
def _flow_step(law, r, w, h, m_inv, alpha, strength, stiffness):
    """One classical Runge-Kutta step of ``r'' = m_inv F(r)``: ``(r1, w1, a0)`` (``a0``: the start's ``r''``)."""
    k1r = w
    k1w = m_inv * law_force(law, alpha, strength, stiffness, r)
    k2r = w + 0.5 * h * k1w
    k2w = m_inv * law_force(law, alpha, strength, stiffness, r + 0.5 * h * k1r)
    k3r = w + 0.5 * h * k2w
    k3w = m_inv * law_force(law, alpha, strength, stiffness, r + 0.5 * h * k2r)
    k4r = w + h * k3w
    k4w = m_inv * law_force(law, alpha, strength, stiffness, r + h * k3r)
    return r + h / 6.0 * (k1r + 2.0 * k2r + 2.0 * k3r + k4r), w + h / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w), k1w


@kernel(internal=True)
def _gap_step(law, r, g, h, compliance, alpha, strength, stiffness):
    """One classical Runge-Kutta step of ``r' = g + compliance F(r)``: ``(r1, r'(0))``."""
    k1 = g + compliance * law_force(law, alpha, strength, stiffness, r)
    k2 = g + compliance * law_force(law, alpha, strength, stiffness, r + 0.5 * h * k1)
    k3 = g + compliance * law_force(law, alpha, strength, stiffness, r + 0.5 * h * k2)
    k4 = g + compliance * law_force(law, alpha, strength, stiffness, r + h * k3)
    return r + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4), k1


@kernel(internal=True)
def overlap_flow(law, r, w, dt, m_inv, alpha, strength, stiffness):
    """Flow of ``r'' = m_inv F(r)`` over ``dt`` for a law acting on overlap only.

    Exact drift outside the overlap, classical Runge-Kutta inside it with
    :data:`_SUBSTEPS_PER_SCALE` sub-steps per time scale of the contact (the
    deepest overlap the energy allows over the speed, and the inverse contact
    frequency there).  The first sub-step and the one in which the ends part are
    taken again in :data:`_EXIT_SPLIT` parts (the force has a kink at touching)
    and the exit is located on the cubic through the last part's ends.
    """
    remaining = dt
    if r >= 0.0:
        if w >= 0.0 or r + w * remaining >= 0.0:
            return r + w * remaining, w
        hit = r / (-w)
        remaining -= hit
        r = 0.0
    energy = 0.5 * w * w + m_inv * law_potential(law, alpha, strength, stiffness, r)
    if energy <= 0.0:
        return r + w * remaining, w
    # np.bool_: a literal True (and False in overlap_gap) would compile _deepest_overlap once for each
    deepest = _deepest_overlap(law, alpha, strength, stiffness, energy / m_inv, np.bool_(True))
    speed = math.sqrt(2.0 * energy)
    frequency = math.sqrt(m_inv * law_stiffness(law, alpha, strength, stiffness, -deepest))
    rate = max(speed / deepest, frequency) * _SUBSTEPS_PER_SCALE
    n = min(max(int(math.ceil(remaining * rate)), 1), _MAX_SUBSTEPS)  # noqa: RUF046 (numba)
    h = remaining / n
    for i in range(n):
        r1, w1, _a0 = _flow_step(law, r, w, h, m_inv, alpha, strength, stiffness)
        if i == 0 or (r1 > 0.0 and w1 > 0.0):
            # the ends part within this sub-step: again in finer parts, then the exit on the last one
            part = h / _EXIT_SPLIT
            elapsed = 0.0
            for _ in range(int(_EXIT_SPLIT)):
                r1, w1, a0 = _flow_step(law, r, w, part, m_inv, alpha, strength, stiffness)
                if r1 > 0.0 and w1 > 0.0:
                    theta = _hermite_root(r, r1, w * part, w1 * part)
                    exit_speed = _hermite(theta, w, w1, a0 * part, 0.0)
                    return exit_speed * (remaining - elapsed - theta * part), exit_speed
                r = r1
                w = w1
                elapsed += part
            remaining -= h
            continue
        r = r1
        w = w1
        remaining -= h
    return r, w


@kernel(internal=True)
def overlap_gap(law, r, g, duration, compliance, alpha, strength, stiffness):
    """Solve ``r' = g + compliance F(r)`` over ``duration`` for a law acting on overlap only.

    Exact drift outside the overlap; inside it classical Runge-Kutta with
    :data:`_SUBSTEPS_PER_SCALE` sub-steps per time scale (the time to close
    the deepest overlap at rate ``|g|``, and ``1 / (compliance k)`` at that
    overlap: the gap relaxes towards the root of ``g + C F(r) = 0``); the
    first sub-step and the one in which the overlap ends are refined as in
    :func:`overlap_flow`.
    """
    remaining = duration
    if r >= 0.0:
        if g >= 0.0 or r + g * remaining >= 0.0:
            return r + g * remaining
        remaining -= r / (-g)
        r = 0.0
    deepest = -r
    if g < 0.0:
        deepest = max(deepest, _deepest_overlap(law, alpha, strength, stiffness, -g / compliance, np.bool_(False)))
    if deepest <= 0.0:
        return r + g * remaining
    relax = compliance * law_stiffness(law, alpha, strength, stiffness, -deepest)
    rate = max(abs(g) / deepest, relax) * _SUBSTEPS_PER_SCALE
    n = min(max(int(math.ceil(remaining * rate)), 1), _MAX_SUBSTEPS)  # noqa: RUF046 (numba)
    h = remaining / n
    for i in range(n):
        r1, _k1 = _gap_step(law, r, g, h, compliance, alpha, strength, stiffness)
        if i == 0 or r1 > 0.0:
            part = h / _EXIT_SPLIT
            elapsed = 0.0
            for _ in range(int(_EXIT_SPLIT)):
                r1, k1 = _gap_step(law, r, g, part, compliance, alpha, strength, stiffness)
                if r1 > 0.0:
                    theta = _hermite_root(r, r1, k1 * part, g * part)
                    return g * (remaining - elapsed - theta * part)
                r = r1
                elapsed += part
            remaining -= h
            continue
        r = r1
        remaining -= h
    return r


# --- the dispatch the kernels call --------------------------------------------------------------------


@kernel(internal=True)
def law_flow(law, plastic, r, w, dt, m_inv, alpha, strength, stiffness):
    """Two-body flow of the gap over ``dt``: ``(r1, w1)``; a hard law is an elastic mirror or, with
    ``plastic``, the perfectly plastic node impact (:func:`hard_plastic_update`)."""
    if law == LAW_EXPONENTIAL:
        return exponential_flow(r, w, dt, m_inv, alpha, strength)
    if law == LAW_PENALTY:
        return penalty_flow(r, w, dt, m_inv, stiffness)
    if law == LAW_HARD:
        if plastic:
            return hard_plastic_update(r, w, dt)
        return hard_elastic_flow(r, w, dt)
    return overlap_flow(law, r, w, dt, m_inv, alpha, strength, stiffness)


@kernel(internal=True)
def law_gap(law, r, g, duration, compliance, alpha, strength, stiffness):
    """The massless-end gap after ``duration`` (``r' = g + compliance F(r)``)."""
    if law == LAW_EXPONENTIAL:
        return exponential_gap(r, g, duration, compliance, alpha, strength)
    if law == LAW_PENALTY:
        return penalty_gap(r, g, duration, compliance, stiffness)
    if law == LAW_HARD:
        return hard_gap(r, g, duration)
    return overlap_gap(law, r, g, duration, compliance, alpha, strength, stiffness)
