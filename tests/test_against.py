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
    assert done.returncode == 0, done.stdout + done.stderr
    rows = [line for line in done.stdout.splitlines() if line.startswith("| scene |")]
    assert len(rows) == 1, done.stdout
    cells = [cell.strip() for cell in rows[0].strip("|").split("|")]
    ratio, spread, flag = float(cells[3]), float(cells[4]), cells[5]
    assert 0.5 < ratio < 2.0 and spread >= 0.0 and flag == ""
    assert "load average" in done.stdout


def test_against_refuses_an_unknown_revision():
    done = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "against.py"),
                           "no-such-revision-xyz", "--only",
                           "scene", "--repeats", "1"], check=False, cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode != 0
    assert "no-such-revision-xyz" in done.stderr and "Traceback" not in done.stderr
