"""benchmarks/compile_times.py --only ... --update-docs rewrites only the rows it measured again."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _load():
    spec = importlib.util.spec_from_file_location("compile_times_script", ROOT / "benchmarks" / "compile_times.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def test_rerun_rows_replace_their_own_rows_only():
    script = _load()
    block = ("`python benchmarks/compile_times.py`: load average 1.0 on 2 cores at the start.\n\n"
             "| command (`wavecontact ...`) | compile CPU (s) |\n|---|---|\n"
             "| `collide --gamma 0.6 --kappa 100` | 9.29 |\n| `converge --gamma 0.6` | 50.6 |\n"
             "| `collide --gamma 0.6 --kappa inf` | 4.56 |\n")
    fresh = ("| command (`wavecontact ...`) | compile CPU (s) |\n|---|---|\n"
             "| `collide --gamma 0.6 --kappa inf` | 2.79 |\n| `map --kappa inf 100` | 5.38 |\n")
    merged = script.merged_rows(block, fresh, "`python benchmarks/compile_times.py --only collide-inf map`: load 4.")
    lines = merged.splitlines()
    assert lines[0].startswith("`python benchmarks/compile_times.py`: load average 1.0")
    assert lines[1] == "The rows of `python benchmarks/compile_times.py --only collide-inf map`: load 4."
    rows = [line for line in lines if line.startswith("| `")]
    assert rows == ["| `collide --gamma 0.6 --kappa 100` | 9.29 |", "| `converge --gamma 0.6` | 50.6 |",
                    "| `collide --gamma 0.6 --kappa inf` | 2.79 |", "| `map --kappa inf 100` | 5.38 |"]
    assert script.read_block("performance.md", "compile-times").count("| `collide --gamma 0.6 --kappa 100`") == 1


def test_a_header_whose_rows_were_all_measured_again_is_dropped():
    script = _load()
    block = ("`python benchmarks/compile_times.py`: load average 1.0 on 2 cores at the start.\n"
             "The rows of `python benchmarks/compile_times.py --only gas`: load 1.8.\n"
             "The rows of `python benchmarks/compile_times.py --only converge gas`: load 1.1.\n\n"
             "| command (`wavecontact ...`) | compile CPU (s) |\n|---|---|\n"
             "| `gas --rods 50` | 10.4 |\n| `converge --gamma 0.6` | 28.0 |\n")
    fresh = "| command (`wavecontact ...`) | compile CPU (s) |\n|---|---|\n| `gas --rods 50` | 11.2 |\n"
    merged = script.merged_rows(block, fresh, "`python benchmarks/compile_times.py --only collide-100 gas`: load 0.7.")
    headers = [line for line in merged.splitlines() if line.startswith("The rows of")]
    # the `--only gas` line describes no row any more; the converge row still comes from the older run
    assert headers == ["The rows of `python benchmarks/compile_times.py --only collide-100 gas`: load 0.7.",
                       "The rows of `python benchmarks/compile_times.py --only converge gas`: load 1.1."]
