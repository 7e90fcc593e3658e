"""One thermal collision: the same realisation through all three solvers (Sec. VI)."""

import math

import numpy as np
import pytest

import wavecontact
from wavecontact import two_rods
from wavecontact.api import solve
from wavecontact.bath import ThermalBath

WARM = {"bath_temperature": 0.5, "bath_modes": 10, "seed": 3}


@pytest.fixture(scope="module")
def delay_reference():
    return wavecontact.collide(0.6, 20.0, "delay", **WARM)


def test_delay_energy_split_adds_up_to_the_translational_loss(delay_reference):
    gain = delay_reference.extra["vibration_energy_gain"]
    eps = delay_reference.restitution
    assert gain.sum() == pytest.approx((1.0 - eps**2) / 4.0, abs=1e-9)


def test_cold_split_gives_the_long_rod_almost_everything():
    # hard-core limit: the short rod leaves without vibrations (Eq. 25); at kappa = 1000 nearly so
    result = wavecontact.collide(0.6, 1000.0, "delay")
    gain = result.extra["vibration_energy_gain"]
    assert abs(gain[0]) < 0.01 * gain[1]
    assert gain.sum() == pytest.approx((1 - result.restitution**2) / 4, abs=1e-8)


def test_the_result_of_a_thermal_scene_is_complete_when_the_solver_returns():
    """solve() of a thermal scene carries the per-rod split and the bath's parameters, the same as
    collide() returns: nothing is added to the result after the solver returns."""
    from wavecontact.bath.collide import thermal_scene

    scene = thermal_scene(0.6, 20.0, ThermalBath(WARM["bath_temperature"], WARM["bath_modes"]), WARM["seed"])
    for solver, options in (("delay", {}), ("modal", {"modes": 40})):
        result = solve(scene, solver, **options)
        assert result.extra["bath"] == {"temperature": [0.5, 0.5], "modes": 10, "seed": 3}
        through_collide = wavecontact.collide(0.6, 20.0, solver, **options, **WARM)
        assert result.restitution == through_collide.restitution
        assert result.extra["vibration_energy_gain"].shape == (2,)
        assert np.array_equal(result.extra["vibration_energy_gain"], through_collide.extra["vibration_energy_gain"])
    cold = solve(two_rods(0.6, 20.0), "modal", modes=40)
    assert "bath" not in cold.extra and "vibration_energy_gain" not in cold.extra


def test_modal_solver_agrees_on_the_same_realisation(delay_reference):
    modal = wavecontact.collide(0.6, 20.0, "modal", modes=100, **WARM)
    assert modal.restitution == pytest.approx(delay_reference.restitution, abs=5e-5)
    # per-rod split of the delay solver against the modal energies
    assert np.allclose(modal.extra["vibration_energy_gain"], delay_reference.extra["vibration_energy_gain"], atol=5e-4)


def test_fem_converges_to_the_delay_result_on_the_same_realisation(delay_reference):
    elements = np.array([200, 400, 800])
    runs = [wavecontact.collide(0.6, 20.0, "fem", elements=int(n), **WARM) for n in elements]
    errors = np.array([abs(r.restitution - delay_reference.restitution) for r in runs])
    assert errors[-1] < 1e-5
    assert np.polyfit(np.log(elements), np.log(errors), 1)[0] < -1.5  # second order (observed ~2)
    split_errors = [np.max(np.abs(r.extra["vibration_energy_gain"] - delay_reference.extra["vibration_energy_gain"]))
                    for r in runs]
    assert split_errors[-1] < 1e-3
    assert np.polyfit(np.log(elements), np.log(split_errors), 1)[0] < -1.5


def test_result_does_not_depend_on_the_start_gap_or_the_end_time():
    gamma, kappa = 0.6, 50.0
    v = ThermalBath(1.0, 20).draw((0.8, 0.8 / 0.6), 9)
    chosen = two_rods(gamma, kappa, vibrations=v)
    farther = two_rods(gamma, kappa, vibrations=v, gap=chosen.gaps[0] + 0.75)
    a = solve(chosen, "delay")
    b = solve(farther, "delay")
    c = solve(chosen, "delay", end_time=a.time[-1] + 30.0)
    assert b.restitution == pytest.approx(a.restitution, abs=1e-9)
    assert c.restitution == pytest.approx(a.restitution, abs=1e-9)
    # and not on the realisation's bookkeeping: the hard-core grid moved by the same amount
    hard_a = solve(two_rods(gamma, math.inf, contact="hard", vibrations=v), "delay")
    hard_b = solve(two_rods(gamma, math.inf, contact="hard", vibrations=v, gap=1.25 + chosen.gaps[0]), "delay")
    assert hard_b.restitution == pytest.approx(hard_a.restitution, abs=3 * max(hard_a.error_estimate, 1e-6))


def test_a_cold_bath_is_the_cold_collision():
    warm = wavecontact.collide(0.6, 100.0, "delay", bath_temperature=0.0, bath_modes=5, seed=1)
    assert warm.restitution == pytest.approx(0.646697087, abs=2e-9)  # MODEL.md section 5


def test_one_cold_rod_takes_no_noise():
    v = ThermalBath((0.0, 1.0), 10).draw((0.8, 0.8 / 0.6), 4)
    (_o1, a1, b1), (_o2, a2, _b2) = v.noise_coefficients(10.0)
    assert not np.any(a1) and not np.any(b1) and np.any(a2)


