"""benchmarks/compile_breakdown.py: per-kernel table of the recorded compilations."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _load():
    sys.path.insert(0, str(ROOT / "benchmarks"))  # the script imports compile_times from its own folder
    return importlib.import_module("compile_breakdown")


def test_own_times_leave_callees_out_and_trees_sum_to_the_outermost_compilations():
    script = _load()
    # a leaf compiled twice (two signatures) on the way, its caller from Python, and a second kernel from Python
    rows = [{"kernel": "m.leaf", "total": 0.5, "own": 0.5, "outermost": False},
            {"kernel": "m.leaf", "total": 0.25, "own": 0.25, "outermost": False},
            {"kernel": "m.loop", "total": 3.0, "own": 2.25, "outermost": True},
            {"kernel": "m.setup", "total": 1.0, "own": 1.0, "outermost": True}]
    lines = script.table(rows, top=2)
    assert lines[2] == "| `m.loop` | 2.25 | 3.00 | 1 |"
    assert lines[3] == "| `m.setup` | 1.00 | 1.00 | 1 |"
    assert lines[4] == "| 1 more kernels | 0.75 | - | - |"  # the leaf's two specialisations
    assert lines[5].startswith("| **all** (4 specialisations of 3 kernels, 2 compiled from Python) | 4.00 | 4.00 | 4 |")
    full = script.table(rows, top=10)
    assert "| `m.leaf` | 0.75 | - | 2 |" in full
