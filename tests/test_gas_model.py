"""Rod gas set-up: random_gas gives what it promises; RodGas refuses inconsistent states."""

import numpy as np
import pytest

from wavecontact.errors import InvalidParameterError
from wavecontact.gas import AlternatingLengths, EqualLengths, RodGas, UniformLengths, random_gas


@pytest.mark.parametrize("boundary", ["ring", "walls"])
def test_random_gas_has_the_requested_packing_temperature_and_momentum(boundary):
    gas = random_gas(1000, seed=3, lengths=UniformLengths(0.2, 0.7), packing_fraction=0.3, temperature=2.5,
                     bath_temperature=0.1, boundary=boundary)
    assert gas.lengths.min() >= 0.2 and gas.lengths.max() <= 0.7
    assert gas.lengths.sum() / gas.system_length == pytest.approx(0.3, rel=1e-12)
    assert np.sum(gas.masses * gas.velocities**2) / gas.rods == pytest.approx(2.5, rel=1e-12)
    if boundary == "ring":
        assert abs(np.sum(gas.masses * gas.velocities)) < 1e-10
    np.testing.assert_array_equal(gas.bath_temperatures, 0.1)


def test_same_seed_same_gas_and_equal_lengths():
    a = random_gas(50, seed=np.random.SeedSequence(9), lengths=EqualLengths(0.5))
    b = random_gas(50, seed=np.random.SeedSequence(9), lengths=EqualLengths(0.5))
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.lengths, 0.5)


def test_alternating_lengths_give_every_neighbour_pair_on_an_even_ring_one_ratio():
    gas = random_gas(10, seed=4, lengths=AlternatingLengths(0.8, 1.0), packing_fraction=0.2)
    np.testing.assert_array_equal(gas.lengths, [0.8, 1.0] * 5)
    neighbours = np.roll(gas.lengths, -1)  # the ring: rod 0 follows rod N-1
    ratio = np.minimum(gas.lengths, neighbours) / np.maximum(gas.lengths, neighbours)
    np.testing.assert_array_equal(ratio, 0.8)
    assert AlternatingLengths(0.8, 1.0).smallest_ratio == 0.8
    # no random numbers drawn for the lengths: the same stream gives the same gaps as equal lengths do
    equal = random_gas(10, seed=4, lengths=EqualLengths(0.9), packing_fraction=0.2)
    np.testing.assert_allclose(np.diff(gas.positions) - 0.5 * (gas.lengths[:-1] + gas.lengths[1:]),
                               (np.diff(equal.positions) - 0.9) * (gas.free_length / equal.free_length), rtol=1e-9)
    with pytest.raises(InvalidParameterError, match="long rod length"):
        AlternatingLengths(1.0, 1.0)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"lengths": [1, 1], "positions": [0.0, 3.0], "velocities": [0, 0], "bath_temperatures": [0, -1]}, ">= 0"),
        ({"lengths": [1, 1], "positions": [0.0, 3.0], "velocities": [0, np.nan], "bath_temperatures": [0, 0]},
         "finite"),
        ({"lengths": [1, 1, 1], "positions": [0.0, 3.0], "velocities": [0, 0], "bath_temperatures": [0, 0]},
         "one entry per rod"),
        ({"lengths": [1, 1], "positions": [0.6, 3.0], "velocities": [0, 0], "bath_temperatures": [0, 0],
          "boundary": "walls", "system_length": 3.2}, "inside the box"),
    ],
)
def test_inconsistent_states_are_refused(kwargs, message):
    kwargs = {"system_length": 10.0, **kwargs}
    with pytest.raises(InvalidParameterError, match=message):
        RodGas(**kwargs)
