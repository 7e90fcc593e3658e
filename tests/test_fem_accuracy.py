"""The finite-element solver against independent references: the delay equation,
the hard-core limit epsilon = gamma, Saint-Venant's wave theory and the
two-material wave-theory result of docs/fem.md."""

import math

import numpy as np
import pytest

import wavecontact as wc
from wavecontact import Exponential, Hard, Rod, Scene
from wavecontact.fem.solver import EXPECTED_ORDER


def delay_reference(gamma, kappa):
    return wc.collide(gamma, kappa, solver="delay").restitution


@pytest.mark.parametrize("gamma, kappa", [(0.6, 20), (0.6, 100), (0.6173, 1000)])
def test_agrees_with_delay_equation_where_contact_is_resolved(gamma, kappa):
    result = wc.collide(gamma, kappa, solver="fem", elements=800)
    assert abs(result.restitution - delay_reference(gamma, kappa)) < 1e-6


def test_model_reference_values_at_800_elements():
    # MODEL.md section 5, computed independently of this project
    assert abs(wc.collide(0.6, 100, solver="fem", elements=800).restitution - 0.646697087) < 1e-6
    assert abs(wc.collide(0.6, 20, solver="fem", elements=800).restitution - 0.75301321) < 1e-6


@pytest.mark.parametrize("gamma", [0.95, 0.99, 1.0])
def test_gamma_near_one_where_the_contact_is_resolved(gamma):
    # both reflected waves return almost together and the release is as sharp as the onset:
    # the step means of the incoming rate alone (linear reconstruction) gave 3e-6 at gamma = 1
    for kappa in (100, 1000):
        result = wc.collide(gamma, kappa, solver="fem", elements=800)
        assert abs(result.restitution - delay_reference(gamma, kappa)) < 1e-6


@pytest.mark.parametrize("kappa", [1e4, 1e5])
def test_stiff_exponential_contact_within_1e4(kappa):
    result = wc.collide(0.6, kappa, solver="fem", elements=800)
    assert abs(result.restitution - delay_reference(0.6, kappa)) < 1e-4


def test_kappa_1e6_matches_asymptotic_formula():
    # Eq. 23, accurate far below 1e-6 at this kappa (MODEL.md section 5)
    gamma, kappa = 0.6, 1e6
    asymptotic = gamma + math.log(kappa * (1 / gamma - gamma)) / kappa
    result = wc.collide(gamma, kappa, solver="fem", elements=3200)
    assert abs(result.restitution - asymptotic) < 1e-4


@pytest.mark.parametrize("gamma", [1.0, 0.97, 0.77, 0.6173, 0.6, 0.5, 0.3, 0.12])
def test_hard_limit_is_exact_for_any_gamma(gamma):
    # the exact lattice reproduces the wave solution; epsilon = gamma to round-off
    for elements in (200, 800):
        result = wc.collide(gamma, math.inf, solver="fem", elements=elements)
        assert abs(result.restitution - gamma) < 1e-11


@pytest.mark.parametrize("gamma", [0.6173, 0.97, 0.3])
def test_very_stiff_exponential_contact_any_gamma(gamma):
    for kappa in (1e5, 1e6):
        result = wc.collide(gamma, kappa, solver="fem", elements=800)
        assert abs(result.restitution - delay_reference(gamma, kappa)) < 1e-6


@pytest.mark.parametrize("gamma", [0.1, 0.6, 1.0])
@pytest.mark.parametrize("kappa", [0.1, 100, 1e6, math.inf])
def test_corners_of_the_hard_cases_on_the_coarsest_mesh(gamma, kappa):
    # 10 elements on the short rod (the coarsest mesh the solver accepts): no watchdog false alarm
    # (the lattice's staggered energy misses the end nodes' inertia during contact and one cell per
    # sharp front, up to ~5 % here even where epsilon is exact), and an answer within 2e-2 of the
    # reference (measured worst: 9.9e-3 at gamma = 1, kappa = 100)
    result = wc.collide(gamma, kappa, solver="fem", elements=10)
    reference = delay_reference(gamma, kappa) if math.isfinite(kappa) else gamma
    assert abs(result.restitution - reference) < 2e-2


@pytest.mark.parametrize("gamma", [0.1, 1.0])
def test_corners_of_the_hard_cases_on_ten_thousand_elements(gamma):
    for kappa in (100, 1e6, math.inf):
        result = wc.collide(gamma, kappa, solver="fem", elements=10_000)
        reference = delay_reference(gamma, kappa) if math.isfinite(kappa) else gamma
        assert abs(result.restitution - reference) < 1e-6, kappa


