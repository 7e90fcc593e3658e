"""The solver contract, run over every registered solver (in the style of diffrax's test_ode_order).

Each solver declares its options (validated dataclass), its resolution parameter, its expected
order and its test cases (``order_case``, ``agreement_case``); these tests hold every solver to
those declarations and to one meaning of every result key.  A toy solver that is not shipped
(tests/toy_solver.py) joins every test through one registry line, :data:`TOY`.
"""

from __future__ import annotations

import dataclasses
import inspect
import math

import numpy as np
import pytest

import wavecontact
from wavecontact.contact import Exponential
from wavecontact.errors import InvalidParameterError, SolverFailure, UnsupportedSceneError
from wavecontact.result import CollisionResult, Outcome
from wavecontact.scene import Rod, Scene, two_rods
from wavecontact.solvers import SOLVER_NAMES, get_solver, registered, solver_names, solvers_with
from wavecontact.solvers.base import (
    CAPABILITIES,
    RING,
    CollisionFields,
    RepeatedCollisions,
    Solver,
    SolverBase,
    option_help,
)

# MODEL.md section 5, computed independently of this package
EPS_06_20 = 0.7530132413

#: the one line that registers a new solver for the contract tests: (name, module holding SOLVER)
TOY = ("toy", "toy_solver")
NAMES = SOLVER_NAMES + (TOY[0],)


@pytest.fixture(params=NAMES)
def name(request):
    """Every shipped solver, then the toy (registered while its test runs)."""
    if request.param == TOY[0]:
        with registered(*TOY):
            yield request.param
    else:
        yield request.param


def _cheap(solver) -> dict:
    """The options of the coarsest run of a solver's order case."""
    case = solver.order_case
    return {**case["options"], solver.resolution: case["resolutions"][0]}


def test_a_solver_registered_with_one_line_joins_the_registry():
    assert TOY[0] not in solver_names()
    with registered(*TOY) as toy:
        assert solver_names() == SOLVER_NAMES + (TOY[0],)
        assert get_solver(TOY[0]) is toy and toy.name == TOY[0]
        assert wavecontact.collide(0.6, 20, TOY[0], rtol=1e-6).solver == TOY[0]
        assert all(TOY[0] not in solvers_with(c) for c in CAPABILITIES)  # it offers nothing beyond solve
        with pytest.raises(InvalidParameterError, match="already registered"), registered(*TOY):
            pass
    assert TOY[0] not in solver_names()
    with pytest.raises(InvalidParameterError, match="solver must be one of"):
        get_solver(TOY[0])


def test_solvers_offer_what_they_declare_and_nothing_else(name):
    """No side door: every public method of a solver is a method of the contract (SolverBase), and a
    solver overrides a capability's methods exactly when it declares the capability."""
    solver = get_solver(name)
    contract = {n for n in dir(SolverBase) if not n.startswith("_")}
    extra = {n for n in dir(type(solver)) if not n.startswith("_")} - contract
    assert not extra, f"{name} has public attributes outside the contract: {sorted(extra)}"
    assert set(solver.capabilities) <= set(CAPABILITIES)
    for capability in CAPABILITIES.values():
        own = [m for m in capability.methods if getattr(type(solver), m) is not getattr(SolverBase, m)]
        if capability.name in solver.capabilities:
            assert own == list(capability.methods), (name, capability.name)
            assert name in solvers_with(capability.name)
        else:
            assert own == [], (name, capability.name)
            assert name not in solvers_with(capability.name)
            with pytest.raises(UnsupportedSceneError, match=capability.name):
                method = getattr(solver, capability.methods[0])
                method(*[None] * sum(p.default is inspect.Parameter.empty
                                     for p in inspect.signature(method).parameters.values()))


def test_collide_returns_typed_fields(name):
    solver = get_solver(name)
    fields = solver._collide(two_rods(0.6, 20), solver.options(_cheap(solver)))
    assert isinstance(fields, CollisionFields)
    assert dataclasses.is_dataclass(fields)


def test_every_registered_solver_satisfies_the_protocol(name):
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


def test_unknown_and_invalid_options_are_refused_by_name(name):
    solver = get_solver(name)
    with pytest.raises(InvalidParameterError, match="unknown option"):
        wavecontact.collide(0.6, 20, name, no_such_option=1)
    spec = solver.Options.__dataclass_fields__[solver.resolution].metadata["option"]
    # a resolution outside its declared range (below for a mesh, above for a tolerance)
    bad = {solver.resolution: spec["low"] - 1 if solver.refines > 0 else 2.0 * spec["high"]}
    with pytest.raises(InvalidParameterError, match=solver.resolution):
        solver.Options(**bad)
    with pytest.raises(InvalidParameterError, match=solver.resolution):
        solver.Options(**{solver.resolution: "many"})


def test_results_mean_the_same_for_every_solver(name):
    options, tolerance = get_solver(name).agreement_case
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
                                       "interpreted_kernels", "error_estimate_method", "error_estimate_seconds",
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


def test_results_round_trip_through_npz(tmp_path, name):
    options = _cheap(get_solver(name))
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


def test_observed_order_matches_the_declared_order(name):
    """Fit log(error) against log(resolution) and compare with ``expected_order``."""
    solver = get_solver(name)
    case = solver.order_case
    reference = wavecontact.collide(0.6, 20, "delay", rtol=1e-13).restitution
    errors = []
    for value in case["resolutions"]:
        options = {**case["options"], solver.resolution: value}
        errors.append(abs(wavecontact.collide(0.6, 20, name, **options).restitution - reference))
    expected = solver.expected_order(solver.options(case["options"]))
    errors = np.array(errors)
    if solver.refines < 0:
        # a tolerance, not a mesh: the error must stay below it (order 1 in rtol at worst)
        assert np.all(errors <= np.array(case["resolutions"]))
        return
    resolution = np.array(case["resolutions"], dtype=float)
    slope = -np.polyfit(np.log(resolution), np.log(errors), 1)[0]
    assert slope == pytest.approx(expected, abs=0.35), (errors, slope)


def test_only_the_solvers_that_offer_it_run_a_ring(name):
    from wavecontact.scene import two_rods_on_a_ring

    scene = two_rods_on_a_ring(0.6, 100)
    solver = get_solver(name)
    if not solver.offers(RING):
        with pytest.raises(wavecontact.UnsupportedSceneError, match="modal"):
            solver.simulate(scene, None)
        return
    simulation = solver.simulate(scene, _cheap(solver))
    assert isinstance(simulation, RepeatedCollisions)
    record = simulation.next_collision()
    assert record.index == 0 and record.pair == 0
    with pytest.raises(ValueError):
        record.modal_energies[0, 0] = 1.0  # records are frozen, their arrays read-only


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


def test_validated_options_are_reused_but_never_for_a_value_of_another_type(name):
    solver = get_solver(name)
    first = solver.options(_cheap(solver))
    assert solver.options(_cheap(solver)) is first  # frozen: one object serves
    # True is cached now; 1 == True and hashes alike, yet a bool option must still refuse it
    flag = next(row[0] for row in option_help(solver.Options) if row[2].startswith("True or False"))
    solver.options({flag: True})
    with pytest.raises(InvalidParameterError, match=flag):
        solver.options({flag: 1})
