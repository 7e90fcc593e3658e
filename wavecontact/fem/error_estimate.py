"""The FE solver's a posteriori error estimate: a pure function of the coarser runs' restitutions.

After the requested run on ``N`` elements the FE solver runs the same collision on ``N/2``
and ``N/4`` elements (same contact scheme) and turns the restitutions into an
estimate of ``|epsilon(N) - epsilon_exact|`` with :func:`estimate_from_levels`.  On small
meshes it also runs ``2N`` elements and estimates the error with :func:`estimate_with_finer`
(the difference to that run plus the rule's estimate of the finer run's own error).  The rule
depends only on those restitutions and on three numbers known before the run: the contact
resolution ``x = alpha V h / c`` at ``N``, the declared order and whether the run uses the
characteristic interface of P1 lumped.  The benchmark (``benchmarks/error_estimates.py
--offline``) re-applies it to stored sweeps; docs/error_estimates.md section 1 argues it.
"""

from __future__ import annotations

import itertools
import math

__all__ = [
    "CHARACTERISTIC_FLOOR",
    "CROSSING_MARGIN",
    "CROSSING_RATIO",
    "ESTIMATE_SAFETY",
    "LATTICE_STEP_BELOW",
    "OBSERVED_BELOW",
    "P1_LUMPED_PARTLY_RESOLVED_ORDER",
    "P1_LUMPED_UNRESOLVED_ORDER",
    "QUADRATURE_NOISE_BELOW",
    "RESOLVED_BELOW",
    "ROUNDING_FLOOR",
    "TOO_FAST_MARGIN",
    "UNRESOLVED_ORDER",
    "estimate_from_levels",
    "estimate_with_finer",
]

#: order of an unresolved impact, whose front spreads over about h^(2/3) (docs/fem.md section 3)
UNRESOLVED_ORDER = 2.0 / 3.0
#: orders of P1 lumped on the characteristic lattice where the contact is not resolved.  Where
#: alpha V dt = x > LATTICE_STEP_BELOW the lattice holds the incoming rate constant over a step
#: (docs/fem.md section 7) and its errors fall by 2.0 to 2.3 per halving of h (first order); between
#: RESOLVED_BELOW and that the contact is partly resolved within a step and they fall faster, by about 3
#: per halving (the sweeps of seeds 2027-2029, docs/error_estimates.md section 1)
P1_LUMPED_UNRESOLVED_ORDER = 1.0
P1_LUMPED_PARTLY_RESOLVED_ORDER = 1.5
LATTICE_STEP_BELOW = 10.0
#: x = alpha V h / c at or below which the declared order holds from the coarsest meshes on
RESOLVED_BELOW = 1.0
#: x up to which the order observed on the runs is used (the contact becomes resolved within them)
OBSERVED_BELOW = 30.0
#: factor on the Richardson extrapolation of the error
ESTIMATE_SAFETY = 2.0
#: a coarser difference more than this many times the finer one, of the other sign, is a fast
#: convergence that crossed the limit between the coarser runs, not a finer pair agreeing by accident
CROSSING_RATIO = 10.0
#: the sub-step gap quadrature of the characteristic interface leaves errors of about this size
#: where the differences of the runs do not show them (docs/fem.md section 7)
CHARACTERISTIC_FLOOR = 1e-9
#: on the characteristic lattice, differences of the runs that change sign below this size are the
#: quadrature's noise (its errors reach about 1e-8, docs/fem.md section 7), not a convergence
QUADRATURE_NOISE_BELOW = 1e-7
#: a finest difference below the coarser one by more than an order this much above the runs' scheme's
#: is read as two finest runs that agree by accident (the error changed sign between the coarser runs:
#: issue 23's gamma = 0.7558, kappa = 140.8, P2 lumped on 65 elements, errors +2.2e-4, -1.64e-4, -1.65e-4
#: on 16, 32, 65 elements, observed order 9; or stalled), not as a faster convergence.  2 keeps the
#: characteristic lattice's third order (docs/fem.md section 7) out of it
TOO_FAST_MARGIN = 2.0
#: where the two differences are of opposite signs the limit on their ratio is this much higher: a
#: fast convergence that crossed the limit between the coarser runs (CROSSING_RATIO) is not an accident
#: (issue 23's seed 42045: P1 lumped on 358 elements, errors -6.66e-7, -6.53e-7, -1.53e-5, ratio 1100)
CROSSING_MARGIN = 2.0
#: round-off of a run of many steps in an O(1) restitution
ROUNDING_FLOOR = 1e-12


