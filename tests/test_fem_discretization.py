"""Matrices, stable step and contact flows of the finite-element solver."""

import math

import numpy as np
import pytest
import scipy.linalg
from scipy.integrate import solve_ivp

import wavecontact as wc
from wavecontact import Rod
from wavecontact.fem.contact_flows import (
    exponential_flow,
    exponential_gap,
    exponential_gap_quartic,
    penalty_flow,
    penalty_gap,
)
from wavecontact.fem.discretization import discretize_rod, matched_nodes, uniform_nodes
from wavecontact.fem.stability import largest_eigenvalue, stable_step


@pytest.mark.parametrize(
    "order, mass, courant", [(1, "lumped", 1.0), (1, "consistent", 0.57735), (2, "lumped", 0.40825),
                             (2, "consistent", 0.25820)],
)
def test_stable_step_table_on_uniform_mesh(order, mass, courant):
    disc = discretize_rod(Rod(1.0), uniform_nodes(1.0, 40), order, mass)
    assert stable_step([disc]) * 40 == pytest.approx(courant, abs=1e-5)


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("mass", ["lumped", "consistent"])
def test_largest_eigenvalue_matches_dense_solver_on_irregular_mesh(order, mass):
    rng = np.random.default_rng(1)
    vertices = np.concatenate([[0.0], np.sort(rng.uniform(0, 2.0, 30)), [2.0]])
    disc = discretize_rod(Rod(2.0, density=3.0, youngs_modulus=5.0), vertices, order, mass)
    dense = scipy.linalg.eigh(disc.stiffness.toarray(), disc.mass_matrix.toarray(), eigvals_only=True).max()
    assert largest_eigenvalue(disc) == pytest.approx(dense, rel=1e-10)


def test_mass_and_stiffness_invariants():
    rod = Rod(1.7, density=2.0, youngs_modulus=3.0, area=0.5)
    nodes = matched_nodes(rod.length, 0.1, from_left=True)  # 17 elements, no remainder
    assert nodes.size == 18
    nodes = matched_nodes(rod.length, 0.3, from_left=True)  # 5 elements + point mass
    for order in (1, 2):
        for mass in ("lumped", "consistent"):
            disc = discretize_rod(rod, nodes, order, mass, remainder_at="right")
            assert disc.lumped_mass.sum() == pytest.approx(rod.mass, rel=1e-13)
            assert disc.mass_matrix.sum() == pytest.approx(rod.mass, rel=1e-13)
            assert np.abs(disc.stiffness @ np.ones(disc.n_nodes)).max() < 1e-12
            # stress of a uniform strain 0.01 is E * 0.01 at every node
            stress = disc.stress_recovery() @ (0.01 * disc.x)
            assert stress == pytest.approx(np.full(disc.n_nodes, 0.03), rel=1e-12)
            assert disc.cells.shape == (disc.n_elements, order + 1)


def test_exponential_flow_matches_ode_solution():
    m_inv, alpha, strength = 3.0, 50.0, 0.01

    def rhs(t, y):
        return [y[1], m_inv * alpha * strength * np.exp(-alpha * y[0])]

    for r, w, dt in [(0.05, -1.0, 0.01), (0.05, -1.0, 0.3), (-0.01, 0.4, 0.05)]:
        exact = solve_ivp(rhs, (0, dt), [r, w], rtol=1e-12, atol=1e-14).y[:, -1]
        assert exponential_flow(r, w, dt, m_inv, alpha, strength) == pytest.approx(exact, abs=1e-9)
    # far apart the force underflows: plain drift, no NaN
    assert exponential_flow(1e3, -1.0, 0.1, 1.0, 10.0, 1.0) == (999.9, -1.0)


def test_penalty_flow_matches_ode_solution():
    m_inv, k = 3.0, 100.0
    for r, w, dt in [(0.001, -1.0, 0.01), (0.001, -1.0, 0.3), (-0.01, 0.2, 0.05)]:
        exact = solve_ivp(lambda t, y: [y[1], -m_inv * k * min(y[0], 0.0)], (0, dt), [r, w], rtol=1e-12,
                          atol=1e-14, max_step=1e-4).y[:, -1]
        assert penalty_flow(r, w, dt, m_inv, k) == pytest.approx(exact, abs=1e-8)


