"""The vibration rule's collision law: every pair state covered (two bath temperatures, soft and hard
contacts), energy conserved per collision, the law against direct solves, and the law rule against a solve
per collision on small gases."""

import math
import shlex
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
    contact_draw,
    default_law,
    default_soft_law,
    hard_core_draw,
    kernels,
    random_gas,
)
from wavecontact.gas.collision_law import (
    REGENERATE,
    REGENERATE_SOFT,
    CollisionLaw,
    LawGrid,
    blend_draw,
    build_collision_law,
    kappa_variable,
    level_means,
    load_law,
    merge_kappa_rows,
    parser,
    point_samples,
    row_resolutions,
    soft_corrections,
)

LAW = default_law()
SOFT = default_soft_law()
DATA = Path(__file__).parents[1] / "wavecontact" / "data"


def test_shipped_laws_cover_every_pair_state_and_are_small():
    assert LAW.hard_core and not SOFT.hard_core and SOFT.kappa[0] <= 10 and SOFT.kappa[-1] >= 100
    for law in (LAW, SOFT):
        assert law.gamma[0] <= 0.6 and law.gamma[-1] == 1.0
        assert law.log_x[-1] == 0.0 and law.log_x[0] <= -4.0
        assert law.short_share[0] == 0.0 and law.short_share[-1] == 1.0 and law.short_share.size >= 3
    size = sum((DATA / name).stat().st_size for name in ("collision_law_hardcore.npz", "collision_law_soft.npz"))
    assert size < 1_000_000
    # cold baths (x = 1): the hard-core limit eps = gamma exactly, nothing for the short rod (MODEL.md section 4),
    # whatever the (meaningless) share of two zero temperatures
    cold = LAW.eps2_quantiles[0, :, -1]
    assert np.allclose(cold, LAW.gamma[:, None, None] ** 2, atol=1e-9)
    assert np.allclose(LAW.gain_short[0, :, -1], 0.0, atol=1e-9)
    # the soft law's cold row at kappa = 100, gamma = 0.6 against MODEL.md section 5 (independent reference)
    row, g = list(SOFT.kappa).index(100.0), list(SOFT.gamma).index(0.6)
    assert np.allclose(SOFT.eps2_quantiles[row, g, -1], 0.646697087**2, rtol=1e-6)


def _cell(grid, value):
    i = min(max(np.searchsorted(grid, value, side="right") - 1, 0), grid.size - 2)
    return i, (value - grid[i]) / (grid[i + 1] - grid[i])


def test_kernel_draw_matches_the_law_and_reaches_below_its_last_row():
    _z, log_x, share, probability, quantiles, gains = LAW.kernel_arrays()
    rng = np.random.default_rng(np.random.SeedSequence(5))
    for _ in range(200):
        g = rng.uniform(LAW.gamma[0], LAW.gamma[-1])
        x = 10.0 ** rng.uniform(log_x[0], 0.0)
        s = rng.random()
        u = rng.random()
        ig, wg = _cell(LAW.gamma, g)
        below, ir, wr, i_s, ws = kernels._law_point(math.log10(x), s, log_x, share)
        assert not below
        eps2, gain = kernels._table_draw(u, ig, wg, ir, wr, i_s, ws, probability, True, quantiles[0], gains[0], True)
        expected = LAW.draw(g, x, u, s)
        assert eps2 == pytest.approx(expected[0], rel=1e-12, abs=1e-14)
        assert gain == pytest.approx(expected[1], rel=1e-12, abs=1e-14)
    # below the last row: that row's law (documented, counted by the gas), never a refusal
    assert LAW.draw(0.7, 10.0 ** (log_x[0] - 3), 0.3, 0.2) == LAW.draw(0.7, 10.0 ** log_x[0], 0.3, 0.2)
    assert kernels._law_point(log_x[0] - 1, 0.2, log_x, share)[0]


