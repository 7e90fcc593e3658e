"""The rods' matrices without scikit-fem's set-up are scikit-fem's to the last bit (fem/line_assembly.py).

The reference is the assembly the solver made before: ``Basis(MeshLine(vertices), ElementLineP{1,2}())``, the
forms ``laplace`` and ``mass`` of ``skfem.models.poisson``, the renumbering from left to right and scipy's sum
of the far end's point mass, written out here as it was.
"""

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse as sp
from skfem import Basis, ElementLineP1, ElementLineP2, MeshLine
from skfem.models.poisson import laplace, mass

from wavecontact import Rod
from wavecontact.fem.discretization import discretize_rod, matched_nodes, uniform_nodes
from wavecontact.fem.line_assembly import line_matrices

_ELEMENTS = {1: ElementLineP1, 2: ElementLineP2}


def _scikit_fem(rod, vertices, order, mass_kind, remainder_at):
    """``(x, cells, stiffness, consistent, lumped, mass_matrix)`` as scikit-fem and scipy build them."""
    basis = Basis(MeshLine(vertices), _ELEMENTS[order]())
    perm = np.argsort(basis.doflocs[0], kind="stable")
    inverse = np.empty_like(perm)
    inverse[perm] = np.arange(perm.size)
    stiffness = (laplace.assemble(basis) * (rod.youngs_modulus * rod.area)).tocsr()[perm][:, perm].tocsr()
    consistent = (mass.assemble(basis) * (rod.density * rod.area)).tocsr()[perm][:, perm].tocsr()
    x = basis.doflocs[0][perm].copy()
    missing = rod.length - (vertices[-1] - vertices[0])
    if missing > 1e-12 * rod.length:
        end = 0 if remainder_at == "left" else x.size - 1
        extra = sp.csr_matrix(([rod.density * rod.area * missing], ([end], [end])), shape=consistent.shape)
        consistent = (consistent + extra).tocsr()
    cells = inverse[basis.element_dofs.T]
    if order == 2:
        left_first = x[cells[:, 0]] < x[cells[:, 1]]
        cells[~left_first, :2] = cells[~left_first, 1::-1]
    else:
        cells = np.sort(cells, axis=1)
    cells = cells[np.argsort(x[cells[:, 0]])]
    lumped = np.asarray(consistent.sum(axis=1)).ravel()
    mass_matrix = sp.diags(lumped).tocsr() if mass_kind == "lumped" else consistent
    return x, cells, stiffness, consistent, lumped, mass_matrix


def _same(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def _same_matrix(a, b):
    return all(_same(getattr(a, name), getattr(b, name)) for name in ("data", "indices", "indptr"))


def _meshes():
    rng = np.random.default_rng(20261206)
    meshes = [
        ("one element", 1.0, np.array([0.0, 1.0]), None),
        ("two elements", 1.0, np.array([0.0, 0.3, 1.0]), None),
        ("uniform 800", 0.8, uniform_nodes(0.8, 800), None),
        ("matched long rod", 4 / 3, matched_nodes(4 / 3, 0.8 / 800, from_left=True), "right"),
        ("matched left rod", 4 / 3, matched_nodes(4 / 3, 0.8 / 800, from_left=False), "left"),
        ("matched 3 elements", 1.0, matched_nodes(1.0, 0.3, from_left=True), "right"),
    ]
    for k in range(6):
        count = int(rng.integers(3, 70))
        length = float(rng.uniform(1e-3, 1e3))
        graded = np.cumsum(np.concatenate([[0.0], rng.uniform(0.05, 1.0, count)]))
        meshes.append((f"random {k}", length, graded / graded[-1] * length, None))
    return meshes


@pytest.mark.parametrize("name, length, vertices, remainder_at", _meshes(), ids=[m[0] for m in _meshes()])
def test_discretize_rod_equals_scikit_fem_bit_for_bit(name, length, vertices, remainder_at):
    del name
    rod = Rod(length, density=2.7, youngs_modulus=3.1, area=0.37)
    for order in (1, 2):
        for mass_kind in ("lumped", "consistent"):
            disc = discretize_rod(rod, vertices, order, mass_kind, remainder_at)
            x, cells, stiffness, consistent, lumped, mass_matrix = _scikit_fem(rod, vertices, order, mass_kind,
                                                                               remainder_at)
            assert _same(disc.x, x) and _same(disc.cells, cells)
            assert _same_matrix(disc.stiffness, stiffness)
            assert _same_matrix(disc.mass_matrix, mass_matrix)
            assert _same(disc.lumped_mass, lumped)
            bands = np.zeros((order + 1, x.size))
            for d in range(order + 1):
                bands[d, : x.size - d] = stiffness.diagonal(d)
            assert _same(disc.stiffness_bands, bands)
            if mass_kind == "consistent":
                lower = np.zeros((order + 1, x.size))
                for d in range(order + 1):
                    lower[d, : x.size - d] = consistent.diagonal(-d)
                assert _same(disc.mass_cholesky, scipy.linalg.cholesky_banded(lower, lower=True))


def test_line_matrices_declines_midpoints_out_of_order():
    """Elements so short against their position that the mapped midpoint rounds onto a vertex: scikit-fem's
    stable sort would number them otherwise, so the line is left to scikit-fem."""
    start = 1.0
    vertices = np.array([0.0, start, np.nextafter(start, 2.0), 2.0])
    assert line_matrices(vertices, 2) is None
    rod = Rod(2.0)
    disc = discretize_rod(rod, vertices, 2, "consistent")
    x, cells, stiffness, _, lumped, _ = _scikit_fem(rod, vertices, 2, "consistent", None)
    assert _same(disc.x, x) and _same(disc.cells, cells) and _same_matrix(disc.stiffness, stiffness)
    assert _same(disc.lumped_mass, lumped)
