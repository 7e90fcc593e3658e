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


def test_steel_striker_on_aluminium_bar(tmp_path):
    out = load("steel_striker_on_aluminium_bar").main(str(tmp_path))
    assert out["hard"] == pytest.approx(out["theory"]["restitution"], abs=1e-12)
    delay = out["delay"].restitution
    assert abs(out["fem"].restitution - delay) < 1e-4 and abs(out["modal"].restitution - delay) < 1e-4
    assert all(a > b for a, b in zip(out["restitution"], out["restitution"][1:]))  # towards the hard core
    assert 0.0 < out["restitution"][-1] - out["hard"] < 2e-3
    for name in ("striker_xt.png", "striker_restitution.png"):
        assert (tmp_path / name).stat().st_size > 10_000
