"""Every example in examples/ runs and prints what it promises (scikit-fem's test_examples, our way).

Examples are found by glob, not listed here. Each one is a script with
``main(out_dir)`` returning a dict of its key numbers, and ``EXPECTED = {key: (value,
tolerance, source)}``: one of those numbers and the independent reference it must meet
(the wave theory, the paper's formulas, a value computed outside this package, or another
solver). Each must save at least one PNG figure into ``out_dir``. Each example runs once;
the tests below share its output.
"""

import importlib.util
import sys
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).resolve().parent.parent / "examples").glob("[!_]*.py"))
_RUNS = {}


def load(path):
    spec = importlib.util.spec_from_file_location(f"example_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def run_example(tmp_path_factory):
    """``run_example(path) -> (module, numbers, printed, out_dir)``, each example run once."""

    def run(path):
        if path not in _RUNS:
            module = load(path)
            out = tmp_path_factory.mktemp(path.stem)
            import contextlib
            import io

            printed = io.StringIO()
            with contextlib.redirect_stdout(printed):
                numbers = module.main(str(out))
            _RUNS[path] = (module, numbers, printed.getvalue(), out)
        return _RUNS[path]

    return run


def test_there_are_examples():
    assert len(EXAMPLES) >= 8


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_runs_and_meets_its_reference(path, run_example):
    module, numbers, printed, out = run_example(path)
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
    _, out, _, directory = run_example(path)
    assert out["hard"] == pytest.approx(out["theory"]["restitution"], abs=1e-12)
    delay = out["delay"].restitution
    assert abs(out["fem"].restitution - delay) < 1e-4 and abs(out["modal"].restitution - delay) < 1e-4
    assert all(a > b for a, b in zip(out["restitution"], out["restitution"][1:]))  # towards the hard core
    assert 0.0 < out["restitution"][-1] - out["hard"] < 2e-3
    for name in ("striker_xt.png", "striker_restitution.png"):
        assert (directory / name).stat().st_size > 10_000
