"""The general explicit step's mass solve (fem/explicit_step.py) against scipy's sparse solver."""

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spl

from wavecontact import Rod
from wavecontact.fem.discretization import discretize_rod
from wavecontact.fem.explicit_step import elastic_acceleration, mass_acceleration, prepare_mass, step_rod


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("mass", ["lumped", "consistent"])
@pytest.mark.parametrize("elements", [1, 2, 3, 4, 5, 6, 7, 8, 9, 60, 61])  # both sides of the twisted solve's minimum
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


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("mass", ["lumped", "consistent"])
@pytest.mark.parametrize("elements", [1, 2, 3, 8, 61])
def test_fused_step_equals_a_step_written_with_sparse_matrices(order, mass, elements):
    """Ten steps of ``step_rod`` against ``v += dt M^-1 (-K u)``, ``u += dt v`` with scipy on an irregular mesh."""
    rng = np.random.default_rng(3 * elements + order)
    length = 0.9
    interior = np.sort(rng.uniform(0.0, length, elements - 1))
    disc = discretize_rod(Rod(length, 2.0, 3.0, 0.5), np.r_[0.0, interior, length], order, mass)
    kind, table = prepare_mass(disc)
    u, v = rng.normal(size=disc.n_nodes), rng.normal(size=disc.n_nodes)
    u_ref, v_ref = u.copy(), v.copy()
    mass_matrix = disc.mass_matrix.tocsc()
    bands = disc.stiffness_bands  # upper bands of the assembled K: bands[d, i] = K[i, i + d]
    stiffness = sum(sp.diags(bands[d, : disc.n_nodes - d], d) for d in range(1, bands.shape[0]))
    stiffness = stiffness + stiffness.T + sp.diags(bands[0])
    dt = 1e-3
    scratch = np.empty(disc.n_nodes)
    for _ in range(10):
        step_rod(u, v, scratch, disc.stiffness_bands, kind, table, dt)
        v_ref += dt * spl.spsolve(mass_matrix, -(stiffness @ u_ref))
        u_ref += dt * v_ref
    np.testing.assert_allclose(v, v_ref, rtol=0, atol=1e-11 * np.abs(v_ref).max())
    np.testing.assert_allclose(u, u_ref, rtol=0, atol=1e-12 * np.abs(u_ref).max())
