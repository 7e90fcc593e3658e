"""The exact-lattice kernel (d'Alembert buffers, O(1) per step) against a node-by-node lattice,
and its far ends with an unmeshed remainder against d'Alembert's solution.

The reference below is the straightforward two-level lattice written here in
NumPy: every node is updated every step (``u_new = u_left + u_right - u_old``
inside, the general central difference at the two end nodes of each rod,
whose masses differ), with the characteristic contact treatment of
:func:`wavecontact.fem.lattice.advance_lattice` read off the node arrays.
It has no delay line, so it is compared on meshes without a remainder.
"""

import itertools
import math

import numpy as np
import pytest

import wavecontact as wc
from wavecontact import Hard, Rod, Scene
from wavecontact.fem import kernels, lattice, layout
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
        incoming = 2.0 * mean_rate - self.state[layout.S_INCOMING]
        rates = np.zeros(5)
        rates[:3] = self.state[layout.S_INCOMING_EARLIER], self.state[layout.S_INCOMING], incoming
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
                variation = abs(incoming - state[layout.S_INCOMING])
            varies = s.law == LAW_EXPONENTIAL and variation > (1e-13 if s.gauss else 1e-7) * abs(incoming)
        earlier = state[layout.S_INCOMING]
        state[layout.S_INCOMING_EARLIER] = earlier
        state[layout.S_INCOMING] = incoming
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
        r_after = math.nan
        if varies and s.centered:
            substeps = 0 if s.gauss else s.gap_substeps
            r_after = exponential_gap_quartic(r_now, rates, dt, compliance, s.alpha, s.strength, substeps)
        elif varies:
            slope = (incoming - earlier) / dt
            r_after = exponential_gap_linear(r_now, incoming, slope, dt, compliance, s.alpha, s.strength,
                                             s.gap_substeps)
        elif s.centered:
            r_after = lattice._one_jump_gap(np.int64(s.law), r_now, rates, dt, compliance, s.alpha, s.strength, s.stiffness)
        if math.isnan(r_after):
            r_after = interface_gap(s.law, r_now, incoming, dt, compliance, s.alpha, s.strength, s.stiffness)
        shift = (r_after - r_free) / self.m_inv
        new[0][-1] -= self.inverse_mass[0][-1] * shift
        new[1][0] += self.inverse_mass[1][0] * shift
        self.w, self.u = self.u, new
        state[layout.S_MOMENTUM1] -= shift / dt
        state[layout.S_MOMENTUM2] += shift / dt
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
    # (scene, elements): gamma = 0.6 with 39 elements leaves no remainder on rod 2 (65 elements)
    (_scene(100.0), 39),  # quartic reconstruction (resolved)
    (_scene(100.0), 39, {"gap_quadrature": "gauss"}),
    (_scene(1e4), 39),  # unresolved: constant-rate gap equation
    (_scene(100.0, gamma=0.75, gap=30.0), 3),  # rods of 4 and 5 nodes: linear reconstruction, 8 sub-steps
    (_scene(math.inf), 39),  # hard contact
]


@pytest.mark.parametrize("case", CASES, ids=["quartic", "gauss", "stiff", "short-rods", "hard"])
def test_lattice_kernel_matches_node_by_node_reference_in_chunks(case):
    scene, elements, options = (case + ({},))[:3]
    setup = build_setup(scene, elements=elements, **options)
    run = _Run(setup, energy_tolerance=10.0)  # the coarse cases are judged against the reference only
    assert run.lattice
    assert setup.far_theta == (0.0, 0.0)
    reference = ReferenceLattice(run)
    scale = max(np.abs(np.concatenate(run.u)).max(), setup.gap, 1.0)  # gaps and u grow to ~ the start gap
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


def _even_extension(profile, length, x):
    """``profile`` on [0, length] continued evenly about both ends, 2 length periodic (free ends)."""
    x = np.mod(x, 2.0 * length)
    return profile(np.where(x > length, 2.0 * length - x, x))


def _free_rods_with_a_pulse(elements, profile, long_rod=1.3733):
    """Two rods far apart (no contact), a displacement pulse at rest in each."""
    scene = Scene(rods=(Rod(1.0), Rod(long_rod)), velocities=(1e-2, 0.0), contact=Hard(), gaps=(10.0,),
                  initial_displacement=(lambda x: profile(1.0 - x), profile))
    setup = build_setup(scene, elements=elements)
    run = _Run(setup, energy_tolerance=10.0)
    assert run.lattice
    return setup, run


