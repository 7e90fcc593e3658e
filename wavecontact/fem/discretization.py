"""Finite-element matrices of one rod, assembled once with scikit-fem.

Each rod is a :class:`skfem.MeshLine` with Lagrange elements of order 1 or 2.
The stiffness ``K = E A int phi_i' phi_j' ds`` and the mass
``M = rho A int phi_i phi_j ds`` are assembled with the ready-made forms
``laplace`` and ``mass`` of :mod:`skfem.models.poisson`; the degrees of
freedom are then renumbered from left to right, so that both matrices are
banded with half-bandwidth equal to the element order.  The time loop only
sees the plain arrays of :class:`RodDiscretization`; nothing calls
scikit-fem after this module.

Lumped mass is the row sum of the consistent mass.  In 1D it equals the
nodal quadrature of Gauss-Lobatto type for P1 (``h/2, h/2``) and Simpson's
rule for P2 (``h/6, 2h/3, h/6``): all entries positive.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse as sp
from skfem import Basis, ElementLineP1, ElementLineP2, MeshLine
from skfem.models.poisson import laplace, mass

from ..errors import InvalidParameterError
from ..scene import Rod
from .line_assembly import line_matrices

__all__ = [
    "ELEMENT_ORDERS",
    "MASS_KINDS",
    "RodDiscretization",
    "check_nodes",
    "discretize_rod",
    "matched_nodes",
    "uniform_nodes",
]

ELEMENT_ORDERS = (1, 2)
MASS_KINDS = ("lumped", "consistent")
_ELEMENTS = {1: ElementLineP1, 2: ElementLineP2}


@dataclass(frozen=True)
class RodDiscretization:
    """Plain-array finite-element model of one rod (nodes numbered left to right).

    Attributes
    ----------
    rod : Rod
        The material and geometry discretized.
    order : int
        Lagrange element order.
    mass_kind : str
        ``'lumped'`` or ``'consistent'``.
    x : ndarray, shape (n,)
        Node coordinates along the rod, from 0 to ``rod.length`` (length).
    cells : ndarray, shape (n_el, order + 1)
        Node indices of each element: left vertex, right vertex, then the
        interior node for P2 (the VTK/meshio ``line3`` order).
    stiffness_bands : ndarray, shape (order + 1, n)
        Upper bands of ``K``: ``stiffness_bands[d, i] = K[i, i + d]`` (force/length).
    lumped_mass : ndarray, shape (n,)
        Row sums of the consistent mass (mass); the diagonal mass when lumped,
        and the weights that give momentum and centre of mass in both cases.
    mass_cholesky : ndarray, shape (order + 1, n) or None
        Lower banded Cholesky factor of the consistent mass
        (``mass_cholesky[d, j] = L[j + d, j]``); ``None`` when lumped.
    stiffness : scipy.sparse.csr_matrix
        ``K`` in the left-to-right numbering.
    mass_matrix : scipy.sparse.csr_matrix
        ``M`` (diagonal when lumped) in the same numbering.
    """

    rod: Rod
    order: int
    mass_kind: str
    x: np.ndarray
    cells: np.ndarray
    stiffness_bands: np.ndarray
    lumped_mass: np.ndarray
    mass_cholesky: np.ndarray | None
    stiffness: sp.csr_matrix
    mass_matrix: sp.csr_matrix

    def stress_recovery(self) -> sp.csr_matrix:
        """Matrix mapping nodal displacements to nodal stress ``E du/ds`` (force/area).

        Element derivatives at each node, averaged over the elements sharing it.
        """
        return _stress_recovery(self.x, self.cells, self.rod.youngs_modulus).tocsr()

    @property
    def n_nodes(self) -> int:
        return self.x.size

    @property
    def n_elements(self) -> int:
        return self.cells.shape[0]

    @property
    def vertex_coordinates(self) -> np.ndarray:
        """Element end points (length), shape ``(n_el + 1,)``."""
        return np.unique(self.x[self.cells[:, :2]])

    def inverse_mass_column(self, node: int, cutoff: float = 1e-20) -> np.ndarray:
        """Column ``M^-1 e_node`` (1/mass) with entries below ``cutoff`` of its peak set to 0.

        For a lumped mass this is ``e_node / m_node``; for a consistent mass it
        decays geometrically away from ``node``.
        """
        e = np.zeros(self.n_nodes)
        e[node] = 1.0
        if self.mass_cholesky is None:
            column = e / self.lumped_mass
        else:
            column = scipy.linalg.cho_solve_banded((self.mass_cholesky, True), e)
        column[np.abs(column) < cutoff * np.abs(column).max()] = 0.0
        return column

    def energy(self, displacement: np.ndarray, velocity: np.ndarray) -> tuple:
        """Kinetic and strain energy (energy) of a nodal state."""
        kinetic = 0.5 * velocity @ (self.mass_matrix @ velocity)
        strain = 0.5 * displacement @ (self.stiffness @ displacement)
        return kinetic, strain


def check_nodes(name: str, nodes, length: float, remainder_at=None) -> np.ndarray:
    """Validate node coordinates of a rod (strictly increasing, from 0 to ``length``).

    With ``remainder_at`` = ``'left'`` / ``'right'`` the nodes may stop short
    of that end (the unmeshed piece is carried as a point mass).
    """
    try:
        x = np.asarray(nodes, dtype=float).ravel()
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be an array of node coordinates") from None
    if x.size < 2:
        raise InvalidParameterError(f"{name} needs at least 2 node coordinates, got {x.size}")
    if not np.all(np.isfinite(x)):
        raise InvalidParameterError(f"{name} must be finite")
    if np.any(np.diff(x) <= 0.0):
        raise InvalidParameterError(f"{name} must be strictly increasing")
    tol = 1e-12 * length
    starts_ok = abs(x[0]) <= tol or (remainder_at == "left" and -tol <= x[0] < length)
    ends_ok = abs(x[-1] - length) <= tol or (remainder_at == "right" and 0.0 < x[-1] <= length + tol)
    if not (starts_ok and ends_ok):
        raise InvalidParameterError(
            f"{name} must run from 0 to the rod length {length:g}, got [{x[0]:g}, {x[-1]:g}]"
        )
    if abs(x[0]) <= tol:
        x[0] = 0.0
    if abs(x[-1] - length) <= tol:
        x[-1] = length
    return x


def uniform_nodes(length: float, elements: int) -> np.ndarray:
    """``elements + 1`` equally spaced element end points on ``[0, length]``."""
    return np.linspace(0.0, length, elements + 1)


def matched_nodes(length: float, element_size: float, from_left: bool) -> np.ndarray:
    """Element end points of exactly ``element_size``, as many as fit into ``length``.

    The rod gets ``floor(length / element_size)`` equal elements starting at
    its contact end (``s = 0`` if ``from_left``, else ``s = length``); the
    remaining piece (shorter than one element) is not meshed: its mass is
    lumped on the far end node (``remainder_at`` of :func:`discretize_rod`).
    A longer odd element would reflect part of every wave early, during the
    window in which the ends graze after the contact; a point mass at the far
    end reflects only at the far end (docs/fem.md).
    """
    count = max(1, int(np.floor(length / element_size * (1.0 + 1e-12))))
    span = min(count * element_size, length)
    steps = np.linspace(0.0, span, count + 1)
    if abs(span - length) <= 1e-12 * length:
        steps[-1] = length
    if from_left:
        return steps
    return length - steps[::-1]


def _left_to_right(basis) -> tuple:
    """Permutation that numbers the DOFs by coordinate, and its inverse."""
    coordinates = basis.doflocs[0]
    order = np.argsort(coordinates, kind="stable")
    inverse = np.empty_like(order)
    inverse[order] = np.arange(order.size)
    return order, inverse


def _bands(matrix: sp.csr_matrix, width: int) -> np.ndarray:
    n = matrix.shape[0]
    bands = np.zeros((width + 1, n))
    for d in range(width + 1):
        bands[d, : n - d] = matrix.diagonal(d)
    return bands


def _stress_recovery(x: np.ndarray, cells: np.ndarray, modulus: float) -> sp.csr_matrix:
    """Nodal stress ``E du/ds`` averaged over the elements around each node."""
    n = x.size
    rows, cols, vals = [], [], []
    count = np.zeros(n)
    local_count = cells.shape[1]
    for local in range(local_count):
        # Lagrange basis of the element (nodes in cell order) differentiated at node `local`.
        for other in range(local_count):
            xs = x[cells]  # (n_el, p+1)
            derivative = _lagrange_derivative(xs, other, local)
            rows.append(cells[:, local])
            cols.append(cells[:, other])
            vals.append(modulus * derivative)
        np.add.at(count, cells[:, local], 1.0)
    matrix = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
    )
    return sp.diags(1.0 / count) @ matrix


def _lagrange_derivative(xs: np.ndarray, j: int, k: int) -> np.ndarray:
    """d/ds of the Lagrange polynomial of node ``j`` evaluated at node ``k`` (per element)."""
    m = xs.shape[1]
    if j != k:
        value = 1.0 / (xs[:, j] - xs[:, k])
        for i in range(m):
            if i not in (j, k):
                value = value * (xs[:, k] - xs[:, i]) / (xs[:, j] - xs[:, i])
        return value
    value = np.zeros(xs.shape[0])
    for i in range(m):
        if i != j:
            value = value + 1.0 / (xs[:, j] - xs[:, i])
    return value


def discretize_rod(
    rod: Rod,
    vertices: np.ndarray,
    order: int = 1,
    mass_kind: str = "lumped",
    remainder_at=None,
    lump_remainder: bool = True,
) -> RodDiscretization:
    """Assemble the finite-element model of ``rod`` on the given element end points.

    Parameters
    ----------
    rod : Rod
        Material (density, modulus, section) and length.
    vertices : array_like
        Element end points from 0 to ``rod.length`` (length), strictly increasing.
    order : {1, 2}
        Lagrange element order.
    mass_kind : {'lumped', 'consistent'}
        Row-sum lumped (diagonal) or consistent mass.
    remainder_at : {None, 'left', 'right'}
        If the vertices stop short of that end of the rod, the mass of the
        missing piece is added to the end node there (total mass is exact).
    lump_remainder : bool
        False: leave the missing piece out (the model rod is shorter and
        lighter by less than one element; the caller accounts for its mass).

    Returns
    -------
    RodDiscretization
    """
    if order not in ELEMENT_ORDERS:
        raise InvalidParameterError(f"order must be one of {ELEMENT_ORDERS}, got {order!r}")
    if mass_kind not in MASS_KINDS:
        raise InvalidParameterError(f"mass must be one of {MASS_KINDS}, got {mass_kind!r}")
    vertices = check_nodes("nodes", vertices, rod.length, remainder_at)
    missing = rod.length - (vertices[-1] - vertices[0])
    remainder = lump_remainder and missing > 1e-12 * rod.length
    line = line_matrices(vertices, order)
    if line is not None and (line.sorted or not remainder):
        return _from_line(rod, order, mass_kind, line, missing if remainder else None, remainder_at)
    if line is None:  # round-off puts a mapped midpoint out of order: scikit-fem's own numbering
        mesh = MeshLine(vertices)
        basis = Basis(mesh, _ELEMENTS[order]())
        perm, inverse = _left_to_right(basis)
        stiffness = (laplace.assemble(basis) * (rod.youngs_modulus * rod.area)).tocsr()[perm][:, perm].tocsr()
        consistent = (mass.assemble(basis) * (rod.density * rod.area)).tocsr()[perm][:, perm].tocsr()
        x = basis.doflocs[0][perm].copy()
        cells = _ordered_cells(order, x, inverse[basis.element_dofs.T])
    else:
        stiffness = line.matrix(line.stiffness * (rod.youngs_modulus * rod.area))
        consistent = line.matrix(line.mass * (rod.density * rod.area))
        x, cells = line.x, line.cells
    if remainder:
        end = 0 if remainder_at == "left" else x.size - 1
        extra = sp.csr_matrix(([rod.density * rod.area * missing], ([end], [end])), shape=consistent.shape)
        consistent = (consistent + extra).tocsr()
    return _discretization(rod, order, mass_kind, x, cells, stiffness, consistent)


def _from_line(rod, order: int, mass_kind: str, line, missing, remainder_at) -> RodDiscretization:
    """The :class:`RodDiscretization` of an assembled line, the arrays written directly as scikit-fem's and
    scipy's operations leave them: the mass of the ``missing`` piece (None: none) added to the end node's
    entry (scipy's sum of two matrices with increasing indices in each row), the row sums in stored order."""
    stiffness = line.matrix(line.stiffness * (rod.youngs_modulus * rod.area))
    consistent = line.mass * (rod.density * rod.area)
    if missing is not None:
        end = 0 if remainder_at == "left" else line.x.size - 1
        at = line.position(end, end)
        consistent[at] = consistent[at] + rod.density * rod.area * missing
    lumped = line.row_sums(consistent)
    bands = line.upper_bands(stiffness.data)
    if mass_kind == "lumped":
        n = lumped.size
        return _discretization(rod, order, mass_kind, line.x, line.cells, stiffness, None, lumped,
                               sp.csr_matrix((lumped.copy(), np.arange(n, dtype=np.int32),
                                              np.arange(n + 1, dtype=np.int32)), shape=(n, n)), bands)
    return _discretization(rod, order, mass_kind, line.x, line.cells, stiffness, line.matrix(consistent), lumped,
                           stiffness_bands=bands)


def assembled_discretization(rod, order: int, mass_kind: str, basis, inverse, x, stiffness, consistent):
    """The :class:`RodDiscretization` of assembled matrices in the left-to-right numbering (``inverse``: that
    numbering of scikit-fem's degrees of freedom; ``x`` the node coordinates in it)."""
    return _discretization(rod, order, mass_kind, x, _ordered_cells(order, x, inverse[basis.element_dofs.T]),
                           stiffness, consistent)


def _ordered_cells(order: int, x: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Element node indices (left vertex, right vertex, then the midpoint for P2), elements left to right."""
    if order == 2:
        # scikit-fem's local order is (vertex, vertex, midpoint); make vertices left, right.
        left_first = x[cells[:, 0]] < x[cells[:, 1]]
        cells[~left_first, :2] = cells[~left_first, 1::-1]
    else:
        cells = np.sort(cells, axis=1)
    return cells[np.argsort(x[cells[:, 0]])]


def _discretization(rod, order: int, mass_kind: str, x, cells, stiffness, consistent, lumped=None,
                    diagonal=None, stiffness_bands=None) -> RodDiscretization:
    """The :class:`RodDiscretization` of assembled matrices and element node indices, left to right (``lumped``:
    the row sums of ``consistent``, ``diagonal`` the lumped mass matrix, ``stiffness_bands`` the upper bands of
    ``stiffness``, where the caller has them)."""
    if lumped is None:
        lumped = np.asarray(consistent.sum(axis=1)).ravel()
    if np.any(lumped <= 0.0):  # cannot happen for P1/P2 in 1D; guard for future orders
        raise InvalidParameterError(f"row-sum lumping of order {order} gives non-positive masses")
    if mass_kind == "lumped":
        mass_matrix = sp.diags(lumped).tocsr() if diagonal is None else diagonal
        cholesky = None
    else:
        mass_matrix = consistent
        cholesky = scipy.linalg.cholesky_banded(_lower_bands(consistent, order), lower=True)
    return RodDiscretization(
        rod=rod,
        order=order,
        mass_kind=mass_kind,
        x=x,
        cells=np.ascontiguousarray(cells),
        stiffness_bands=_bands(stiffness, order) if stiffness_bands is None else stiffness_bands,
        lumped_mass=lumped,
        mass_cholesky=cholesky,
        stiffness=stiffness,
        mass_matrix=mass_matrix,
    )


def _lower_bands(matrix: sp.csr_matrix, width: int) -> np.ndarray:
    n = matrix.shape[0]
    bands = np.zeros((width + 1, n))
    for d in range(width + 1):
        bands[d, : n - d] = matrix.diagonal(-d)
    return bands