def test_collide_refuses_bad_bath_input_in_one_line():
    for kwargs, message in (({"bath_temperature": -1.0}, "temperature"), ({"bath_temperature": 1.0, "bath_modes": 0},
                                                                             "nu_max"),
                            ({"bath_temperature": 1.0, "seed": -3}, "seed")):
        with pytest.raises(wavecontact.InvalidParameterError, match=message) as info:
            wavecontact.collide(0.6, 10.0, **kwargs)
        assert "\n" not in str(info.value)


# Bath scenes of the cross-solver audit (benchmarks/cross_solver_audit.py --scenes 200 --seed 2324 --part 4/4)
# whose FE estimate at 400 elements was below the FE result's distance to the delay solver (by up to 4.6x):
# (gamma, kappa, T_B / E_tr, bath modes, seed)
FE_BATH_MISSES = [
    (0.9800509256374312, 36.49297957064959, 0.4663542330840856, 10, 375882875),
    (0.7260602672535181, 394.05630926721625, 2.042670456649323, 40, 1803073150),
    (0.31426035808541136, 18.873727736992375, 0.1896422786167757, 14, 918216416),
    (0.6672875103755098, 435.3487047699468, 1.720212351976372, 29, 1942364984),
    (0.636728074576907, 12.826022832899465, 0.2639744282356104, 31, 1858211656),
    (0.3599681758300711, 10.868118252030841, 2.806312889838347, 23, 2145039511),
    (0.6261967461372762, 27.31920977248454, 0.16861748326361434, 39, 920756033),
    (0.9796829284031208, 57.43451599626175, 0.6363796360193562, 35, 1781140363),
    (0.6635862796585159, 220.5727101485897, 0.6580976261698293, 37, 71064479),
]


@pytest.mark.parametrize("gamma, kappa, temperature, modes, seed", FE_BATH_MISSES)
def test_fem_estimate_with_a_bath_bounds_its_distance_to_the_delay_solver(gamma, kappa, temperature, modes, seed):
    from wavecontact.bath.collide import thermal_scene

    scene = thermal_scene(gamma, kappa, ThermalBath(temperature, modes), seed)
    reference = solve(scene, "delay", rtol=1e-12, energy_split=False)
    fem = solve(scene, "fem", elements=400)
    assert abs(fem.restitution - reference.restitution) <= fem.error_estimate + reference.error_estimate
    assert "elements=800" in fem.diagnostics["error_estimate_method"]  # the run at 2N (docs/error_estimates.md)


def test_fem_with_a_bath_has_an_estimate_where_its_coarser_run_fails():
    # 200 elements: the run at 100 fails the energy check (the bath's 37 modes, about 5 elements a wavelength),
    # which left no estimate; the run at 400 gives one, and it bounds the distance to the delay solver
    from wavecontact.bath.collide import thermal_scene

    scene = thermal_scene(*FE_BATH_MISSES[-1][:2], ThermalBath(*FE_BATH_MISSES[-1][2:4]), FE_BATH_MISSES[-1][4])
    with pytest.raises(wavecontact.errors.SolverFailure, match="energy"):
        solve(scene, "fem", elements=100, estimate_error=False)
    fem = solve(scene, "fem", elements=200)
    reference = solve(scene, "delay", rtol=1e-12, energy_split=False)
    assert abs(fem.restitution - reference.restitution) <= fem.error_estimate + reference.error_estimate


def test_thermal_runs_carry_a_crossing_coarser_difference_down():
    # a cold sequence whose coarser difference is of the other sign and 40 times larger is read as a fast
    # convergence that crossed the limit; with a bath (seed 2325 scene 35 of the audit: errors 2.45e-5,
    # 2.19e-5, 1.26e-4 on 800, 400, 200 elements) it is carried down, as for any runs that do not converge
    # monotonically
    from wavecontact.fem.error_estimate import estimate_from_levels

    exact = 0.5
    levels = [(800, exact + 2.45e-5), (400, exact + 2.19e-5), (200, exact + 1.26e-4)]
    cold = estimate_from_levels(levels, 2.0, 2.0, True, 2.0)[0]
    warm = estimate_from_levels(levels, 2.0, 2.0, True, 2.0, thermal=True)[0]
    assert cold < 2.45e-5 <= warm


def test_thermal_estimate_with_a_finer_run_keeps_the_coarser_runs_reading():
    # the cross-solver audit's seed 2323 scene 15 (FE errors 5.33e-5, 2.20e-6, 9.05e-7, 1.30e-6 on 100, 200,
    # 400 and 800 elements, alpha V h / c = 2.3 with the ends' thermal speed): the run at 800 agrees with 400
    # by accident and |eps(400) - eps(800)| + E(800) is 0.99 of the error; the coarser runs' own estimate,
    # which carries the large difference of 100 and 200 elements down, bounds it
    from wavecontact.fem.error_estimate import estimate_with_finer

    exact = 0.68
    finer = (800, exact + 1.30e-6)
    levels = [(400, exact + 9.05e-7), (200, exact + 2.20e-6), (100, exact + 5.33e-5)]
    cold = estimate_with_finer(finer, levels, 2.3, 2.0, True, 2.0)[0]
    warm = estimate_with_finer(finer, levels, 2.3, 2.0, True, 2.0, thermal=True)[0]
    assert cold < 9.05e-7 <= warm