def test_equal_rods_at_unresolved_stiffness_converge_past_the_crossover():
    # gamma = 1 gives epsilon = 1 for every kappa (MODEL.md section 4). With alpha V dt > 10 the
    # release is a fraction of a step: a mesh-independent error of about 0.7/kappa (docs/fem.md 7),
    # inside 1e-4; once alpha V h/c drops below about 4 the scheme converges again.
    kappa = 1e5
    plateau = [abs(wc.collide(1.0, kappa, solver="fem", elements=n).restitution - 1.0) for n in (800, 3200)]
    assert max(plateau) < 1e-5
    resolved = [abs(wc.collide(1.0, kappa, solver="fem", elements=n).restitution - 1.0) for n in (25600, 51200)]
    assert resolved[0] < plateau[1] / 4
    assert resolved[1] < resolved[0] / 4


def test_wave_theory_plateau_and_duration():
    gamma = 0.6
    result = wc.collide(gamma, math.inf, solver="fem", elements=800)
    l1 = (1 + gamma) / 2
    assert result.contact_duration == pytest.approx(2 * l1, rel=0.01)  # 2 l1 / c
    inside = (result.time > result.contact_start + 0.1) & (result.time < result.contact_start + 2 * l1 - 0.1)
    # Z V / 2 with Z = rho c A = 1 and V = 1
    assert np.median(result.contact_force[inside]) == pytest.approx(0.5, rel=0.01)
    assert np.all(np.abs(result.contact_force[inside] - 0.5) < 0.005)


def test_two_materials_against_wave_theory():
    # rod 1: Z1 = 1, round trip 2; rod 2: Z2 = 2, c2 = 1/2, round trip 4 (docs/fem.md):
    # epsilon = (Z2 - Z1 + 2 Z2 m1 / m2) / (Z1 + Z2)
    rod1, rod2 = Rod(1.0, density=1.0), Rod(1.0, density=4.0)
    z1, z2, m1, m2 = rod1.impedance, rod2.impedance, rod1.mass, rod2.mass
    expected = (z2 - z1 + 2 * z2 * m1 / m2) / (z1 + z2)
    scene = Scene(rods=(rod1, rod2), velocities=(1.0, 0.0), contact=Hard())
    result = wc.solve(scene, "fem", elements=200)
    assert result.restitution == pytest.approx(expected, abs=1e-12)
    assert result.contact_duration == pytest.approx(rod1.round_trip_time, rel=0.01)
    stiff = Scene(rods=(rod1, rod2), velocities=(1.0, 0.0), contact=Exponential(1e5, 1e-12))
    # finite stiffness shifts epsilon by O(ln(alpha) / alpha), as Eq. 23 does for one material
    assert wc.solve(stiff, "fem", elements=400).restitution == pytest.approx(expected, abs=5e-4)


def _observed_order(elements, errors):
    slope = np.polyfit(np.log(elements), np.log(errors), 1)[0]
    return -slope


def _uniform(length, elements):
    return np.linspace(0.0, length, elements + 1)


# gamma = 0.6: the long rod is a whole number of elements (l2 / h = N / 0.6), no far-end remainder
ORDER_MESHES = np.array([24, 48, 96, 192])


