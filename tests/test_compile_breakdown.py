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
    rows = [{"kernel": "m.leaf", "total": 0.5, "own": 0.5, "llvm": 0.25, "outermost": False},
            {"kernel": "m.leaf", "total": 0.25, "own": 0.25, "llvm": 0.125, "outermost": False},
            {"kernel": "m.loop", "total": 3.0, "own": 2.25, "llvm": 1.0, "outermost": True},
            {"kernel": "m.setup", "total": 1.0, "own": 1.0, "llvm": 0.5, "outermost": True}]
    lines = script.table(rows, top=2)
    assert lines[2] == "| `m.loop` | 2.25 | 1.00 | 3.00 | 1 |"
    assert lines[3] == "| `m.setup` | 1.00 | 0.50 | 1.00 | 1 |"
    assert lines[4] == "| 1 more kernels | 0.75 | 0.38 | - | - |"  # the leaf's two specialisations
    assert lines[5].startswith("| **all** (4 specialisations of 3 kernels, 2 compiled from Python) | 4.00 | 1.88 | 4.00 "
                               "| 4 |")
    full = script.table(rows, top=10)
    assert "| `m.leaf` | 0.75 | 0.38 | - | 2 |" in full


def test_phases_split_the_outermost_compilations_between_llvm_and_the_front_end():
    script = _load()
    rows = [{"kernel": "m.leaf", "total": 0.5, "own": 0.5, "llvm": 0.25, "outermost": False},
            {"kernel": "m.loop", "total": 3.0, "own": 2.5, "llvm": 1.0, "outermost": True}]
    llvm = {"function passes": 0.25, "module passes": 0.5, "machine code": 0.5}
    sentence = script.phases(rows, llvm)
    assert sentence.startswith("Of the 3.00 s: LLVM 1.25 s (function passes 0.25 s, module passes 0.50 s, machine "
                               "code 0.50 s)")
    assert sentence.endswith(" 1.75 s.")


def test_a_recorded_run_times_llvm_inside_the_compilations():
    """The child's wrappers around numba's code library see real compilations: LLVM time is part of each
    kernel's own time, and the phases sum to the rows' LLVM column."""
    script = _load()
    report = script.record("collide --gamma 0.6 --kappa 100")
    rows, llvm = report["rows"], report["llvm"]
    assert rows and set(llvm) == {"function passes", "module passes", "machine code"}
    assert all(0.0 <= row["llvm"] <= row["own"] + 1e-9 for row in rows)
    assert all(seconds > 0.0 for seconds in llvm.values())
    assert abs(sum(llvm.values()) - sum(row["llvm"] for row in rows)) < 1e-6