def test_kernel_blend_over_kappa_matches_the_plain_python_statement():
    hard = LAW.kernel_arrays()
    soft = VibrationLaw(LAW, SOFT).soft_arrays()
    corrections = soft_corrections(LAW, SOFT)
    rng = np.random.default_rng(np.random.SeedSequence(6))
    for kappa in (3.0, 10.0, 17.0, 30.0, 55.0, 100.0, 400.0, 1e5):
        for _ in range(20):
            g, lx, s, u = rng.uniform(0.6, 1.0), rng.uniform(-4.0, 0.0), rng.random(), rng.random()
            ig, wg = _cell(LAW.gamma, g)
            _below, ir, wr, i_s, ws = kernels._law_point(lx, s, hard[1], hard[2])
            e_hard, g_hard = kernels._table_draw(u, ig, wg, ir, wr, i_s, ws, hard[3], True, hard[4][0], hard[5][0],
                                                 True)
            eps2, gain, softer, _below, _floored = kernels._soft_draw(u, g, kappa, lx, s, e_hard, g_hard, soft)
            expected = blend_draw(LAW, SOFT, g, 10.0**lx, u, s, kappa, corrections)
            assert eps2 == pytest.approx(expected[0], rel=1e-9, abs=1e-12)
            assert gain == pytest.approx(expected[1], rel=1e-9, abs=1e-12)
            assert softer == expected[2] == (kappa < SOFT.kappa[0])


# cold collisions at gamma = 0.6 (MODEL.md section 5): the blend in z = ln(kappa)/kappa between the soft
# law's rows and the hard core against independent reference values.  The bound is the blend's stated
# accuracy in the cold limit (docs/gas.md, approximation 1: within 0.01 in eps between the rows 10 ... 100
# and above them)
@pytest.mark.parametrize(("kappa", "epsilon"), [(20, 0.7530132413), (250, 0.622343998), (1000, 0.606972294),
                                                (10000, 0.600927488)])
def test_blend_over_kappa_reproduces_cold_reference_restitutions(kappa, epsilon):
    eps2, _gain, softer = blend_draw(LAW, SOFT, 0.6, 1.0, 0.5, 0.5, kappa)
    assert not softer
    assert abs(math.sqrt(eps2) - epsilon) < 0.01


def _mean_and_sem(values):
    values = np.asarray(values, dtype=float)
    return values.mean(), values.std(ddof=1) / math.sqrt(values.size)


def _law_sample(law, gamma, x, share, row=0):
    levels = (np.arange(law.samples_per_point) + 0.5) / law.samples_per_point
    draws = np.array([law.draw(gamma, x, u, share, row) for u in levels])
    return draws[:, 0], draws[:, 1]


@pytest.mark.parametrize(("gamma", "log_x", "share"), [(0.6, -4.5, 0.5), (0.9, -4.5, 0.5), (0.75, -2.25, 0.5),
                                                       (0.7, -0.6, 0.1), (0.85, -1.2, 0.9), (0.65, -0.3, 0.0)])
def test_law_agrees_with_direct_hard_core_solves(gamma, log_x, share):
    """Direct solves (independent seeds, each rod at its own temperature) against the law's draws: same
    distribution of eps^2 (KS, both samples' sizes) and the same mean short-rod gain within three standard
    errors.  Two points lie below the law's last row (where the rule takes that row's law), the others
    between grid points in gamma, x and the short rod's share s."""
    n = 40
    eps2, gain = point_samples(gamma, log_x, n, 99, bath_modes=LAW.bath_modes, resolution=LAW.resolution,
                               short_share=share)
    law_eps2, law_gain = _law_sample(LAW, gamma, 10.0**log_x, share)
    assert stats.ks_2samp(eps2, law_eps2).pvalue > 1e-3
    m_direct, s_direct = _mean_and_sem(gain)
    # the law's gains are conditional means (their spread underestimates the samples'): use the direct spread
    assert abs(law_gain.mean() - m_direct) < 3.0 * s_direct * math.sqrt(1.0 + n / LAW.samples_per_point)


