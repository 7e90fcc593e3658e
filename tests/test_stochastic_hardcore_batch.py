"""The batched stochastic hard-core mode: bit-identical samples, an independent reference, the stop certificate."""

import math
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import pytest

from wavecontact.bath import ThermalBath
from wavecontact.bath.streams import SpawnedSeeds
from wavecontact.delay.stochastic_hardcore_batch import (
    HardCoreGrid,
    cached_grid,
    hard_core_restitution,
    hard_core_restitutions,
)
from wavecontact.errors import InvalidParameterError
from wavecontact.solvers import get_solver
from wavecontact.studies.ensemble import ensemble, sample_seed


def _lengths(gamma):
    return (0.5 * (1 + gamma), 0.5 * (1 + gamma) / gamma)


def _reference(gamma, vibrations, n1, periods_after=12.0):
    """Eq. 26 on a grid written independently: the noise summed mode by mode (no FFT, no tables), both
    memory terms by linear interpolation of the stored history, no peak correction, and a fixed long
    run (``periods_after`` times Gamma_1 + Gamma_2 after the last rise) instead of a stop rule."""
    g1, g2 = 1.0 + gamma, 1.0 + 1.0 / gamma
    h = g1 / n1
    terms = vibrations.noise_coefficients(1.0)
    bound = sum(float(np.sum(np.abs(a) + np.abs(b))) for _o, a, b in terms)
    t0 = -bound - h
    size = int((bound + 4 * (g1 + g2)) / h) + 1
    t = t0 + h * np.arange(size)

    def noise(times):
        total = np.zeros_like(times)
        for (omega, a, b), period in zip(terms, (g1, g2)):
            phase = np.outer(times, 2.0 * math.pi * np.arange(1, a.size + 1) / period)
            total += np.cos(phase) @ a + np.sin(phase) @ b
        return total

    q = noise(t)
    w = np.zeros(size)
    running = 0.0
    last = 0
    k = 0
    while True:
        if k == size:  # extend the run
            extra = t[-1] + h * np.arange(1, size + 1)
            t, q, w = np.concatenate([t, extra]), np.concatenate([q, noise(extra)]), np.concatenate([w, np.zeros(size)])
            size *= 2
        copies = 0.0
        for period in (g1, g2):
            back = t[k] - period * np.arange(1, int((t[k] - t0) / period) + 1)
            copies += float(np.sum(np.interp(back, t[:k + 1], w[:k + 1], left=0.0)))
        value = t[k] - copies + q[k]
        if value > running:
            running = value
            last = k
        w[k] = running
        if running > 0.0 and k - last > periods_after * (g1 + g2) / h:
            return running - 1.0
        k += 1


def test_samples_do_not_depend_on_the_batch():
    gamma, seeds = 0.6173, [sample_seed(4, j) for j in range(70)]
    together = hard_core_restitutions(gamma, 1.0, seeds, modes=60)
    alone = np.array([hard_core_restitutions(gamma, 1.0, [s], modes=60)[0] for s in seeds])
    split = np.concatenate([hard_core_restitutions(gamma, 1.0, seeds[a:b], modes=60)
                            for a, b in ((0, 7), (7, 40), (40, 70))])
    assert np.array_equal(together, alone)
    assert np.array_equal(together, split)


def test_the_batch_solves_the_realisation_that_thermal_bath_draws():
    # the same numbers through ThermalBath.draw -> BathRealisation, the registry and a Generator
    gamma, bath = 0.4, ThermalBath(0.7, 40)
    seeds = [sample_seed(9, j) for j in range(6)]
    batch = hard_core_restitutions(gamma, 0.7, seeds, modes=40)
    delay = get_solver("delay")
    for j, seed in enumerate(seeds):
        vibrations = bath.draw(_lengths(gamma), seed)
        assert delay.hard_core_thermal_restitution(gamma, vibrations) == batch[j]
        assert hard_core_restitution(gamma, (0.7, 0.7), 40, np.random.default_rng(seed)) == batch[j]


