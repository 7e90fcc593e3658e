"""Rods of different materials and sections: delay, FE and modal solvers against
each other and against the wave theory of impact (docs/theory.md, "Two materials")."""

import math

import numpy as np
import pytest
from delay_reference import radau_method_of_steps

import wavecontact
from wavecontact.analytic import two_material_impact
from wavecontact.delay.noise import FourierNoise
from wavecontact.delay.parameters import delay_parameters

# (Z2/Z1, T1/T2, c2, A2): the short-transit rod softer (i) or stiffer (ii), either rod first
CASES = {
    "soft-short": (2.5, 0.6, 1.0, 1.0),
    "stiff-short": (0.4, 0.6, 2.0, 2.0),
    "stiff-short-4-steps": (0.2, 0.25, 0.5, 1.0),
    "stiff-short-right": (3.0, 2.5, 1.5, 0.5),
}


def _scene(impedance_ratio, time_ratio, wave_speed, area, contact, velocities=(1.0, 0.0)):
    """Rod 1: rho = E = A = 1, l = 1 (Z = 1, T = 2); rod 2 with the given ratios, speed and section.
    Element travel times match when 'elements' is a multiple of the ratio's denominator."""
    density = impedance_ratio / (wave_speed * area)
    rod_2 = wavecontact.Rod(wave_speed / time_ratio, density=density, youngs_modulus=density * wave_speed**2,
                            area=area)
    return wavecontact.Scene(rods=(wavecontact.Rod(1.0), rod_2), velocities=velocities, contact=contact)


def _kappa_scene(case, kappa):
    hard = _scene(*CASES[case], wavecontact.Hard())
    return _scene(*CASES[case], wavecontact.Exponential(kappa / delay_parameters(hard).time_unit))


@pytest.mark.parametrize("case", sorted(CASES))
def test_hard_impact_follows_the_wave_theory(case):
    scene = _scene(*CASES[case], wavecontact.Hard())
    theory = two_material_impact(*scene.rods, 1.0)
    delay = wavecontact.solve(scene, "delay")
    fem = wavecontact.solve(scene, "fem", elements=60)
    assert delay.restitution == pytest.approx(theory["restitution"], abs=1e-12)
    assert fem.restitution == pytest.approx(theory["restitution"], abs=1e-12)
    assert delay.contact_duration == pytest.approx(theory["duration"], abs=1e-12)
    # FE: force above 1% of its peak, sampled per step (one step h/c = 1/60 of rod 1's transit)
    assert abs(fem.contact_duration - theory["duration"]) <= 1.0 / 60 + 1e-9
    assert np.max(delay.contact_force) == pytest.approx(theory["force"], rel=1e-12)  # Z1 Z2 V / (Z1 + Z2)
    assert len(delay.extra["contacts"]) == 1
    # energy: what the translation lost is in the rods' vibrations, split as the wave theory says;
    # the FE lattice loses O(h) of it when the end nodes merge at impact (docs/fem.md, section 6),
    # so compare the extrapolation from h and 2h
    coarse = wavecontact.solve(scene, "fem", elements=30).extra["rod_energy_after"]
    for fine_energy, coarse_energy, exact in zip(fem.extra["rod_energy_after"], coarse, theory["vibration_energy"]):
        assert 2.0 * fine_energy - coarse_energy == pytest.approx(exact, rel=2e-3, abs=1e-12)


def test_hard_force_steps_down_at_each_echo():
    scene = _scene(*CASES["stiff-short-4-steps"], wavecontact.Hard())
    theory = two_material_impact(*scene.rods, 1.0)
    delay = wavecontact.solve(scene, "delay")
    fem = wavecontact.solve(scene, "fem", elements=60)
    for start, end, force in theory["steps"]:  # four steps of 2, ratio 2/3
        middle = 0.5 * (start + end)
        # the hard-core force is stepwise: contact_force[i] holds on (time[i - 1], time[i]]
        piece = np.searchsorted(delay.time - delay.contact_start, middle)
        assert delay.contact_force[piece] == pytest.approx(force, rel=1e-12)
        near = np.abs(fem.time - fem.contact_start - middle) < 0.25 * (end - start)
        assert np.allclose(fem.contact_force[near], force, rtol=1e-9)


