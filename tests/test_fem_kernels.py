"""The exact-lattice kernel (d'Alembert buffers, O(1) per step) against a node-by-node lattice.

The reference below is the straightforward two-level lattice written here in
NumPy: every node is updated every step (``u_new = u_left + u_right - u_old``
inside, the general central difference at the two end nodes of each rod,
whose masses differ), with the characteristic contact treatment of
:func:`wavecontact.fem.kernels.advance_lattice` read off the node arrays.
"""

import itertools
import math

import numpy as np
import pytest

import wavecontact as wc
from wavecontact.fem import kernels
from wavecontact.fem.contact_flows import (
    LAW_EXPONENTIAL,
    exponential_gap,
    exponential_gap_linear,
    exponential_gap_quartic,
    interface_gap,
)
from wavecontact.fem.simulation import _Run, build_setup


def _end_rule(u, w, bands, inverse_mass, dt):
    """New end displacements of one rod (general central difference)."""
    scale = dt * dt
    first = 2.0 * u[0] - w[0] - scale * inverse_mass[0] * bands[1, 0] * (u[1] - u[0])
    last = 2.0 * u[-1] - w[-1] - scale * inverse_mass[-1] * bands[1, u.size - 2] * (u[-2] - u[-1])
    return first, last


class ReferenceLattice:
    """Node-by-node two-level lattice of both rods with the characteristic contact."""

    def __init__(self, run):
        self.setup = run.setup
        self.u = [u.copy() for u in run.u]
        self.w = [w.copy() for w in run.w]
        self.state = run.state.copy()
        self.inverse_mass = run.inverse_mass
        self.m_inv = run.m_inv
        self.masses = [float(d.lumped_mass.sum()) for d in run.setup.rods]

    def _incoming(self):
        (u1, u2), (w1, w2), dt = self.u, self.w, self.setup.dt
        mean_rate = ((u2[1] - w2[0]) - (u1[-2] - w1[-1])) / dt
        incoming = 2.0 * mean_rate - self.state[kernels.S_INCOMING]
        rates = np.zeros(5)
        rates[:3] = self.state[kernels.S_INCOMING_EARLIER], self.state[kernels.S_INCOMING], incoming
        if self.setup.centered:
            for j in (2, 3):
                later = ((u2[j] - w2[j - 1]) - (u1[-1 - j] - w1[-j])) / dt
                rates[j + 1] = 2.0 * later - rates[j]
        return incoming, rates

    def step(self):
        """One step; returns ``(force, gap)`` as the kernel records them."""
        s, state = self.setup, self.state
        (u1, u2), dt = self.u, s.dt
        r_now = s.gap + u2[0] - u1[-1]
        incoming, rates = self._incoming()
        compliance = 0.5 * self.m_inv * dt
        varies = False
        if s.gap_substeps > 1:
            if s.centered:
                variation = np.max(np.abs(rates[[0, 1, 3, 4]] - incoming))
            else:
                variation = abs(incoming - state[kernels.S_INCOMING])
            varies = s.law == LAW_EXPONENTIAL and variation > (1e-13 if s.gauss else 1e-7) * abs(incoming)
        earlier = state[kernels.S_INCOMING]
        state[kernels.S_INCOMING_EARLIER] = earlier
        state[kernels.S_INCOMING] = incoming
        new = []
        for u, w, disc, inverse_mass in zip(self.u, self.w, s.rods, self.inverse_mass):
            first, last = _end_rule(u, w, disc.stiffness_bands, inverse_mass, dt)
            after = np.empty_like(u)
            after[1:-1] = u[:-2] + u[2:] - w[1:-1]
            after[0], after[-1] = first, last
            new.append(after)
        r_free = s.gap + new[1][0] - new[0][-1]
        if varies:
            closest = min(r_now, r_free)
            far = s.alpha * s.strength * math.exp(-s.alpha * closest) * self.m_inv * dt * dt < 1e-17 * closest
            varies = not (s.alpha * closest > 40.0 and far)
        if varies and s.centered:
            substeps = 0 if s.gauss else s.gap_substeps
            r_after = exponential_gap_quartic(r_now, rates, dt, compliance, s.alpha, s.strength, substeps)
        elif varies:
            slope = (incoming - earlier) / dt
            r_after = exponential_gap_linear(r_now, incoming, slope, dt, compliance, s.alpha, s.strength,
                                             s.gap_substeps)
        else:
            r_after = interface_gap(s.law, r_now, incoming, dt, compliance, s.alpha, s.strength, s.stiffness)
        shift = (r_after - r_free) / self.m_inv
        new[0][-1] -= self.inverse_mass[0][-1] * shift
        new[1][0] += self.inverse_mass[1][0] * shift
        self.w, self.u = self.u, new
        state[kernels.S_MOMENTUM1] -= shift / dt
        state[kernels.S_MOMENTUM2] += shift / dt
        return shift / dt / dt, s.gap + new[1][0] - new[0][-1]

    def energies(self):
        """Kinetic and strain energy of the staggered pair (u, w)."""
        dt, kinetic, strain = self.setup.dt, 0.0, 0.0
        for u, w, disc in zip(self.u, self.w, self.setup.rods):
            kinetic += 0.5 * np.sum(disc.lumped_mass * ((u - w) / dt) ** 2)
            strain -= 0.5 * np.sum(disc.stiffness_bands[1, :-1] * np.diff(w) * np.diff(u))
        return kinetic, strain