def test_ensembles_are_identical_across_executors_and_batch_sizes():
    args = (0.6173, math.inf, 0.5, 90, 21)
    serial = ensemble(*args, bath_modes=50, batch_size=90).restitution
    with ProcessPoolExecutor(2) as pool:
        pooled = ensemble(*args, bath_modes=50, batch_size=13, executor=pool).restitution
    one_by_one = [ensemble(*args[:3], 1, 21, bath_modes=50).restitution[0]]
    assert np.array_equal(serial, pooled)
    assert one_by_one[0] == serial[0]


@pytest.mark.parametrize("gamma", [0.6, 0.6173, 0.2173])
def test_cold_bath_gives_the_exact_restitution(gamma):
    eps = hard_core_restitutions(gamma, 0.0, [1, 2], modes=10)
    assert np.all(np.abs(eps - gamma) < 1e-12)


def test_agrees_with_an_independent_recursion_and_converges_at_first_order_or_better():
    gamma, modes = 0.6, 6
    bath = ThermalBath(1.5, modes)
    resolutions = np.array([8, 16, 32, 64])
    errors = []
    for j in range(4):
        seed = sample_seed(31, j)
        reference = _reference(gamma, bath.draw(_lengths(gamma), seed), 1536, periods_after=4.0)
        errors.append([abs(HardCoreGrid(gamma, modes, int(r), min_points=0).restitutions(
            np.random.default_rng(seed).standard_normal((1, 2, 2, modes)), np.full((1, 2), 1.5))[0] - reference)
            for r in resolutions])
    median = np.median(np.array(errors), axis=0)
    slope = np.polyfit(np.log(resolutions), np.log(median + 1e-12), 1)[0]
    assert slope < -0.8
    assert median[-1] < 2e-3


def test_stop_certificate_misses_no_late_contact():
    # hot baths with few modes re-touch long after the first separation: the certified stop must
    # give what a run 12 memory periods beyond the last rise gives (to the grid's own error)
    gamma, modes, temperature = 0.6173, 4, 20.0
    bath = ThermalBath(temperature, modes)
    grid = HardCoreGrid(gamma, modes, 256, min_points=0)
    differences = []
    for j in range(5):
        seed = sample_seed(47, j)
        fast = grid.restitutions(np.random.default_rng(seed).standard_normal((1, 2, 2, modes)),
                                 np.full((1, 2), temperature))[0]
        differences.append(abs(fast - _reference(gamma, bath.draw(_lengths(gamma), seed), 512)))
    assert max(differences) < 3e-3
    assert np.median(differences) < 5e-4


def test_equal_rods_bounce_elastically():
    # paper Sec. VI: gamma = 1 gives epsilon = 1 in every realisation; the grid approaches it as it refines
    errors = [np.abs(hard_core_restitutions(1.0, 2.0, range(8), modes=20, points_per_period=r) - 1.0) for r in (16, 256)]
    assert np.all(errors[1] < 3e-3)
    assert np.median(errors[1]) < np.median(errors[0]) / 4


@pytest.mark.parametrize("call, match", [
    (lambda: HardCoreGrid(0.0, 10), "gamma"),
    (lambda: HardCoreGrid(0.5, 0), "nu_max"),
    (lambda: HardCoreGrid(0.5, 10, 1), "hard_core_resolution"),
    (lambda: hard_core_restitutions(0.5, -1.0, [1], modes=5), "temperature"),
    (lambda: hard_core_restitutions(0.5, np.ones((3, 2)), [1, 2], modes=5), "temperature"),
    (lambda: ensemble(0.5, math.inf, 1.0, 4, 0, rtol=1e-6), "hard_core_resolution"),
])
def test_bad_input_is_refused_in_one_line(call, match):
    with pytest.raises(InvalidParameterError, match=match):
        call()


def test_threads_sharing_one_cached_grid_give_the_serial_samples():
    # found by CI: the grid kept its work arrays between calls, and threads sampling the same
    # cached grid (the kernel runs without the GIL) overwrote each other's
    grid = cached_grid(0.6173, 40)
    blocks = [[sample_seed(11, 8 * b + j) for j in range(8)] for b in range(24)]
    temperatures = [0.3 + 0.4 * (b % 5) for b in range(24)]  # blocks of different lengths
    serial = [hard_core_restitutions(0.6173, t, seeds, grid=grid) for t, seeds in zip(temperatures, blocks)]
    with ThreadPoolExecutor(6) as pool:
        threaded = list(pool.map(lambda args: hard_core_restitutions(0.6173, args[0], args[1], grid=grid),
                                 zip(temperatures, blocks)))
    for one, other in zip(serial, threaded):
        assert np.array_equal(one, other)


