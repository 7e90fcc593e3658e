"""Every command refuses bad input before any work: one line naming the option, exit 2, no traceback, no file.

The table holds the cases of issue 23 (output paths, sizes, ranges, options that would be ignored).
Each case runs ``wavecontact.cli.main`` in-process in an empty folder with every study entry point
replaced by a function that fails the test: a refusal that came after the work had started
would show as that failure, not as a pass.
"""

import os
import time
from pathlib import Path

import pytest

from wavecontact.cli import main

#: The entry points of the commands' work (module, attribute): none may be reached by a refused run.
WORK = [
    ("wavecontact.api", "collide"),
    ("wavecontact.studies.convergence", "convergence_study"),
    ("wavecontact.studies.compare", "compare_solvers"),
    ("wavecontact.studies.ring", "run_ring"),
    ("wavecontact.studies.equipartition", "equipartition_by_modes"),
    ("wavecontact.studies.markov", "markov_chains"),
    ("wavecontact.studies.ensemble", "ensemble"),
    ("wavecontact.studies.bath_figures", "noise_covariance"),
    ("wavecontact.studies.bath_figures", "stochastic_histories"),
    ("wavecontact.studies.bath_figures", "spread_against_temperature"),
    ("wavecontact.studies.bath_figures", "restitution_law"),
    ("wavecontact.studies.restitution_tables", "restitution_table"),
    ("wavecontact.gas", "random_gas"),
    ("wavecontact.studies.material_map", "material_map"),
    ("wavecontact.studies.paper_figures", "run_figures"),
    ("wavecontact.api", "solve"),
]

RING = ["ring", "--gamma", "0.6", "--kappa", "100", "--modes", "20", "--collisions", "10", "--no-progress"]
EQUI = ["equipartition", "--gamma", "0.6", "--kappa", "100", "--modes", "10", "--no-progress"]
ENSEMBLE = ["ensemble", "--gamma", "0.6", "--kappa", "100", "--temperature", "1", "--samples", "10", "--seed", "0"]
TABLE = ["restitution-table", "--gamma", "0.6", "--temperature", "1", "--samples", "10", "--seed", "0"]
GAS = ["gas", "--rods", "10", "--collisions", "100", "--rule", "fixed", "--restitution", "1"]
MARKOV = ["markov", "--gamma", "0.6", "--no-progress"]
COLLIDE = ["collide", "--gamma", "0.6", "--kappa", "20"]
CONVERGE = ["converge", "--gamma", "0.6", "--kappa", "20"]
COMPARE = ["compare", "--gamma", "0.6", "--kappa", "100"]
SCENE = str(Path(__file__).resolve().parent.parent / "examples" / "scenes" / "hammer_on_bar.toml")
CLOSED = "tcp://127.0.0.1:9"  # the discard port: nothing listens there

