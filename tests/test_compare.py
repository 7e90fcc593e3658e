"""Regression guard for the cross-solver comparison: agreement and the ordering of errors (not times)."""

import json
import math

import pytest

from wavecontact.cli import main
from wavecontact.studies.compare import Method, compare_solvers

SMALL = [
    Method("delay", {"rtol": 1e-4}),
    Method("delay", {"rtol": 1e-9}),
    Method("fem", {"elements": 50, "order": 1, "mass": "lumped"}, work_unit="element_steps"),
    Method("fem", {"elements": 200, "order": 1, "mass": "lumped"}, work_unit="element_steps"),
    Method("modal", {"modes": 20, "correction": "static"}),
    Method("modal", {"modes": 80, "correction": "static"}),
    Method("modal", {"modes": 80, "correction": "none", "static_correction": False}),
]


@pytest.fixture(scope="module")
def table():
    return compare_solvers(0.6, 20.0, SMALL, progress=False)


def test_reference_is_the_independent_value(table):
    # checked against an independent Radau method of steps in test_delay_solver.py
    assert table.reference == pytest.approx(0.7530132413, abs=1e-9)


def test_every_solver_agrees_with_the_reference(table):
    assert all(row.ok for row in table.rows), [row.status for row in table.rows]
    by_label = {(row.solver, row.resolution): row for row in table.rows}
    assert by_label[("delay", "rtol=1e-09")].error < 1e-10
    assert by_label[("fem", "elements=200, order=1, mass=lumped")].error < 1e-4
    assert by_label[("modal", "modes=80, correction=static")].error < 1e-4


def test_errors_shrink_with_resolution(table):
    rows = table.rows
    assert rows[1].error < rows[0].error  # delay: tighter tolerance
    assert rows[3].error < rows[2].error  # fem: finer mesh
    assert rows[5].error < rows[4].error  # modal: more modes
    assert rows[5].error < rows[6].error  # the static correction helps at equal N


def test_failures_are_rows_with_a_message():
    table = compare_solvers(0.6, 20.0, [Method("delay", {"rtol": 5.0})], progress=False)
    (row,) = table.rows
    assert not row.ok and "rtol" in row.status and row.restitution is None


def test_cli_json(capsys):
    assert main(["compare", "--gamma", "0.6", "--kappa", "inf", "--json", "--no-progress"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["kappa"] == "inf" and record["reference"] == pytest.approx(0.6, abs=1e-12)
    finite = [r for r in record["rows"] if r["status"] == "ok"]
    assert finite and all(math.isfinite(r["restitution"]) for r in finite)


def test_calls_that_prepare_kernels_are_not_timed(monkeypatch):
    """Each discretization's first call may compile its own kernels (P1 consistent after P1 lumped):
    that call is repeated, whichever method it falls on."""
    import time

    from wavecontact.result import CollisionResult
    from wavecontact.studies import compare

    calls = []

    def fake_collide(gamma, kappa, solver="delay", **options):
        key = (solver, tuple(sorted(options.items())))
        preparing = key not in calls and solver == "fem"
        calls.append(key)
        if preparing:
            time.sleep(0.3)  # stands for numba's compilation
        result = CollisionResult(restitution=0.7, solver=solver, wall_time_s=0.0, time=[0.0],
                                 relative_velocity=[-1.0])
        result.diagnostics["includes_kernel_preparation"] = preparing
        return result

    monkeypatch.setattr(compare, "collide", fake_collide)
    methods = [Method("fem", {"elements": 50, "order": 1, "mass": "lumped"}),
               Method("fem", {"elements": 50, "order": 1, "mass": "consistent"})]
    table = compare.compare_solvers(0.6, 20.0, methods, progress=False)
    assert all(row.wall_time_s < 0.1 for row in table.rows), [row.wall_time_s for row in table.rows]
