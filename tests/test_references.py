"""Self-checks of the impact references in tests/references/ (no wavecontact inside them)."""

import math

import numpy as np
import pytest
from references.central_differences import extrapolate, run
from references.characteristics import chain
from references.saint_venant import end_velocity_mean, saint_venant


@pytest.mark.parametrize("ratio", [0.25, 1.0, 4.0])
def test_saint_venant_conserves_energy_and_momentum(ratio):
    """M/m_rod = ratio, rod of unit length, impedance, wave speed; V = 1."""
    r = saint_venant(mass=ratio, rod_length=1.0, impedance=1.0, wave_speed=1.0, velocity=1.0)
    assert ratio * r.mass_velocity + 1.0 * r.rod_velocity == pytest.approx(ratio, rel=1e-13)
    energy = 0.5 * ratio * r.mass_velocity**2 + r.rod_energy  # rod energy from Z int f'^2 over a round trip
    assert energy == pytest.approx(0.5 * ratio, rel=1e-11)
    # the far-end reflection sign: the end's mean velocity after contact is the rod's momentum per mass
    assert end_velocity_mean(r, r.last_contact + 0.37) == pytest.approx(r.rod_velocity, rel=1e-11)


@pytest.mark.parametrize("ratio", [0.25, 1.0, 4.0])
def test_saint_venant_free_free_rod_single_contact_of_one_round_trip(ratio):
    """Closed form: the force Z V exp(-t/tau) runs until the reflected tension arrives at T = 2l/c,
    when the end jumps to 2V > v_mass; the end then repeats its motion every T with mean I/m above
    the mass's V exp(-2m/M), and the gap, concave within each period, never closes again."""
    length, Z, c, V = 1.5, 2.0, 3.0, 0.7
    m_rod = Z * length / c
    r = saint_venant(mass=ratio * m_rod, rod_length=length, impedance=Z, wave_speed=c, velocity=V)
    T = 2 * length / c
    assert len(r.intervals) == 1
    assert r.intervals[0] == pytest.approx((0.0, T), abs=1e-14)
    assert r.mass_velocity == pytest.approx(V * math.exp(-2.0 / ratio), rel=1e-13)
    assert r.impulse == pytest.approx(ratio * m_rod * V * (1 - math.exp(-2.0 / ratio)), rel=1e-13)


def test_lattice_conserves_energy_and_momentum():
    rods = [[(0.5, 1.0)], [(1.5, 1.0)], [(1.0, 2.0), (0.75, 1.0)], [(0.25, 0.5)]]
    v0 = np.array([1.0, 0.0, 0.0, 0.0])
    r = chain(rods, v0)
    masses = np.array([sum(L * Z for L, Z in rod) for rod in rods])  # c = 1: rho A = Z
    assert r.momentum == pytest.approx(masses @ v0, rel=1e-13)
    assert r.energy == pytest.approx(0.5 * masses @ v0**2, rel=1e-13)
    assert masses @ r.velocities == pytest.approx(masses @ v0, rel=1e-13)


@pytest.mark.parametrize("n", [3, 5])
def test_lattice_equal_chain_passes_the_striker_velocity_to_the_last_rod(n):
    r = chain([[(1.0, 1.0)]] * n, [1.0] + [0.0] * (n - 1))
    assert r.velocities == pytest.approx([0.0] * (n - 1) + [1.0], abs=1e-15)
    assert r.internal_energies == pytest.approx([0.0] * n, abs=1e-15)
    for i, contact in enumerate(r.contacts):  # the pulse (duration 2l/c) passes one interface per l/c
        assert len(contact.intervals) == 1
        assert contact.intervals[0] == pytest.approx((float(i), i + 2.0), abs=1e-14)
        assert contact.impulse == pytest.approx(1.0, rel=1e-14)


