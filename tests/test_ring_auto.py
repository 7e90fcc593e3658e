"""``wavecontact ring`` without ``--modes``: the modes from a tolerance on each collision's restitution.

The chosen modes are checked against references the choice does not use: the collisions recomputed
from the same states with eight times the modes (a longer run's collisions, ring circumferences the
calibration did not use), and the delay solver for the first collision from rest (the two-rod problem).
"""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest

from wavecontact import two_rods
from wavecontact.cli import main as cli_main
from wavecontact.errors import InvalidParameterError, LimitError
from wavecontact.scene import two_rods_on_a_ring
from wavecontact.solvers import auto_ring, get_solver
from wavecontact.solvers.auto_ring import ERROR_QUANTILE, choose_modes, load_ring_model
from wavecontact.studies.ring import run_ring

GAMMA = 0.6173


def _with_modes_at_rest(state: dict, modes: int, more: int) -> dict:
    """A ring state with ``modes`` per rod as one with ``more`` per rod (written apart from auto_ring)."""
    out = {key: np.array(value) for key, value in state.items()}
    for key in ("q", "v"):
        rods = np.asarray(state[key]).reshape(2, modes)
        out[key] = np.concatenate([np.pad(rods[0], (0, more - modes)), np.pad(rods[1], (0, more - modes))])
    out["parameters"] = np.array(state["parameters"], dtype=float)
    out["parameters"][2] = more
    return out


def test_the_choice_grows_with_a_stricter_tolerance():
    for kappa in (10.0, 40.0, 400.0):
        modes = [choose_modes(GAMMA, kappa, 1, tolerance=t).modes for t in (3e-2, 1e-3, 1e-4, 1e-5)]
        assert all(a < b for a, b in itertools.pairwise(modes)), (kappa, modes)
        predicted = [choose_modes(GAMMA, kappa, 1, tolerance=t).predicted_error for t in (3e-2, 1e-3, 1e-4, 1e-5)]
        assert all(p <= t for p, t in zip(predicted, (3e-2, 1e-3, 1e-4, 1e-5)))


def test_the_choice_is_the_fewest_modes_predicted_to_meet_the_tolerance():
    model = load_ring_model()
    choice = choose_modes(GAMMA, 40.0, 100, tolerance=1e-3)
    assert choice.chosen and model.predict(GAMMA, 40.0, choice.modes)[0] <= 1e-3
    assert model.predict(GAMMA, 40.0, choice.modes - 1)[0] > 1e-3
    assert f"N = {choice.modes}" in choice.reason and "1e-3" in choice.reason.replace("0.001", "1e-3")


def test_given_modes_are_kept_and_the_prediction_reported():
    choice = choose_modes(GAMMA, 4000.0, 4500, modes=75)
    assert choice.modes == 75 and not choice.chosen
    assert choice.tolerance == auto_ring.DEFAULT_TOLERANCE and choice.predicted_error > 0
    assert "75 given" in choice.reason


