"""The noise Q(tau) (Eq. 17): its tables and its covariance (Eq. 19, Fig. 4)."""

import math

import numpy as np
import pytest

from wavecontact.bath import ThermalBath, covariance_eq19, covariance_series
from wavecontact.bath.noise import noise_tables
from wavecontact.delay.kernels import table_value

GAMMA = 0.6173
LENGTHS = (0.5 * (1 + GAMMA), 0.5 * (1 + GAMMA) / GAMMA)
PERIODS = (1 + GAMMA, 1 + 1 / GAMMA)


def _direct(coefficients, t, contact_time):
    total = np.zeros_like(t)
    for omega, a, b in coefficients:
        phase = np.outer(t - contact_time, omega)
        total += np.cos(phase) @ a + np.sin(phase) @ b
    return total


def test_tables_reproduce_the_fourier_sum():
    v = ThermalBath(1.0, modes=250).draw(LENGTHS, 5)
    coefficients = v.noise_coefficients(100.0)
    tables = noise_tables(coefficients, PERIODS, contact_time=3.7)
    t = np.linspace(0.0, 9.0, 1001)
    table = np.array([sum(table_value(x, tables.periods[i], tables.values[i], tables.slopes[i])[0]
                          for i in range(2)) for x in t])
    exact = _direct(coefficients, t, 3.7)
    scale = np.max(np.abs(exact))
    assert np.max(np.abs(table - exact)) < 1e-5 * scale


def test_eq19_is_the_limit_of_the_series_with_error_falling_like_one_over_modes():
    tau = np.linspace(0.0, 7.0, 301)
    exact = covariance_eq19(tau, GAMMA, 10.0, (1.0, 1.0))
    modes = np.array([25, 50, 100, 200, 400])
    errors = [np.max(np.abs(covariance_series(tau, GAMMA, 10.0, (1.0, 1.0), m) - exact)) for m in modes]
    slope = np.polyfit(np.log(modes), np.log(errors), 1)[0]
    assert -1.1 < slope < -0.9  # the tail sum_{nu > M} 1/nu^2 ~ 1/M


def test_eq19_with_equal_temperatures_is_the_papers_formula():
    # sigma^2 {sum_i (tau - Gamma_i/2 - Gamma_i sum_n theta(tau - n Gamma_i))^2 / (2 Gamma_i) - Gamma_1 Gamma_2 / 24}
    kappa, ratio = 7.0, 0.8
    sigma2 = kappa**2 * ratio / 2.0
    tau = np.linspace(0.0, 9.0, 97)
    paper = -PERIODS[0] * PERIODS[1] / 24.0
    for g in PERIODS:
        paper = paper + (tau - g / 2 - g * np.floor(tau / g)) ** 2 / (2 * g)
    assert np.allclose(covariance_eq19(tau, GAMMA, kappa, (ratio, ratio)), sigma2 * paper, rtol=1e-12, atol=1e-12)


def test_sampled_noise_has_the_covariance_of_eq19():
    # Fig. 4: <Q(t') Q(t' + tau)> over realisations against the series (exact for nu_max modes)
    # and Eq. 19 (nu_max -> inf); tolerance from the spread of the products
    modes, kappa, ratio, count = 100, 1.0, 1.0, 3000
    lags = np.array([0.0, 0.3, 0.8, 1.6, 2.5])
    products = []
    for s in range(count):
        coefficients = ThermalBath(ratio, modes).draw(LENGTHS, s).noise_coefficients(kappa)
        q = _direct(coefficients, 0.9 + lags, 0.0)
        products.append(q[0] * q)
    products = np.array(products)
    mean = products.mean(axis=0)
    error = products.std(axis=0, ddof=1) / math.sqrt(count)
    series = covariance_series(lags, GAMMA, kappa, (ratio, ratio), modes)
    assert np.all(np.abs(mean - series) < 4.5 * error)
    tail = covariance_series(lags, GAMMA, kappa, (ratio, ratio), modes) - covariance_eq19(lags, GAMMA, kappa, (ratio,) * 2)
    assert np.max(np.abs(tail)) < 0.01 * covariance_eq19(0.0, GAMMA, kappa, (ratio, ratio))


def test_unequal_temperatures_split_the_covariance_by_rod():
    tau = np.linspace(0.0, 5.0, 51)
    both = covariance_eq19(tau, GAMMA, 3.0, (0.2, 1.4))
    parts = covariance_eq19(tau, GAMMA, 3.0, (0.2, 0.0)) + covariance_eq19(tau, GAMMA, 3.0, (0.0, 1.4))
    assert np.allclose(both, parts)
    # rod 1's part is periodic in Gamma_1 alone
    rod1 = covariance_eq19(tau, GAMMA, 3.0, (0.2, 0.0))
    assert np.allclose(rod1, covariance_eq19(tau + PERIODS[0], GAMMA, 3.0, (0.2, 0.0)))


def test_harmonics_of_another_period_are_refused():
    from wavecontact import InvalidParameterError

    omega = 2 * math.pi * np.arange(1, 4) / 1.0
    with pytest.raises(InvalidParameterError, match="harmonics"):
        noise_tables([(omega, np.ones(3), np.ones(3))], (2.0,), 0.0)