def test_collide_returns_the_ensembles_sample_bit_for_bit():
    # collide(kappa=inf) answers from the grid at twice its hard_core_resolution: the ensemble's
    # sample of the same seed at that resolution, whatever the batch it came in
    import wavecontact

    gamma, temperature = 0.6173, 0.8
    samples = ensemble(gamma, math.inf, temperature, 6, 5, bath_modes=40, batch_size=4,
                       hard_core_resolution=16).restitution
    for j in range(6):
        result = wavecontact.collide(gamma, math.inf, bath_temperature=temperature, bath_modes=40,
                                     seed=sample_seed(5, j), hard_core_resolution=8)
        assert result.restitution == samples[j]
        # the history from the per-sample grid ends where the batched grid does, to the grid's error
        assert abs(result.relative_velocity[-1] - result.restitution) < 1e-3


def test_default_grid_bias_is_far_below_a_fig8_standard_error():
    # the paper's setting (nu_max 250, T_B/E_tr 1): the mean of epsilon at the default 8 points per period
    # against the same samples at 64 points (whose own error is an eighth of it at first order, and
    # the independent recursion above shows the grid converges) stays far below the standard error of
    # a 2500-sample point of Fig. 8 (about 0.006), and the finer grid moves it less than the coarser
    seeds = SpawnedSeeds(2024, 0, 400)
    eps = {r: hard_core_restitutions(0.6173, 1.0, seeds, modes=250, points_per_period=r) for r in (4, 8, 64)}
    bias = {r: float(np.mean(eps[r] - eps[64])) for r in (4, 8)}
    spread = {r: float(np.std(eps[r] - eps[64]) / math.sqrt(len(seeds))) for r in (4, 8)}
    assert abs(bias[8]) + 3.0 * spread[8] < 1e-3
    assert abs(bias[8]) < abs(bias[4])


def test_rod2_table_adds_an_unbiased_error_below_the_grids():
    # rod 2's Hermite table at half the grid's points per period against one eight times finer (same grid):
    # no mean shift beyond four standard errors, and per sample smaller than the grid's own error
    # (the default grid against 64 points per period)
    seeds = SpawnedSeeds(31, 0, 300)
    normals = np.array([np.random.default_rng(s).standard_normal((2, 2, 250)) for s in seeds])
    temperatures = np.ones((len(seeds), 2))
    default = HardCoreGrid(0.6173, 250).restitutions(normals, temperatures)
    fine_table = HardCoreGrid(0.6173, 250, rod2_points=32).restitutions(normals, temperatures)
    fine_grid = HardCoreGrid(0.6173, 250, 64).restitutions(normals, temperatures)
    table = default - fine_table
    assert abs(table.mean()) < 4.0 * table.std() / math.sqrt(table.size)
    assert np.median(np.abs(table)) < np.median(np.abs(default - fine_grid))


def test_plain_python_kernels_give_the_compiled_samples():
    # WAVECONTACT_PURE_PYTHON=1 runs the streams, bounds, chunks and certificate as plain Python
    import os
    import subprocess
    import sys

    code = ("from wavecontact.delay.stochastic_hardcore_batch import hard_core_restitutions;"
            "from wavecontact.bath.streams import SpawnedSeeds;"
            "print(hard_core_restitutions(0.6173, 1.0, SpawnedSeeds(3, 0, 3), modes=12).tobytes().hex())")
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env = dict(os.environ, WAVECONTACT_PURE_PYTHON="1")
    pure = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True, cwd=root)
    compiled = hard_core_restitutions(0.6173, 1.0, SpawnedSeeds(3, 0, 3), modes=12)
    assert bytes.fromhex(pure.stdout.strip()) == compiled.tobytes()