@pytest.mark.slow
@pytest.mark.parametrize(("gamma", "log_x", "share", "kappa"), [(0.7, -0.7, 0.25, 20.0), (0.9, -2.5, 0.75, 50.0)])
def test_soft_law_agrees_with_direct_finite_kappa_solves(gamma, log_x, share, kappa):
    """Finite-kappa delay solves (each rod at its own temperature) against the law (hard-core draw plus the
    soft law's correction) between grid points in every variable: KS on eps^2 and the mean gain within
    three standard errors."""
    n = 30
    eps2, gain = point_samples(gamma, log_x, n, 98, bath_modes=SOFT.bath_modes, short_share=share, kappa=kappa)
    levels = (np.arange(SOFT.samples_per_point) + 0.5) / SOFT.samples_per_point
    corrections = soft_corrections(LAW, SOFT)
    draws = np.array([blend_draw(LAW, SOFT, gamma, 10.0**log_x, u, share, kappa, corrections)[:2] for u in levels])
    assert stats.ks_2samp(eps2, draws[:, 0]).pvalue > 1e-3
    m_direct, s_direct = _mean_and_sem(gain)
    assert abs(draws[:, 1].mean() - m_direct) < 3.0 * s_direct * math.sqrt(1.0 + n / SOFT.samples_per_point)


def _warm(gas, temperatures):
    """The same rods with the baths at ``temperatures`` (energy per mode)."""
    return RodGas(gas.lengths, gas.positions, gas.velocities, temperatures, gas.system_length, gas.boundary)


def _energy(sim):
    return sim._energies()[4]  # kinetic + bath + lost + dissipated


