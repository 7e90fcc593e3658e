"""`wavecontact markov` end to end."""

import json
import math

import numpy as np
from cli_in_process import run_in_process

from wavecontact.cli import main
from wavecontact.studies.markov import load_result


def test_json_summary_has_the_documented_keys_and_boltzmann_values(capsys):
    assert main(["markov", "--gamma", "0.6", "--rule", "glauber", "--chains", "8", "--steps", "3000", "--seed", "4",
                 "--json", "--no-progress"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert {"mean_energy", "fraction_below_bath_temperature", "ks_pvalue", "steps", "chains"} <= set(record)
    assert record["steps"] == 3000 and record["chains"] == 8
    # Glauber's rule is stationary after one step: Eq. 30 within 5 standard errors of the chains' spread
    assert abs(record["mean_energy"] - 1.0) < 5.0 * record["mean_energy_standard_error"]
    assert 0.0 <= record["ks_pvalue"] <= 1.0


def test_out_and_plot_write_files_that_read_back(tmp_path, capsys):
    out, plot = tmp_path / "run", tmp_path / "fig10.png"
    assert main(["markov", "--gamma", "0.6", "--rule", "solve", "--bath-modes", "20", "--chains", "2", "--steps", "30",
                 "--seed", "1", "--out", str(out), "--plot", str(plot), "--no-progress"]) == 0
    assert "KS test" in capsys.readouterr().out
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    result = load_result(out)
    summary = json.loads((out / "summary.json").read_text())
    assert result.energy.shape == (2, 31) and summary["chains"] == 2
    np.testing.assert_array_equal(result.energy[:, 1:], result.eps2 * result.energy[:, :-1])
    assert math.isinf(result.spec.kappa)


def test_bad_arguments_end_with_one_line_and_status_2(capsys):
    for args in (["--rule", "table"], ["--steps", "0"], ["--gamma", "1.5"], ["--plot", "/nonexistent/x.png"],
                 ["--rule", "glauber", "--table", "t.npz"]):
        done = run_in_process(capsys, "markov", "--gamma", "0.6", *args)
        assert done.returncode == 2, (args, done.stderr)
        assert len(done.stderr.strip().splitlines()) == 1, done.stderr
