"""The hard-core thermal collision with its per-rod split, against the delay solver at large finite kappa."""

import numpy as np
import pytest

from wavecontact import collide
from wavecontact.errors import InvalidParameterError
from wavecontact.gas.hardcore_collision import hard_core_collision


@pytest.mark.parametrize(("gamma", "ratio", "seed"), [(0.6, 1.0, 0), (0.8, 3.0, 1)])
def test_split_approaches_the_delay_solvers_split_as_kappa_grows(gamma, ratio, seed):
    """The same bath realisation: the delay solver's per-rod gains (an independent quadrature of the soft
    contact) move towards the hard-core split as kappa grows, and end within 5 % of it."""
    eps2, gain_1, gain_2 = hard_core_collision(gamma, ratio, seed, resolution=32)
    assert gain_1 + gain_2 == pytest.approx(1.0 - eps2, abs=1e-12)
    distances = []
    for kappa in (300.0, 1000.0, 3000.0):
        soft = collide(gamma, kappa, "delay", bath_temperature=ratio, seed=seed)
        gains = 4.0 * np.asarray(soft.extra["vibration_energy_gain"])  # units with E_tr = 1/4
        distances.append(abs(gains[0] - gain_1))
        last = (soft.restitution**2, gains)
    assert distances[2] < distances[0]
    assert last[0] == pytest.approx(eps2, rel=0.02)
    assert last[1][0] == pytest.approx(gain_1, rel=0.05)
    assert last[1][1] == pytest.approx(gain_2, rel=0.05)


def test_cold_collision_is_the_hard_core_limit_with_the_energy_in_the_long_rod():
    """Cold rods, kappa = inf: eps = gamma (MODEL.md) and the short rod keeps no vibration."""
    eps2, gain_1, gain_2 = hard_core_collision(0.6, 0.0, 0)
    assert eps2 == pytest.approx(0.36, abs=1e-9)
    assert gain_1 == pytest.approx(0.0, abs=1e-9)
    assert gain_2 == pytest.approx(0.64, abs=1e-9)


def test_split_converges_with_the_grid():
    """First order or better: each halving of the step at least halves the change of the short rod's gain."""
    gains = [hard_core_collision(0.8, 3.0, 1, resolution=r)[1] for r in (16, 32, 64)]
    assert abs(gains[2] - gains[1]) < 0.5 * abs(gains[1] - gains[0])


def test_bad_inputs_are_refused():
    with pytest.raises(InvalidParameterError, match="gamma"):
        hard_core_collision(1.5, 1.0, 0)
    with pytest.raises(InvalidParameterError, match="resolution"):
        hard_core_collision(0.6, 1.0, 0, resolution=1)
    with pytest.raises(InvalidParameterError, match="temperature"):
        hard_core_collision(0.6, -1.0, 0)