@pytest.mark.parametrize("z2", [2.0, 0.5])
def test_lattice_stepped_bar_transmits_and_reflects_with_the_impedance_ratio(z2):
    """Striker [0, 1] (Z1 = 1, V = 1) on a bar [1, 4] (Z1) + [4, 7] (Z2): the incident force is -Z1 V/2,
    transmitted 2 Z2/(Z1+Z2), reflected (Z2 - Z1)/(Z1+Z2) of it."""
    r = chain([[(1.0, 1.0)], [(3.0, 1.0), (3.0, z2)]], [1.0, 0.0], cell=0.25)

    def force(x, t):
        return r.forces[round(t / r.dt), int(np.argmin(abs(r.cell_x - x)))]

    incident = force(3.875, 3.0)  # front at x = 3.875 after t = 2.875, the reflection after 3.125
    assert incident == pytest.approx(-0.5, rel=1e-14)
    assert force(3.875, 4.0) / incident - 1.0 == pytest.approx((z2 - 1.0) / (1.0 + z2), rel=1e-13)
    assert force(4.125, 4.0) / incident == pytest.approx(2 * z2 / (1.0 + z2), rel=1e-13)


def test_lattice_refuses_what_it_cannot_represent():
    rods = [[(0.5, 1.0)], [(1.5, 1.0)], [(1.0, 2.0), (0.75, 1.0)], [(0.25, 0.5)]]
    with pytest.raises(ValueError, match="gap closes inside a step"):
        chain(rods, [1.0, 0.0, 0.0, -0.25])
    with pytest.raises(ValueError, match="whole number of cells"):
        chain([[(1.0, 1.0)], [(0.3, 1.0)]], [1.0, 0.0], cell=0.25)


@pytest.mark.parametrize("ratio", [0.25, 1.0, 4.0])
def test_saint_venant_restitution_closed_form(ratio):
    """e = (v_rod - v_mass) / V = (M/m) (1 - exp(-2m/M)) - exp(-2m/M)."""
    r = saint_venant(mass=ratio, rod_length=1.0, impedance=1.0, wave_speed=1.0, velocity=1.0)
    decay = math.exp(-2.0 / ratio)
    assert r.rod_velocity - r.mass_velocity == pytest.approx(ratio * (1 - decay) - decay, rel=1e-12)


@pytest.mark.parametrize("ratio", [0.25, 1.0, 4.0])
def test_central_differences_extrapolate_to_saint_venant_within_their_bound(ratio):
    """The separately written finite differences (first order at a hard impact) and Richardson's
    bound: the closed form lies within it."""
    ref = saint_venant(mass=ratio, rod_length=1.0, impedance=1.0, wave_speed=1.0, velocity=1.0)
    levels = [run([ratio, [(1.0, 1.0, 1.0, 1.0, 1.0)]], [1.0, 0.0], n, 4.0) for n in (100, 200, 400)]
    value, bound, _ = extrapolate([o.velocities for o in levels])
    error = np.abs(value - [ref.mass_velocity, ref.rod_velocity])
    assert np.all(error <= bound), (error, bound)
    assert np.all(error > 0)  # not exact: the bound is doing the work
    # the discrete contact ends when the reflected tension arrives (or earlier, where the force at T,
    # Z V exp(-2m/M), is below what the mesh resolves: 3e-4 at M/m = 0.25)
    assert ref.last_contact - 0.05 <= levels[-1].last_contact <= ref.last_contact + 0.01


def test_central_differences_in_the_uniform_limit_of_a_taper_within_their_bound():
    ref = chain([[(0.5, 1.0)], [(1.0, 1.0)]], [1.0, 0.0])
    levels = [run([[(0.5, 1.0, 1.0, 1.0, 1.0)], [(1.0, 1.0, 1.0, 1.0, 1.0)]], [1.0, 0.0], n, 5.0)
              for n in (100, 200, 400)]
    value, bound, _ = extrapolate([o.velocities for o in levels])
    assert np.all(np.abs(value - ref.velocities) <= bound)
    masses = np.array([0.5, 1.0])
    assert masses @ levels[-1].velocities == pytest.approx(0.5, rel=1e-12)  # momentum: exact
