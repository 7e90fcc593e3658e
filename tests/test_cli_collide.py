"""`wavecontact collide` end to end, through the installed console script."""

import json
import subprocess
import sys

import pytest

from wavecontact.cli import main
from wavecontact.result import CollisionResult

MODEL_KAPPA_100 = 0.646697087


def run_cli(*args):
    return subprocess.run(
        [sys.executable, "-m", "wavecontact", *args], check=False, capture_output=True, text=True, timeout=300
    )


def test_json_output_has_the_documented_keys():
    done = run_cli("collide", "--gamma", "0.6", "--kappa", "100", "--json")
    assert done.returncode == 0, done.stderr
    record = json.loads(done.stdout)
    assert {"restitution", "solver", "gamma", "kappa", "wall_time_s"} <= set(record)
    assert record["solver"] == "delay"
    assert abs(record["restitution"] - MODEL_KAPPA_100) < 1e-8


def test_kappa_inf_selects_the_hard_limit(capsys):
    assert main(["collide", "--gamma", "0.6", "--kappa", "inf", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["kappa"] == "inf"
    assert abs(record["restitution"] - 0.6) < 1e-12


def test_plot_writes_a_png(tmp_path, capsys):
    path = tmp_path / "w.png"
    assert main(["collide", "--gamma", "0.6", "--kappa", "20", "--plot", str(path)]) == 0
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "epsilon = 0.7530132" in capsys.readouterr().out


def test_save_writes_histories(tmp_path):

    path = tmp_path / "run.npz"
    assert main(["collide", "--gamma", "0.6", "--kappa", "20", "--save", str(path)]) == 0
    loaded = CollisionResult.load_npz(path)
    assert loaded.relative_velocity[0] == pytest.approx(-1.0)
    assert loaded.solver == "delay" and loaded.gamma == 0.6 and loaded.kappa == 20


@pytest.mark.parametrize(
    "args",
    [
        ["collide", "--gamma", "1.5", "--kappa", "10"],
        ["collide", "--gamma", "0.6", "--kappa", "-1"],
        ["collide", "--gamma", "0.6", "--kappa", "nan"],
        ["collide", "--gamma", "abc", "--kappa", "10"],
        ["collide", "--gamma", "0.6", "--kappa", "10", "--solver", "magic"],
        ["collide", "--gamma", "0.6", "--kappa", "10", "--rtol", "2"],
        ["collide", "--gamma", "0.6", "--kappa", "10", "--modes", "10"],
        ["collide", "--gamma", "0.6", "--kappa", "10", "--contact", "penalty"],
    ],
)
def test_invalid_arguments_exit_nonzero_with_one_line(args):
    done = run_cli(*args)
    assert done.returncode != 0
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "error" in lines[0]
    assert "Traceback" not in done.stderr