def estimate_from_levels(levels, resolution: float, declared: float, characteristic: bool,
                         scheme_order: float | None = None, thermal: bool = False) -> tuple:
    """``(estimate, rule)``: the error of the first level's restitution.

    Richardson extrapolation ``SAFETY |d0| / (r**p - 1)`` of the finest difference
    ``d0 = eps(N) - eps(N/2)`` (``r = N / (N/2)``) with an order ``p`` chosen by the regime
    ``x = alpha V h / c`` (docs/error_estimates.md section 1):

    * ``x <= RESOLVED_BELOW``: the declared order;
    * ``RESOLVED_BELOW < x <= OBSERVED_BELOW`` (not the characteristic lattice), where the runs
      converge monotonically and not too fast (below): the order observed on the three finest runs,
      clamped to ``[UNRESOLVED_ORDER, declared]``;
    * otherwise :data:`UNRESOLVED_ORDER`; on the characteristic lattice
      :data:`P1_LUMPED_PARTLY_RESOLVED_ORDER` up to ``x = LATTICE_STEP_BELOW``, then
      :data:`P1_LUMPED_UNRESOLVED_ORDER`.

    Further coarser levels, if given, are not used.  Three guards: where the finest difference is
    below the coarser one by more than the runs' scheme allows (``|d1| / |d0| > r**(scheme_order +
    TOO_FAST_MARGIN)``, the exponent raised by :data:`CROSSING_MARGIN` where the differences are of
    opposite signs: the error changed sign between the coarser runs or stalled,
    and the two finest agree by accident), the sequence is treated as not monotone (the regime's
    lowest order where ``x > RESOLVED_BELOW``) and the next coarser difference carried down to ``N``
    is a second lower bound, at any ``x``; the same
    carried difference where ``x > RESOLVED_BELOW`` and the runs do not converge monotonically,
    except where that difference is of the other sign and more than :data:`CROSSING_RATIO` times
    larger, but not too fast (a fast convergence that crossed the limit); on the characteristic lattice, where the
    two finest differences change sign below :data:`QUADRATURE_NOISE_BELOW` (the quadrature's
    noise), the larger of them.  Floors: :data:`CHARACTERISTIC_FLOOR` (characteristic lattice,
    finite stiffness) or :data:`ROUNDING_FLOOR`.

    Parameters
    ----------
    levels : sequence of (int, float)
        ``(elements, restitution)`` of the requested run first, then of the coarser runs
        (each about half the elements of the previous one; at least one).
    resolution : float
        ``alpha V h / c`` at the requested mesh (dimensionless; inf for hard and penalty contact).
    declared : float
        The discretization's order where the contact is resolved.
    characteristic : bool
        Whether the run uses the characteristic interface with the sub-step gap quadrature
        (P1 lumped, Courant number 1, exponential contact).
    scheme_order : float or None
        The order in ``h`` of the contact scheme all the runs use (the massless-end interface: 1,
        below the declared order; None: ``declared``), the base of the too-fast guard.
    thermal : bool
        Whether the collision starts with thermal vibrations.  Its runs converge irregularly (several
        contact episodes, each timed by the vibrations' phases), so a coarser difference of the other
        sign is no sign of a fast convergence that crossed the limit: the :data:`CROSSING_RATIO`
        exemption from carrying it down does not apply.

    Returns
    -------
    tuple of (float, str)
        The estimate of ``|epsilon - epsilon_exact|`` (dimensionless) and a one-line account
        of the rule that produced it.
    """
    x = resolution
    if not characteristic:
        lowest = UNRESOLVED_ORDER
    else:
        lowest = P1_LUMPED_PARTLY_RESOLVED_ORDER if x <= LATTICE_STEP_BELOW else P1_LUMPED_UNRESOLVED_ORDER
    elements = [n for n, _ in levels]
    values = [value for _, value in levels]
    d = [a - b for a, b in itertools.pairwise(values)]
    ratio = [a / b for a, b in itertools.pairwise(elements)]
    monotone = len(d) > 1 and d[0] * d[1] > 0.0 and abs(d[1]) > abs(d[0])
    # a finest difference smaller than the scheme's order allows (by TOO_FAST_MARGIN) is two runs that
    # agree by accident (the error changed sign between the coarser runs, or stalled), not a faster
    # convergence; the sign of so small a difference says nothing
    fastest = (declared if scheme_order is None else scheme_order) + TOO_FAST_MARGIN
    if not monotone:
        fastest += CROSSING_MARGIN
    too_fast = len(d) > 1 and abs(d[1]) > ratio[1] ** fastest * abs(d[0])
    if x <= RESOLVED_BELOW:
        order, how = declared, "declared"
    elif x <= OBSERVED_BELOW and monotone and not too_fast and not characteristic:
        observed = math.log(abs(d[1]) / abs(d[0])) / math.log(ratio[1])
        order, how = min(max(observed, lowest), declared), f"observed {observed:.3g}, clamped"
    else:
        order = lowest
        how = "faster than the scheme's order" if too_fast else \
            "unresolved contact" if monotone or len(d) < 2 else "not monotone"
    estimate = ESTIMATE_SAFETY * abs(d[0]) / (ratio[0] ** order - 1.0)
    if len(d) > 1:
        crossing = not thermal and d[0] * d[1] < 0.0 and abs(d[1]) > CROSSING_RATIO * abs(d[0])
        if too_fast or (x > RESOLVED_BELOW and not monotone and not crossing):
            carried = ESTIMATE_SAFETY * abs(d[1]) / (ratio[1] ** order - 1.0) / ratio[0] ** order
            estimate, how = max(estimate, carried), how + ", coarser pair carried down"
        if characteristic and d[0] * d[1] < 0.0 and max(abs(d[0]), abs(d[1])) < QUADRATURE_NOISE_BELOW:
            estimate, how = max(estimate, abs(d[0]), abs(d[1])), how + ", quadrature noise"
    floor = CHARACTERISTIC_FLOOR if characteristic and x < math.inf else ROUNDING_FLOOR
    return (max(estimate, floor),
            f"order {order:.3g} ({how}; alpha V h / c = {x:.3g}), safety {ESTIMATE_SAFETY:g}, floor {floor:g}")


