"""Every example in examples/ runs and prints what it promises (scikit-fem's test_examples, our way).

Examples are found by glob, not listed here. Each one is a script with
``main(out_dir)`` returning a dict of its key numbers, and ``EXPECTED = {key: (value,
tolerance, source)}``: one of those numbers and the independent reference it must meet
(the wave theory, the paper's formulas, a value computed outside this package, or another
solver). Each must save at least one PNG figure into ``out_dir``. Each example runs once;
the tests below share its output.
"""

import importlib.util
import os
import runpy
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = sorted((ROOT / "examples").glob("[!_]*.py"))
_RUNS = {}


def tree_state():
    """What running an example must not change: the files of the current directory and, in a git
    checkout, ``git status`` of the repository (untracked files included, ignored ones not)."""
    listing = sorted(os.listdir("."))
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        return listing, None
    status = subprocess.run(["git", "status", "--porcelain", "--untracked-files=all"], cwd=ROOT,
                            capture_output=True, text=True, check=True).stdout
    return listing, status


def load(path):
    spec = importlib.util.spec_from_file_location(f"example_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def run_example(tmp_path_factory):
    """``run_example(path) -> (module, numbers, printed, out_dir, tree)``, each example run once;
    ``tree`` is the state of the working tree before and after (:func:`tree_state`)."""

    def run(path):
        if path not in _RUNS:
            module = load(path)
            out = tmp_path_factory.mktemp(path.stem)
            import contextlib
            import io

            printed = io.StringIO()
            before = tree_state()
            with contextlib.redirect_stdout(printed):
                numbers = module.main(str(out))
            _RUNS[path] = (module, numbers, printed.getvalue(), out, (before, tree_state()))
        return _RUNS[path]

    return run


def test_there_are_examples():
    assert len(EXAMPLES) >= 8


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_runs_and_meets_its_reference(path, run_example):
    module, numbers, printed, out, (before, after) = run_example(path)
    new = [sorted(set(b.splitlines() if isinstance(b, str) else b) - set(a.splitlines() if isinstance(a, str) else a))
           for a, b in zip(before, after) if a is not None]
    assert after == before, f"{path.name} wrote outside its output folder: {new}"
    assert module.__doc__ and f"python examples/{path.name}" in module.__doc__, "docstring says how to run it"
    expected = getattr(module, "EXPECTED", None)
    assert isinstance(expected, dict) and expected, f"{path.name} declares no EXPECTED reference"
    assert printed.strip(), f"{path.name} printed nothing"
    for key, (value, tolerance, source) in expected.items():
        assert numbers[key] == pytest.approx(value, abs=tolerance), f"{path.name}: {key} vs {source}"
    figures = list(out.glob("*.png"))
    assert figures and all(f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for f in figures)


def test_steel_striker_on_aluminium_bar(run_example):
    path = next(p for p in EXAMPLES if p.stem == "steel_striker_on_aluminium_bar")
    _, out, _, directory, _ = run_example(path)
    assert out["hard"] == pytest.approx(out["theory"]["restitution"], abs=1e-12)
    delay = out["delay"].restitution
    assert abs(out["fem"].restitution - delay) < 1e-4 and abs(out["modal"].restitution - delay) < 1e-4
    assert all(a > b for a, b in zip(out["restitution"], out["restitution"][1:]))  # towards the hard core
    assert 0.0 < out["restitution"][-1] - out["hard"] < 2e-3
    for name in ("striker_xt.png", "striker_restitution.png"):
        assert (directory / name).stat().st_size > 10_000


def test_an_example_run_as_a_script_writes_into_examples_output_only(tmp_path, monkeypatch, capsys):
    """``python examples/NAME.py`` from any directory: its files go to ``examples_output/`` there, nothing else
    appears in that directory, and the repository's working tree is unchanged. ``--out DIR`` is run in this
    process (the script's ``__main__`` block with that command line), the default in a fresh interpreter."""
    before = tree_state()[1]
    script = ROOT / "examples" / "restitution_vs_kappa.py"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
           "MPLBACKEND": "Agg"}
    done = subprocess.run([sys.executable, str(script)], cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=600, check=False)
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["examples_output"]
    assert (tmp_path / "examples_output" / "restitution_vs_kappa.png").stat().st_size > 10_000
    assert "figure: examples_output/restitution_vs_kappa.png" in done.stdout
    other = tmp_path / "elsewhere"
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(script.parent))  # as for a script: its folder first on the path
    monkeypatch.setattr(sys, "argv", [str(script), "--out", str(other)])
    runpy.run_path(str(script), run_name="__main__")
    assert (other / "restitution_vs_kappa.png").exists() and f"figure: {other}" in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["elsewhere", "examples_output"]
    assert tree_state()[1] == before


def test_examples_output_is_ignored_by_git():
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    done = subprocess.run(["git", "check-ignore", "-q", "examples_output/figure.png"], cwd=ROOT, check=False)
    assert done.returncode == 0, ".gitignore does not cover examples_output/"
