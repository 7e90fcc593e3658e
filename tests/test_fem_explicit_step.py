"""The general explicit step's mass solve (fem/explicit_step.py) against scipy's sparse solver."""

import numpy as np
import pytest
import scipy.sparse.linalg as spl

from wavecontact import Rod
from wavecontact.fem.discretization import discretize_rod
from wavecontact.fem.explicit_step import elastic_acceleration, mass_acceleration, prepare_mass


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("mass", ["lumped", "consistent"])
@pytest.mark.parametrize("elements", [1, 2, 3, 4, 5, 7, 60])  # below, at and above the four-fold unrolling
def test_mass_solve_equals_a_sparse_direct_solve(order, mass, elements):
    rng = np.random.default_rng(elements + 10 * order)
    length = 1.3
    interior = np.sort(rng.uniform(0.0, length, elements - 1))
    disc = discretize_rod(Rod(length, 2.0, 3.0, 0.5), np.r_[0.0, interior, length], order, mass)
    kind, table = prepare_mass(disc)
    forces = rng.normal(size=disc.n_nodes)
    expected = spl.spsolve(disc.mass_matrix.tocsc(), forces)
    mass_acceleration(kind, table, forces)
    np.testing.assert_allclose(forces, expected, rtol=0, atol=1e-13 * np.abs(expected).max())


def test_rigid_motion_has_no_acceleration():
    disc = discretize_rod(Rod(1.0), np.linspace(0.0, 1.0, 41), 2, "consistent")
    kind, table = prepare_mass(disc)
    out = np.empty(disc.n_nodes)
    elastic_acceleration(np.full(disc.n_nodes, 3.7), disc.stiffness_bands, kind, table, out)
    assert np.all(out == 0.0)
