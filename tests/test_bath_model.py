"""The thermal bath: equipartition (Eq. 18), seeds, fields and refusals."""

import math

import numpy as np
import pytest

from wavecontact import InvalidParameterError, two_rods
from wavecontact.bath import ThermalBath
from wavecontact.bath.model import seed_sequence

LENGTHS = (0.8, 0.8 / 0.6)


def test_each_mode_holds_the_temperature_on_average():
    # Eq. 18: <m omega^2 q^2 / 2> = <m omega^2 r^2 / 2> = T / 2, so a mode holds T on average
    bath = ThermalBath((0.5, 2.0), modes=40)
    energies = np.array([bath.draw(LENGTHS, s).modal_energies() for s in range(400)])  # (400, 2, 40)
    mean = energies.mean(axis=0) / 0.25  # in units of E_tr = 1/4
    # a mode's energy is T times a chi-square with 2 degrees of freedom over 2: std = T / sqrt(n) of the mean
    for rod, ratio in enumerate((0.5, 2.0)):
        tolerance = 4.0 * ratio / math.sqrt(400)
        assert np.all(np.abs(mean[rod] - ratio) < tolerance)


def test_same_seed_same_realisation_and_sequences_are_accepted():
    bath = ThermalBath(1.0, modes=5)
    a = bath.draw(LENGTHS, 7)
    b = bath.draw(LENGTHS, np.random.SeedSequence(7))
    c = bath.draw(LENGTHS, 8)
    assert all(np.array_equal(x, y) for x, y in zip(a.displacement, b.displacement))
    assert not np.array_equal(a.displacement[0], c.displacement[0])


def test_free_vibration_keeps_each_mode_energy_and_is_reversible():
    v = ThermalBath(1.0, modes=30).draw(LENGTHS, 3)
    w = v.evolved(1.234)
    assert np.allclose(np.concatenate(w.modal_energies()), np.concatenate(v.modal_energies()), rtol=1e-12)
    back = w.evolved(-1.234)
    assert np.allclose(back.displacement[1], v.displacement[1], atol=1e-15)


def test_fields_are_the_mode_sums_with_the_rod_energy():
    # the strain and kinetic energy of the sampled fields equal the modal energy
    v = ThermalBath(0.7, modes=12).draw(LENGTHS, 11)
    for rod in range(2):
        length = LENGTHS[rod]
        s = np.linspace(0.0, length, 40001)
        u = v.displacement_field(rod)(s)
        du = v.velocity_field(rod)(s)
        strain = np.gradient(u, s)
        kinetic = 0.5 * np.trapezoid(du**2, s)
        potential = 0.5 * np.trapezoid(strain**2, s)
        assert kinetic + potential == pytest.approx(v.vibration_energy()[rod], rel=1e-6)
        assert np.trapezoid(u, s) == pytest.approx(0.0, abs=1e-9)  # no rigid shift


def test_scene_fields_start_the_realisation_before_contact():
    v = ThermalBath(1.0, modes=8).draw(LENGTHS, 2)
    scene = two_rods(0.6, 100.0, vibrations=v)
    gap = scene.gaps[0]
    # the gap exceeds the largest possible approach of the ends, plus the force's range
    assert gap > 40.0 / 100.0
    # evolving the initial fields forward by the gap (V = 1) gives the realisation back
    start = v.evolved(-gap)
    s = np.array([0.0, LENGTHS[0]])
    assert np.allclose(scene.initial_displacement[0](s), start.displacement_field(0)(s))


@pytest.mark.parametrize("temperature, modes, message", [
    (-0.1, 10, "temperature"), (math.nan, 10, "temperature"), ((1.0, 2.0, 3.0), 10, "pair"),
    (1.0, 0, "nu_max"), (1.0, 10**6, "nu_max"), (1.0, 2.5, "nu_max"),
])
def test_bad_bath_is_refused_in_one_line(temperature, modes, message):
    with pytest.raises(InvalidParameterError, match=message) as info:
        ThermalBath(temperature, modes)
    assert "\n" not in str(info.value)


def test_bad_seed_and_mismatched_rods_are_refused():
    with pytest.raises(InvalidParameterError, match="seed"):
        seed_sequence(-1)
    v = ThermalBath(1.0, modes=3).draw((1.0, 2.0), 0)
    with pytest.raises(InvalidParameterError, match="length"):
        two_rods(0.6, 10.0, vibrations=v)


def test_batched_draws_are_the_single_draws_bit_for_bit():
    from wavecontact.bath.scene import end_reach, end_reaches

    bath = ThermalBath((0.3, 1.7), modes=33)
    seeds = [np.random.SeedSequence(4, spawn_key=(j,)) for j in range(5)]
    q, r = bath.draw_amplitudes(LENGTHS, seeds, masses=(0.7, 1.1), wave_speeds=(1.0, 1.3))
    reaches = end_reaches(q, r)
    for k, seed in enumerate(seeds):
        one = bath.draw(LENGTHS, seed, masses=(0.7, 1.1), wave_speeds=(1.0, 1.3))
        for i in range(2):
            assert np.array_equal(q[k, i], one.displacement[i]) and np.array_equal(r[k, i], one.velocity_amplitude[i])
        assert reaches[k] == end_reach(one)
