"""The vibration rule's real data: the shipped table computed from rod collisions, the refusal of gas states
outside it, and the per-collision solve (VibrationSolve + wavecontact.collide) against the table rule."""

import math

import numpy as np
import pytest

from wavecontact import collide
from wavecontact.errors import InvalidParameterError
from wavecontact.gas import (
    GasSimulation,
    RodGas,
    UniformLengths,
    VibrationSolve,
    VibrationTable,
    collision_draw,
    random_gas,
    rod_table,
)

TABLE = rod_table()
EPS_COLD_06 = 0.646697087  # MODEL.md: gamma 0.6, kappa 100, cold rods


def test_shipped_table_comes_from_rod_collisions_and_has_the_cold_limit_of_model_md():
    meta = TABLE.metadata()
    assert TABLE.solver == "delay" and meta["kappa"] == 100.0 and TABLE.bath_modes == 250
    assert TABLE.samples_per_point >= 100
    # at T_B = 0 the collision is deterministic: every quantile is MODEL.md's cold eps^2
    g = int(np.flatnonzero(TABLE.gamma == 0.6)[0])
    assert TABLE.temperature_ratio[0] == 0.0
    np.testing.assert_allclose(TABLE.eps2_quantiles[g, 0], EPS_COLD_06**2, rtol=1e-6)
    # hot baths spread the law and give energy back: some eps^2 > 1 at the hottest point
    assert TABLE.eps2_quantiles[g, -1, -1] > 1.0
    assert TABLE.eps2_quantiles[g, -1, -1] - TABLE.eps2_quantiles[g, -1, 0] > 0.1


def test_the_gas_stops_with_a_message_when_a_pair_meets_outside_the_table():
    top = TABLE.temperature_ratio[-1]
    # two rods (gamma 0.8) approaching slowly in baths much hotter than the pair's translational energy
    gas = RodGas([0.8, 1.0], [2.0, 5.0], [1e-3, -1e-3], [1.0, 1.0], 10.0)
    sim = GasSimulation(gas, VibrationTable(TABLE), seed=1, max_frames=0)
    mu = 0.8 * 1.0 / 1.8
    assert 1.0 / (0.5 * mu * 2e-3**2) > top
    result = sim.run(5)
    assert result.status == "off_table"
    assert result.collisions == 0
    assert "outside the restitution table's range" in result.message and f"{top:g}" in result.message
    np.testing.assert_array_equal(result.velocities, [1e-3, -1e-3])  # nothing was clipped and applied
    with pytest.raises(InvalidParameterError):
        sim.run(1)


def test_gas_lengths_outside_the_table_are_refused_before_the_run():
    with pytest.raises(InvalidParameterError, match="table covers gamma"):
        GasSimulation(random_gas(20, seed=0, lengths=UniformLengths(0.2, 1.0)), VibrationTable(TABLE))


def test_collision_draw_is_one_thermal_collide_per_seed():
    draw = collision_draw(100.0)
    seed = np.random.SeedSequence(5)
    eps2, share = draw(0.7, 2.0, seed)
    direct = collide(0.7, 100.0, bath_temperature=2.0, seed=np.random.SeedSequence(5))
    assert eps2 == direct.restitution**2
    gain = direct.extra["vibration_energy_gain"]
    assert share == pytest.approx(gain[0] / (gain[0] + gain[1]), rel=1e-12)
    # the gains add up to the lost translational energy (units with E_tr = 1/4)
    assert float(gain[0] + gain[1]) == pytest.approx(0.25 * (1.0 - eps2), abs=1e-6)
    assert draw(0.7, 2.0, np.random.SeedSequence(6))[0] != eps2
    with pytest.raises(InvalidParameterError, match="T_B/E_tr"):
        draw(0.7, 1e6, seed)


def test_a_solved_gas_conserves_energy_and_repeats_bit_for_bit():
    gas = random_gas(6, seed=3, lengths=UniformLengths(0.6, 1.0), bath_temperature=0.3)
    runs = []
    for _ in range(2):
        sim = GasSimulation(gas, VibrationSolve(collision_draw(100.0)), seed=4, record_every=1, max_frames=0)
        result = sim.run(12)
        assert result.status == "completed", result.message
        assert abs(result.energy_drift) < 1e-12
        runs.append(result)
    np.testing.assert_array_equal(runs[0].velocities, runs[1].velocities)
    np.testing.assert_array_equal(runs[0].bath_temperatures, runs[1].bath_temperatures)


@pytest.mark.slow  # ~1-3 min: ~250 delay solves
def test_solving_each_collision_agrees_statistically_with_the_table_rule():
    """Same small gases, one run with a solve per collision and one with the shipped table (independent
    streams); the mean over realisations of the translational share of the energy after 25 collisions must
    agree within the realisations' spread.  A realisation in which either run meets a pair outside the
    table's range (or the solve's accepted range, the same [0, 100]) is left out of both (at most 4 of 12)."""
    finals = {"table": [], "solve": []}
    for seed in range(12):
        gas = random_gas(8, seed=200 + seed, lengths=UniformLengths(0.6, 1.0), bath_temperature=0.05)
        pair = {}
        for name, rule in (("table", VibrationTable(TABLE)), ("solve", VibrationSolve(collision_draw(100.0)))):
            try:
                result = GasSimulation(gas, rule, seed=seed, record_every=25, max_frames=0).run(25)
            except InvalidParameterError:
                break  # the solve refused a ratio beyond 100
            if result.status != "completed":
                assert result.status == "off_table", result.message
                break
            h = result.history
            pair[name] = h["kinetic_energy"][-1] / (h["kinetic_energy"][-1] + h["bath_energy"][-1])
        if len(pair) == 2:
            for name, value in pair.items():
                finals[name].append(value)
    a, b = np.array(finals["table"]), np.array(finals["solve"])
    assert a.size >= 8
    spread = math.sqrt(np.var(a, ddof=1) / a.size + np.var(b, ddof=1) / b.size)
    assert abs(a.mean() - b.mean()) < 4 * spread