def _wavy(amplitude, wavenumber):
    return lambda x: amplitude * np.sin(wavenumber * x + 0.3)


def _scene(kappa, gamma=0.6, gap=1.0):
    """Two rods with internal vibrations already under way (non-trivial initial fields), ``gap`` apart."""
    return wc.two_rods(gamma, kappa, gap=gap, initial_displacement=(_wavy(0.02, 7.0), _wavy(-0.01, 3.0)),
                       initial_velocity=(_wavy(0.3, 5.0), _wavy(0.2, 11.0)))


CASES = [
    # (scene, elements): quartic reconstruction (resolved), the far node of rod 2 carries the remainder
    (_scene(100.0), 40),
    (_scene(100.0), 40, {"gap_quadrature": "gauss"}),
    (_scene(1e4), 40),  # unresolved: constant-rate gap equation, no remainder node
    (_scene(100.0, gamma=0.7, gap=30.0), 3),  # rods of 4 and 5 nodes: linear reconstruction, 8 sub-steps
    (_scene(math.inf), 40),  # hard contact
]


@pytest.mark.parametrize("case", CASES, ids=["quartic", "gauss", "stiff", "short-rods", "hard"])
def test_lattice_kernel_matches_node_by_node_reference_in_chunks(case):
    scene, elements, options = (case + ({},))[:3]
    setup = build_setup(scene, elements=elements, **options)
    run = _Run(setup, energy_tolerance=10.0)  # the coarse cases are judged against the reference only
    assert run.lattice
    reference = ReferenceLattice(run)
    scale = max(np.abs(np.concatenate(run.u)).max(), 1.0)
    chunks = [1, 2, 37, 5, 64, 1, 100, 13, 90]  # the check schedule restarts with every call
    total = 0
    forces = []
    for chunk in chunks:
        status, hist, energies = run.advance(chunk)
        done = hist[0].size
        expected = np.array([reference.step() for _ in range(done)]).reshape(done, 2)
        total += done
        forces.append(hist[1])
        force_scale = max(np.abs(expected[:, 0]).max(), 1.0)
        np.testing.assert_allclose(hist[1], expected[:, 0], rtol=0, atol=1e-11 * force_scale)
        np.testing.assert_allclose(hist[3], expected[:, 1], rtol=0, atol=1e-12 * scale)
        for mine, theirs in zip(run.u + run.w, reference.u + reference.w):
            np.testing.assert_allclose(mine, theirs, rtol=0, atol=1e-12 * scale)
        if done % run.check_every == 0 and energies[1].size:  # the last sample is at the chunk's end
            kinetic, strain = reference.energies()
            assert energies[1][-1] == pytest.approx(kinetic, rel=1e-11)
            assert energies[2][-1] == pytest.approx(strain, rel=1e-11, abs=1e-12 * kinetic)
        if status != kernels.STATUS_RUNNING:
            break
    assert total >= 100
    assert np.abs(np.concatenate(forces)).max() > 0.1  # the rods were in contact


