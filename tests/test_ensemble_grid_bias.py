"""Hard-core ensembles state their grid bias: checked against exact limits and direct fine runs."""

import json
import math

import numpy as np
import pytest

from wavecontact import InvalidParameterError
from wavecontact.cli import main
from wavecontact.delay.stochastic_hardcore_batch import hard_core_restitutions
from wavecontact.errors import AccuracyError
from wavecontact.studies.ensemble import ensemble, grid_bias_indices, sample_seed

# the first-order estimate 2 mean(eps_8 - eps_16) measured 0.89 to 0.97 of the actual bias at gamma = 1
# (benchmarks/hard_core_bias.py): what is left of the bias after subtracting the estimate
MODEL_ERROR = 0.15


@pytest.mark.parametrize("temperature", [1.0, 100.0])
@pytest.mark.parametrize("seed", [7, 31])
def test_equal_rods_mean_is_one_within_the_stated_total_error(temperature, seed):
    # independent reference: gamma = 1 gives epsilon = 1 exactly in every realisation (paper Sec. VI)
    result = ensemble(1.0, math.inf, temperature, 400, seed)
    bias = result.grid_bias
    assert abs(result.mean - 1.0) <= 3.0 * result.total_error
    # and the stated bias is what the mean is off by, not just a large number: the deviation left
    # after subtracting it is within its errors (the standard error alone is 20 times too small)
    assert abs(result.mean - 1.0) > 10.0 * result.standard_error
    left = abs(result.mean - 1.0 - bias.value)
    assert left <= 3.0 * math.hypot(result.standard_error, bias.standard_error) + MODEL_ERROR * abs(bias.value)


@pytest.mark.parametrize(("gamma", "temperature"), [(0.9, 100.0), (1.0, 10.0)])
def test_stated_bias_agrees_with_a_direct_fine_run_on_the_same_seeds(gamma, temperature):
    samples, seed = 400, 5
    result = ensemble(gamma, math.inf, temperature, samples, seed, batch_size=100)
    # the same seeds on a grid eight times finer (its own error is 1/8 of the default's at first order)
    seeds = [sample_seed(seed, j) for j in range(samples)]
    fine = hard_core_restitutions(gamma, temperature, seeds, points_per_period=64)
    direct = result.restitution - fine
    if gamma == 1.0:
        direct = result.restitution - 1.0  # here the exact value is known
    spread = float(np.std(direct, ddof=1)) / math.sqrt(samples)
    bias = result.grid_bias
    assert abs(bias.value - direct.mean()) <= (3.0 * math.hypot(bias.standard_error, spread)
                                               + (MODEL_ERROR + 0.125) * abs(direct.mean()))
    if gamma == 1.0:  # there the bias is many of its standard errors: the grid misses maxima, eps comes out low
        assert bias.value < -3.0 * bias.standard_error


def test_grid_bias_subset_cost_and_identity_across_batches():
    assert grid_bias_indices(400).size == 67 and grid_bias_indices(2500).size == 65
    assert grid_bias_indices(30).size == 30  # small ensembles rerun every sample
    one = ensemble(0.6173, math.inf, 1.0, 300, 3, bath_modes=40, batch_size=300)
    other = ensemble(0.6173, math.inf, 1.0, 300, 3, bath_modes=40, batch_size=7)
    assert one.grid_bias.value == other.grid_bias.value
    assert np.array_equal(one.grid_bias.check_restitution, other.grid_bias.check_restitution)
    # bath_modes 40: 8 points per period give the 320-point floor of the grid, and the check grid doubles it
    assert one.grid_bias.factor == 2.0


def test_tolerance_refuses_a_bias_above_it_with_advice():
    with pytest.raises(AccuracyError, match="hard_core_resolution") as caught:
        ensemble(1.0, math.inf, 1.0, 200, 2, tolerance=1e-4)
    advised = int(caught.value.advice.split("=")[1])
    assert advised > 8
    assert caught.value.result.grid_bias.resolution == 8
    ensemble(1.0, math.inf, 1.0, 200, 2, tolerance=0.05)  # a bias of about 4e-3 meets it
    with pytest.raises(InvalidParameterError, match="hard-core"):
        ensemble(0.6173, 50.0, 1.0, 2, 2, bath_modes=8, tolerance=0.01)
    with pytest.raises(InvalidParameterError, match="tolerance"):
        ensemble(1.0, math.inf, 1.0, 2, 2, tolerance=-1.0)


def test_cli_states_the_grid_bias(tmp_path, capsys):
    out = tmp_path / "e"
    args = ["ensemble", "--gamma", "1", "--kappa", "inf", "--temperature", "1", "--samples", "150", "--seed", "9",
            "--no-progress"]
    assert main([*args, "--json", "--out", str(out)]) == 0
    summary = json.loads(capsys.readouterr().out)
    direct = ensemble(1.0, math.inf, 1.0, 150, 9)
    assert summary["grid_bias"] == direct.grid_bias.value
    assert summary["total_error"] == direct.total_error
    assert summary["grid_bias_samples"] == 75 and summary["grid_bias_check_resolution"] == 16
    assert json.loads((out / "summary.json").read_text())["grid_bias"] == direct.grid_bias.value
    with np.load(out / "samples.npz", allow_pickle=False) as data:
        assert np.array_equal(data["grid_bias_check_restitution"], direct.grid_bias.check_restitution)
        assert np.array_equal(data["grid_bias_indices"], grid_bias_indices(150))
    assert main(args) == 0
    assert "grid bias of the mean = " in capsys.readouterr().out
