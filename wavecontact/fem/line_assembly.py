"""Stiffness and mass of a line of Lagrange elements in scikit-fem's arithmetic, without its set-up.

:func:`wavecontact.fem.discretization.discretize_rod` assembled each rod with scikit-fem
(``Basis(MeshLine(vertices), ElementLineP{1,2}())``, the forms ``laplace`` and ``mass``, then a
renumbering of the degrees of freedom from left to right).  On the meshes of one solve that cost about
a millisecond per rod, mostly in the set-up of the basis (quadrature, degree-of-freedom tables, the
sparse format conversions), while the arithmetic is a few vectorised products over the elements.

:func:`line_matrices` does that arithmetic alone: the element matrices with the same quadrature, the
same operations in the same order and the same array layouts (so the same roundings, sums over the
quadrature points included), the element contributions summed into the same compressed-row arrays
scikit-fem's assembly and the renumbering produce (indices, their order within each row, values).
``tests/test_fem_line_assembly.py`` checks every array against scikit-fem to the last bit on uniform,
matched, graded and random meshes of both orders.  Where the left-to-right numbering would not be the
interleaving of vertices and midpoints (a mesh whose mapped midpoints fall out of order by round-off)
it returns None and the caller assembles with scikit-fem.
"""

from __future__ import annotations

import functools

import numpy as np
import scipy.sparse as sp
from skfem import ElementLineP1, ElementLineP2
from skfem.quadrature import get_quadrature_line

__all__ = ["LineMatrices", "line_matrices"]

_ELEMENTS = {1: ElementLineP1, 2: ElementLineP2}


@functools.cache
def _reference(order: int) -> tuple:
    """Quadrature points and weights of scikit-fem's default rule (degree ``2 order``) and the reference basis
    values and derivatives of each local function at them."""
    element = _ELEMENTS[order]()
    points, weights = get_quadrature_line(2 * element.maxdeg)
    local = [element.lbasis(points, i) for i in range(order + 1)]
    return points, weights, [phi for phi, _ in local], [dphi for _, dphi in local]


class LineMatrices:
    """Plain arrays of one assembled line, in the left-to-right numbering of the degrees of freedom.

    Attributes
    ----------
    x : ndarray, shape (n,)
        Node coordinates as scikit-fem maps them (length; an element's right vertex is ``(b - a) * 1 + a``).
    cells : ndarray of intp, shape (n_el, order + 1)
        Node indices of each element: left vertex, right vertex, then the midpoint for P2.
    indptr, indices : ndarray of int32
        The compressed-row structure of both matrices (indices in scikit-fem's order within each row; shared
        with other lines of as many elements: read only).
    stiffness, mass : ndarray
        Values of ``int phi_i' phi_j' ds`` (1/length) and ``int phi_i phi_j ds`` (length) in that structure.
    sorted : bool
        Whether each row's indices increase (P1; P2 rows keep scikit-fem's vertices-first order).
    """

    __slots__ = ("cells", "indices", "indptr", "mass", "sorted", "stiffness", "x")

    def __init__(self, x, cells, indptr, indices, stiffness, mass, sorted_rows):
        self.x, self.cells, self.indptr, self.indices = x, cells, indptr, indices
        self.stiffness, self.mass, self.sorted = stiffness, mass, sorted_rows

    def matrix(self, values: np.ndarray) -> sp.csr_matrix:
        """The compressed-row matrix of ``values`` (an attribute's values, scaled) in the shared structure."""
        n = self.x.size
        return sp.csr_matrix((values, self.indices.copy(), self.indptr.copy()), shape=(n, n))

    def position(self, row: int, column: int) -> int:
        """Index into the values of the entry ``(row, column)``."""
        start = self.indptr[row]
        return int(start + np.flatnonzero(self.indices[start:self.indptr[row + 1]] == column)[0])

    def row_sums(self, values: np.ndarray) -> np.ndarray:
        """Each row's values summed as ``scipy.sparse`` sums them for ``matrix.sum(axis=1)``: numpy's
        ``add.reduceat`` over the stored order, which adds the first entry to the sum of the others."""
        if not self.sorted:
            return np.add.reduceat(values, self.indptr[:-1].astype(np.intp))
        sums = np.empty(self.x.size)
        rows = _p1_rows(values)
        sums[0] = values[0] + values[1]
        sums[1:-1] = rows[:, 0] + (rows[:, 1] + rows[:, 2])
        sums[-1] = values[-2] + values[-1]
        return sums

    def upper_bands(self, values: np.ndarray) -> np.ndarray | None:
        """P1: ``bands[d, i]`` the entry ``(i, i + d)`` of ``values`` (zero past the end), as
        ``matrix.diagonal(d)`` reads them; None for P2 (its rows are not in column order)."""
        if not self.sorted:
            return None
        bands = np.zeros((2, self.x.size))
        rows = _p1_rows(values)
        bands[0, 0], bands[0, 1:-1], bands[0, -1] = values[0], rows[:, 1], values[-1]
        bands[1, 0], bands[1, 1:-1] = values[1], rows[:, 2]
        return bands


