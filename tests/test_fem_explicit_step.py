"""The general explicit step's mass solve (fem/explicit_step.py) against scipy's sparse solver."""

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spl
from pure_python_runs import pure_and_compiled_outputs
from scipy.linalg import solve_banded

from wavecontact import Rod
from wavecontact.fem.discretization import discretize_rod
from wavecontact.fem.explicit_step import (
    T_CHAIN_BACKWARD,
    T_CHAIN_BURN_IN,
    T_CHAIN_FORWARD,
    _burn_in,
    _chains,
    elastic_acceleration,
    mass_acceleration,
    prepare_mass,
    rod_acceleration,
    step_rod,
)
from wavecontact.fem.interleaved_step import L_SHAPE, LANE_MIN_UNKNOWNS, LANE_MIN_VERTICES, LANES


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
def test_rod_acceleration_is_the_elastic_acceleration(order, mass):
    """The Python entry (a lumped mass without the compiled solves) gives ``M^-1 (-K u)`` of scipy, and bit for
    bit what the compiled :func:`elastic_acceleration` gives (the time loops' energy checks use that one)."""
    rng = np.random.default_rng(order + 5)
    interior = np.sort(rng.uniform(0.0, 1.3, 16))
    disc = discretize_rod(Rod(1.3, 2.0, 3.0, 0.5), np.r_[0.0, interior, 1.3], order, mass)
    kind, table = prepare_mass(disc)
    u = rng.normal(size=disc.n_nodes)
    out = np.empty(disc.n_nodes)
    rod_acceleration(u, disc.stiffness_bands, kind, table, out)
    compiled = np.empty(disc.n_nodes)
    elastic_acceleration(u, disc.stiffness_bands, kind, table, compiled)
    assert np.array_equal(out, compiled)
    matrix = sp.diags(disc.lumped_mass) if mass == "lumped" else disc.mass_matrix
    expected = spl.spsolve(matrix.tocsc(), -(disc.stiffness @ u))
    np.testing.assert_allclose(out, expected, rtol=0, atol=1e-12 * np.abs(expected).max())


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


def _graded_nodes(rng, elements, length, spread):
    """A mesh whose element lengths vary by up to a factor ``spread`` from one element to the next."""
    sizes = np.exp(rng.uniform(0.0, np.log(spread), elements))
    return np.r_[0.0, np.cumsum(sizes)] * (length / sizes.sum())


def _banded_mass(disc):
    """The assembled mass matrix in scipy.linalg.solve_banded's upper-form layout (an independent solve)."""
    dense = disc.mass_matrix.toarray()
    width = 1 if disc.order == 1 else 2
    banded = np.zeros((2 * width + 1, disc.n_nodes))
    for d in range(-width, width + 1):
        diagonal = np.diagonal(dense, d)
        if d >= 0:
            banded[width - d, d:] = diagonal
        else:
            banded[width - d, : disc.n_nodes + d] = diagonal
    return (width, width), banded


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("spread", [1.0, 3.0])
@pytest.mark.parametrize("elements", [700, 1501])
def test_chained_mass_solve_equals_a_banded_solve_to_rounding(order, spread, elements):
    """The interleaved chains of a large consistent mass (burn-in instead of exact starts) against LAPACK."""
    rng = np.random.default_rng(elements + 100 * order + int(10 * spread))
    disc = discretize_rod(Rod(1.7, 2.0, 3.0, 0.5), _graded_nodes(rng, elements, 1.7, spread), order, "consistent")
    kind, table = prepare_mass(disc)
    assert table[T_CHAIN_BURN_IN, 0] > 0  # the chained solve is the one under test
    (lower, upper), banded = _banded_mass(disc)
    for _ in range(3):
        forces = rng.normal(size=disc.n_nodes) * np.exp(rng.uniform(-5.0, 5.0, disc.n_nodes))
        expected = solve_banded((lower, upper), banded, forces)
        mass_acceleration(kind, table, forces)
        np.testing.assert_allclose(forces, expected, rtol=0, atol=2e-15 * np.abs(expected).max())


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("mass, interleaved", [("lumped", True), ("consistent", True), ("consistent", False)])
@pytest.mark.parametrize("elements", [150, 500, 1301, 2533])
def test_many_fast_steps_equal_a_reference_step_with_a_banded_solve(order, mass, interleaved, elements):
    """400 steps of ``step_rod`` near the stability limit against a step written with scipy's banded solver.

    Consistent masses: the flat layout (asked for; the energy checks' solve): the twisted solve (150, and
    P1 at 500), the chained one (P2 at 500 and all at 1301, 2533); the interleaved layout from
    ``LANE_MIN_UNKNOWNS`` (P1) or ``LANE_MIN_VERTICES`` (P2), every size here, with unknowns that do not
    fill the last row, and chunks shorter (150) and longer than their coupling rows.
    """
    rng = np.random.default_rng(7 * order + len(mass) + elements)
    length = 1.1
    disc = discretize_rod(Rod(length, 2.0, 3.0, 0.5), _graded_nodes(rng, elements, length, 2.0), order, mass)
    kind, table = prepare_mass(disc, interleaved=interleaved)
    if mass == "consistent":
        unknowns = elements + 1
        assert unknowns >= (LANE_MIN_UNKNOWNS if order == 1 else LANE_MIN_VERTICES)
        assert (table[L_SHAPE, 0] > 0) == interleaved
        if interleaved:
            assert unknowns % LANES != 0
        else:
            assert (table[T_CHAIN_BURN_IN, 0] > 0) == (elements > 500 or order == 2 and elements == 500)
    assert_steps_equal_a_banded_solve(disc, kind, table, rng)


