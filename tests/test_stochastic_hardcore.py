"""The hard-core limit with noise (Eq. 26 on a grid): exactness, convergence, the finite-kappa limit."""

import math

import numpy as np
import pytest

import wavecontact
from wavecontact.bath import ThermalBath
from wavecontact.delay.stochastic_hardcore import hard_core_noise


def _lengths(gamma):
    return (0.5 * (1 + gamma), 0.5 * (1 + gamma) / gamma)


@pytest.mark.parametrize("gamma", [0.6, 0.6173, 0.2173])
def test_cold_grid_is_the_exact_deterministic_limit(gamma):
    _t, w = hard_core_noise(gamma, None, 1.0)
    assert w[-1] - 1.0 == pytest.approx(gamma, abs=1e-12)


def test_equal_rods_bounce_elastically_for_every_realisation():
    # paper Sec. VI: gamma = 1 gives epsilon = 1 whatever the noise; the grid approaches it as it refines
    bath = ThermalBath(2.0, 100)
    errors = []
    for seed in range(5):
        v = bath.draw(_lengths(1.0), seed)
        errors.append([abs(hard_core_noise(1.0, v, 5.0, r)[1][-1] - 2.0) for r in (8, 64, 512)])
    errors = np.array(errors)
    assert np.all(errors[:, -1] < 5e-4)
    assert np.median(errors[:, -1]) < np.median(errors[:, 0]) / 10


def test_grid_converges_as_it_resolves_the_noise():
    # errors against a grid 64x finer, over several realisations: median error falls with h
    gamma = 0.6
    bath = ThermalBath(1.0, 20)
    resolutions = np.array([16, 32, 64, 128])
    errors = []
    for seed in range(6):
        v = bath.draw(_lengths(gamma), seed)
        reference = hard_core_noise(gamma, v, 3.0, 2048, min_points=0)[1][-1]
        errors.append([abs(hard_core_noise(gamma, v, 3.0, int(r), min_points=0)[1][-1] - reference)
                       for r in resolutions])
    median = np.median(np.array(errors), axis=0)
    slope = np.polyfit(np.log(resolutions), np.log(median + 1e-15), 1)[0]
    assert slope < -0.8  # first order or better (kinks of the memory terms limit it to first order)
    assert median[-1] < 1e-3


def test_stated_error_has_the_size_of_the_actual_error():
    # the estimate (largest change over the two coarser grids) is a typical size, not a bound:
    # over realisations the median of actual / estimated stays below 1
    from wavecontact.bath.scene import start_gap
    from wavecontact.contact import Hard

    gamma = 0.6173
    bath = ThermalBath(1.0, 50)
    ratios = []
    for seed in range(12):
        result = wavecontact.collide(gamma, math.inf, "delay", bath_temperature=1.0, bath_modes=50, seed=seed)
        v = bath.draw(_lengths(gamma), np.random.SeedSequence(seed))
        reference = hard_core_noise(gamma, v, start_gap(v, Hard()), 512)[1][-1] - 1.0
        ratios.append(abs(result.restitution - reference) / max(result.error_estimate, 1e-12))
        assert abs(result.restitution - reference) < 5e-3
    assert np.median(ratios) < 1.0


def test_a_stiff_contact_does_not_step_over_a_short_rise_of_the_noise():
    # this realisation first touches on a narrow bump of the noise; a step that strode over it
    # missed that contact and ended 0.05 away from the hard-core limit at kappa = 3200
    warm = {"bath_temperature": 0.5, "bath_modes": 10, "seed": 1}
    hard = wavecontact.collide(0.6, math.inf, "delay", hard_core_resolution=128, **warm).restitution
    stiff = wavecontact.collide(0.6, 800.0, "delay", rtol=1e-6, energy_split=False, **warm).restitution
    assert abs(stiff - hard) < 0.003


@pytest.mark.slow
def test_finite_kappa_approaches_the_hard_core_mode():
    # the same realisations at growing kappa: |eps(kappa) - eps(inf)| falls roughly like ln(kappa)/kappa
    kappas = np.array([40.0, 400.0])
    differences = []
    for seed in range(3):
        warm = {"bath_temperature": 0.5, "bath_modes": 10, "seed": seed}
        hard = wavecontact.collide(0.6, math.inf, "delay", hard_core_resolution=256, **warm).restitution
        differences.append([abs(wavecontact.collide(0.6, k, "delay", rtol=1e-7, energy_split=False,
                                                    **warm).restitution - hard) for k in kappas])
    median = np.median(np.array(differences), axis=0)
    assert median[-1] < median[0] / 4
    assert median[-1] < 0.01
