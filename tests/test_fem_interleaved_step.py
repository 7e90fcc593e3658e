"""The interleaved layout of large consistent masses (fem/interleaved_step.py): layout, solve, time loop."""

import numpy as np
import pytest
import scipy.sparse.linalg as spl
from scipy.linalg import solve_banded
from test_fem_explicit_step import _banded_mass, _graded_nodes

import wavecontact
from wavecontact import Rod
from wavecontact.fem import interleaved_step
from wavecontact.fem.discretization import discretize_rod
from wavecontact.fem.explicit_step import prepare_mass, step_rod
from wavecontact.fem.interleaved_step import (
    L_SHAPE,
    LANES,
    node_position,
    pack_nodes,
    table_width,
    unpack_nodes,
)
from wavecontact.fem.simulation import _Run, build_setup, run_collision


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("elements", [63, 64, 100, 1301])
def test_packing_places_every_node_where_node_position_says(order, elements):
    nodes = order * elements + 1
    unknowns = elements + 1  # P1 nodes, or P2 vertices
    rows = -(-unknowns // LANES)
    x = np.arange(nodes, dtype=float) + 1.0
    packed = np.zeros(order * (rows + 1) * LANES)
    pack_nodes(x, packed, rows, order)
    for node in range(nodes):
        assert packed[node_position(node, rows, order)] == x[node]
    assert np.count_nonzero(packed) == nodes  # the padding stays zero
    back = np.zeros(nodes)
    unpack_nodes(packed, back, rows, order)
    np.testing.assert_array_equal(back, x)


def test_table_rows_do_not_start_a_multiple_of_4_kib_apart():
    for minimum in (10, 1000, 10752, 43008):
        width = table_width(minimum)
        assert width >= minimum and (width * 8) % 4096 == 192


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("elements", [70, 333])  # 2 and 11 rows per chunk: fewer rows than the corrections span
def test_short_chunks_equal_a_reference_step_with_a_banded_solve(monkeypatch, order, elements):
    """Chunks shorter than the rows their neighbour's correction reaches (the corrections then cross whole
    chunks): 400 steps near the stability limit against a step with LAPACK's banded solver."""
    monkeypatch.setattr(interleaved_step, "LANE_MIN_UNKNOWNS", 0)
    monkeypatch.setattr(interleaved_step, "LANE_MIN_VERTICES", 0)
    rng = np.random.default_rng(elements + order)
    disc = discretize_rod(Rod(1.1, 2.0, 3.0, 0.5), _graded_nodes(rng, elements, 1.1, 3.0), order, "consistent")
    kind, table = prepare_mass(disc)
    rows, forward_rows, backward_rows = table[L_SHAPE, :3]
    assert 2 <= rows <= min(forward_rows, backward_rows)  # every row of a chunk is corrected
    (lower, upper), banded = _banded_mass(disc)
    stiffness = disc.stiffness
    highest = spl.eigsh(stiffness, k=1, M=disc.mass_matrix.tocsc(), which="LM", return_eigenvectors=False)[0]
    dt = 1.9 / np.sqrt(highest)
    u = 1e-3 * np.sin(3.0 * disc.x) + 1e-6 * rng.normal(size=disc.n_nodes)
    v = rng.normal(size=disc.n_nodes) * 1e-3
    u_ref, v_ref = u.copy(), v.copy()
    scratch = np.empty(disc.n_nodes)
    for _ in range(400):
        step_rod(u, v, scratch, disc.stiffness_bands, kind, table, dt)
        v_ref += dt * solve_banded((lower, upper), banded, -(stiffness @ u_ref))
        u_ref += dt * v_ref
    np.testing.assert_allclose(v, v_ref, rtol=0, atol=1e-11 * np.abs(v_ref).max())
    np.testing.assert_allclose(u, u_ref, rtol=0, atol=1e-11 * np.abs(u_ref).max())


@pytest.mark.parametrize("order", [1, 2])
def test_collision_in_the_interleaved_layout_equals_the_flat_one_to_rounding(monkeypatch, order):
    """A whole collision (contact on the packed ends, energy checks on the unpacked state) in both layouts."""
    scene = wavecontact.two_rods(0.6, 100)
    results = []
    for threshold in (10**9, 0):
        monkeypatch.setattr(interleaved_step, "LANE_MIN_UNKNOWNS", threshold)
        monkeypatch.setattr(interleaved_step, "LANE_MIN_VERTICES", threshold)
        setup = build_setup(scene, elements=300, order=order, mass="consistent")
        run = _Run(setup, 0.05)
        assert [int(table[L_SHAPE, 0]) > 0 for _, table in run.mass_solves] == [threshold == 0] * 2
        results.append(run_collision(setup))
    flat, packed = results
    assert flat["steps"] == packed["steps"]
    scale = np.abs(flat["contact_force"]).max()
    np.testing.assert_allclose(packed["contact_force"], flat["contact_force"], rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(packed["relative_velocity"], flat["relative_velocity"], rtol=0, atol=1e-12)
    for name in ("kinetic", "strain"):
        np.testing.assert_allclose(packed[name], flat[name], rtol=1e-11)
    for flat_u, packed_u in zip(flat["run"].u, packed["run"].u):  # the final fields, unpacked
        np.testing.assert_allclose(packed_u, flat_u, rtol=0, atol=1e-11 * np.abs(flat_u).max())
    momentum = packed["run"].momentum()
    assert abs(momentum - packed["run"].momentum0) <= 1e-12 * packed["run"].momentum_scale
