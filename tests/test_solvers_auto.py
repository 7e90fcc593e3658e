"""solver='auto' (wavecontact.solvers.auto): meets the tolerance against independent references,
refines where the first run misses, refuses before the work where the limits cannot allow it."""

import json
import math

import pytest

import wavecontact
from wavecontact import solve, two_rods
from wavecontact.analytic import hard_core_restitution
from wavecontact.bath.collide import thermal_scene
from wavecontact.bath.model import ThermalBath
from wavecontact.cli import main
from wavecontact.errors import AccuracyError, InvalidParameterError, LimitError
from wavecontact.solvers import get_solver
from wavecontact.solvers.auto import DEFAULT_TOLERANCE, solve_auto, solve_refined
from wavecontact.solvers.base import reusing_runs
from wavecontact.solvers.cost_model import CostModel

#: shared/MODEL.md, section 5 (cold bath, a0 large), to the digits shown there
MODEL_MD = {(0.6, 20.0): (0.7530132413, 1e-10), (0.6, 100.0): (0.646697087, 1e-9), (0.6, 1e4): (0.600927488, 1e-9)}


@pytest.mark.parametrize("gamma, kappa", sorted(MODEL_MD))
@pytest.mark.parametrize("tolerance", [1e-3, 1e-6, 1e-8])
def test_auto_meets_the_tolerance_against_model_md(gamma, kappa, tolerance):
    value, digits = MODEL_MD[(gamma, kappa)]
    result = solve(two_rods(gamma, kappa), tolerance=tolerance)
    assert result.error_estimate <= tolerance
    assert abs(result.restitution - value) <= tolerance + digits
    auto = result.diagnostics["auto"]
    assert auto["method"].split(":")[0] == result.solver
    assert auto["reason"] and auto["predicted_cpu_s"] > 0 and auto["actual_cpu_s"] > 0


def test_default_tolerance_is_the_documented_one():
    result = solve(two_rods(0.6, 100.0))
    assert DEFAULT_TOLERANCE == 1e-6
    assert result.diagnostics["auto"]["tolerance"] == 1e-6
    assert abs(result.restitution - MODEL_MD[(0.6, 100.0)][0]) <= 1e-6 + 1e-9


def test_auto_hard_core_is_the_wave_theory():
    result = solve(two_rods(0.4, math.inf), tolerance=1e-9)
    assert abs(result.restitution - hard_core_restitution(0.4)) <= 1e-9


@pytest.mark.parametrize("tolerance", [1e-3, 1e-9])
def test_auto_penalty_contact_against_the_other_solver(tolerance):
    scene = two_rods(0.5, 50.0, contact="penalty")  # the delay solver does not take it: FE or modal
    result = solve(scene, tolerance=tolerance)
    other = "fem" if result.solver == "modal" else "modal"
    reference = solve(scene, other, **({"elements": 1600} if other == "fem" else {"modes": 256}))
    assert result.solver in ("fem", "modal")
    assert abs(result.restitution - reference.restitution) <= tolerance + reference.error_estimate


def test_auto_thermal_against_the_delay_solver_at_tight_rtol():
    scene = thermal_scene(0.6, 100.0, ThermalBath(0.05, 250), 2)
    result = solve(scene, tolerance=1e-8)
    reference = solve(scene, "delay", rtol=1e-13)
    assert abs(result.restitution - reference.restitution) <= 1e-8 + reference.error_estimate


def _model(solver, ladder, error_log10, cost_log10=-3.0):
    """A cost model with one fit for cold two rods: constant predicted error and cost."""
    fit = {"error": {"coef": [error_log10, 0, 0, 0, 0], "margin": 0.0},
           "cost": {"coef": [cost_log10, 0, 0, 0, 0], "margin": 0.0}}
    return CostModel({"format": 1, "ladders": {solver: ladder}, "fits": {"cold": {solver: fit}}})


def test_refinement_reaches_a_tolerance_the_first_run_missed():
    # a model that wrongly promises 1e-20 from 25 elements: the first run misses, the order observed
    # in its own levels predicts the mesh that meets the tolerance
    scene = two_rods(0.6, 100.0)
    result = solve_auto(scene, tolerance=1e-7, model=_model("fem", [25], -20.0))
    auto = result.diagnostics["auto"]
    assert result.solver == "fem" and len(auto["attempts"]) >= 2
    assert auto["attempts"][0]["method"] == "fem: elements=25" and auto["attempts"][0]["error_estimate"] > 1e-7
    assert result.error_estimate <= 1e-7
    assert abs(result.restitution - MODEL_MD[(0.6, 100.0)][0]) <= 1e-7 + 1e-9
    assert any("above the predicted" in miss for miss in auto["misses"])  # the model's miss is logged