def highest_eigenvalue(disc):
    """omega_max^2 of ``K x = omega^2 M x`` (1 / time^2) by Lanczos to a relative 1e-3 (scipy's eigsh).

    The Ritz value lies below omega_max^2 and, on the tests' meshes, within a relative 1.5e-4 of it (measured
    against tol=1e-6 on equal elements of 2^-10, 161 to 1599 elements with far-end remainders of 0, 1/3, 2/3, P1
    and P2: 1.4e-4 at most; graded meshes: 2e-7), so 1.9 / sqrt of it stays below the stability limit
    2 / omega_max (by 5 %) and every mode stays active.  The top of the
    spectrum of equal elements is clustered (gaps of ~1e-6 relative): tol=1e-6 took over 10,000 Lanczos
    iterations there (10 s on 1600 P2 elements, 0.1 s at tol=1e-3).
    """
    return spl.eigsh(disc.stiffness, k=1, M=disc.mass_matrix.tocsc(), which="LM", return_eigenvectors=False,
                     tol=1e-3)[0]


def assert_steps_equal_a_banded_solve(disc, kind, table, rng, steps=400):
    """``steps`` steps of ``step_rod`` near the stability limit from a random state (drawn from ``rng``)
    against a step written with scipy's banded solve of the assembled matrices, to rounding."""
    (lower, upper), banded = _banded_mass(disc)
    stiffness = disc.stiffness  # the assembled K
    highest = highest_eigenvalue(disc)
    dt = 1.9 / np.sqrt(highest)  # stable (central differences need dt < 2 / omega_max), every mode active
    u = 1e-3 * np.sin(3.0 * disc.x) + 1e-6 * rng.normal(size=disc.n_nodes)
    v = rng.normal(size=disc.n_nodes) * 1e-3
    u_ref, v_ref = u.copy(), v.copy()
    scratch = np.empty(disc.n_nodes)
    for _ in range(steps):
        step_rod(u, v, scratch, disc.stiffness_bands, kind, table, dt)
        v_ref += dt * solve_banded((lower, upper), banded, -(stiffness @ u_ref))
        u_ref += dt * v_ref
    # rounding differences grow at most like the number of steps times the conditioning of the step
    np.testing.assert_allclose(v, v_ref, rtol=0, atol=1e-11 * np.abs(v_ref).max())
    np.testing.assert_allclose(u, u_ref, rtol=0, atol=1e-11 * np.abs(u_ref).max())


def test_burn_in_is_refused_when_the_factors_do_not_decay():
    """Factors near 1 (no decay within the chain length): no burn-in, the twisted solve is kept."""
    assert _burn_in(np.full(500, 0.99), np.full(500, 0.99), 60) == 0
    assert _burn_in(np.full(500, -0.2), np.full(500, 0.1), 60) == 28  # 0.2^28 < 2^-64 < 0.2^27
    assert _burn_in(np.full(500, 0.2), np.full(500, 0.1), 27) == 0
    assert _burn_in(np.r_[0.5, np.full(499, 0.1)], np.full(500, 0.1), 60) == 20  # 0.5 * 0.1^19 < 2^-64 < 0.1^19


def test_compiled_chains_equal_their_pure_python_form_bit_for_bit():
    """The interleaved chains compiled by numba and run as plain Python give the same bits (no reassociation)."""
    rng = np.random.default_rng(5)
    disc = discretize_rod(Rod(1.0), _graded_nodes(rng, 900, 1.0, 2.0), 1, "consistent")
    _, table = prepare_mass(disc)
    burn_in = int(table[T_CHAIN_BURN_IN, 0])
    forces = rng.normal(size=disc.n_nodes)
    results = []
    for chains in (_chains, _chains.py_func):
        x = forces.copy()
        chains(x, x, table[T_CHAIN_FORWARD], x.size, burn_in)
        reverse = x[::-1]
        chains(reverse, reverse, table[T_CHAIN_BACKWARD, ::-1], x.size, burn_in)
        results.append(x)
    assert burn_in > 0
    np.testing.assert_array_equal(results[0], results[1])


