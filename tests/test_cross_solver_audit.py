"""Cross-solver random audit (benchmarks/cross_solver_audit.py, seeded and small): every pair of solvers of
the registry that takes a scene agrees within the sum of their stated error estimates.

The FE estimate bounds its error in about 97 % of random collisions and is never off by more than a
factor 10 (docs/error_estimates.md section 2): a pair with FE is held to ten times the summed estimates
one by one, and to the sum in all but a few of the pairs together.  The modal solver with a thermal bath
and with two materials in small units is wrong with an estimate of 1e-11 (issue 23, items 1 and 2); its
pairs on those scenes are marked xfail(strict) until the fix on branch h/modal is merged."""

import functools
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import cross_solver_audit as audit

from wavecontact.solvers import SOLVER_NAMES

SEED = 2323
FAST = (0, 1, 2, 3, 4, 6)  # of the slow sample's scenes: cold, hard, materials, bath, cold, materials
SCENES = 24
ELEMENTS, MODES = 400, 60
MODAL_FIX = pytest.mark.xfail(strict=True, reason="modal bath/two-material fix on branch h/modal")
# (scene, pair) the audit finds wrong today: the modal solver with a bath (item 1) and with two materials
# in a small time unit (item 2); filled in from the audit's output, each one checked to fail
MODAL_FAILURES = {
    (3, ("delay", "modal")), (3, ("fem", "modal")),
}


@functools.cache
def _scene(index):
    (record,) = audit.audit(SCENES, SEED, elements=ELEMENTS, modes=MODES, indices={index})
    return record


def _pair(index, pair):
    record = _scene(index)
    verdicts = [p for p in record["pairs"] if p[:2] == pair]
    return record, verdicts[0] if verdicts else None


def _cases(indices):
    cases = []
    for index in indices:
        for pair in ((a, b) for i, a in enumerate(SOLVER_NAMES) for b in SOLVER_NAMES[i + 1:]):
            marks = [MODAL_FIX] if (index, pair) in MODAL_FAILURES else []
            cases.append(pytest.param(index, pair, marks=marks, id=f"scene{index}-{pair[0]}-{pair[1]}"))
    return cases


def _check(index, pair):
    record, verdict = _pair(index, pair)
    if verdict is None:  # one of the two does not take the scene (the registry decides)
        statuses = {name: record["runs"][name]["status"] for name in pair}
        assert "unsupported" in statuses.values(), statuses
        return
    a, b, outcome, difference, allowed = verdict
    assert outcome != "no estimate", (record["code"], record["runs"][a]["method"], record["runs"][b]["method"])
    bound = 10.0 * allowed if "fem" in pair else allowed
    assert difference <= bound, audit.reproducer(record["drawn"], record["runs"], a, b)


@pytest.mark.parametrize("index, pair", _cases(FAST))
def test_pairs_agree_within_their_estimates(index, pair):
    _check(index, pair)


@pytest.mark.slow
@pytest.mark.parametrize("index, pair", _cases([i for i in range(SCENES) if i not in FAST]))
def test_pairs_agree_within_their_estimates_slow(index, pair):
    _check(index, pair)


def test_every_solver_takes_the_two_rod_scenes():
    # the registry's three solvers all take two rods on a line, cold, hard, two materials or with a bath
    for index in FAST:
        assert {run["status"] for run in _scene(index)["runs"].values()} == {"ok"}, index


def test_pairs_with_fem_agree_within_the_sum_in_most_scenes():
    # the FE estimate's coverage (0.97 on the acceptance sweeps): at most one of the fast sample's pairs with FE
    # outside the summed estimates (a pair the other solver gets wrong is excluded: it is listed above)
    outside = [(index, verdict) for index in FAST for verdict in _scene(index)["pairs"]
               if "fem" in verdict[:2] and (index, verdict[:2]) not in MODAL_FAILURES and verdict[2] == "disagree"]
    assert len(outside) <= 1, outside


def test_audit_sees_a_wrong_estimate():
    # the audit's own check fails where it should: a pair whose difference exceeds the summed estimates
    runs = {"delay": {"status": "ok", "restitution": 0.5, "estimate": 1e-10},
            "fem": {"status": "ok", "restitution": 0.5 + 3e-10, "estimate": 1e-10},
            "modal": {"status": "unsupported"}}
    assert audit.compare(runs) == [("delay", "fem", "disagree", pytest.approx(3e-10), 2e-10)]