def test_block_maxima_bound_the_interpolated_noise_on_any_interval():
    from wavecontact.delay.kernels import noise_upper_bound

    v = ThermalBath(1.0, modes=60).draw(LENGTHS, 11)
    tables = noise_tables(v.noise_coefficients(250.0), PERIODS, contact_time=2.3, points_per_period=8)
    rng = np.random.default_rng(4)
    samples = lambda s: sum(table_value(s, tables.periods[i], tables.values[i], tables.slopes[i])[0] for i in range(2))
    slack = []
    for start, length in zip(rng.uniform(0.0, 9.0, 60), np.geomspace(1e-4, 3.0, 60)):
        bound = noise_upper_bound(start, start + length, tables.periods, tables.values, tables.slopes, tables.block_max)
        dense = max(samples(s) for s in np.linspace(start, start + length, 400))
        assert dense <= bound
        slack.append(bound - dense)
    # a bound, not a guess: the worst excess over the dense maximum stays a fraction of the noise's spread
    assert np.median(slack) < 0.5 * np.std(tables.values.sum(axis=0))


def test_curvature_blocks_bound_the_noise_curvature_on_any_interval():
    # the step limit's local bound of |Q''|: never below the curvature of the tables' Fourier sums
    from wavecontact.delay.kernels import noise_curvature_bound

    v = ThermalBath(1.0, modes=60).draw(LENGTHS, 12)
    coefficients = v.noise_coefficients(250.0)
    tables = noise_tables(coefficients, PERIODS, contact_time=2.3)

    def curvature(s):
        total = np.zeros_like(s)
        for omega, a, b in coefficients:
            phase = np.outer(s - 2.3, omega)
            total += -(np.cos(phase) * omega**2) @ a - (np.sin(phase) * omega**2) @ b
        return total

    rng = np.random.default_rng(5)
    local = []
    for start, length in zip(rng.uniform(0.0, 9.0, 60), np.geomspace(1e-4, 3.0, 60)):
        bound = noise_curvature_bound(start, start + length, tables.periods, tables.values, tables.curvature_blocks)
        dense = np.max(np.abs(curvature(np.linspace(start, start + length, 400))))
        assert dense <= bound <= tables.curvature_bound
        local.append(bound)
    # local: short intervals are bounded well below the period's maximum on average
    assert np.mean(local[:20]) < 0.8 * tables.curvature_bound


def test_batched_tables_are_the_single_tables_bit_for_bit():
    from wavecontact.bath.noise import noise_table_batch

    bath = ThermalBath((0.4, 1.0), modes=50)
    realisations = [bath.draw(LENGTHS, s) for s in range(3)]
    coefficients = [v.noise_coefficients(80.0) for v in realisations]
    a = np.array([[c[i][1] for i in range(2)] for c in coefficients])
    b = np.array([[c[i][2] for i in range(2)] for c in coefficients])
    contact_times = np.array([1.3, 2.9, 0.4])
    batch = noise_table_batch(a, b, PERIODS, contact_times, 0.0, 16)
    for k, c in enumerate(coefficients):
        one = noise_tables(c, PERIODS, contact_times[k], 0.0, 16)
        for name in ("values", "slopes", "block_max", "curvature_blocks"):
            assert np.array_equal(getattr(batch[k], name), getattr(one, name))
        assert (batch[k].slope_bound, batch[k].curvature_bound) == (one.slope_bound, one.curvature_bound)


@pytest.mark.parametrize("points_per_period", [4, 8, 32])
def test_interpolation_bound_holds_against_the_fourier_sum(points_per_period):
    # the tables' stated interpolation error bounds their distance to the Fourier sum evaluated directly,
    # and is not vacuous (within a factor 100 of the largest distance seen)
    v = ThermalBath(1.0, modes=40).draw(LENGTHS, 11)
    coefficients = v.noise_coefficients(100.0)
    tables = noise_tables(coefficients, PERIODS, contact_time=1.3, points_per_period=points_per_period)
    t = np.linspace(0.0, 2.0 * PERIODS[1], 20001)
    table = np.array([sum(table_value(x, tables.periods[i], tables.values[i], tables.slopes[i])[0]
                          for i in range(2)) for x in t])
    distance = np.max(np.abs(table - _direct(coefficients, t, 1.3)))
    assert distance <= tables.interpolation_bound <= 100.0 * distance


def test_tolerance_refines_the_tables_until_their_bound_is_below_it():
    v = ThermalBath(1.0, modes=40).draw(LENGTHS, 11)
    coefficients = v.noise_coefficients(100.0)
    coarse = noise_tables(coefficients, PERIODS, contact_time=1.3)
    wanted = coarse.interpolation_bound / 1000.0
    fine = noise_tables(coefficients, PERIODS, contact_time=1.3, tolerance=wanted)
    # cubic Hermite: the bound falls 16 times per doubling, so 1000 times takes three doublings
    assert fine.values.shape[1] == 8 * coarse.values.shape[1]
    assert fine.interpolation_bound <= wanted < 16.0 * fine.interpolation_bound
    # a tolerance the coarse tables meet leaves them as they are, bit for bit
    same = noise_tables(coefficients, PERIODS, contact_time=1.3, tolerance=coarse.interpolation_bound)
    assert np.array_equal(same.values, coarse.values) and np.array_equal(same.slopes, coarse.slopes)