@pytest.mark.parametrize(("seed", "stiffness"), [(1, None), (2, None), (3, 20.0)])
def test_every_collision_conserves_energy_including_the_baths(seed, stiffness):
    """Collision by collision (kinetic + bath + dissipated), with warm baths of unequal temperatures and damping
    (and, for one realisation, soft contacts)."""
    gas = random_gas(60, seed=seed, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    gas = _warm(gas, rng.exponential(0.5, gas.rods) * gas.kinetic_energy() / gas.rods)
    sim = GasSimulation(gas, VibrationLaw(LAW, SOFT), seed=seed, damping=30.0, record_every=1, max_frames=0,
                        contact_stiffness=stiffness)
    before = _energy(sim)
    for _ in range(400):
        result = sim.run(1)
        assert result.status == "completed"
        after = _energy(sim)
        assert after == pytest.approx(before, rel=1e-12)
        before = after
    assert np.all(sim.temperature >= 0.0)


def _small_gas_statistic(rule, seeds, rods, collisions, stiffness=None):
    values = []
    for seed in seeds:
        gas = random_gas(rods, seed=seed, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
        rng = np.random.default_rng(np.random.SeedSequence([seed, 1]))
        # unequal warm baths (T_B ~ E_tr on average): the two temperatures of a pair differ from the start
        gas = _warm(gas, rng.exponential(1.0, rods) * gas.kinetic_energy() / rods)
        start = gas.kinetic_energy()
        result = GasSimulation(gas, rule, seed=seed, record_every=collisions, max_frames=0,
                               contact_stiffness=stiffness).run(collisions)
        assert result.status == "completed" and abs(result.energy_drift) < 1e-12
        values.append(math.log(result.final_energy / start))
    return _mean_and_sem(values)


def test_law_rule_and_solve_rule_agree_on_a_small_gas_statistic():
    """Eight small gases with unequal warm baths, the same initial states: mean log of the final kinetic energy
    with the law (in the kernel) and with one hard-core solve per collision (each rod at its own temperature)
    agree within three combined standard errors."""
    seeds = range(8)
    m1, s1 = _small_gas_statistic(VibrationLaw(LAW), seeds, 12, 30)
    m2, s2 = _small_gas_statistic(VibrationSolve(hard_core_draw(resolution=LAW.resolution), per_rod=True),
                                  seeds, 12, 30)
    assert abs(m1 - m2) < 3.0 * math.hypot(s1, s2)


@pytest.mark.slow
def test_soft_law_rule_and_finite_kappa_solve_rule_agree_on_a_small_gas_statistic():
    """The same with a contact stiffness: the blended law against one finite-kappa delay solve per collision
    at the collision's own kappa = alpha V l."""
    seeds = range(8)
    rule = VibrationLaw(LAW, SOFT)
    m1, s1 = _small_gas_statistic(rule, seeds, 10, 20, stiffness=30.0)
    m2, s2 = _small_gas_statistic(VibrationSolve(contact_draw(), per_rod=True), seeds, 10, 20, stiffness=30.0)
    assert abs(m1 - m2) < 3.0 * math.hypot(s1, s2)


def test_two_temperatures_cut_the_bath_limited_draws():
    """In a cooling gas the short rods' baths run dry; a law that knows each rod's temperature asks them for
    less than they hold far more often than the one-temperature law (three realisations each, difference beyond
    three combined standard errors)."""
    fractions = {"two": [], "one": []}
    for seed in range(3):
        gas = random_gas(300, seed=seed, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
        for name, law in (("two", LAW), ("one", LAW.equal_temperature_slice())):
            result = GasSimulation(gas, VibrationLaw(law), seed=seed, record_every=30_000, max_frames=0).run(30_000)
            assert result.status == "completed"
            fractions[name].append(result.bath_limited / result.collisions)
    (m2, s2), (m1, s1) = _mean_and_sem(fractions["two"]), _mean_and_sem(fractions["one"])
    assert m1 - m2 > 3.0 * math.hypot(s1, s2)


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


def test_level_means_files_and_refusals(tmp_path):
    probability = np.linspace(0, 1, 5)
    rng = np.random.default_rng(np.random.SeedSequence(3))
    order, values = rng.random(1000), rng.random(1000)
    means = level_means(order, values, probability)
    widths = np.diff(probability)
    assert np.sum(0.5 * (means[1:] + means[:-1]) * widths) == pytest.approx(values.mean(), abs=0.03)
    with pytest.raises(InvalidParameterError, match="empty"):
        level_means(order[:3], values[:3], np.linspace(0, 1, 11))
    for law in (LAW, SOFT):
        again = load_law(law.save(tmp_path / "law.npz"))
        assert np.array_equal(again.eps2_quantiles, law.eps2_quantiles) and np.array_equal(again.kappa, law.kappa)
    with pytest.raises(InvalidParameterError, match="log_x must end at 0"):
        CollisionLaw(LAW.kappa, LAW.gamma, LAW.log_x - 1, LAW.short_share, LAW.probability, LAW.eps2_quantiles,
                     LAW.gain_short)
    with pytest.raises(InvalidParameterError, match="short_share must run from 0 to 1"):
        CollisionLaw(LAW.kappa, LAW.gamma, LAW.log_x, LAW.short_share * 0.5, LAW.probability, LAW.eps2_quantiles,
                     LAW.gain_short)
    (tmp_path / "bad.npz").write_bytes(b"not a file")
    with pytest.raises(InvalidParameterError, match="not a readable"):
        load_law(tmp_path / "bad.npz")
    gas = random_gas(20, seed=1, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
    with pytest.raises(InvalidParameterError, match="no soft"):
        GasSimulation(gas, VibrationLaw(LAW), contact_stiffness=10.0)
    with pytest.raises(InvalidParameterError, match="contact_stiffness alpha must"):
        GasSimulation(gas, VibrationLaw(LAW, SOFT), contact_stiffness=-1.0)
    assert kappa_variable(math.inf) == 0.0 and kappa_variable(100.0) == pytest.approx(math.log(100) / 100)


@pytest.mark.parametrize("stiffness", [None, 40.0])
def test_law_rule_checkpoint_resumes_bit_for_bit(tmp_path, stiffness):
    gas = random_gas(80, seed=4, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
    rule = VibrationLaw(LAW, SOFT)
    straight = GasSimulation(gas, rule, seed=9, damping=20.0, record_every=500, contact_stiffness=stiffness)
    straight.run(3000)
    first = GasSimulation(gas, rule, seed=9, damping=20.0, record_every=500, contact_stiffness=stiffness)
    first.run(1500)
    first.save_checkpoint(tmp_path / "law.npz")
    resumed = GasSimulation.resume(tmp_path / "law.npz")
    assert isinstance(resumed.rule, VibrationLaw) and resumed.contact_stiffness == stiffness
    resumed.run(1500)
    for name in ("x", "v", "temperature", "local_time", "counters"):
        assert np.array_equal(getattr(straight, name), getattr(resumed, name))


def _law_mean(law, gamma_index, row, share_index):
    """Mean of a tabulated quantile function (trapezoid over the levels) and its sampling error."""
    q = law.eps2_quantiles[0, gamma_index, row, share_index]
    w = np.zeros(law.probability.size)
    w[1:] += 0.5 * np.diff(law.probability)
    w[:-1] += 0.5 * np.diff(law.probability)
    mean = float(np.sum(q * w))
    return mean, math.sqrt(float(np.sum((q - mean) ** 2 * w)) / law.samples_per_point)


# The stated grid error of the max-plus solve at gamma = 1 (docs/gas.md, "Grid error of the law"): first order in
# the step and proportional to the noise amplitude, 1 - eps^2 ~ C sqrt(1/x - 1) / r at r points per period, with
# C = 0.06 ... 0.08 measured by docs/law_grid_study.py on fresh realisations at r = 16 ... 1024 (where the exact
# answer is 1) for s = 1/2, and about the same at s = 0 ... 1.  The stated bound takes C = 0.1; it is not a value
# of the shipped law.
GRID_ERROR_CONSTANT = 0.1


def test_gamma_one_rows_of_the_law_lie_within_their_stated_grid_error_of_one():
    """Equal rods in the hard-core limit leave with eps = 1 in every realisation (the paper; independent of the
    grid): every gamma = 1 row of the shipped law, at every share s, lies below 1 by no more than the stated grid
    error at that row's resolution, and the rows are refined enough that this error is below 0.04 everywhere
    (at the base resolution 16 it would reach 0.6 at x = 1e-4)."""
    g = LAW.gamma.size - 1
    assert LAW.gamma[g] == 1.0
    for b, log_x in enumerate(LAW.log_x):
        r = LAW.point_resolution(g, b)
        bound = GRID_ERROR_CONSTANT * math.sqrt(10.0 ** -log_x - 1.0) / r
        assert bound < 0.04
        for c in range(LAW.short_share.size):
            mean, sem = _law_mean(LAW, g, b, c)
            assert -3.0 * sem - 1e-12 <= 1.0 - mean <= bound + 3.0 * sem, (log_x, LAW.short_share[c], mean, bound)


@pytest.mark.parametrize("log_x", [-1.0, -2.0])
def test_gamma_one_rows_of_the_law_fall_below_one_by_grid_error_only(log_x):
    """The shipped law's gamma = 1 deficit 1 - eps^2 is the max-plus grid's error at the row's resolution: fresh
    solves at that resolution show the same deficit (within the two samples' errors), and on the same realisations
    it shrinks below a half at 4x the resolution (first order: a quarter)."""
    n = 24
    g, b = LAW.gamma.size - 1, list(LAW.log_x).index(log_x)
    r = LAW.point_resolution(g, b)
    assert r > LAW.resolution  # the rows are refined (the resolution rule), not the base grid's
    coarse_eps2, _ = point_samples(1.0, log_x, n, 12, bath_modes=LAW.bath_modes, resolution=r)
    fine_eps2, _ = point_samples(1.0, log_x, n, 12, bath_modes=LAW.bath_modes, resolution=4 * r)
    law_mean, law_sem = _law_mean(LAW, g, b, list(LAW.short_share).index(0.5))
    deficit, sem = _mean_and_sem(1.0 - coarse_eps2)
    assert deficit > 3.0 * sem  # the grid error is real at the law's resolution ...
    assert abs((1.0 - law_mean) - deficit) < 3.0 * math.hypot(sem, law_sem)  # ... and is all of the law's deficit
    fine_deficit, _ = _mean_and_sem(1.0 - fine_eps2)
    gained, gained_sem = _mean_and_sem(fine_eps2 - coarse_eps2)
    assert gained > 3.0 * gained_sem and fine_deficit < deficit / 2.0


def test_resolution_rule_grows_like_sqrt_of_one_over_x_and_is_stored(tmp_path):
    """The builder's rule min(cap, ceil(r sqrt(1/x))) per row, stored in the file and read back; on the same
    realisations a gamma = 1 row built with it is nearer the exact eps^2 = 1 than at the fixed resolution."""
    assert row_resolutions([-4.0, -2.0, -0.5, 0.0], 16, 256) == (256, 160, 29, 16)
    assert row_resolutions([-4.0, 0.0], 16) == (16, 16)
    with pytest.raises(InvalidParameterError, match="resolution cap"):
        row_resolutions([0.0], 16, 8)
    options = {"levels": 5, "bath_modes": 250, "resolution": 16}
    fixed = build_collision_law(LawGrid([1.0], [-3.0, 0.0]), 8, 5, **options)
    grown = build_collision_law(LawGrid([1.0], [-3.0, 0.0]), 8, 5, resolution_cap=128, **options)
    assert fixed.row_resolution == () and grown.row_resolution == (128, 16)
    again = load_law(grown.save(tmp_path / "grown.npz"))
    assert again.row_resolution == (128, 16) and np.array_equal(again.eps2_quantiles, grown.eps2_quantiles)
    assert np.allclose(grown.eps2_quantiles[0, 0, 1], 1.0) and np.allclose(fixed.eps2_quantiles[0, 0, 1], 1.0)
    fixed_deficit = 1.0 - _law_mean(fixed, 0, 0, 0)[0]
    grown_deficit = 1.0 - _law_mean(grown, 0, 0, 0)[0]
    assert 0.0 <= grown_deficit < fixed_deficit / 3.0
    with pytest.raises(InvalidParameterError, match="row_resolution"):
        CollisionLaw(grown.kappa, grown.gamma, grown.log_x, grown.short_share, grown.probability,
                     grown.eps2_quantiles, grown.gain_short, row_resolution=(16,))


def test_a_cap_per_gamma_and_reused_points_give_the_same_law_as_a_full_build(tmp_path):
    """One cap per gamma row is stored per (gamma, row); a build that copies the points of an earlier law at the
    same resolution (same grid and seeds) equals a full build bit for bit, and a law with another seed is not
    copied from."""
    grid = (LawGrid([0.9, 1.0], [-3.0, -1.0, 0.0], short_shares=(0.0, 0.5, 1.0)), 8, 5)
    options = {"levels": 5, "bath_modes": 250, "resolution": 16}
    fixed = build_collision_law(*grid, **options)
    full = build_collision_law(*grid, resolution_cap=(16, 128), **options)
    assert full.row_resolution == ((16, 16, 16), (128, 51, 16))
    assert [full.point_resolution(1, b) for b in range(3)] == [128, 51, 16] and full.point_resolution(0, 0) == 16
    solved = []
    reused = build_collision_law(*grid, resolution_cap=(16, 128), reuse=fixed,
                                 progress=lambda done, todo: solved.append(todo), **options)
    assert solved[-1] == 2 * 3  # the gamma = 1 rows at x = 1e-3 and 1e-1, three shares each; the rest copied
    assert np.array_equal(reused.eps2_quantiles, full.eps2_quantiles)
    assert np.array_equal(reused.gain_short, full.gain_short)
    assert np.array_equal(full.eps2_quantiles[0, 0], fixed.eps2_quantiles[0, 0])
    other = build_collision_law(grid[0], grid[1], 6, **options)
    solved.clear()
    build_collision_law(*grid, resolution_cap=(16, 128), reuse=other,
                        progress=lambda done, todo: solved.append(todo), **options)
    assert solved[-1] == 2 * 3 * 3  # another seed: nothing copied
    again = load_law(full.save(tmp_path / "caps.npz"))
    assert again.row_resolution == full.row_resolution
    with pytest.raises(InvalidParameterError, match="one per gamma"):
        build_collision_law(*grid, resolution_cap=(16, 32, 64), **options)
    with pytest.raises(InvalidParameterError, match="row_resolution"):
        CollisionLaw(full.kappa, full.gamma, full.log_x, full.short_share, full.probability, full.eps2_quantiles,
                     full.gain_short, row_resolution=((16, 16, 16), (128, 51)))


# (point, tolerance): 0 is bit for bit.  The soft law's rows kappa = 10, 30, 100 were built before the delay
# kernel's stopping rule changed (the stop certificate, commit 37e0e2f), which moves its eps^2 by round-off
# (about 1e-13); the kappa = 5 row and the hard-core law were built with the present code.
@pytest.mark.parametrize(("command", "points"), [
    (REGENERATE, [((0, 0, 14, 0), 0.0), ((0, 5, 14, 1), 0.0)]),
    (REGENERATE_SOFT, [((3, 0, 6, 1), 0.0), ((0, 0, 6, 1), 0.0)]),
    # built by an earlier delay kernel, and before the delay solver refined its noise tables to the tolerance: a
    # rebuild today moves its eps^2 quantiles by up to 2.3e-8 and its gains by up to 1.7e-6 (the old tables'
    # interpolation error, which that solver left out of its estimate). Expected to fail until the shipped soft
    # law is rebuilt with its stored command (hours of CPU); strict, so the rebuild must remove this mark.
    pytest.param(REGENERATE_SOFT, [((3, 1, 5, 1), 1e-9)], marks=pytest.mark.xfail(
        strict=True, reason="shipped soft law built before the noise tables were refined to the tolerance")),
    pytest.param(REGENERATE_SOFT, [((0, 1, 5, 1), 0.0)], marks=pytest.mark.slow),  # 64 solves of 0.1 to 0.3 s
], ids=["hard-core", "soft", "soft-built-before-table-refinement", "soft-kappa-5-warm"])
def test_the_shipped_laws_are_what_their_stored_commands_build(command, points):
    """The commands in the file's metadata describe the shipped grid, seeds, caps and sample counts (a soft law
    merged from two builds: each build's kappa rows and seed), and re-solving a few of its points (the cheap
    ones near x = 1) from the commands' seeds reproduces the file: bit for bit where the present code built it,
    to round-off where an earlier delay kernel did."""
    law = LAW if command == REGENERATE else SOFT
    assert law.metadata()["regenerate"] == command
    builds = [parser().parse_args(shlex.split(part)[3:]) for part in command.split(" && ")]
    merge = [b for b in builds if b.merge]
    builds = [b for b in builds if not b.merge]
    assert len(merge) == (len(builds) > 1)
    assert sorted(k for b in builds for k in b.kappa) == law.kappa.tolist()
    seeds = {k: b.seed for b in builds for k in b.kappa}
    assert [seeds[k] for k in law.kappa] == list(law.kappa_seeds or [law.seed] * law.kappa.size)
    for args in builds:
        assert np.array_equal(law.gamma, args.gamma) and np.array_equal(law.log_x, sorted(args.log_x))
        assert np.array_equal(law.short_share, sorted(args.share))
        assert (law.samples_per_point, law.probability.size, law.bath_modes) == (args.samples, args.levels,
                                                                                 args.bath_modes)
        caps = args.resolution_cap or [None]
        caps = caps * law.gamma.size if len(caps) == 1 else caps
        for a, cap in enumerate(caps):
            assert [law.point_resolution(a, b) for b in range(law.log_x.size)] == list(
                row_resolutions(law.log_x, args.resolution, cap))
    for index, tolerance in points:
        k, g, b, c = index
        args = next(a for a in builds if law.kappa[k] in a.kappa)
        rows = sorted(args.kappa)
        shape = (len(rows),) + law.shape[1:4]
        children = np.random.SeedSequence(args.seed).spawn(int(np.prod(shape)))
        seeds = children[np.ravel_multi_index((rows.index(law.kappa[k]), g, b, c), shape)]
        eps2, gain = point_samples(law.gamma[g], law.log_x[b], law.samples_per_point, seeds,
                                   bath_modes=law.bath_modes, resolution=law.point_resolution(g, b),
                                   short_share=law.short_share[c], kappa=law.kappa[k])
        quantiles, gains = np.quantile(eps2, law.probability), level_means(eps2, gain, law.probability)
        if tolerance == 0.0:
            assert np.array_equal(quantiles, law.eps2_quantiles[index])
            assert np.array_equal(gains, law.gain_short[index])
        else:
            np.testing.assert_allclose(quantiles, law.eps2_quantiles[index], rtol=0, atol=tolerance)
            np.testing.assert_allclose(gains, law.gain_short[index], rtol=0, atol=tolerance)


def test_soft_laws_merge_along_kappa_and_refuse_other_grids(tmp_path):
    """Merging keeps every row's arrays and seed, sorts the rows by kappa, and refuses laws on other grids."""
    parts = {name: CollisionLaw(kappa, SOFT.gamma, SOFT.log_x, SOFT.short_share, SOFT.probability,
                                SOFT.eps2_quantiles[rows], SOFT.gain_short[rows], samples_per_point=64, seed=seed)
             for name, kappa, rows, seed in (("stiff", SOFT.kappa[2:], slice(2, None), 7),
                                             ("soft", SOFT.kappa[:2], slice(0, 2), 8))}
    merged = merge_kappa_rows([parts["stiff"], parts["soft"]])
    assert np.array_equal(merged.kappa, SOFT.kappa) and merged.kappa_seeds == (8, 8) + (7,) * (SOFT.kappa.size - 2)
    assert np.array_equal(merged.eps2_quantiles, SOFT.eps2_quantiles)
    assert np.array_equal(merged.gain_short, SOFT.gain_short)
    assert load_law(merged.save(tmp_path / "merged.npz")).kappa_seeds == merged.kappa_seeds
    with pytest.raises(InvalidParameterError, match="distinct kappa"):
        merge_kappa_rows([parts["stiff"], parts["stiff"]])
    with pytest.raises(InvalidParameterError, match="share their gamma"):
        merge_kappa_rows([parts["soft"], SOFT.equal_temperature_slice()])
    with pytest.raises(InvalidParameterError, match="finite-kappa"):
        merge_kappa_rows([parts["soft"], LAW])


def test_equal_temperature_slice_is_the_middle_share_of_the_law():
    """The one-temperature comparison law is the s = 1/2 slice of the shipped arrays, nothing else changed."""
    single = LAW.equal_temperature_slice()
    middle = list(LAW.short_share).index(0.5)
    assert list(single.short_share) == [0.5]
    np.testing.assert_array_equal(single.eps2_quantiles[..., 0, :], LAW.eps2_quantiles[..., middle, :])
    np.testing.assert_array_equal(single.gain_short[..., 0, :], LAW.gain_short[..., middle, :])
    assert (single.kappa.tolist(), single.gamma.tolist(), single.log_x.tolist()) == (
        LAW.kappa.tolist(), LAW.gamma.tolist(), LAW.log_x.tolist())
    assert (single.resolution, single.row_resolution, single.seed) == (LAW.resolution, LAW.row_resolution, LAW.seed)
    ends_only = single.__class__(single.kappa, single.gamma, single.log_x, [0.0, 1.0], single.probability,
                                 np.repeat(single.eps2_quantiles, 2, axis=3), np.repeat(single.gain_short, 2, axis=3))
    with pytest.raises(InvalidParameterError, match="no short_share = 0.5"):
        ends_only.equal_temperature_slice()