def _p1_rows(values: np.ndarray) -> np.ndarray:
    """The interior rows of a P1 line's values, ``(r, r - 1), (r, r), (r, r + 1)`` per row (a view)."""
    return values[2:-2].reshape(-1, 3)


def _element_values(vertices: np.ndarray, order: int) -> tuple:
    """``(stiffness, mass)``: dicts ``(j, i) -> value per element`` with the roundings of scikit-fem's
    ``BilinearForm._kernel``, ``np.sum(form * dx, axis=1)``: its affine map of the reference element
    (``A = b - a``, gradients ``(1 / A) phi'``, weights ``|A| W``), the form's product at each quadrature point
    times the weight, and the sum over the points from the first to the last (numpy's order for these few
    points; the test against scikit-fem holds it to that)."""
    _points, weights, phis, dphis = _reference(order)
    a = vertices[1:] - vertices[:-1]
    inverse = 1.0 / a
    if order == 1 and _plain_p1(weights, dphis):
        return _p1_values(inverse, np.abs(a) * weights[0], phis)
    dx = [np.abs(a) * w for w in weights]
    grads = [[inverse * d for d in dphi[0]] for dphi in dphis]
    stiffness, mass = {}, {}
    for j in range(order + 1):
        for i in range(j, order + 1):
            # the products commute exactly: entry (i, j) equals entry (j, i) bit for bit
            stiffness[j, i] = stiffness[i, j] = _in_order([gj * gi * w for gj, gi, w in zip(grads[j], grads[i], dx)])
            mass[j, i] = mass[i, j] = _in_order([(pj * pi) * w for pj, pi, w in zip(phis[j], phis[i], dx)])
    return stiffness, mass


def _plain_p1(weights, dphis) -> bool:
    """Whether the P1 rule has equal weights and the derivatives ``-1, +1`` at every point (scikit-fem's)."""
    return bool(weights[0] == weights[-1] and np.all(dphis[0] == -1.0) and np.all(dphis[1] == 1.0))


def _p1_values(inverse: np.ndarray, dx: np.ndarray, phis: list) -> tuple:
    """:func:`_element_values` of P1 with equal weights (``dx`` at every point) and gradients ``-1 / A`` and
    ``1 / A``: their products are ``+-(1 / A)^2`` exactly, so every stiffness entry is ``+-`` one sum."""
    term = (inverse * inverse) * dx
    diagonal = _in_order([term] * len(phis[0]))
    stiffness = {(0, 0): diagonal, (1, 1): diagonal, (0, 1): -diagonal, (1, 0): -diagonal}
    mass = {}
    for j, i in ((0, 0), (0, 1), (1, 1)):
        mass[j, i] = mass[i, j] = _in_order([(pj * pi) * dx for pj, pi in zip(phis[j], phis[i])])
    return stiffness, mass


def _in_order(terms: list) -> np.ndarray:
    total = terms[0] + terms[1]
    for term in terms[2:]:
        total = total + term
    return total


def _mapped_nodes(vertices: np.ndarray, order: int) -> np.ndarray:
    """Node coordinates in the left-to-right numbering as scikit-fem's ``doflocs`` maps them, ``A X + a`` of
    each element's local nodes: the first vertex ``A 0 + a``, every other vertex the right end of its left
    element ``A 1 + a`` (written last), midpoints ``A / 2 + a``."""
    a = vertices[1:] - vertices[:-1]
    left = vertices[:-1]
    ends = np.empty(vertices.size)
    ends[0] = a[0] * 0.0 + left[0]
    ends[1:] = a * 1.0 + left
    if order == 1:
        return ends
    x = np.empty(2 * vertices.size - 1)
    x[0::2] = ends
    x[1::2] = a * 0.5 + left
    return x


def line_matrices(vertices: np.ndarray, order: int) -> LineMatrices | None:
    """The assembled line on ``vertices`` (strictly increasing element end points, length) with Lagrange
    elements of ``order`` (1 or 2); None where scikit-fem's left-to-right numbering (a stable sort of the
    mapped nodes) would not be the interleaving of vertices and midpoints."""
    x = _mapped_nodes(vertices, order)
    if not np.all(x[1:] > x[:-1]):
        return None
    stiffness, mass = _element_values(vertices, order)
    indptr, indices, placements, cells = _layout(vertices.size - 1, order)
    values = []
    for local in (stiffness, mass):
        data = np.empty(indices.size)
        if order == 1:  # the placements below, by slices
            diagonal, following = _shared_vertices(local), local[0, 1]
            rows = _p1_rows(data)
            data[0], data[1], data[-2], data[-1] = diagonal[0], following[0], following[-1], diagonal[-1]
            rows[:, 0], rows[:, 1], rows[:, 2] = following[:-1], diagonal[1:-1], following[1:]
        else:
            for positions, key in placements:
                data[positions] = _shared_vertices(local) if key is None else local[key]
        values.append(data)
    return LineMatrices(x, cells.copy(), indptr, indices, values[0], values[1], order == 1)


