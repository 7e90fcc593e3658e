"""Free-free vibration modes of rods, and the static flexibility of the modes left out.

Every mode is stored mass-normalised: its coordinate ``eta`` obeys
``eta'' = -omega^2 eta + (end value) * (end force)`` with unit modal mass, and
the displacement of a rod end is ``sum_nu end_value_nu * eta_nu``.  For a
uniform rod of mass ``m`` this is the paper's expansion (Eq. 4) with
``q = eta / sqrt(m)``: the left end value is ``sqrt(2 / m)`` and the right end
value ``(-1)^nu sqrt(2 / m)``.

Two sources of modes give the same data structure, :class:`RodModes`:

* :func:`analytic_modes` -- closed form for a uniform rod,
  ``omega_nu = c pi nu / l``;
* :func:`fe_modes` -- eigenpairs of the finite-element matrices of the rod
  (scikit-fem ``MeshLine`` with P1 or P2 elements), for comparison and for
  discretisations of the same rod.

Residual (static) flexibility
-----------------------------
Truncating the expansion after ``N`` modes makes each end too stiff: the
omitted modes, whose periods are shorter than anything the contact resolves,
would answer a slowly varying end force quasi-statically.  Their combined
end compliance (length/force)

``C_ab = sum_{nu > N} phi_nu(a) phi_nu(b) / omega_nu^2``,   a, b in {left, right},

is what :attr:`RodModes.residual_compliance` holds.  For a uniform rod
(``EA`` = Young's modulus times section)

``C_LL = C_RR = 2 l / (pi^2 EA) * psi'(N + 1)``,
``C_LR = 2 l / (pi^2 EA) * sum_{nu > N} (-1)^nu / nu^2``,

with the trigamma function ``psi'``; for ``N = 0`` the diagonal is ``l / (3 EA)``,
the inertia-relief compliance of a free rod pushed at one end.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy import special

from ..errors import InvalidParameterError, require_integer
from ..scene import Rod

__all__ = ["RodModes", "analytic_modes", "fe_modes", "rod_modes", "uniform_residual_compliance"]


@dataclass(frozen=True)
class RodModes:
    """The kept modes of one rod and the static compliance of the omitted ones.

    Attributes
    ----------
    rod : Rod
        The rod the modes belong to.
    omega : ndarray, shape (N,)
        Angular frequencies (1/time), increasing, all > 0 (the rigid mode is
        not included: it is the centre-of-mass motion).
    left, right : ndarray, shape (N,)
        Mass-normalised mode values at the left (``s = 0``) and right
        (``s = l``) end (1/sqrt(mass)); ``left > 0`` fixes the sign.
    residual_compliance : ndarray, shape (2, 2)
        End compliance of the omitted modes (length/force), rows and columns
        ordered (left, right).
    source : str
        ``"analytic"`` or ``"fe-P1"``, ``"fe-P2"``.
    """

    rod: Rod
    omega: np.ndarray
    left: np.ndarray
    right: np.ndarray
    residual_compliance: np.ndarray
    source: str

    @property
    def count(self) -> int:
        return int(self.omega.size)


def _check_count(modes) -> int:
    return require_integer("modes", modes, 1, allowed="an integer >= 1 (modes per rod)")


def uniform_residual_compliance(rod: Rod, modes: int) -> np.ndarray:
    """End compliance (2 x 2, length/force) of the modes above ``modes`` of a uniform rod.

    Parameters
    ----------
    rod : Rod
        A uniform rod.
    modes : int
        Number of kept modes ``N >= 0``.

    Examples
    --------
    >>> from wavecontact import Rod
    >>> c = uniform_residual_compliance(Rod(1.0), 0)
    >>> round(c[0, 0], 12), round(c[0, 1], 12)   # l/(3EA) and -l/(6EA)
    (0.333333333333, -0.166666666667)
    """
    n = int(modes)
    scale = 2.0 * rod.length / (math.pi**2 * rod.youngs_modulus * rod.area)
    same_end, alternating = _omitted_mode_sums(n)
    return scale * np.array([[same_end, alternating], [alternating, same_end]])


@functools.lru_cache(maxsize=256)
def _omitted_mode_sums(n: int):
    """``sum_{nu>n} 1/nu^2`` and ``sum_{nu>n} (-1)^nu/nu^2`` (cached: scipy's polygamma costs ~0.1 ms)."""
    same_end = float(special.polygamma(1, n + 1))
    # sum_{nu>N} (-1)^nu / nu^2 = (-1)^(N+1) [psi'((N+1)/2) - psi'((N+2)/2)] / 4
    alternating = (-1.0) ** (n + 1) * 0.25 * float(
        special.polygamma(1, 0.5 * (n + 1)) - special.polygamma(1, 0.5 * (n + 2))
    )
    return same_end, alternating


def analytic_modes(rod: Rod, modes: int) -> RodModes:
    """The first ``modes`` free-free modes of a uniform rod in closed form.

    ``omega_nu = c pi nu / l``; end values ``sqrt(2/m)`` (left) and
    ``(-1)^nu sqrt(2/m)`` (right), ``m = rho A l``.  Recent ones are remembered (read-only arrays:
    a collision and its error estimate's run, and repeated collisions, build them once).
    """
    n = _check_count(modes)
    try:
        return _analytic_modes(rod, n)
    except TypeError:  # a rod whose fields do not hash
        return _analytic_modes.__wrapped__(rod, n)


@functools.lru_cache(maxsize=32)
def _analytic_modes(rod: Rod, n: int) -> RodModes:
    nu = np.arange(1, n + 1, dtype=float)
    omega = rod.wave_speed * math.pi * nu / rod.length
    amplitude = math.sqrt(2.0 / rod.mass)
    left = np.full(n, amplitude)
    right = amplitude * (-1.0) ** nu
    compliance = uniform_residual_compliance(rod, n)
    for array in (omega, left, right, compliance):
        array.flags.writeable = False
    return RodModes(rod, omega, left, right, compliance, "analytic")


def fe_matrices(rod: Rod, elements: int, order: int = 1):
    """Stiffness and consistent mass matrices of a rod (scikit-fem, uniform mesh).

    Returns
    -------
    stiffness, mass : scipy.sparse matrices
        ``EA int u' v'`` and ``rho A int u v`` over ``[0, l]``.
    left_dof, right_dof : int
        Degrees of freedom of the two end nodes.
    """
    from skfem import Basis, ElementLineP1, ElementLineP2, MeshLine, asm
    from skfem.models.poisson import laplace, mass

    elements = require_integer("elements", elements, 1)
    element = {1: ElementLineP1, 2: ElementLineP2}.get(order)
    if element is None:
        raise InvalidParameterError(f"order must be 1 or 2 for FE modes, got {order!r}")
    mesh = MeshLine(np.linspace(0.0, rod.length, int(elements) + 1))
    basis = Basis(mesh, element())
    stiffness = rod.youngs_modulus * rod.area * asm(laplace, basis)
    mass_matrix = rod.density * rod.area * asm(mass, basis)
    x = basis.doflocs[0]
    return stiffness.tocsr(), mass_matrix.tocsr(), int(np.argmin(np.abs(x))), int(np.argmin(np.abs(x - rod.length)))


def fe_modes(rod: Rod, modes: int, elements: int | None = None, order: int = 1) -> RodModes:
    """The lowest ``modes`` elastic eigenmodes of the rod's finite-element model.

    Solves ``K phi = omega^2 M phi`` (consistent mass) with
    :func:`scipy.linalg.eigh` (dense; all modes, so the residual compliance
    of the omitted discrete modes is exact for the discrete model) when the
    model has at most 600 unknowns, else with :func:`scipy.sparse.linalg.eigsh`
    in shift-invert mode, the residual then following from the inertia-relief
    compliance of the whole discrete rod minus the kept modes.

    Parameters
    ----------
    rod : Rod
        The rod (uniform here; the matrices are what matter).
    modes : int
        Number of elastic modes to keep.
    elements : int or None
        Number of elements; default ``max(8 * modes, 64)``.
    order : {1, 2}
        Lagrange element order.
    """
    from scipy import linalg
    from scipy.sparse.linalg import eigsh

    n = _check_count(modes)
    if elements is None:
        elements = max(8 * n, 64)
    stiffness, mass_matrix, i_left, i_right = fe_matrices(rod, elements, order)
    size = stiffness.shape[0]
    if n > size - 1:
        raise InvalidParameterError(
            f"modes ({n}) must be below the number of unknowns of the FE model ({size}); use more elements"
        )
    ends = np.array([i_left, i_right])
    if size <= 600:
        values, vectors = linalg.eigh(stiffness.toarray(), mass_matrix.toarray())
        values, vectors = values[1:], vectors[:, 1:]  # drop the rigid mode
        end_values = vectors[ends, :]
        kept = slice(0, n)
        omitted = slice(n, None)
        residual = (end_values[:, omitted] / values[omitted]) @ end_values[:, omitted].T
        values, end_values = values[kept], end_values[:, kept]
    else:
        values, vectors = eigsh(stiffness, k=n + 1, M=mass_matrix, sigma=-1.0, which="LM")
        order_index = np.argsort(values)
        values, vectors = values[order_index][1:], vectors[:, order_index][:, 1:]
        end_values = vectors[ends, :]
        residual = _inertia_relief_compliance(stiffness, mass_matrix, ends) - (end_values / values) @ end_values.T
    signs = np.where(end_values[0] < 0.0, -1.0, 1.0)
    end_values = end_values * signs
    omega = np.sqrt(np.maximum(values, 0.0))
    return RodModes(rod, omega, end_values[0].copy(), end_values[1].copy(), residual, f"fe-P{order}")


def _inertia_relief_compliance(stiffness, mass_matrix, ends) -> np.ndarray:
    """End compliance of all elastic modes of a free discrete rod (2 x 2).

    Uses ``(K + M r r^T M)^-1 = sum_elastic phi phi^T / omega^2 + r r^T`` for
    the mass-normalised rigid mode ``r``.
    """
    from scipy.sparse.linalg import splu

    size = stiffness.shape[0]
    total_mass = float(mass_matrix.sum())
    rigid = np.full(size, 1.0 / math.sqrt(total_mass))
    m_rigid = mass_matrix @ rigid
    # (K + u u^T)^-1 b by Sherman-Morrison on a K made regular by a tiny shift is fragile;
    # solve the bordered system instead: [K  M r; r^T M  0] [x; lam] = [e; 0] gives the
    # elastic response x orthogonal (in M) to the rigid mode, after removing the rigid load.
    from scipy.sparse import bmat, csc_matrix

    bordered = bmat([[stiffness, csc_matrix(m_rigid[:, None])], [csc_matrix(m_rigid[None, :]), None]]).tocsc()
    lu = splu(bordered)
    out = np.empty((2, 2))
    for col, dof in enumerate(ends):
        load = np.zeros(size + 1)
        load[dof] = 1.0
        load[:size] -= m_rigid * rigid[dof]  # remove the part that only accelerates the rod
        x = lu.solve(load)[:size]
        out[:, col] = x[ends]
    return out


def rod_modes(rod: Rod, modes: int, source: str = "analytic", elements: int | None = None, order: int = 1) -> RodModes:
    """Modes of ``rod`` from ``source`` (``"analytic"`` or ``"fe"``)."""
    if source == "analytic":
        return analytic_modes(rod, modes)
    if source == "fe":
        return fe_modes(rod, modes, elements=elements, order=order)
    raise InvalidParameterError(f"mode source must be 'analytic' or 'fe', got {source!r}")