# (argv, words the one-line message must contain)
CASES = [
    # output paths: a folder for a file, an empty name, a missing folder, a FIFO, two options on one file
    (COLLIDE + ["--plot", "adir"], ["--plot", "directory"]),
    (COLLIDE + ["--plot", ""], ["--plot", "empty"]),
    (COLLIDE + ["--save", "fifo.npz"], ["--save", "not a regular file"]),
    (COLLIDE + ["--plot", "missing/w.png"], ["--plot", "does not exist"]),
    (COLLIDE + ["--solver", "fem", "--plot", "p.png", "--xt-plot", "p.png"], ["--xt-plot", "same path"]),
    (CONVERGE + ["--plot", "adir"], ["--plot", "directory"]),
    (COMPARE + ["--plot", "missing/c.png"], ["--plot", "does not exist"]),
    (COMPARE + ["--plot", "adir"], ["--plot", "directory"]),
    (RING + ["--out", "afile.txt"], ["--out", "not a directory"]),
    (RING + ["--out", ""], ["--out", "empty"]),
    (RING + ["--out", "fifodir"], ["--out", "not a regular file"]),  # a FIFO in place of the checkpoint
    (EQUI + ["--out", "afile.txt"], ["--out", "not a directory"]),
    (EQUI + ["--out", ""], ["--out", "empty"]),
    (MARKOV + ["--plot", "adir"], ["--plot", "directory"]),
    (MARKOV + ["--out", ""], ["--out", "empty"]),
    (MARKOV + ["--plot", "missing/f.png"], ["--plot", "does not exist"]),
    (ENSEMBLE + ["--out", ""], ["--out", "empty"]),
    (ENSEMBLE + ["--out", "afile.txt"], ["--out", "not a directory"]),
    (ENSEMBLE + ["--plot", "adir"], ["--plot", "directory"]),
    (ENSEMBLE + ["--plot", "missing/law.png"], ["--plot", "does not exist"]),
    (["bath-figure", "4", "--out", "adir"], ["--out", "directory"]),
    (["bath-figure", "4", "--out", "missing/f.png"], ["--out", "does not exist"]),
    (["bath-figure", "4", "--json", "X.png", "--out", "X.png"], ["--json"]),
    (["bath-figure", "4", "--json", "fifo.npz", "--out", "f.png"], ["--json"]),
    (TABLE + ["--out", "adir"], ["--out", "directory"]),
    (TABLE + ["--out", "t.csv", "t.csv"], ["--out", "twice"]),
    (TABLE + ["--out", "missing/t.csv"], ["--out", "does not exist"]),
    (GAS + ["--out", "afile.txt"], ["--out", "not a directory"]),
    (GAS + ["--out", ""], ["--out", "empty"]),
    (["map", "--out", "afile.txt"], ["--out", "not a directory"]),
    (["map", "--out", ""], ["--out", "empty"]),
    (["paper-figures", "--out", "afile.txt"], ["--out", "not a directory"]),
    (["paper-figures", "--out", "figs", "--page", "adir"], ["--page", "directory"]),
    (["solve", "missing.toml"], ["missing.toml", "cannot read"]),
    (["solve", "afile.txt"], ["afile.txt", ".toml or .json"]),
    (["solve", SCENE, "--out", "adir"], ["--out", "directory"]),
    (["solve", SCENE, "--out", "r.npz"], ["--out", ".json"]),
    (["solve", SCENE, "--xt-plot", "missing/f.png"], ["--xt-plot", "does not exist"]),
    # sizes: refused with the estimate, the bound and the option
    (EQUI + ["--collisions", "1000000000000", "--out", "e"], ["equipartition", "--collisions"]),
    (EQUI[:5] + ["--modes", "20000", "--collisions", "5", "--out", "e"], ["max_work", "--modes"]),
    (RING[:5] + ["--modes", "20000", "--collisions", "5", "--out", "r"], ["max_work", "--modes"]),
    (RING[:7] + ["--collisions", "1000000000000", "--out", "r"], ["--collisions"]),
    (RING[:7] + ["--collisions", "1e12", "--out", "r"], ["--collisions"]),
    # the softest kappa at two repeats: about 4e11 updates (the modal estimate's one-mode run brought one repeat
    # to 1.99e11, just under the default max_work of 2e11)
    (["compare", "--gamma", "0.6", "--kappa", "0.01", "--repeats", "2"], ["max_work", "--kappa"]),
    (COMPARE + ["--repeats", "100000000"], ["max_work", "--repeats"]),
    (["bath-figure", "4", "--samples", "100000000", "--out", "f.png"], ["--samples"]),
    (["bath-figure", "9", "--samples", "100000000", "--out", "f.png"], ["--samples"]),
    (["map", "--impedance-ratio", "1:2:100000000", "--out", "m"], ["--impedance-ratio", "1000000"]),
    (["map", "--impedance-ratio", "1:2:2000", "--time-ratio", "1:2:2000", "--out", "m"], ["--impedance-ratio"]),
    (TABLE[:6] + ["--samples", "10000000", "--seed", "0", "--out", "t.csv"], ["--samples"]),
    (ENSEMBLE[:8] + ["--samples", "100000000", "--seed", "0"], ["samples"]),
    (CONVERGE + ["--elements", "100000", "200000"], ["max_work", "--elements"]),
    (MARKOV + ["--steps", "20000000", "--rule", "glauber"], ["steps", "19999999"]),
    (MARKOV + ["--steps", "10000000", "--chains", "2", "--rule", "glauber"], ["chains x (steps + 1)"]),
    (MARKOV + ["--chains", "100", "--steps", "100000"], ["max_work", "--steps"]),
    (GAS[:4] + ["1000000000000000"] + GAS[5:], ["--collisions", "--resume"]),
    # ranges: kappa outside [1e-2, 1e7] (or nan) refused alike by every command that takes it
    (RING[:4] + ["1e-12"] + RING[5:] + ["--out", "r"], ["--kappa", "1e+07"]),
    (RING[:4] + ["1e12"] + RING[5:] + ["--out", "r"], ["--kappa", "1e+07"]),
    (EQUI[:4] + ["1e12"] + EQUI[5:] + ["--out", "e"], ["--kappa", "1e+07"]),
    (["map", "--kappa", "1e-5", "--out", "m"], ["--kappa", "1e+07"]),
    (ENSEMBLE[:4] + ["1e12"] + ENSEMBLE[5:], ["--kappa", "1e+07"]),
    (["bath-figure", "9", "--kappa", "1e-5", "--out", "f.png"], ["--kappa", "1e+07"]),
    (MARKOV + ["--kappa", "1e12"], ["--kappa", "1e+07"]),
    (COLLIDE[:4] + ["nan"], ["--kappa"]),
    (GAS + ["--lengths", "1e-300", "1e-300"], ["--lengths", "1e-30"]),
    (GAS + ["--lengths", "1e200", "1e200"], ["--lengths", "1e+30"]),
    (["bath-figure", "8", "--seed", "-1", "--out", "f.png"], ["--seed"]),
    (ENSEMBLE[:-1] + ["-1"], ["--seed"]),
    (TABLE[:-1] + ["-1", "--out", "t.csv"], ["--seed"]),
    (TABLE[:2] + ["0.6", "0.5"] + TABLE[3:] + ["--out", "t.csv"], ["--gamma", "ascending"]),
    (TABLE + ["--kappa", "inf", "--out", "t.csv"], ["--kappa", "finite"]),
    (EQUI[:5] + ["--modes", "1", "--out", "e"], ["--modes"]),
    # options that would be silently ignored
    (MARKOV + ["--rule", "glauber", "--solver", "fem"], ["--solver", "glauber"]),
    (MARKOV + ["--rule", "glauber", "--kappa", "100"], ["--kappa", "glauber"]),
    (["bath-figure", "7", "--kappa", "5", "--out", "f.png"], ["--kappa", "Fig. 7"]),
    (["bath-figure", "7", "--samples", "5", "--out", "f.png"], ["--samples", "Fig. 7"]),
    (["bath-figure", "4", "--workers", "2", "--out", "f.png"], ["--workers", "Fig. 4"]),
    # executors: both at once, a scheduler nobody runs (refused within the connect timeout)
    (MARKOV + ["--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], ["--workers", "--scheduler"]),
    (MARKOV + ["--scheduler", CLOSED], ["--scheduler", "cannot reach"]),
    (ENSEMBLE + ["--scheduler", CLOSED], ["--scheduler", "cannot reach"]),
    (TABLE + ["--scheduler", CLOSED, "--out", "t.csv"], ["--scheduler", "cannot reach"]),
    (["bath-figure", "8", "--samples", "4", "--scheduler", CLOSED, "--out", "f.png"], ["--scheduler", "cannot reach"]),
]


def _tree(root):
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


@pytest.fixture()
def folder(tmp_path, monkeypatch):
    """An empty working folder with a directory, a file, a FIFO and a directory holding a FIFO checkpoint."""
    (tmp_path / "adir").mkdir()
    (tmp_path / "afile.txt").write_text("x")
    os.mkfifo(tmp_path / "fifo.npz")
    (tmp_path / "fifodir").mkdir()
    os.mkfifo(tmp_path / "fifodir" / "checkpoint.npz")
    monkeypatch.chdir(tmp_path)
    # the closed scheduler port is refused after the connect timeout: 0.5 s here instead of 3 s (four cases);
    # the real timeout is tested in test_cli_endings (test_a_scheduler_at_a_closed_port_is_given_up_...)
    from wavecontact.cli import executors

    monkeypatch.setattr(executors, "CONNECT_TIMEOUT_S", 0.5)
    import importlib

    modules = [importlib.import_module(module) for module, _ in WORK]  # all imported before any is patched
    for (module, name), loaded in zip(WORK, modules):
        def refuse(*args, _name=name, **kwargs):
            raise AssertionError(f"{_name} was called: the refusal came after the work had started")

        monkeypatch.setattr(loaded, name, refuse)
    return tmp_path


def test_every_command_has_cases():
    from wavecontact.cli import COMMANDS

    assert {argv[0] for argv, _ in CASES} == set(COMMANDS)


@pytest.mark.parametrize("argv, words", CASES, ids=[" ".join(a)[:80] for a, _ in CASES])
def test_bad_input_is_refused_before_any_work(folder, capsys, argv, words):
    before = _tree(folder)
    started, wall = time.process_time(), time.monotonic()
    try:
        code = main(list(argv))
    except SystemExit as exit_:  # argparse: an option's type or choice
        code = exit_.code
    spent, waited = time.process_time() - started, time.monotonic() - wall
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert code == 2, (code, captured.err)
    assert len(lines) == 1 and lines[0].startswith("wavecontact: error:"), captured.err
    assert "Traceback" not in captured.err and captured.out == ""
    for word in words:
        assert word in lines[0], (word, lines[0])
    assert _tree(folder) == before, "a refused run wrote a file"
    assert spent < 5.0 and waited < 30.0, (spent, waited)  # refused before work, the scheduler within its timeout
