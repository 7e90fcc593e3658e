"""DelaySolver.thermal_restitutions with one ThermalBath per seed (Markov chains in lockstep)."""

import numpy as np
import pytest

from wavecontact.bath.model import ThermalBath
from wavecontact.errors import InvalidParameterError
from wavecontact.solvers import get_solver
from wavecontact.studies.ensemble import ENSEMBLE_DELAY_OPTIONS, sample_seed


def test_each_seed_gets_what_its_own_bath_gives_alone():
    solver = get_solver("delay")
    seeds = [sample_seed(3, j) for j in range(4)]
    baths = [ThermalBath(t, 20) for t in (0.1, 2.0, (0.5, 1.5), 0.0)]
    eps, errors = solver.thermal_restitutions(0.6, 100.0, baths, seeds, ENSEMBLE_DELAY_OPTIONS)
    for j, (bath, seed) in enumerate(zip(baths, seeds)):
        alone, error = solver.thermal_restitutions(0.6, 100.0, bath, [seed], ENSEMBLE_DELAY_OPTIONS)
        assert (eps[j], errors[j]) == (alone[0], error[0])
    assert len(set(eps.tolist())) == 4


def test_mismatched_baths_are_refused():
    solver = get_solver("delay")
    seeds = [sample_seed(3, j) for j in range(2)]
    with pytest.raises(InvalidParameterError, match="one ThermalBath per seed"):
        solver.thermal_restitutions(0.6, 100.0, [ThermalBath(1.0, 20)], seeds)
    with pytest.raises(InvalidParameterError, match="equal nu_max"):
        solver.thermal_restitutions(0.6, 100.0, [ThermalBath(1.0, 20), ThermalBath(1.0, 30)], seeds)
    with pytest.raises(InvalidParameterError, match="ThermalBath"):
        solver.thermal_restitutions(0.6, 100.0, 1.0, seeds)
    assert np.asarray(solver.thermal_restitutions(0.6, 100.0, [], [])[0]).size == 0
