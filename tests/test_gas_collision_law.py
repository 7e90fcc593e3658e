"""The vibration rule's hard-core collision law: every pair state covered, energy conserved per collision,
the law against direct solves, and the law rule against a solve per collision on a small gas."""

import math
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from wavecontact.errors import InvalidParameterError
from wavecontact.gas import (
    GasSimulation,
    RodGas,
    UniformLengths,
    VibrationLaw,
    VibrationSolve,
    default_law,
    hard_core_draw,
    kernels,
    random_gas,
)
from wavecontact.gas.collision_law import CollisionLaw, level_means, load_law, point_samples

LAW = default_law()


def test_shipped_law_covers_gamma_and_every_temperature_ratio_and_is_small():
    assert LAW.gamma[0] <= 0.6 and LAW.gamma[-1] == 1.0
    assert LAW.log_x[-1] == 0.0 and LAW.log_x[0] <= -4.0
    assert (Path(__file__).parents[1] / "wavecontact" / "data" / "collision_law_hardcore.npz").stat().st_size < 200_000
    # cold baths (x = 1): the hard-core limit eps = gamma exactly, nothing for the short rod (MODEL.md)
    cold = LAW.eps2_quantiles[:, -1, :]
    assert np.allclose(cold, LAW.gamma[:, None] ** 2, atol=1e-9)
    assert np.allclose(LAW.gain_short[:, -1, :], 0.0, atol=1e-9)


def test_kernel_draw_matches_the_law_and_reaches_below_its_last_row():
    law_arrays = LAW.arrays()
    log_x, probability, quantiles, gains = law_arrays[1:]
    rng = np.random.default_rng(np.random.SeedSequence(5))
    for _ in range(200):
        g = rng.uniform(LAW.gamma[0], LAW.gamma[-1])
        x = 10.0 ** rng.uniform(log_x[0], 0.0)
        u = rng.random()
        ig = min(np.searchsorted(LAW.gamma, g, side="right") - 1, LAW.gamma.size - 2)
        wg = (g - LAW.gamma[ig]) / (LAW.gamma[ig + 1] - LAW.gamma[ig])
        ir, wr = kernels._lookup(log_x, math.log10(x))
        eps2, gain = kernels._table_draw(u, ig, wg, ir, wr, probability, True, quantiles, gains, True)
        expected = LAW.draw(g, x, u)
        assert eps2 == pytest.approx(expected[0], rel=1e-12, abs=1e-14)
        assert gain == pytest.approx(expected[1], rel=1e-12, abs=1e-14)
    # below the last row: that row's law (documented, counted by the gas), never a refusal
    assert LAW.draw(0.7, 10.0 ** (log_x[0] - 3), 0.3) == LAW.draw(0.7, 10.0 ** log_x[0], 0.3)


def _mean_and_sem(values):
    values = np.asarray(values, dtype=float)
    return values.mean(), values.std(ddof=1) / math.sqrt(values.size)


@pytest.mark.parametrize(("gamma", "log_x"), [(0.6, -4.5), (0.9, -4.5), (0.75, -2.25)])
def test_law_agrees_with_direct_hard_core_solves(gamma, log_x):
    """Direct solves (independent seeds) against the law's draws: same distribution of eps^2 (KS, both
    samples' sizes) and the same mean short-rod gain within three combined standard errors.  Two points
    lie below the law's last row (where the rule takes that row's law), one between grid points in
    gamma and x."""
    n = 40
    eps2, gain = point_samples(gamma, log_x, n, 99, bath_modes=LAW.bath_modes, resolution=LAW.resolution)
    x = 10.0**log_x
    levels = (np.arange(LAW.samples_per_point) + 0.5) / LAW.samples_per_point
    law_eps2 = np.array([LAW.draw(gamma, x, u)[0] for u in levels])
    law_gain = np.array([LAW.draw(gamma, x, u)[1] for u in levels])
    assert stats.ks_2samp(eps2, law_eps2).pvalue > 1e-3
    m_direct, s_direct = _mean_and_sem(gain)
    # the law's gains are conditional means (their spread underestimates the samples'): use the direct spread
    assert abs(law_gain.mean() - m_direct) < 3.0 * s_direct * math.sqrt(1.0 + n / LAW.samples_per_point)


def _warm(gas, temperatures):
    """The same rods with the baths at ``temperatures`` (energy per mode)."""
    return RodGas(gas.lengths, gas.positions, gas.velocities, temperatures, gas.system_length, gas.boundary)


