"""benchmarks/against.py: the side-by-side timing of this checkout against an older revision."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_against_head_on_a_case_without_kernels_reports_a_ratio_near_one_and_no_flag():
    # HEAD against the working tree: the same code (or nearly), so the ratio is about 1 whatever the load;
    # the case builds a scene only, so neither tree compiles kernels and the test stays fast
    done = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "against.py"),
                           "HEAD", "--only", "scene",
                           "--repeats", "2"], check=False, cwd=ROOT, capture_output=True, text=True, timeout=600)
    # timing is the benchmark's business, not the test's: the flag and the exit status follow the numbers printed
    rows = [line for line in done.stdout.splitlines() if line.startswith("| scene |")]
    assert len(rows) == 1, done.stdout + done.stderr
    cells = [cell.strip() for cell in rows[0].strip("|").split("|")]
    ratio, spread, flag = float(cells[3]), float(cells[4]), cells[5]
    assert ratio > 0.0 and spread >= 0.0
    assert flag in ("", "SLOWER")
    if abs(ratio - spread - 1.10) > 2e-3:  # away from the threshold, where the printed rounding cannot decide
        assert (flag == "SLOWER") == (ratio - spread > 1.10), rows[0]
    assert done.returncode == (1 if flag else 0), done.stdout + done.stderr
    assert "load average" in done.stdout


def test_a_case_is_slower_only_beyond_ten_percent_plus_its_spread():
    import importlib.util

    spec = importlib.util.spec_from_file_location("against", ROOT / "benchmarks" / "against.py")
    against = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(against)
    assert against.judge([1.0, 1.0, 1.0]) == (1.0, 0.0, False)
    assert against.judge([1.2, 1.2, 1.2])[2]  # 20 % slower, no spread
    ratio, spread, slower = against.judge([1.0, 1.3, 1.15])  # 15 % slower but spread 0.15: within the noise
    assert (ratio, slower) == (1.15, False) and abs(spread - 0.15) < 1e-12
    assert not against.judge([0.5, 0.6])[2]


def test_against_refuses_an_unknown_revision():
    done = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "against.py"),
                           "no-such-revision-xyz", "--only",
                           "scene", "--repeats", "1"], check=False, cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode != 0
    assert "no-such-revision-xyz" in done.stderr and "Traceback" not in done.stderr


def test_a_case_doing_more_work_now_is_shown_as_such_and_does_not_set_the_exit_status():
    import importlib.util

    spec = importlib.util.spec_from_file_location("against", ROOT / "benchmarks" / "against.py")
    against = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(against)
    row = {"case": "collide-fem", "old_s": 0.0075, "new_s": 0.015, "ratio": 2.0, "spread": 0.1, "slower": True}
    assert against.regressions([row]) == ["collide-fem"]  # equal work (the default): a regression
    assert against.table_row(row, "abc").endswith("| SLOWER | equal |")
    more = {**row, "work": "more"}
    assert against.regressions([more]) == []
    assert "| SLOWER | more now: an error estimate, none at abc |" in against.table_row(more, "abc")
    assert against.regressions([more, {**row, "case": "gas"}]) == ["gas"]


def test_a_result_carries_an_estimate_or_not_or_is_no_single_result():
    # an ensemble's arrays are no single result (None); a collision result with a finite estimate is True,
    # with None (older trees) or NaN (estimate_error=False) False; a value without a restitution is None
    import importlib.util

    import numpy as np

    spec = importlib.util.spec_from_file_location("against", ROOT / "benchmarks" / "against.py")
    against = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(against)

    class Result:
        def __init__(self, restitution, estimate):
            self.restitution, self.error_estimate = restitution, estimate

    assert against.estimated(Result(np.zeros(2), np.zeros(2))) is None
    assert against.estimated(Result(0.5, 1e-9)) is True
    assert against.estimated(Result(0.5, None)) is False
    assert against.estimated(Result(0.5, float("nan"))) is False
    assert against.estimated(3) is None
    assert "def estimated(value)" in against._CHILD  # the child runs the same function