@pytest.mark.parametrize("case", ["soft-short", "stiff-short"])
def test_modal_hard_impact_converges_to_the_wave_theory(case):
    scene = _scene(*CASES[case], wavecontact.Hard())
    exact = two_material_impact(*scene.rods, 1.0)["restitution"]
    modes = np.array([50, 100, 200])
    # the statically corrected expansion (the end-response default is exact in N, see docs/modal.md)
    errors = [abs(wavecontact.solve(scene, "modal", modes=int(m), correction="static").restitution - exact)
              for m in modes]
    slope = np.polyfit(np.log(modes), np.log(errors), 1)[0]
    assert slope < -0.9
    assert errors[-1] < 1e-3


@pytest.mark.parametrize("case", ["soft-short", "stiff-short-right"])
def test_delay_agrees_with_an_independent_integrator(case):
    scene = _kappa_scene(case, 20.0)
    params = delay_parameters(scene)
    reference = radau_method_of_steps(params.round_trip_times, params.echo_weights, params.kappa)
    result = wavecontact.solve(scene, "delay")
    assert result.error_estimate < 1e-8
    assert abs(result.restitution - reference) < 1e-8


@pytest.mark.parametrize("case", sorted(CASES))
def test_three_solvers_agree_at_finite_stiffness(case):
    scene = _kappa_scene(case, 20.0)
    delay = wavecontact.solve(scene, "delay").restitution
    elements = np.array([60, 120, 240])
    fem_errors = np.array([wavecontact.solve(scene, "fem", elements=int(n)).restitution - delay for n in elements])
    order = -np.polyfit(np.log(elements), np.log(np.abs(fem_errors)), 1)[0]
    assert 1.8 < order < 2.2
    assert abs(fem_errors[-1]) < 1e-6
    modes = np.array([50, 100, 200])
    modal_errors = np.array([wavecontact.solve(scene, "modal", modes=int(m), correction="static").restitution - delay
                             for m in modes])
    assert -np.polyfit(np.log(modes), np.log(np.abs(modal_errors)), 1)[0] > 2.5
    assert abs(modal_errors[1]) < 1e-6


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("kappa", [2.0, 50.0, 1e4])
def test_one_force_pulse_and_no_late_contact(case, kappa):
    scene = _kappa_scene(case, kappa)
    params = delay_parameters(scene)
    base = wavecontact.solve(scene, "delay", rtol=1e-10)
    late = wavecontact.solve(scene, "delay", rtol=1e-10, end_time=40.0 / kappa + 30.0 * sum(params.round_trip_times))
    assert abs(late.restitution - base.restitution) < 1e-11
    force = late.contact_force / late.contact_force.max()
    peak = int(np.argmax(force))
    quiet = np.flatnonzero(force[peak:] < 1e-6)
    assert quiet.size and force[peak + quiet[0]:].max() < 1e-6  # once quiet, quiet for good


@pytest.mark.parametrize("kappa", [3.0, 300.0, math.inf])
def test_swapping_the_rods_changes_nothing(kappa):
    forward = _kappa_scene("stiff-short", kappa) if math.isfinite(kappa) else _scene(*CASES["stiff-short"],
                                                                                     wavecontact.Hard())
    backward = wavecontact.Scene(rods=forward.rods[::-1], velocities=(0.0, -1.0), contact=forward.contact)
    a, b = wavecontact.solve(forward, "delay"), wavecontact.solve(backward, "delay")
    assert abs(a.restitution - b.restitution) < 1e-10


def test_one_material_in_other_units_is_the_papers_collision():
    # gamma = 0.6, kappa = 100 with steel rods in SI units
    steel = {"density": 7850.0, "youngs_modulus": 210e9, "area": 3e-4}
    rods = (wavecontact.Rod(0.3, **steel), wavecontact.Rod(0.5, **steel))
    wave_speed, ell = rods[0].wave_speed, 2 * 0.3 * 0.5 / 0.8
    scene = wavecontact.Scene(rods=rods, velocities=(2.0, -0.5),
                              contact=wavecontact.Exponential(100.0 * wave_speed / (2.5 * ell)))
    result = wavecontact.solve(scene, "delay")
    assert result.restitution == pytest.approx(0.646697087, abs=5e-10)  # MODEL.md
    assert result.relative_velocity[0] == pytest.approx(-2.5)
    assert result.relative_velocity[-1] == pytest.approx(2.5 * result.restitution)


def test_a_constant_noise_only_shifts_the_start_for_two_materials():
    scene = _kappa_scene("stiff-short", 50.0)
    cold = wavecontact.solve(scene, "delay").restitution
    shifted = wavecontact.solve(scene, "delay", noise=FourierNoise([0.0], [5.0], [0.0])).restitution
    assert abs(shifted - cold) < 1e-10


