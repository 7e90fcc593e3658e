"""Fuzzing every command's arguments (hypothesis; tests/test_fuzz.py fuzzes ``collide`` with the solves).

Whatever the arguments, a command either refuses them (exit 2, one line, no traceback, nothing
written) or reaches its work; the work itself is replaced by a stand-in, so that the checks made
before it are what is exercised, fast.
"""

import importlib
import os
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_cli_bad_inputs import WORK

from wavecontact.cli import COMMANDS, main


class Reached(Exception):
    """The command got past every check to its work."""


VALUES = ["0.6", "1", "2", "0", "-1", "inf", "nan", "1e12", "1e-12", "1e300", "100", "20000", "1000000000000",
          "x", "", "adir", "afile.txt", "fifo.npz", "out.png", "out.json", "t.csv", "d", "missing/f.png",
          "1:2:3", "1:2:100000000", "0.5,2", "fixed", "vibration", "glauber", "table", "solve", "fem", "modal",
          "delay", "4", "7", "8", "9"]
OPTIONS = ["--gamma", "--kappa", "--modes", "--collisions", "--out", "--plot", "--json", "--samples", "--seed",
           "--temperature", "--rule", "--solver", "--steps", "--chains", "--workers", "--repeats", "--rods",
           "--restitution", "--lengths", "--impedance-ratio", "--time-ratio", "--bath-modes", "--page", "--only",
           "--elements", "--realisations", "--no-progress", "--max-work", "--quick", "--levels"]

#: A valid start for each command, so that the fuzz reaches the checks behind the parser.
BASES = {
    "collide": ["--gamma", "0.6", "--kappa", "20"],
    "converge": ["--gamma", "0.6", "--kappa", "20", "--elements", "10", "20"],
    "compare": ["--gamma", "0.6", "--kappa", "100"],
    "ring": ["--gamma", "0.6", "--kappa", "100", "--modes", "4", "--collisions", "8", "--out", "d"],
    "equipartition": ["--gamma", "0.6", "--kappa", "100", "--modes", "4", "--out", "d"],
    "markov": ["--gamma", "0.6"],
    "ensemble": ["--gamma", "0.6", "--kappa", "100", "--temperature", "1", "--samples", "4", "--seed", "0"],
    "bath-figure": ["4", "--out", "out.png"],
    "restitution-table": ["--gamma", "0.6", "--temperature", "1", "--samples", "4", "--seed", "0", "--out", "t.csv"],
    "gas": ["--rods", "10", "--collisions", "100", "--rule", "fixed", "--restitution", "1"],
    "map": ["--out", "d"],
    "paper-figures": ["--out", "d", "--quick"],
    "solve": [str(Path(__file__).resolve().parent.parent / "examples" / "scenes" / "hammer_on_bar.toml")],
}


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    root = tmp_path_factory.mktemp("fuzz")
    (root / "adir").mkdir()
    (root / "afile.txt").write_text("x")
    os.mkfifo(root / "fifo.npz")
    return root


def _tree(root):
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(command=st.sampled_from(sorted(COMMANDS)),
       extra=st.lists(st.one_of(st.sampled_from(OPTIONS), st.sampled_from(VALUES)), max_size=8))
def test_every_command_refuses_in_one_line_or_reaches_its_work(folder, monkeypatch, capsys, command, extra):
    def reached(*args, **kwargs):
        raise Reached

    with monkeypatch.context() as patch:
        patch.chdir(folder)
        modules = [importlib.import_module(module) for module, _ in WORK]  # imported before any is patched
        for (_module, name), loaded in zip(WORK, modules):
            patch.setattr(loaded, name, reached)
        before = _tree(folder)
        started = time.process_time()
        try:
            code = main([command, *BASES[command], *extra])
        except SystemExit as exit_:
            code = exit_.code
        except Reached:
            code = None
        spent = time.process_time() - started
        captured = capsys.readouterr()
        new = [folder / name for name in _tree(folder) if name not in before]
        files = [path for path in new if not path.is_dir()]
        for path in sorted(new, reverse=True):  # the next example starts from the same folder
            path.rmdir() if path.is_dir() else path.unlink()
    assert spent < 10.0
    assert "Traceback" not in captured.err
    assert not files, f"written before the work: {files}"
    if code is None:  # past the checks (an output folder may have been created): nothing refused
        return
    assert not new, f"a refused run created {new}"
    if code == 0:  # --help, --version
        return
    assert code == 2, (code, captured.err)
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("wavecontact: error:"), captured.err