def test_pure_python_steps_equal_the_compiled_ones_bit_for_bit(tmp_path):
    """WAVECONTACT_PURE_PYTHON=1 (no numba) in a separate process gives the compiled steps' bits, every kind.

    700 elements: the consistent masses take the chained solve (flat layout asked for), 1250 (graded) the
    interleaved layout's arrays, 3001 and 800 (equal elements) also its constants of the uniform rows, and
    these steps with a load on either end node (the force scheme's contact in the time loop) (800:
    P2's 801 vertices in chunks of 26 rows, the last chunk padding only, the padding after the first
    padding unknown held and the backward burn-in over whole chunks) (no reassociation, no fused
    multiply-add in the compiled kernels, so the vectorized passes round exactly as the plain Python loops
    do).
    """

    script = (
        "import sys, numpy as np\n"
        "sys.path.insert(0, sys.argv[2])\n"
        "from wavecontact import Rod\n"
        "from wavecontact.fem.discretization import discretize_rod\n"
        "from wavecontact.fem import interleaved_step as lanes\n"
        "from wavecontact.fem.explicit_step import T_CHAIN_INVERSE, prepare_mass, step_rod\n"
        "out = {}\n"
        "for order, mass, elements in ((1, 'lumped', 700), (2, 'lumped', 700), (1, 'consistent', 700),\n"
        "                              (2, 'consistent', 700), (1, 'consistent', 1250), (2, 'consistent', 1250),\n"
        "                              (1, 'consistent', 3001), (2, 'consistent', 3001), (1, 'consistent', 161),\n"
        "                              (2, 'consistent', 161)):\n"
        "    if True:\n"
        "        rng = np.random.default_rng(order)\n"
        "        sizes = np.exp(rng.uniform(0.0, np.log(2.0), elements))\n"
        "        nodes = np.r_[0.0, np.cumsum(sizes)] / sizes.sum()\n"
        "        if elements in (161, 3001):  # equal elements: the uniform rows run with constants\n"
        "            nodes = np.linspace(0.0, 1.0, elements + 1)\n"
        "        disc = discretize_rod(Rod(1.0, 2.0, 3.0, 0.5), nodes, order, mass)\n"
        "        kind, table = prepare_mass(disc, interleaved=elements != 700)\n"
        "        u, v = 1e-3 * np.sin(7.0 * disc.x), rng.normal(size=disc.n_nodes)\n"
        "        scratch = np.zeros(disc.n_nodes)\n"
        "        for _ in range(5):\n"
        "            step_rod(u, v, scratch, disc.stiffness_bands, kind, table, 1e-4)\n"
        "        out[f'u{order}{mass}{elements}'], out[f'v{order}{mass}{elements}'] = u, v\n"
        "        out[f'layout{order}{mass}{elements}'] = table[24, :3]\n"
        "        out[f'uniform{order}{mass}{elements}'] = table[45, :2]\n"
        "        if mass == 'consistent' and elements != 700:  # the interleaved step with an end load\n"
        "            rows = int(table[lanes.L_SHAPE, 0])\n"
        "            step = lanes.step_tridiagonal_loaded if order == 1 else lanes.step_condensed_loaded\n"
        "            for node in (0, disc.n_nodes - 1):\n"
        "                scale = table[T_CHAIN_INVERSE, node // order]\n"
        "                for force in (1e3, -2e3, 5e2):\n"
        "                    step(table, 1e-4, lanes.node_position(node, rows, order), force * scale)\n"
        "            out[f'loaded{order}{elements}'] = table[lanes.L_U].copy() + table[lanes.L_V]\n"
        "np.savez(sys.argv[1], **out)\n"
    )
    root = Path(__file__).resolve().parents[1]  # this checkout's package
    outputs = pure_and_compiled_outputs(script, tmp_path, root)
    assert len(outputs[0]) == 46
    for order in (1, 2):
        lo, hi = outputs[1][f"uniform{order}consistent3001"]
        assert hi - lo > 50 and np.all(outputs[1][f"uniform{order}consistent1250"] == 1.0)  # constants / arrays
        lo, hi = outputs[1][f"uniform{order}consistent161"]
        assert hi - lo >= 5
    assert outputs[1]["layout2consistent161"][0] == outputs[1]["layout2consistent161"][2] == 22  # burn-in: all rows
    assert outputs[1]["layout1consistent1250"][0] > 0 and outputs[1]["layout2consistent1250"][0] > 0  # interleaved
    assert outputs[1]["layout1consistent700"][0] == 0
    for name in outputs[0]:
        np.testing.assert_array_equal(outputs[0][name], outputs[1][name], err_msg=name)