@pytest.mark.parametrize("case", ["soft-short", "stiff-short-4-steps"])
@pytest.mark.parametrize("kappa", [0.3, 2.0])
def test_comb_sums_carry_the_weights(monkeypatch, case, kappa):
    """Soft contacts take old copies from per-rod comb sums, weighted afterwards;
    the result must equal the one that interpolates every weighted copy."""
    from wavecontact.delay import solver as delay

    scene = _kappa_scene(case, kappa)
    with_comb = wavecontact.solve(scene, "delay", rtol=1e-10).restitution
    monkeypatch.setattr(delay, "COMB_BELOW_KAPPA", 0.0)
    every_copy = wavecontact.solve(scene, "delay", rtol=1e-10).restitution
    assert abs(with_comb - every_copy) < 1e-11


def test_initial_vibrations_enter_as_the_noise():
    """A mode of each rod at the start, given to FE and modal as initial velocity
    fields and to the delay solver as Q(tau) (frequencies in units of Z_s / mu),
    from the same placed gap: the three agree."""
    hard = _scene(*CASES["soft-short"], wavecontact.Hard())
    params = delay_parameters(hard)
    rod_1, rod_2 = hard.rods
    alpha = 20.0 / params.time_unit
    gap = (40.0 + math.log(alpha**2 * params.reduced_mass / params.series_impedance**2)) / alpha  # a0 = 40
    amplitude_1, amplitude_2 = 0.03, 0.05  # velocity amplitudes of mode 2 of rod 1 and mode 1 of rod 2
    omega_1 = 2.0 * math.pi * rod_1.wave_speed / rod_1.length
    omega_2 = math.pi * rod_2.wave_speed / rod_2.length
    warm = wavecontact.Scene(
        rods=hard.rods, velocities=(1.0, 0.0), contact=wavecontact.Exponential(alpha), gaps=(gap,),
        initial_velocity=(lambda s: amplitude_1 * np.cos(omega_1 * s / rod_1.wave_speed),
                          lambda s: amplitude_2 * np.cos(omega_2 * s / rod_2.wave_speed)),
    )
    cold = wavecontact.Scene(rods=hard.rods, velocities=(1.0, 0.0), contact=wavecontact.Exponential(alpha),
                             gaps=(gap,))
    # the gap closes by u_1(l_1, t) - u_2(0, t): (+1) A_1 sin(w_1 t) / w_1 - A_2 sin(w_2 t) / w_2, times alpha
    noise = FourierNoise([omega_1 * params.time_unit, omega_2 * params.time_unit], [0.0, 0.0],
                         [alpha * amplitude_1 / omega_1, -alpha * amplitude_2 / omega_2])
    delay = wavecontact.solve(cold, "delay", noise=noise).restitution
    assert abs(delay - wavecontact.solve(cold, "delay").restitution) > 1e-3  # the vibration matters
    elements = np.array([60, 120, 240])
    fem_errors = [abs(wavecontact.solve(warm, "fem", elements=int(n)).restitution - delay) for n in elements]
    assert 1.8 < -np.polyfit(np.log(elements), np.log(fem_errors), 1)[0] < 2.2
    assert fem_errors[-1] < 1e-6
    assert abs(wavecontact.solve(warm, "modal", modes=200).restitution - delay) < 1e-6


@pytest.mark.parametrize("impedance_ratio", [1.0, 0.4, 0.1])
@pytest.mark.parametrize("rtol", [1e-8, 1e-11])
def test_stiff_force_plateau_meets_rtol_against_an_independent_integrator(impedance_ratio, rtol):
    """kappa = 1e6 with Z2 <= Z1: the force sits on a plateau until the long rod's echo, where
    W'' = W'(g' - W') is lost in round-off; the solver must still reach rtol, as Radau says."""
    from wavecontact.delay.parameters import echoes_from_ratios
    from wavecontact.delay.solver import solve_delay_equation

    kappa = 1e6
    delays, weights = echoes_from_ratios(impedance_ratio, 0.6)
    with np.errstate(over="ignore"):
        reference = radau_method_of_steps(delays, weights, kappa)
    _t, w, _d1, error, _work, _a0 = solve_delay_equation(0.6, kappa, rtol=rtol, impedance_ratio=impedance_ratio)
    assert error < 10.0 * rtol
    assert abs(w[-1] / kappa - 1.0 - reference) < min(rtol, error)