@pytest.mark.parametrize(
    "order, mass, options",
    [
        (1, "consistent", {}),
        (2, "lumped", {}),
        (2, "consistent", {}),
        (1, "lumped", {"courant": 0.9}),  # off the exact lattice
        (1, "lumped", {"unequal": True}),  # user meshes, element sizes 3:4 across the contact
    ],
)
def test_observed_order_where_the_contact_is_resolved(order, mass, options):
    gamma, kappa = 0.6, 20.0  # alpha V h / c <= 0.67 on these meshes: 'auto' picks the force scheme
    reference = delay_reference(gamma, kappa)
    l1, l2 = (1 + gamma) / 2, (1 + gamma) / (2 * gamma)
    errors = []
    for n in ORDER_MESHES:
        kwargs = dict(options)
        if kwargs.pop("unequal", False):
            kwargs["nodes"] = (_uniform(l1, int(n)), _uniform(l2, int(n) * 5 // 4))
        result = wc.collide(gamma, kappa, solver="fem", elements=int(n), order=order, mass=mass, **kwargs)
        assert "force at the end nodes" in result.extra["scheme"]
        errors.append(abs(result.restitution - reference))
    observed = _observed_order(ORDER_MESHES, errors)
    assert abs(observed - EXPECTED_ORDER[(order, mass)]) < 0.3, (observed, errors)


def test_massless_end_interface_is_first_order():
    # the fallback for unresolved contact, forced here on a resolved one to expose its O(h) error
    reference = delay_reference(0.6, 20)
    errors = [
        abs(wc.collide(0.6, 20, solver="fem", elements=int(n), order=2, scheme="interface").restitution - reference)
        for n in ORDER_MESHES
    ]
    assert abs(_observed_order(ORDER_MESHES, errors) - 1.0) < 0.2, errors


@pytest.mark.parametrize("options", [{"order": 2}, {"mass": "consistent"}, {"courant": 0.9}])
def test_dispersive_discretizations_converge_like_h_to_two_thirds_in_the_hard_limit(options):
    # a second-order scheme spreads a step front over (c t h^2)^(1/3) (docs/fem.md section 3): the
    # release, timed by that front, converges like h^(2/3) whatever the contact treatment
    elements = np.array([100, 200, 400, 800])
    errors = [abs(wc.collide(0.6, math.inf, solver="fem", elements=int(n), **options).restitution - 0.6)
              for n in elements]
    assert abs(_observed_order(elements, errors) - 2 / 3) < 0.1, errors


def test_auto_scheme_falls_back_to_the_interface_for_unresolved_contact():
    for kappa, expected in ((100, "force at the end nodes"), (1e4, "massless-end interface"),
                            (math.inf, "massless-end interface")):
        result = wc.collide(0.6, kappa, solver="fem", elements=200, order=2)
        assert expected in result.extra["scheme"]


def test_observed_order_of_the_characteristic_scheme():
    # errors of one sign here; the long rod's far-end remainder (a delayed echo, third-order
    # interpolation) and the rest of the scheme are at least second order. N = 800 is left out: the
    # sub-step quadrature's floor (~6e-10, docs/fem.md 7) is reached there.
    reference = wc.collide(0.6173, 100, solver="delay", rtol=1e-13).restitution
    elements = np.array([50, 100, 200, 400])
    errors = [abs(wc.collide(0.6173, 100, solver="fem", elements=int(n)).restitution - reference) for n in elements]
    observed = _observed_order(elements, errors)
    assert EXPECTED_ORDER[(1, "lumped")] - 0.2 < observed < 3.5, (observed, errors)


def test_energy_and_momentum_conservation():
    result = wc.collide(0.6, 100, solver="fem", elements=800)
    # the contact is resolved: the leapfrog energy is kept to ~1e-5 of the relative energy
    assert result.diagnostics["energy_drift"] < 5e-5
    # round-off: velocities are displacement differences over dt, |u| / (V dt) ~ 1e3 times eps
    assert result.diagnostics["momentum_drift"] < 1e-11
    energies = result.extra["energies"]
    total = energies["kinetic"] + energies["strain"] + energies["contact"]
    assert np.ptp(total) / total[0] < 1e-3
    # hard contact of equal rods: the lattice is exact, energy to round-off
    exact = wc.collide(1.0, math.inf, solver="fem", elements=200)
    assert exact.diagnostics["energy_drift"] < 1e-11
    assert exact.diagnostics["momentum_drift"] < 1e-11


def test_energy_after_collision_goes_to_the_long_rod():
    gamma = 0.6
    result = wc.collide(gamma, math.inf, solver="fem", elements=800)
    short, long_ = result.extra["rod_energy_after"]
    translational = 0.25  # mu V^2 / 2
    assert short < 1e-10
    # (1 - gamma^2) E_tr up to the O(h) energy of the merged end nodes at impact
    assert long_ == pytest.approx((1 - gamma**2) * translational, rel=2e-3)


def test_kappa_1e6_costs_about_the_same_as_kappa_100():
    cheap = wc.collide(0.6, 100, solver="fem", elements=800).work["element_steps"]
    stiff = wc.collide(0.6, 1e6, solver="fem", elements=800).work["element_steps"]
    assert stiff <= 3 * cheap


def test_result_histories_and_run_control():
    result = wc.collide(0.6, 100, solver="fem", elements=200)
    assert result.relative_velocity[0] == pytest.approx(-1.0, abs=1e-9)
    assert result.relative_velocity[-1] == pytest.approx(result.restitution, abs=1e-12)
    assert np.all(np.isfinite(result.contact_force))
    # started out of range: the first force is negligible
    assert result.contact_force[0] < 1e-12
    assert result.work["steps"] == result.time.size
    assert result.work["element_steps"] == result.work["steps"] * sum(result.work["elements"])


def test_contact_window_agrees_with_the_delay_solver():
    for kappa in (100, 1e4):
        fem = wc.collide(0.6, kappa, solver="fem", elements=800)
        delay = wc.collide(0.6, kappa, solver="delay")
        # same definition (force above 1% of its peak); the FE force is a mean over each step
        assert fem.contact_duration == pytest.approx(delay.contact_duration, abs=5 * fem.work["dt"])
