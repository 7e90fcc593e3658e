"""Closed-form results checked against independent computations."""

import math

import numpy as np
import pytest

from wavecontact import Rod
from wavecontact.analytic import (
    asymptotic_velocity_increase,
    boltzmann_density,
    equilibrium_spectral_entropy,
    equilibrium_translational_energy,
    force_plateau,
    hard_core_contact_duration,
    hard_core_modal_energies,
    hard_core_relative_velocity,
    hard_core_restitution,
    noise_covariance,
    two_material_impact,
)
from wavecontact.delay.solver import solve_delay_equation


def test_hard_core_restitution_is_the_length_ratio():
    assert hard_core_restitution(0.6) == 0.6
    assert hard_core_restitution(1 / 0.6) == pytest.approx(0.6)


@pytest.mark.parametrize("gamma", [0.3, 0.6, 0.9])
def test_modal_energies_add_up_to_the_lost_energy(gamma):
    energies = hard_core_modal_energies(gamma, 200_000)
    assert np.all(energies[0] == 0.0)  # the short rod leaves without vibration
    assert energies[1].sum() == pytest.approx(1 - gamma**2, abs=2e-5)


def test_velocity_history_is_piecewise_linear():
    tau = np.array([-1.0, 0.0, 0.8, 1.6, 3.0])
    assert hard_core_relative_velocity(tau, 0.6) == pytest.approx([-1, -1, -0.2, 0.6, 0.6])


def test_asymptotic_w_matches_the_delay_solution_at_large_kappa():
    kappa = 100.0
    t, w, _, _, _, a0 = solve_delay_equation(0.6, kappa, rtol=1e-12)
    approx = asymptotic_velocity_increase(t, 0.6, kappa, tau_free=a0 / kappa)
    assert np.max(np.abs(approx - w)) / kappa < 1e-9


def test_asymptotic_w_does_not_overflow():
    w = asymptotic_velocity_increase(np.linspace(0, 20, 50), 0.6, 1e6, tau_free=1.0)
    assert np.all(np.isfinite(w))
    assert w[-1] / 1e6 == pytest.approx(1.6, abs=1e-4)


def test_noise_covariance_equals_its_mode_sum():
    """Eq. 19 against the covariance of the Fourier series Eq. 17 with the
    thermal variances Eq. 18: 2 kappa^2 T_B sum_i sum_nu Gamma_i/(2 pi^2 nu^2) cos(2 pi nu tau/Gamma_i)."""
    gamma, kappa, temperature = 0.6173, 7.0, 0.3
    g1, g2 = 1 + gamma, 1 + 1 / gamma
    tau = np.linspace(-3.0, 9.0, 61)
    nu = np.arange(1, 200_001)[:, None]
    series = sum(
        (gi / (2 * math.pi**2 * nu**2) * np.cos(2 * math.pi * nu * tau / gi)).sum(0) for gi in (g1, g2)
    )
    expected = 2 * kappa**2 * temperature * series
    assert noise_covariance(tau, gamma, kappa, temperature) == pytest.approx(expected, abs=1e-4 * expected.max())


def test_equilibrium_formulas():
    assert equilibrium_translational_energy(75) == pytest.approx(0.5 / (2 * 151))
    assert equilibrium_spectral_entropy(75) == pytest.approx(0.423 / math.log(150))
    energies = np.linspace(0, 50, 200_001)
    density = boltzmann_density(energies, 2.0)
    assert np.trapezoid(density, energies) == pytest.approx(1.0, abs=1e-6)
    assert np.trapezoid(energies * density, energies) == pytest.approx(2.0, abs=1e-4)


def test_wave_theory_of_equal_rods():
    short, long_ = Rod(0.8), Rod(0.8 / 0.6)
    impact = two_material_impact(short, long_, 1.0)
    assert impact["force"] == pytest.approx(force_plateau(short.impedance, 1.0))
    assert impact["duration"] == pytest.approx(hard_core_contact_duration(0.8))
    assert impact["restitution"] == pytest.approx(0.6)


def test_two_materials_force_steps_down_when_the_short_rod_is_stiffer():
    stiff_short = Rod(0.5, youngs_modulus=9.0)  # Z = 3, round trip 1/3
    soft_long = Rod(2.0)  # Z = 1, round trip 4
    impact = two_material_impact(stiff_short, soft_long, 1.0)
    assert impact["reflection"] == pytest.approx(0.5)
    assert impact["duration"] == pytest.approx(4.0)
    # twelve steps of length 1/3: 3/4, 3/8, ...; the impulse is their sum
    forces = [force for _, _, force in impact["steps"]]
    assert len(forces) == 12 and forces == pytest.approx([0.75 * 0.5**k for k in range(12)])
    assert impact["impulse"] == pytest.approx(sum(f / 3.0 for f in forces))
    masses = stiff_short.mass, soft_long.mass
    assert impact["restitution"] == pytest.approx(impact["impulse"] * (1 / masses[0] + 1 / masses[1]) - 1.0)