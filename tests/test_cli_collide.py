"""`wavecontact collide` end to end, through the installed console script."""

import json
import subprocess
import sys

import pytest
from cli_in_process import run_in_process

from wavecontact.cli import main
from wavecontact.result import CollisionResult

MODEL_KAPPA_100 = 0.646697087


def run_cli(*args):
    return subprocess.run(
        [sys.executable, "-m", "wavecontact", *args], check=False, capture_output=True, text=True, timeout=300
    )


def test_json_output_has_the_documented_keys(capsys):
    assert main(["collide", "--gamma", "0.6", "--kappa", "100", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
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
        ["collide", "--gamma", "0.6", "--kappa", "10", "--modes", "10", "--rtol", "1e-8"],
        ["collide", "--gamma", "0.6", "--kappa", "10", "--solver", "delay", "--modes", "10"],
        ["collide", "--gamma", "0.6", "--kappa", "inf", "--solver", "delay", "--contact", "penalty"],
        ["collide", "--gamma", "0.6", "--kappa", "100", "--contact", "hard"],
        ["collide", "--gamma", "0.6", "--kappa", "inf", "--contact", "exponential"],
        ["collide", "--gamma", "0.6", "--kappa", "10", "--order", "3"],
        ["collide", "--gamma", "0.6", "--kappa", "10", "--plot", "figure.txt"],
    ],
)
def test_invalid_arguments_exit_nonzero_with_one_line(args, capsys):
    done = run_in_process(capsys, *args)
    assert done.returncode != 0
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "error" in lines[0]
    assert "Traceback" not in done.stderr


def test_a_refused_argument_ends_the_process_with_status_2_and_one_line():
    """The console entry itself (the cases above run ``main`` in this process)."""
    done = run_cli("collide", "--gamma", "1.5", "--kappa", "10")
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "error" in lines[0] and "--gamma" in lines[0]
    assert "Traceback" not in done.stderr and done.stdout == ""


def test_text_reports_the_solve_and_the_kernel_preparation_apart():
    # on an empty cache the first run answers from interpreted kernels and compiles them afterwards
    # (tests/test_jit_interpreted.py); from then on a fresh process loads them
    run_cli("collide", "--gamma", "0.6", "--kappa", "100")
    done = run_cli("collide", "--gamma", "0.6", "--kappa", "100")
    assert done.returncode == 0, done.stderr
    line = done.stdout.strip()
    assert "epsilon = 0.6466970" in line and "contact = exponential" in line
    solve_ms = float(line.split("solve ")[1].split(" ms")[0])
    # a fresh process always loads kernels; the second, timed solve of the delay equation is fast
    assert "kernel preparation" in line and "includ" not in line and "interpreted" not in line
    assert solve_ms < 50


def _epsilon(out: str) -> float:
    return float(out.split()[2])


def test_penalty_says_how_kappa_sets_the_spring(capsys):
    """kappa is the penalty spring's stiffness k = kappa Z_eff c / l (docs/fem.md): it is used, and printed
    as such; a stiff spring approaches the hard limit epsilon = gamma, a soft one is nearly elastic."""
    printed = {}
    for kappa in ("1", "1e6", "inf"):
        assert main(["collide", "--gamma", "0.6", "--kappa", kappa, "--solver", "fem", "--contact", "penalty",
                     "--elements", "200"]) == 0
        printed[kappa] = capsys.readouterr().out
        assert "contact = penalty" in printed[kappa] and "unused" not in printed[kappa]
    assert "kappa = 1 (penalty stiffness kappa Z_eff c / l)" in printed["1"]
    assert "kappa = inf (penalty stiffness E A / h" in printed["inf"]
    assert _epsilon(printed["1"]) > 0.99  # a soft spring: nearly elastic (docs/fem.md: 0.996)
    assert abs(_epsilon(printed["1e6"]) - 0.6) < 1e-5  # within 1e-5 of the hard limit epsilon = gamma
    assert abs(_epsilon(printed["inf"]) - 0.6) < 0.01  # the mesh-tied spring tends to hard contact


def test_hard_contact_is_printed_as_kappa_inf(capsys):
    assert main(["collide", "--gamma", "0.6", "--kappa", "inf", "--contact", "hard"]) == 0
    assert "kappa = inf, contact = hard" in capsys.readouterr().out


def test_files_written_are_listed_on_stderr_and_in_json(tmp_path, capsys):
    figure, saved = tmp_path / "w.png", tmp_path / "run.npz"
    assert main(["collide", "--gamma", "0.6", "--kappa", "20", "--plot", str(figure), "--save", str(saved),
                 "--json"]) == 0
    captured = capsys.readouterr()
    record = json.loads(captured.out)
    assert record["files_written"] == [str(figure), str(saved)]
    assert f"wrote {figure}" in captured.err and f"wrote {saved}" in captured.err
    assert figure.exists() and saved.exists()


def test_the_step_limit_the_solver_advises_to_raise_is_an_option(capsys):
    assert main(["collide", "--gamma", "0.6", "--kappa", "1", "--max-steps", "3"]) == 2
    err = capsys.readouterr().err
    assert "max_steps" in err and "Traceback" not in err


def test_fields_are_written_with_units_and_listed(tmp_path, capsys):
    from wavecontact.io.fields import read_fields

    out = tmp_path / "fields"
    assert main(["collide", "--solver", "fem", "--gamma", "0.6", "--kappa", "20", "--elements", "20",
                 "--fields", str(out), "--json"]) == 0
    captured = capsys.readouterr()
    record = json.loads(captured.out)
    # the bulky per-sample files are one entry (pattern and count), listed once on stderr
    samples = len(read_fields(out)["time"])
    assert record["files_written"] == [str(out / "fields.pvd"), f"{out / 'fields_*.vtu'} ({samples} files)"]
    assert len(list(out.glob("fields_*.vtu"))) == samples
    assert captured.err.count("wavecontact: wrote") == 2
    back = read_fields(out)
    assert back["units"]["stress"] == "rho c V" and back["parameters"]["gamma"] == 0.6