def test_a_tolerance_out_of_reach_is_refused_before_any_work_with_the_modes_and_cost(tmp_path, capsys):
    with pytest.raises(LimitError, match=r"needs N = \d+ modes per rod.*updates"):
        choose_modes(GAMMA, 4000.0, 4500, tolerance=1e-4)
    out = tmp_path / "out"
    code = cli_main(["ring", "--gamma", "0.6173", "--kappa", "4000", "--collisions", "4500", "--tolerance", "1e-4",
                     "--out", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert code != 0 and err.count("\n") == 1 and "needs N =" in err and "Traceback" not in err
    assert not out.exists() or not any(out.iterdir())


def test_no_choice_without_the_static_correction_or_for_a_bad_tolerance():
    with pytest.raises(InvalidParameterError, match="static correction"):
        choose_modes(GAMMA, 40.0, 100, tolerance=1e-3, static_correction=False)
    for bad in (0.0, -1.0, math.nan, math.inf, "x"):
        with pytest.raises(InvalidParameterError, match="tolerance"):
            choose_modes(GAMMA, 40.0, 100, tolerance=bad)


def test_a_run_with_a_tolerance_reports_its_choice_and_checks_without_changing_the_run(monkeypatch):
    monkeypatch.setattr(auto_ring, "CHECK_EVERY", 2)
    checked = run_ring(GAMMA, 40.0, collisions=5, tolerance=3e-2, progress=False)
    accuracy = checked.metadata["accuracy"]
    assert accuracy["chosen"] and accuracy["modes"] == checked.modes
    assert accuracy["checks"]["collisions"] == [1, 3, 5] and len(accuracy["checks"]["estimates"]) == 3
    plain = run_ring(GAMMA, 40.0, checked.modes, 5, progress=False)
    assert "accuracy" not in plain.metadata
    for name in ("restitution", "modal_energies", "time", "translational_energy"):
        np.testing.assert_array_equal(getattr(plain, name), getattr(checked, name))
    # the first check is the first collision from rest: its estimate against an independent recomputation
    scene = two_rods_on_a_ring(GAMMA, 40.0)
    finer = get_solver("modal").simulate(scene, {"modes": 2 * checked.modes}).next_collision().restitution
    assert accuracy["checks"]["estimates"][0] == pytest.approx(2.0 * abs(checked.restitution[0] - finer), rel=1e-9)


def test_estimates_above_the_tolerance_and_a_wrong_model_are_reported(monkeypatch):
    monkeypatch.setattr(auto_ring, "CHECK_EVERY", 1)
    messages = []
    run = run_ring(GAMMA, 4000.0, 8, 4, tolerance=1e-9, progress=False, log=messages.append)
    checks = run.metadata["accuracy"]["checks"]
    assert checks["above_tolerance"] == [1, 2, 3, 4] and "4 of 4" in checks["verdict"]
    assert messages and "4 of 4" in messages[-1]
    # a model that claims far too little (a deliberately wrong choice) is called wrong by the checks
    wrong = auto_ring.RingChoice(8, 1e-9, 1e-12, None, "a wrong model", True)
    checks = run_ring(GAMMA, 4000.0, None, 4, tolerance=wrong, progress=False).metadata["accuracy"]["checks"]
    assert "the model is wrong here" in checks["verdict"]
    right = auto_ring.RingChoice(8, 1e-9, 10.0, None, "a model that claims enough", True)
    checks = run_ring(GAMMA, 4000.0, None, 4, tolerance=right, progress=False).metadata["accuracy"]["checks"]
    assert "model is wrong" not in checks["verdict"]


def test_cli_chooses_the_modes_and_says_why(tmp_path, capsys):
    out = tmp_path / "ring"
    code = cli_main(["ring", "--gamma", "0.6173", "--kappa", "40", "--collisions", "6", "--tolerance", "3e-2",
                     "--out", str(out), "--no-progress", "--json"])
    assert code == 0
    record = json.loads(capsys.readouterr().out)
    accuracy = record["accuracy"]
    assert record["modes"] == accuracy["modes"] == choose_modes(GAMMA, 40.0, 6, tolerance=3e-2).modes
    assert accuracy["chosen"] and accuracy["predicted_error"] <= 3e-2 and "fewest modes" in accuracy["reason"]
    assert accuracy["checks"]["collisions"] == [1]
    assert json.loads((out / "summary.json").read_text())["accuracy"] == accuracy


def test_the_stored_model_is_what_its_points_give():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "benchmarks" / "ring_model.py"
    spec = importlib.util.spec_from_file_location("ring_model_benchmark", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.main(["--check"]) == 0


@pytest.mark.slow
@pytest.mark.parametrize("kappa, tolerance", [(40.0, 1e-3), (400.0, 3e-2), (10.0, 1e-5)])
def test_the_chosen_modes_meet_the_tolerance_against_eight_times_the_modes(kappa, tolerance):
    choice = choose_modes(GAMMA, kappa, 200, tolerance=tolerance)
    n, more = choice.modes, 8 * choice.modes
    engine = get_solver("modal")
    errors = []
    base = two_rods_on_a_ring(GAMMA, kappa).ring_circumference
    for stretch in (0.007, 0.022):  # circumferences the calibration did not use
        scene = two_rods_on_a_ring(GAMMA, kappa, base * (1 + stretch))
        run, finer = engine.simulate(scene, {"modes": n}), engine.simulate(scene, {"modes": more})
        for j in range(160):
            state = run.get_state()
            record = run.next_collision()
            if j < 3 or (j >= 60 and j % 10 == 0):
                finer.set_state(_with_modes_at_rest(state, n, more))
                errors.append(abs(record.restitution - finer.next_collision().restitution))
    assert np.quantile(errors, ERROR_QUANTILE) <= tolerance, (n, sorted(errors)[-5:])


@pytest.mark.slow
@pytest.mark.parametrize("kappa, tolerance", [(40.0, 1e-3), (400.0, 3e-2)])
def test_the_chosen_modes_meet_the_tolerance_on_the_first_collision_against_the_delay_solver(kappa, tolerance):
    from wavecontact import solve

    choice = choose_modes(GAMMA, kappa, 200, tolerance=tolerance)
    ring = get_solver("modal").simulate(two_rods_on_a_ring(GAMMA, kappa), {"modes": choice.modes})
    reference = solve(two_rods(GAMMA, kappa), solver="delay", rtol=1e-10)
    assert abs(ring.next_collision().restitution - reference.restitution) <= tolerance