def _pulse_errors(elements, profile, long_rod=1.3733):
    """Largest node error of each rod after 3.3 time units against d'Alembert's solution (free true ends)."""
    setup, run = _free_rods_with_a_pulse(elements, profile, long_rod)
    run.advance(int(3.3 / setup.dt))
    time = run.state[layout.S_TIME]
    errors = []
    for index, (length, initial) in enumerate(((1.0, lambda x: profile(1.0 - x)), (long_rod, profile))):
        x = setup.rods[index].x
        exact = 0.5 * (_even_extension(initial, length, x - time) + _even_extension(initial, length, x + time))
        rigid = 1e-2 * time if index == 0 else 0.0
        errors.append(np.abs(run.u[index] - exact - rigid).max())
    return setup.far_theta, errors


def test_far_end_remainder_delays_the_echo_of_a_smooth_pulse_at_third_order():
    # rod 2 (1.3733 long) stops 0.33, 0.66, 0.32 of an element short of its far end at 100, 200, 400
    # elements; the pulse crosses that end (and rod 1's, on a node) within the run
    gaussian = lambda x: 1e-3 * np.exp(-(((x - 0.5) / 0.05) ** 2))
    elements = np.array([100, 200, 400])
    far, short = [], []
    for n in elements:
        theta, (error1, error2) = _pulse_errors(int(n), gaussian)
        assert theta[0] == 0.0 and 0.1 < theta[1] < 0.9
        short.append(error1)
        far.append(error2)
    assert max(short) < 1e-12  # the far end on a node: the exact mirror
    slope = -np.polyfit(np.log(elements), np.log(far), 1)[0]
    assert slope > 2.7, far
    assert far[-1] < 3e-8  # of a 1e-3 pulse


def test_far_end_remainder_reflects_a_piecewise_linear_wave_exactly():
    # a displacement profile with kinks on the lattice (a hard impact's fronts are such) comes back
    # from a far end 0.33 of an element beyond the last node exactly: the interpolation sees lines
    tent = lambda x: 1e-3 * np.maximum(0.0, 1.0 - np.abs(x - 0.5) / 0.1)
    theta, errors = _pulse_errors(100, tent)
    assert 0.1 < theta[1] < 0.9
    assert max(errors) < 1e-12  # of a 1e-3 tent (a step late or early would be ~1e-5)


def test_momentum_with_a_remainder_is_conserved_while_a_wave_crosses_it():
    # the far node stands for half an element, the waves inside the remainder carry the rest
    gaussian = lambda x: 1e-3 * np.exp(-(((x - 0.9) / 0.05) ** 2))
    setup, run = _free_rods_with_a_pulse(100, gaussian)
    start = run.momentum()
    exact, nodes_only = [], []
    for _ in range(40):
        run.advance(3)
        exact.append(abs(run.momentum() - start))
        nodes_only.append(abs(sum(float(d.lumped_mass @ v) for d, v in zip(setup.rods, run.v)) - start))
    assert max(exact) < 1e-13 * abs(start)
    assert max(nodes_only) > 1e-5 * abs(start)  # the pulse did cross the remainder (1.3e-4 measured)


def test_pure_python_kernel_gives_the_compiled_results():
    # WAVECONTACT_PURE_PYTHON=1 runs the same source as plain Python (here with a far-end remainder)
    setup = build_setup(_scene(100.0), elements=13)
    assert setup.far_theta[1] > 0.0
    results = []
    for function in (lattice.advance_lattice, lattice.advance_lattice.py_func):
        run = _Run(setup, energy_tolerance=10.0)
        hist = tuple(np.empty(120) for _ in range(4))
        energies = tuple(np.empty(120 // run.check_every + 1) for _ in range(6))
        left, right = setup.rods
        _status, done, samples = function(
            (run.u[0], run.w[0], left.lumped_mass, left.stiffness_bands),
            (run.u[1], run.w[1], right.lumped_mass, right.stiffness_bands),
            run.rod_parameters[0], run.rod_parameters[1], run.waves[0], run.waves[1],
            run.contact, run.control, run.state, hist, energies, None,  # None: the exponential law
        )
        results.append((done, samples, hist[1][:done], run.u[0].copy(), run.w[1].copy()))
    (done_a, samples_a, force_a, u_a, w_a), (done_b, samples_b, force_b, u_b, w_b) = results
    assert (done_a, samples_a) == (done_b, samples_b)
    np.testing.assert_array_equal(force_a, force_b)
    np.testing.assert_array_equal(u_a, u_b)
    np.testing.assert_array_equal(w_a, w_b)


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