def _shared_vertices(local: dict) -> np.ndarray:
    """Diagonal entries of the vertices: the two elements' contributions summed where two elements meet
    (scikit-fem sums the duplicate entries before any scaling; the two terms commute exactly)."""
    count = local[0, 0].size
    diagonal = np.empty(count + 1)
    diagonal[0] = local[0, 0][0]
    diagonal[-1] = local[1, 1][-1]
    diagonal[1:-1] = local[1, 1][:-1] + local[0, 0][1:]
    return diagonal


@functools.lru_cache(maxsize=32)
def _layout(count: int, order: int) -> tuple:
    """``(indptr, indices, placements, cells)`` of a line of ``count`` elements (read-only arrays, kept for the
    next line of as many elements): ``placements`` lists ``(positions, key)``, the values of the element
    entry ``key = (j, i)`` at ``positions`` (per element), or with ``key`` None the vertices' diagonal."""
    layout = _p1_layout(count) if order == 1 else _p2_layout(count)
    elements = np.arange(count, dtype=np.intp)
    cells = np.empty((count, order + 1), dtype=np.intp)
    cells[:, 0] = order * elements
    cells[:, 1] = order * (elements + 1)
    if order == 2:
        cells[:, 2] = 2 * elements + 1
    for array in (*layout[:2], cells, *(positions for positions, _ in layout[2])):
        array.flags.writeable = False
    return (*layout, cells)


def _structure(counts: np.ndarray) -> tuple:
    indptr = np.zeros(counts.size + 1, dtype=np.int32)
    np.cumsum(counts, out=indptr[1:])
    return indptr, np.empty(indptr[-1], dtype=np.int32)


def _p1_layout(count: int) -> tuple:
    """P1 rows in column order: ``(r, r - 1), (r, r), (r, r + 1)`` (fewer at the ends)."""
    n = count + 1
    rows = np.arange(n, dtype=np.int32)
    counts = np.full(n, 3, dtype=np.int32)
    counts[0] -= 1
    counts[-1] -= 1
    indptr, indices = _structure(counts)
    diagonal = indptr[:-1] + (rows > 0)
    indices[diagonal] = rows
    indices[diagonal[1:] - 1] = rows[:-1]
    indices[diagonal[:-1] + 1] = rows[1:]
    return indptr, indices, [(diagonal, None), (diagonal[1:] - 1, (0, 1)), (diagonal[:-1] + 1, (0, 1))]


def _p2_layout(count: int) -> tuple:
    """P2 rows in scikit-fem's order: its numbering has the vertices first, then the midpoints, and the
    renumbering keeps each row's entries in that numbering's column order.  Vertex ``v`` (node ``2v``):
    ``2v - 2, 2v, 2v + 2, 2v - 1, 2v + 1``; midpoint of element ``e`` (node ``2e + 1``): ``2e, 2e + 2, 2e + 1``."""
    vertices = np.arange(count + 1, dtype=np.int32)
    has_left = (vertices > 0).astype(np.int32)
    has_right = (vertices < count).astype(np.int32)
    counts = np.empty(2 * count + 1, dtype=np.int32)
    counts[0::2] = 1 + 2 * has_left + 2 * has_right
    counts[1::2] = 3
    indptr, indices = _structure(counts)
    start = indptr[:-1][0::2]
    diagonal = start + has_left
    previous, following = start[1:], diagonal[:-1] + 1  # the neighbouring vertices (v >= 1, v < count)
    left_midpoint = diagonal[1:] + 1 + has_right[1:]
    right_midpoint = diagonal[:-1] + 2 + has_left[:-1]
    middle = indptr[:-1][1::2]
    placements = [(diagonal, None), (previous, (0, 1)), (following, (0, 1)), (left_midpoint, (1, 2)),
                  (right_midpoint, (0, 2)), (middle, (0, 2)), (middle + 1, (1, 2)), (middle + 2, (2, 2))]
    columns = [2 * vertices, 2 * vertices[:-1], 2 * vertices[1:], 2 * vertices[:-1] + 1, 2 * vertices[:-1] + 1,
               2 * vertices[:-1], 2 * vertices[1:], 2 * vertices[:-1] + 1]
    for (positions, _), column in zip(placements, columns):
        indices[positions] = column
    return indptr, indices, placements