def test_first_order_gap_equations_match_ode_solution():
    c, alpha, strength = 2.0, 50.0, 0.01
    for r, g, duration in [(0.05, -1.0, 0.01), (0.0, -1.0, 0.1), (-0.01, 0.5, 0.1)]:
        exact = solve_ivp(lambda t, y, g=g: [g + c * alpha * strength * np.exp(-alpha * y[0])], (0, duration),
                          [r], rtol=1e-12, atol=1e-14, method="Radau").y[0, -1]
        assert exponential_gap(r, g, duration, c, alpha, strength) == pytest.approx(exact, abs=1e-11)
    for r, g, duration in [(0.01, -1.0, 0.1), (-0.02, 0.1, 0.1)]:
        exact = solve_ivp(lambda t, y, g=g: [g - c * 30.0 * min(y[0], 0.0)], (0, duration), [r], rtol=1e-12,
                          atol=1e-14, max_step=1e-4).y[0, -1]
        assert penalty_gap(r, g, duration, c, 30.0) == pytest.approx(exact, abs=1e-9)
    # no overflow for an extremely stiff law
    assert math.isfinite(exponential_gap(0.0, -1.0, 1e-3, 2.0, 1e9, 1e-20))


def test_quartic_rate_reconstruction_matches_ode_solution():
    # closing rate a smooth function of time; the kernel only sees its means over five steps
    c, alpha, strength, dt = 2.0, 50.0, 1e-3, 0.02

    def rate(t):
        return -1.0 + 0.8 * np.sin(3.0 * t) + 0.3 * t * t

    def step_mean(k):
        t = np.linspace((k - 0.5) * dt, (k + 0.5) * dt, 2001)
        return np.trapezoid(rate(t), t) / dt

    means = np.array([step_mean(k) for k in range(-2, 3)])
    exact = solve_ivp(lambda t, y: [rate(t) + c * alpha * strength * np.exp(-alpha * y[0])], (-dt / 2, dt / 2),
                      [0.05], rtol=1e-12, atol=1e-14, method="Radau").y[0, -1]
    gauss = exponential_gap_quartic(0.05, means, dt, c, alpha, strength, 0)
    substeps = exponential_gap_quartic(0.05, means, dt, c, alpha, strength, 32)
    constant = exponential_gap(0.05, means[2], dt, c, alpha, strength)
    assert abs(gauss - exact) < 1e-9
    assert abs(substeps - exact) < 1e-8
    assert abs(constant - exact) > 100 * abs(substeps - exact)  # the reconstruction matters here


def test_fields_layout_for_the_io_helpers():
    result = wc.collide(0.6, 100, solver="fem", elements=20, order=2, record_fields=True, field_samples=50)
    fields = result.extra["fields"]
    nt = fields["time"].size
    assert 2 <= nt <= 50
    assert np.all(np.diff(fields["time"]) > 0)
    for rod in fields["rods"]:
        n = rod["x"].size
        for name in ("displacement", "velocity", "stress"):
            assert rod[name].shape == (nt, n)
            assert np.all(np.isfinite(rod[name]))
        assert rod["cells"].shape[1] == 3
        assert rod["cells"].max() == n - 1
    left, right = fields["rods"]
    assert left["x"].max() < right["x"].min()  # rod 1 left of rod 2, contact near x = 0


def test_penalty_contact_runs_and_is_plausible():
    result = wc.collide(0.6, math.inf, solver="fem", contact="penalty", elements=400)
    assert result.restitution == pytest.approx(0.6, abs=0.02)
    # the main contact lasts 2 l1 / c; the ends may touch again briefly while grazing
    force = result.contact_force
    active = force > 1e-3 * force.max()
    first_block_end = np.argmax(~active[np.argmax(active):]) + np.argmax(active)
    main = result.time[first_block_end] - result.time[np.argmax(active)]
    assert main == pytest.approx(1.6, rel=0.02)
