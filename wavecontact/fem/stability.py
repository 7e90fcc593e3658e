"""Stable time step of the explicit scheme, from the discrete system itself.

Central differences (leapfrog) on ``M u'' + K u = 0`` are stable when
``dt <= 2 / sqrt(lambda_max)``, ``lambda_max`` the largest eigenvalue of the
pencil ``(K, M)``.  It is computed here exactly (to ~1e-13) by bisection on
Sylvester's law of inertia: the number of negative pivots of the banded
``LDL^T`` factorization of ``K - sigma M`` is the number of eigenvalues below
``sigma`` (the Sturm-sequence method).  Each count costs O(n); 50 counts pin
``lambda_max`` down to round-off, also on 10^4 elements where Lanczos
iterations crawl because the top of the spectrum is clustered.  The bracket
starts from the element bound of Irons and Fried,
``lambda_max <= max_e lambda_max(K_e, M_e)``.

Most of those counts only confirm what is already known: their shifts lie far
below or far above ``lambda_max``.  For P1 (tridiagonal ``K`` and ``M``) a few
steps of inverse iteration from the element bound give ``lambda_max`` to about
1e-14, two counts confirm a bracket of relative width :data:`BRACKET` around it,
and the bisection then counts only at shifts within :data:`COUNT_MARGIN` of that
bracket, taking every other answer from it: the same shifts, the same answers,
the same ``lambda_max`` to the last bit in a fifth of the counts.  The answers
taken are certain because the computed Sturm count of a symmetric tridiagonal
matrix is the exact count of a matrix whose entries differ by a few rounding
errors each (Kahan 1966; Demmel, *Applied Numerical Linear Algebra*, section
5.3.4), which moves ``lambda_max`` of the pencil by about ``1e-15 lambda_max``,
a thousandth of the margin.  Wider bands (P2) keep every count.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import scipy.linalg
import scipy.linalg.lapack

from .._jit import kernel
from ..errors import InvalidParameterError
from .discretization import RodDiscretization

__all__ = ["BRACKET", "COUNT_MARGIN", "DOMINATED", "STEP_TOLERANCE", "check_time_step", "largest_eigenvalue", "stable_step"]

# A user step may exceed the computed limit by this relative amount (round-off of the limit).
STEP_TOLERANCE = 1e-9
#: relative half-width of the bracket around the inverse iteration's lambda_max that two counts confirm
BRACKET = 1e-12
#: relative distance outside the confirmed bracket beyond which a count's answer is taken as known
COUNT_MARGIN = 1e-12
#: a rod whose eigenvalues all lie this far (relative) below another rod's lambda_max is not bisected
DOMINATED = 1e-11
#: steps of inverse iteration from the element bound (within four they reach ~3e-13 on the solver's meshes)
_ITERATIONS = 5


@kernel
def count_below(stiffness_bands, mass_bands, sigma):
    """Number of eigenvalues of ``(K, M)`` below ``sigma`` (banded ``LDL^T`` inertia).

    ``*_bands[d, i]`` hold ``A[i, i + d]`` for ``d = 0..b``.
    """
    width = stiffness_bands.shape[0] - 1
    n = stiffness_bands.shape[1]
    lower = np.zeros((width + 1, n))  # lower[d, j] = L[j + d, j]
    pivots = np.zeros(n)
    negative = 0
    tiny = 1e-300
    for j in range(n):
        value = stiffness_bands[0, j] - sigma * mass_bands[0, j]
        for k in range(max(0, j - width), j):
            ljk = lower[j - k, k]
            value -= ljk * ljk * pivots[k]
        if value == 0.0:
            value = -tiny
        pivots[j] = value
        if value < 0.0:
            negative += 1
        for i in range(j + 1, min(n, j + width + 1)):
            entry = stiffness_bands[i - j, j] - sigma * mass_bands[i - j, j]
            for k in range(max(0, i - width), j):
                entry -= lower[i - k, k] * lower[j - k, k] * pivots[k]
            lower[i - j, j] = entry / value
    return negative


def banded_mass(disc: RodDiscretization) -> np.ndarray:
    """The mass matrix of ``disc`` in the lower banded storage of its stiffness."""
    bands = np.zeros_like(disc.stiffness_bands)
    if disc.mass_kind == "lumped":
        bands[0] = disc.lumped_mass
    else:
        for d in range(bands.shape[0]):
            bands[d, : disc.n_nodes - d] = disc.mass_matrix.diagonal(d)
    return bands


def _element_bound(disc: RodDiscretization) -> float:
    """Irons-Fried bound ``max_e lambda_max(K_e, M_e)`` (1/time^2).

    Element matrices of one rod differ only by the element size ``h``
    (``K_e = E A / h * K_ref``, ``M_e = rho A h * M_ref``), so the bound is
    ``c^2 / h_min^2`` times the reference element's largest eigenvalue.  A
    point mass on an end node only lowers the spectrum: the bound stays valid.
    """
    sizes = disc.x[disc.cells[:, 1]] - disc.x[disc.cells[:, 0]]
    rod = disc.rod
    return _reference_eigenvalue(disc.order, disc.mass_kind) * rod.wave_speed**2 / sizes.min() ** 2


@functools.cache
def _reference_eigenvalue(order: int, mass_kind: str) -> float:
    from ..scene import Rod
    from .discretization import discretize_rod

    single = discretize_rod(Rod(1.0), np.array([0.0, 1.0]), order, mass_kind)
    return float(
        scipy.linalg.eigh(single.stiffness.toarray(), single.mass_matrix.toarray(), eigvals_only=True).max()
    )


def largest_eigenvalue(disc: RodDiscretization, rtol: float = 1e-13, upper: float | None = None) -> float:
    """Largest eigenvalue of ``M^-1 K`` for one rod (1/time^2), by inertia bisection from ``upper`` (an upper
    bound; None: the element bound of a uniform rod)."""
    stiffness, mass_bands = _pencil(disc)
    if upper is None:
        upper = _element_bound(disc) * (1.0 + 1e-9)
    return _bisection(stiffness, mass_bands, upper, rtol)


def _pencil(disc: RodDiscretization) -> tuple:
    """``(K, M)`` of ``disc`` in contiguous upper band storage."""
    return np.ascontiguousarray(disc.stiffness_bands), np.ascontiguousarray(banded_mass(disc))


def _bisection(stiffness: np.ndarray, mass_bands: np.ndarray, upper: float, rtol: float) -> float:
    """The bisection of :func:`largest_eigenvalue`, each count outside the known answers made."""
    n = stiffness.shape[1]
    lower = 0.0
    below, above = _known_answers(stiffness, mass_bands, upper)
    # a confirmed bracket below ``upper`` answers this count too
    if not above < upper and count_below(stiffness, mass_bands, upper) < n:
        raise InvalidParameterError("element bound below the spectrum: the mesh is degenerate")
    while upper - lower > rtol * upper:
        middle = 0.5 * (lower + upper)
        if middle >= above or (middle > below and count_below(stiffness, mass_bands, middle) >= n):
            upper = middle
        else:
            lower = middle
    return upper


def _known_answers(stiffness: np.ndarray, mass_bands: np.ndarray, upper: float) -> tuple:
    """``(below, above)``: every Sturm count at a shift up to ``below`` finds fewer than ``n`` eigenvalues
    below it, every count from ``above`` on all ``n`` (1/time^2); ``(0, inf)`` where nothing is known
    (bands wider than tridiagonal, or no estimate's bracket confirmed).  The estimates: the Rayleigh
    quotient of the alternating vector (the top mode of a uniform rod with free ends, exactly), else
    that of :func:`_inverse_iteration`."""
    if stiffness.shape[0] != 2:
        return 0.0, math.inf
    known = _confirmed(stiffness, mass_bands, _rayleigh_quotient(stiffness, mass_bands, _alternating(stiffness)))
    if known is None:
        known = _confirmed(stiffness, mass_bands, _inverse_iteration(stiffness, mass_bands, upper))
    return (0.0, math.inf) if known is None else known


def _confirmed(stiffness: np.ndarray, mass_bands: np.ndarray, estimate: float) -> tuple | None:
    """The known answers around ``estimate`` where two counts confirm ``lambda_max`` within :data:`BRACKET` of
    it (the count above first: it fails first for an estimate from below), else None."""
    n = stiffness.shape[1]
    if not math.isfinite(estimate):
        return None
    low, high = estimate * (1.0 - BRACKET), estimate * (1.0 + BRACKET)
    if count_below(stiffness, mass_bands, high) < n or count_below(stiffness, mass_bands, low) >= n:
        return None
    return low * (1.0 - COUNT_MARGIN), high * (1.0 + COUNT_MARGIN)


def _alternating(stiffness: np.ndarray) -> np.ndarray:
    vector = np.ones(stiffness.shape[1])
    vector[1::2] = -1.0
    return vector


def _rayleigh_quotient(stiffness: np.ndarray, mass_bands: np.ndarray, vector: np.ndarray) -> float:
    return float(vector @ _band_product(stiffness, vector)) / float(vector @ _band_product(mass_bands, vector))


def _inverse_iteration(stiffness: np.ndarray, mass_bands: np.ndarray, shift: float) -> float:
    """Rayleigh quotient (1/time^2) after :data:`_ITERATIONS` steps of inverse iteration with the tridiagonal
    ``shift M - K`` (positive definite: ``shift`` is above the spectrum) from the alternating vector; nan
    where the factorization fails.  An estimate only: :func:`_confirmed` checks it by two counts."""
    diagonal, off_diagonal, info = scipy.linalg.lapack.dpttrf(shift * mass_bands[0] - stiffness[0],
                                                              shift * mass_bands[1, :-1] - stiffness[1, :-1])
    if info != 0:
        return math.nan
    vector = _alternating(stiffness)
    for _ in range(_ITERATIONS):
        vector, info = scipy.linalg.lapack.dpttrs(diagonal, off_diagonal, _band_product(mass_bands, vector))
        if info != 0:
            return math.nan
        vector /= math.sqrt(float(vector @ vector))
    return _rayleigh_quotient(stiffness, mass_bands, vector)


def _band_product(bands: np.ndarray, vector: np.ndarray) -> np.ndarray:
    """``A @ vector`` of the symmetric tridiagonal ``A`` with upper bands ``bands``."""
    product = bands[0] * vector
    if np.any(bands[1]):
        product[:-1] += bands[1, :-1] * vector[1:]
        product[1:] += bands[1, :-1] * vector[:-1]
    return product


def stable_step(discretizations) -> float:
    """Largest stable central-difference step ``2 / sqrt(lambda_max)`` over all rods (time).

    Only the largest of the rods' ``lambda_max`` matters: a P1 rod whose every eigenvalue one count shows
    to lie :data:`DOMINATED` below another rod's ``lambda_max`` (the long rod of a matched pair, its far end
    carrying the remainder's mass, below the short uniform rod) is not bisected, since its bisection would
    end below that value and leave the maximum as it is.  The rod with the largest Rayleigh quotient of the
    alternating vector (a lower bound of ``lambda_max``) is bisected first.
    """
    pencils = sorted((_pencil(d) + (_element_bound(d),) for d in discretizations),
                     key=lambda p: -_rayleigh_quotient(p[0], p[1], _alternating(p[0])))
    lam = -math.inf
    for stiffness, mass_bands, bound in pencils:
        n = stiffness.shape[1]
        if stiffness.shape[0] == 2 and lam > 0.0 and count_below(stiffness, mass_bands, lam * (1.0 - DOMINATED)) >= n:
            continue
        lam = max(lam, _bisection(stiffness, mass_bands, bound * (1.0 + 1e-9), 1e-13))
    return 2.0 / math.sqrt(lam)


def check_time_step(dt, limit: float) -> float:
    """Return ``dt`` as a float, refusing non-positive steps and steps above ``limit``."""
    try:
        step = float(dt)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"dt must be a positive number, got {dt!r}") from None
    if not (math.isfinite(step) and step > 0.0):
        raise InvalidParameterError(f"dt must be a positive finite time step, got {dt!r}")
    if step > limit * (1.0 + STEP_TOLERANCE):
        raise InvalidParameterError(
            f"dt = {step:.6g} exceeds the stable step {limit:.6g} of this mesh "
            f"(2/sqrt(lambda_max) of M^-1 K); use dt <= {limit:.6g}, fewer elements, or dt=None"
        )
    return step
