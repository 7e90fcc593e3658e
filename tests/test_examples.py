"""Every example runs and prints what it promises."""

import importlib.util
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_restitution_vs_kappa(tmp_path):
    restitution = load("restitution_vs_kappa").main(str(tmp_path / "fig5.png"))
    assert (tmp_path / "fig5.png").stat().st_size > 1000
    assert restitution[0] == pytest.approx(1.0, abs=1e-6)  # soft limit
    assert abs(restitution[-1] - 0.6) < 2e-3  # hard limit approached


def test_hard_core_collision():
    result = load("hard_core_collision").main()
    assert result.restitution == pytest.approx(0.6, abs=1e-12)
