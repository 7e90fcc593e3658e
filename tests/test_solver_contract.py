"""The solver contract, run over every registered solver (in the style of diffrax's test_ode_order).

Each solver declares its options (validated dataclass), its resolution parameter and its expected
order; these tests hold every solver to those declarations and to one meaning of every result key.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import wavecontact
from wavecontact.contact import Exponential
from wavecontact.errors import InvalidParameterError, SolverFailure
from wavecontact.result import CollisionResult, Outcome
from wavecontact.scene import Rod, Scene, two_rods
from wavecontact.solvers import SOLVER_NAMES, get_solver
from wavecontact.solvers.base import RepeatedCollisions, Solver, option_help

# MODEL.md section 5, computed independently of this package
EPS_06_20 = 0.7530132413

# per solver: resolutions for the order fit (coarse to fine) and options held fixed
ORDER_CASES = {
    "fem": {"resolutions": (24, 48, 96, 192), "options": {"order": 1, "mass": "consistent"}},
    # the static correction: the end-response default has no order in N (exact for cold rods; expected_order None)
    "modal": {"resolutions": (10, 20, 40), "options": {"correction": "static"}},
    "delay": {"resolutions": (1e-4, 1e-6, 1e-8), "options": {}},
}
# resolution at which each solver must agree with the MODEL.md value, and how closely
AGREEMENT = {"fem": ({"elements": 400}, 1e-5), "modal": ({"modes": 100}, 1e-6), "delay": ({}, 1e-9)}


def test_every_registered_solver_satisfies_the_protocol():
    for name in SOLVER_NAMES:
        solver = get_solver(name)
        assert isinstance(solver, Solver)
        assert solver.name == name
        fields = {f.name for f in dataclasses.fields(solver.Options)}
        assert solver.resolution in fields
        assert solver.refines in (1, -1)
        defaults = solver.Options()
        assert dataclasses.is_dataclass(defaults)
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(defaults, solver.resolution, 3)
        # every option is declared with help text and an allowed range
        rows = option_help(solver.Options)
        assert {row[0] for row in rows} == fields
        assert all(row[3] and row[2] for row in rows)


@pytest.mark.parametrize("name", SOLVER_NAMES)
def test_unknown_and_invalid_options_are_refused_by_name(name):
    solver = get_solver(name)
    with pytest.raises(InvalidParameterError, match="unknown option"):
        wavecontact.collide(0.6, 20, name, no_such_option=1)
    bad = {"fem": {"elements": 0}, "modal": {"modes": -3}, "delay": {"rtol": 2.0}}[name]
    with pytest.raises(InvalidParameterError, match=next(iter(bad))):
        solver.Options(**bad)
    with pytest.raises(InvalidParameterError, match=solver.resolution):
        solver.Options(**{solver.resolution: "many"})


@pytest.mark.parametrize("name", SOLVER_NAMES)
def test_results_mean_the_same_for_every_solver(name):
    options, tolerance = AGREEMENT[name]
    result = wavecontact.collide(0.6, 20, name, **options)
    assert isinstance(result, CollisionResult)
    assert result.outcome is Outcome.SEPARATED
    assert abs(result.restitution - EPS_06_20) < tolerance
    # gamma and kappa recovered one way, for a built and a hand-made scene of the same collision
    assert (result.gamma, result.kappa) == (0.6, 20.0)
    built = two_rods(0.6, 20)
    hand_made = Scene(rods=built.rods, velocities=built.velocities, contact=Exponential(20.0, 0.5 / 400))
    other = wavecontact.solve(hand_made, name, **options)
    assert other.gamma == pytest.approx(0.6) and other.kappa == pytest.approx(20.0)
    # the same keys with the same meaning
    assert set(result.diagnostics) == {"energy_drift", "momentum_drift", "includes_kernel_preparation",
                                       "error_estimate_method", "error_estimate_seconds",
                                       "error_estimate_levels", "error_estimate_rough"}
    for key in ("energy_drift", "momentum_drift"):
        value = result.diagnostics[key]
        assert math.isnan(value) or 0.0 <= value < 1e-2  # relative drifts
    assert result.work["steps"] > 0
    assert result.options[get_solver(name).resolution] == get_solver(name).options(options).as_dict()[
        get_solver(name).resolution]
    # one contact-window rule: every solver's duration is the reference's (the start depends on the
    # initial gap each solver chooses, the duration does not)
    reference = wavecontact.collide(0.6, 20, "delay", rtol=1e-12)
    assert result.contact_duration == pytest.approx(reference.contact_duration, rel=1e-2)
    assert result.time[0] <= result.contact_start <= result.time[-1]
    # short repr
    text = repr(result)
    assert len(text) < 200 and name in text and "restitution" in text


@pytest.mark.parametrize("name", SOLVER_NAMES)
def test_results_round_trip_through_npz(tmp_path, name):
    options = {"fem": {"elements": 50}, "modal": {"modes": 20}, "delay": {}}[name]
    result = wavecontact.collide(0.6, 20, name, **options)
    path = tmp_path / f"{name}.npz"
    result.save_npz(path)
    back = CollisionResult.load_npz(path)
    for f in dataclasses.fields(CollisionResult):
        a, b = getattr(result, f.name), getattr(back, f.name)
        _assert_same(a, b, f.name)


def _assert_same(a, b, where):
    if isinstance(a, dict):
        assert set(a) == set(b), where
        for key in a:
            _assert_same(a[key], b[key], f"{where}.{key}")
    elif isinstance(a, (list, tuple)) and not isinstance(b, np.ndarray):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            _assert_same(x, y, f"{where}[{i}]")
    elif isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b), err_msg=where)
    elif isinstance(a, float) and math.isnan(a):
        assert math.isnan(b), where
    elif where.startswith("options") and not isinstance(a, (int, float, str, bool, type(None))):
        assert isinstance(b, str), where  # objects are kept as their repr
    else:
        assert a == b, where


@pytest.mark.parametrize("name", SOLVER_NAMES)
def test_observed_order_matches_the_declared_order(name):
    """Fit log(error) against log(resolution) and compare with ``expected_order``."""
    solver = get_solver(name)
    case = ORDER_CASES[name]
    reference = wavecontact.collide(0.6, 20, "delay", rtol=1e-13).restitution
    errors = []
    for value in case["resolutions"]:
        options = {**case["options"], solver.resolution: value}
        errors.append(abs(wavecontact.collide(0.6, 20, name, **options).restitution - reference))
    expected = solver.expected_order(solver.options(case["options"]))
    errors = np.array(errors)
    if name == "delay":
        # a tolerance, not a mesh: the error must stay below it (order 1 in rtol at worst)
        assert np.all(errors <= np.array(case["resolutions"]))
        return
    resolution = np.array(case["resolutions"], dtype=float)
    slope = -np.polyfit(np.log(resolution), np.log(errors), 1)[0]
    assert slope == pytest.approx(expected, abs=0.35), (errors, slope)


def test_only_the_modal_solver_runs_a_ring():
    from wavecontact.scene import two_rods_on_a_ring

    scene = two_rods_on_a_ring(0.6, 100)
    simulation = get_solver("modal").simulate(scene, {"modes": 8})
    assert isinstance(simulation, RepeatedCollisions)
    record = simulation.next_collision()
    assert record.index == 0 and record.pair == 0
    with pytest.raises(ValueError):
        record.modal_energies[0, 0] = 1.0  # records are frozen, their arrays read-only
    for name in ("delay", "fem"):
        with pytest.raises(wavecontact.UnsupportedSceneError, match="modal"):
            get_solver(name).simulate(scene, None)


def test_failures_carry_an_outcome():
    with pytest.raises(SolverFailure) as info:
        wavecontact.collide(0.6, 100, "delay", max_steps=10)
    assert info.value.outcome is Outcome.STEP_LIMIT
    assert Outcome.STEP_LIMIT.message


def test_a_scene_of_other_rods_reports_nan_gamma():
    scene = Scene(rods=(Rod(1.0, youngs_modulus=2.0), Rod(2.0)), velocities=(1.0, -1.0),
                  contact=wavecontact.Hard())
    result = wavecontact.solve(scene, "fem", elements=20)
    assert math.isnan(result.gamma) and math.isnan(result.kappa)
    assert math.isnan(result.error_estimate) or result.error_estimate >= 0.0


@pytest.mark.parametrize("name", SOLVER_NAMES)
def test_validated_options_are_reused_but_never_for_a_value_of_another_type(name):
    solver = get_solver(name)
    first = solver.options({"rtol": 1e-5} if name == "delay" else {})
    assert solver.options({"rtol": 1e-5} if name == "delay" else {}) is first  # frozen: one object serves
    # True is cached now; 1 == True and hashes alike, yet a bool option must still refuse it
    flag = next(row[0] for row in option_help(solver.Options) if row[2].startswith("True or False"))
    solver.options({flag: True})
    with pytest.raises(InvalidParameterError, match=flag):
        solver.options({flag: 1})