def _energy(sim):
    return sim._energies()[4]  # kinetic + bath + lost + dissipated


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_every_collision_conserves_energy_including_the_baths(seed):
    """Collision by collision (kinetic + bath + dissipated), with warm baths of unequal temperatures and damping."""
    gas = random_gas(60, seed=seed, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    gas = _warm(gas, rng.exponential(0.5, gas.rods) * gas.kinetic_energy() / gas.rods)
    sim = GasSimulation(gas, VibrationLaw(LAW), seed=seed, damping=30.0, record_every=1, max_frames=0)
    before = _energy(sim)
    for _ in range(400):
        result = sim.run(1)
        assert result.status == "completed"
        after = _energy(sim)
        assert after == pytest.approx(before, rel=1e-12)
        before = after
    assert np.all(sim.temperature >= 0.0)


def test_law_rule_and_solve_rule_agree_on_a_small_gas_statistic():
    """Eight small gases, the same initial states: mean log of the final kinetic energy with the law (in the
    kernel) and with one hard-core solve per collision (each rod at its own temperature) agree within
    three combined standard errors."""
    stats_law, stats_solve = [], []
    for seed in range(8):
        gas = random_gas(12, seed=seed, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
        gas = _warm(gas, np.full(gas.rods, gas.kinetic_energy() / gas.rods))  # T_B ~ E_tr: warm from the start
        start = gas.kinetic_energy()
        law = GasSimulation(gas, VibrationLaw(LAW), seed=seed, record_every=30, max_frames=0).run(30)
        solve = GasSimulation(gas, VibrationSolve(hard_core_draw(resolution=LAW.resolution), per_rod=True),
                              seed=seed, record_every=30, max_frames=0).run(30)
        assert law.status == solve.status == "completed"
        assert abs(solve.energy_drift) < 1e-12 and abs(law.energy_drift) < 1e-12
        stats_law.append(math.log(law.final_energy / start))
        stats_solve.append(math.log(solve.final_energy / start))
    (m1, s1), (m2, s2) = _mean_and_sem(stats_law), _mean_and_sem(stats_solve)
    assert abs(m1 - m2) < 3.0 * math.hypot(s1, s2)


def test_a_cold_dense_gas_runs_through_states_far_below_the_old_tables_range():
    """The states that stopped every run of the T_B/E_tr <= 100 table (slow pairs in warm baths) are drawn."""
    gas = random_gas(400, seed=0, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
    sim = GasSimulation(gas, VibrationLaw(LAW), seed=0, record_every=20_000, max_frames=0)
    result = sim.run(60_000)
    assert result.status == "completed" and result.collisions == 60_000
    temperatures = sim._synced_temperatures(sim.time)
    m, v = sim.mass, sim.v
    m2, v2 = np.roll(m, -1), np.roll(v, -1)
    e_tr = 0.5 * m * m2 / (m + m2) * (v - v2) ** 2
    ratio = 0.5 * (temperatures + np.roll(temperatures, -1)) / e_tr
    assert np.max(ratio) > 100.0  # neighbours in states the old table (T_B/E_tr <= 100) refused


def test_level_means_and_files(tmp_path):
    probability = np.linspace(0, 1, 5)
    rng = np.random.default_rng(np.random.SeedSequence(3))
    order, values = rng.random(1000), rng.random(1000)
    means = level_means(order, values, probability)
    widths = np.diff(probability)
    assert np.sum(0.5 * (means[1:] + means[:-1]) * widths) == pytest.approx(values.mean(), abs=0.03)
    with pytest.raises(InvalidParameterError, match="empty"):
        level_means(order[:3], values[:3], np.linspace(0, 1, 11))
    path = LAW.save(tmp_path / "law.npz")
    again = load_law(path)
    assert np.array_equal(again.eps2_quantiles, LAW.eps2_quantiles) and again.resolution == LAW.resolution
    with pytest.raises(InvalidParameterError, match="log_x must end at 0"):
        CollisionLaw(LAW.gamma, LAW.log_x - 1, LAW.probability, LAW.eps2_quantiles, LAW.gain_short)
    (tmp_path / "bad.npz").write_bytes(b"not a file")
    with pytest.raises(InvalidParameterError, match="not a readable"):
        load_law(tmp_path / "bad.npz")


def test_law_rule_checkpoint_resumes_bit_for_bit(tmp_path):
    gas = random_gas(80, seed=4, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
    straight = GasSimulation(gas, VibrationLaw(LAW), seed=9, damping=20.0, record_every=500)
    straight.run(3000)
    first = GasSimulation(gas, VibrationLaw(LAW), seed=9, damping=20.0, record_every=500)
    first.run(1500)
    first.save_checkpoint(tmp_path / "law.npz")
    resumed = GasSimulation.resume(tmp_path / "law.npz")
    assert isinstance(resumed.rule, VibrationLaw)
    resumed.run(1500)
    for name in ("x", "v", "temperature", "local_time"):
        assert np.array_equal(getattr(straight, name), getattr(resumed, name))