def estimate_with_finer(finer, levels, resolution: float, declared: float, characteristic: bool,
                        scheme_order: float | None = None, thermal: bool = False) -> tuple:
    """``(estimate, rule)``: the error of ``levels[0]``'s restitution from a run on a finer mesh.

    By the triangle inequality ``|e(N)| <= |eps(N) - eps(2N)| + |e(2N)|``: the first term is
    measured, the second is :func:`estimate_from_levels` applied to the finer run followed by
    ``levels`` (so its finest difference is ``eps(2N) - eps(N)``), with the regime of the requested
    run (``resolution`` at ``N``, the coarser of the pair: the lower order at the bands' edges).
    Where the runs converge, the measured difference is most of the error and the estimate is
    sharp whatever the order; where ``eps(N)`` is near the limit by accident (the error changes sign
    between ``N/2`` and ``2N``), the estimate is about ``|e(2N)|`` instead of the size of the coarser
    runs' differences.  With ``thermal`` the estimate is at least :func:`estimate_from_levels` of
    ``levels`` alone (the coarser runs' reading: their carried differences see accidents of the finest
    pair).  docs/error_estimates.md section 1 gives the evidence.

    Parameters
    ----------
    finer : (int, float)
        ``(elements, restitution)`` of the finer run (about twice the requested elements).
    levels : sequence of (int, float)
        ``(elements, restitution)`` of the requested run first, then of the coarser runs (at least
        the requested run).
    resolution : float
        ``alpha V h / c`` at the requested mesh (dimensionless; inf for hard and penalty contact).
    declared : float
        The discretization's order where the contact is resolved.
    characteristic : bool
        Whether the run uses the characteristic interface with the sub-step gap quadrature.
    scheme_order, thermal
        As in :func:`estimate_from_levels`.

    Returns
    -------
    tuple of (float, str)
        The estimate of ``|epsilon - epsilon_exact|`` at the requested mesh (dimensionless) and a
        one-line account of the rule.
    """
    difference = abs(levels[0][1] - finer[1])
    finer_error, rule = estimate_from_levels([tuple(finer), *levels], resolution, declared, characteristic,
                                             scheme_order, thermal)
    estimate = difference + finer_error
    rule = f"|eps(N) - eps({finer[0]})| = {difference:.3g} plus the error of the run at {finer[0]}: {rule}"
    if thermal and len(levels) > 1:
        # with a bath the finest runs can agree by accident where the coarser ones show large errors (the
        # audit's seed 2323 scene 15: errors 5.3e-5, 2.2e-6, 9.0e-7, 1.3e-6 on 100 ... 800 elements): the
        # coarser runs' own reading is a second lower bound
        coarse, coarse_rule = estimate_from_levels(levels, resolution, declared, characteristic, scheme_order, thermal)
        if coarse > estimate:
            estimate, rule = coarse, f"the coarser runs' estimate, larger than {rule}: {coarse_rule}"
    return estimate, rule
