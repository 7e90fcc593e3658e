"""The cost model's data (wavecontact/data/cost_model.json): it loads, covers the scene classes, and is
what ``python benchmarks/cost_model.py`` writes for its stored points."""

import copy
import importlib.util
import json
import math
from pathlib import Path

import pytest

from wavecontact import two_rods
from wavecontact.errors import InvalidParameterError
from wavecontact.solvers.cost_model import DATA_PATH, CostModel, fit_points, load_model, scene_class

_SPEC = importlib.util.spec_from_file_location(
    "benchmark_cost_model", Path(__file__).resolve().parents[1] / "benchmarks" / "cost_model.py")
benchmark = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(benchmark)


def test_the_stored_model_loads_and_covers_every_scene_class():
    model = load_model()
    assert set(model.classes()) == {"cold", "hard", "penalty", "thermal", "two_materials", "line_rigid", "line_chain",
                                    "line_stepped", "line_tapered"}
    assert set(model.ladders) == {"delay", "fem", "modal"}
    prediction = model.predict("cold", "delay", {"kappa": 100.0, "time_ratio": 0.6, "vibration_energy": 0.0}, 1e-9)
    assert 0 < prediction.error < 1 and 0 < prediction.cpu_s < 1


def test_the_stored_model_is_what_the_benchmark_writes():
    assert benchmark.check(DATA_PATH) == []
    assert benchmark.main(["--check"]) == 0


def test_check_finds_a_changed_fit(tmp_path):
    data = json.loads(DATA_PATH.read_text(encoding="utf-8"))
    changed = copy.deepcopy(data)
    changed["fits"]["cold"]["delay"]["error"]["coef"][0] += 0.5
    path = tmp_path / "model.json"
    path.write_text(json.dumps(changed), encoding="utf-8")
    assert any("fits differ" in problem for problem in benchmark.check(path))


def test_the_fit_recovers_a_known_power_law():
    # error = 10 * (kappa / N)^2 and cost = 1e-6 N kappa^0.5, exactly: the fit must give these back
    points = [{"class": "cold", "solver": "fem", "resolution": n, "features":
               {"kappa": k, "time_ratio": 0.5, "vibration_energy": 0.0},
               "estimate": 10 * (k / n) ** 2, "cpu_s": 1e-6 * n * k**0.5}
              for n in (25, 100, 400) for k in (10.0, 1e3)]
    fit = fit_points(points)["cold"]["fem"]
    error, cost = fit["error"]["coef"], fit["cost"]["coef"]
    assert error[1] == pytest.approx(2.0) and error[2] == pytest.approx(-2.0)
    assert cost[1] == pytest.approx(0.5) and cost[2] == pytest.approx(1.0)
    assert fit["error"]["margin"] == pytest.approx(0.0, abs=1e-8)


def test_scene_classes():
    assert scene_class(two_rods(0.6, 100.0)) == "cold"
    assert scene_class(two_rods(0.6, math.inf)) == "hard"
    assert scene_class(two_rods(0.6, 100.0, contact="penalty")) == "penalty"
    assert scene_class(benchmark.two_material_scene(2.5, 0.6, 100.0)) == "two_materials"


def test_a_model_of_another_format_is_refused():
    with pytest.raises(InvalidParameterError, match="format"):
        CostModel({"format": 0})