def test_refinement_over_the_limits_is_refused_with_the_cost_it_needs():
    scene = two_rods(0.6, 100.0)
    fem = get_solver("fem")
    first = fem.total_cost(scene, fem.options({"elements": 25}), True).work
    with pytest.raises(AccuracyError, match=r"over the limits.*max_work=") as caught:
        solve_auto(scene, tolerance=1e-9, max_work=2 * first, model=_model("fem", [25], -20.0))
    assert caught.value.result is not None and caught.value.result.error_estimate > 1e-9


def test_a_tolerance_no_method_can_meet_within_the_limits_is_refused_before_any_work(monkeypatch):
    def no_work(*_args, **_kwargs):
        raise AssertionError("a solver ran")

    for name in ("fem", "modal", "delay"):
        monkeypatch.setattr(type(get_solver(name)), "_collide", no_work)
    with pytest.raises(LimitError, match=r"tolerance=1e-06.*updates.*max_work=") as caught:
        solve(two_rods(0.5, 50.0, contact="penalty"), tolerance=1e-6, max_work=10.0)
    assert "pass max_work=" in str(caught.value)


def test_auto_refuses_solver_options():
    with pytest.raises(InvalidParameterError, match="takes no solver options"):
        solve(two_rods(0.6, 100.0), elements=200)


def test_reused_runs_give_the_same_result_with_fewer_runs(monkeypatch):
    scene = two_rods(0.6, 100.0)
    fem = get_solver("fem")
    plain = solve(scene, "fem", elements=400)
    calls = []
    original = type(fem)._collide

    def counted(self, scene_, options):
        calls.append(options.elements)
        return original(self, scene_, options)

    monkeypatch.setattr(type(fem), "_collide", counted)
    with reusing_runs():
        solve(scene, "fem", elements=200)
        calls.clear()
        reused = solve(scene, "fem", elements=400)
    assert calls == [400]  # 200 and its own level 100 were run before: only the new run
    assert reused.restitution == plain.restitution
    assert reused.error_estimate == plain.error_estimate


def test_cli_collide_defaults_to_auto(capsys):
    assert main(["collide", "--gamma", "0.6", "--kappa", "100", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["diagnostics"]["auto"]["tolerance"] == 1e-6
    assert abs(record["restitution"] - MODEL_MD[(0.6, 100.0)][0]) <= 1e-6 + 1e-9


def test_explicit_solver_is_not_auto():
    result = wavecontact.collide(0.6, 100.0)  # collide keeps the delay solver as its default
    assert result.solver == "delay" and "auto" not in result.diagnostics


def test_cli_solver_options_name_the_solver_without_solver(capsys):
    # --solver not given: the solver whose options are given (as --rtol meant the delay solver before auto)
    assert main(["collide", "--gamma", "0.6", "--kappa", "20", "--modes", "16", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["solver"] == "modal" and "auto" not in record["diagnostics"]
    assert main(["collide", "--gamma", "0.6", "--kappa", "20", "--contact", "penalty", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["diagnostics"]["auto"]["scene_class"] == "penalty" and record["solver"] in ("fem", "modal")


@pytest.mark.parametrize("solver, options", [("fem", {"elements": 25, "mass": "lumped"}), ("delay", {"rtol": 1e-3})])
def test_a_named_solver_is_refined_instead_of_refused(solver, options):
    # the same call with tolerance= alone raises AccuracyError: the first run's estimate is above 1e-8
    with pytest.raises(AccuracyError):
        solve(two_rods(0.6, 20.0), solver, tolerance=1e-8, **options)
    result = solve_refined(two_rods(0.6, 20.0), solver, tolerance=1e-8, **options)
    auto = result.diagnostics["auto"]
    assert result.solver == solver and len(auto["attempts"]) >= 2 and result.error_estimate <= 1e-8
    kept = {name: value for name, value in options.items() if name != get_solver(solver).resolution}
    assert all(result.options[name] == value for name, value in kept.items())  # the other options kept
    assert abs(result.restitution - MODEL_MD[(0.6, 20.0)][0]) <= 1e-8 + 1e-10