def test_far_end_remainder_node_is_stepped_with_its_own_mass():
    # the matched mesh of gamma = 0.6 with 40 elements leaves 2/3 of an element on rod 2's far node
    setup = build_setup(_scene(100.0), elements=40)
    masses = setup.rods[1].lumped_mass
    assert not math.isclose(masses[-1], masses[-2] / 2, rel_tol=1e-6)
    run = _Run(setup, energy_tolerance=10.0)
    reference = ReferenceLattice(run)
    _status, hist, _energies = run.advance(250)
    assert hist[0].size > 200
    for _ in range(hist[0].size):
        reference.step()
    np.testing.assert_allclose(run.u[1][-3:], reference.u[1][-3:], rtol=0, atol=1e-12)
    np.testing.assert_allclose(run.w[1][-3:], reference.w[1][-3:], rtol=0, atol=1e-12)


def test_pure_python_kernel_gives_the_compiled_results():
    # WAVECONTACT_PURE_PYTHON=1 runs the same source as plain Python
    setup = build_setup(_scene(100.0), elements=12)
    results = []
    for function in (kernels.advance_lattice, kernels.advance_lattice.py_func):
        run = _Run(setup, energy_tolerance=10.0)
        hist = [np.empty(120) for _ in range(4)]
        energies = [np.empty(120 // run.check_every + 1) for _ in range(6)]
        s = setup
        _status, done, samples = function(
            run.u[0], run.w[0], run.u[1], run.w[1],
            s.rods[0].stiffness_bands, s.rods[1].stiffness_bands, run.inverse_mass[0], run.inverse_mass[1],
            s.rods[0].lumped_mass, s.rods[1].lumped_mass, run.m_inv, s.gap_substeps, s.centered, s.gauss,
            s.gap, s.law, s.alpha, s.strength, s.stiffness,
            s.dt, 120, s.r_stop, run.period, run.check_every, run.bound[0], run.bound[1],
            10.0, run.state, *hist, *energies,
        )
        results.append((done, samples, hist[1][:done], run.u[0].copy(), run.w[1].copy()))
    (done_a, samples_a, force_a, u_a, w_a), (done_b, samples_b, force_b, u_b, w_b) = results
    assert (done_a, samples_a) == (done_b, samples_b)
    np.testing.assert_allclose(force_a, force_b, rtol=1e-13, atol=1e-13 * np.abs(force_a).max())
    np.testing.assert_allclose(u_a, u_b, rtol=0, atol=1e-14)
    np.testing.assert_allclose(w_a, w_b, rtol=0, atol=1e-14)


def _logarithmic_substeps(r, rates, duration, compliance, alpha, strength, substeps):
    """The quartic's sub-step chain, each sub-step the exact constant-rate solution in logarithms."""
    m2, m1, q0, p1, p2 = rates
    coefficients = [  # of s^k, s = (t - mid-step) / duration, as in docs/fem.md
        (9.0 * (m2 + p2) - 116.0 * (m1 + p1) + 2134.0 * q0) / 1920.0,
        (5.0 * (m2 - p2) - 34.0 * (m1 - p1)) / 48.0,
        (-(m2 + p2) + 12.0 * (m1 + p1) - 22.0 * q0) / 16.0,
        (-(m2 - p2) + 2.0 * (m1 - p1)) / 12.0,
        ((m2 + p2) - 4.0 * (m1 + p1) + 6.0 * q0) / 24.0,
    ]
    antiderivative = np.polynomial.Polynomial(coefficients).integ()
    edges = np.linspace(-0.5, 0.5, substeps + 1)
    for a, b in itertools.pairwise(edges):
        mean = (antiderivative(b) - antiderivative(a)) / (b - a)
        r = exponential_gap(r, mean, duration / substeps, compliance, alpha, strength)
    return r


@pytest.mark.parametrize("r", [0.08, 0.02, -0.05, -3.0, -20.0])  # -3 and -20: deep overlap, K out of range
def test_quartic_substeps_in_linear_form_equal_the_logarithmic_chain(r):
    rates = np.array([-1.0, -0.7, -0.2, 0.4, 0.9])
    alpha, strength, compliance, dt = 50.0, 1e-3, 2.0, 0.02
    expected = _logarithmic_substeps(r, rates, dt, compliance, alpha, strength, 32)
    got = exponential_gap_quartic(r, rates, dt, compliance, alpha, strength, 32)
    assert math.isfinite(got)
    assert got == pytest.approx(expected, rel=1e-13, abs=1e-14)
