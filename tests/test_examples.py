"""Every example in examples/ runs and prints what it promises (scikit-fem's test_examples, our way).

Examples are found by glob, not listed here. Each one is a script with
``main(out_dir)`` returning a dict of its key numbers, and ``EXPECTED = {key: (value,
tolerance, source)}``: one of those numbers and the independent reference it must meet
(the wave theory, the paper's formulas, a value computed outside this package, or another
solver). Each must save a figure named after itself into ``out_dir``.
"""

import importlib.util
import sys
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).resolve().parent.parent / "examples").glob("[!_]*.py"))


def load(path):
    spec = importlib.util.spec_from_file_location(f"example_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def test_there_are_examples():
    assert len(EXAMPLES) >= 8


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_runs_and_meets_its_reference(path, tmp_path, capsys):
    module = load(path)
    assert module.__doc__ and f"python examples/{path.name}" in module.__doc__, "docstring says how to run it"
    expected = getattr(module, "EXPECTED", None)
    assert isinstance(expected, dict) and expected, f"{path.name} declares no EXPECTED reference"
    numbers = module.main(str(tmp_path))
    printed = capsys.readouterr().out
    assert printed.strip(), f"{path.name} printed nothing"
    for key, (value, tolerance, source) in expected.items():
        assert numbers[key] == pytest.approx(value, abs=tolerance), f"{path.name}: {key} vs {source}"
    figures = list(tmp_path.glob(f"{path.stem}*.png"))
    assert figures and all(f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for f in figures)
