"""Cross-solver random audit (benchmarks/cross_solver_audit.py, seeded and small): every pair of solvers of
the registry that takes a scene agrees within the sum of their stated error estimates.

Scenes of seed 2323 (the families in turn: cold, hard, two materials in random units, thermal bath), six
in the default run and the rest of 24 marked slow, plus one two-material scene of seed 5 (materials only).
The failures the audit finds today are marked xfail(strict), so that the test fails once they are fixed
and the mark is left behind:

* the modal solver with a thermal bath, and with two materials in a small time unit, is wrong with an
  estimate of 1e-11 (issue 23, items 1 and 2): the fix is on branch h/modal.

The delay solver with a bath once left the interpolation error of its noise tables out of its estimate
(2e-9 to 3e-8 against estimates near 5e-10 on scenes 3, 11 and 19 against the modal solver); it now
refines the tables until their error bound is below its tolerance and adds the bound to its estimate
(docs/error_estimates.md), and those scenes pass.
"""

import functools
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import cross_solver_audit as audit

from wavecontact.solvers import SOLVER_NAMES

SEED, SCENES = 2323, 24
FAST = (0, 1, 2, 3, 6, 7)  # cold, hard, materials, bath, materials, bath
UNITS = (5, 12, 11)  # seed 5, 12 two-material scenes: scene 11 is in a time unit of 1e-4
ELEMENTS, MODES = 400, 60
# (seed, scene, pair) that the audit found wrong (benchmarks/cross_solver_audit.py --scenes 24 --seed 2323
# --verbose, and --scenes 12 --seed 5 --families materials), each checked to fail before its fix: the modal
# solver's bath and unit defects (seed 2323 scenes 7, 23; seed 5 scene 11) and the delay solver's noise-table
# interpolation (seed 2323 scenes 3, 7, 11, 19, 23, delay-modal) are fixed, so none is expected to fail now
KNOWN: dict = {}
PAIRS = [(a, b) for i, a in enumerate(SOLVER_NAMES) for b in SOLVER_NAMES[i + 1:]]


@functools.cache
def _scene(seed, index):
    scenes, families = (SCENES, audit.FAMILIES) if seed == SEED else (UNITS[1], ("materials",))
    (record,) = audit.audit(scenes, seed, families, elements=ELEMENTS, modes=MODES, indices={index})
    return record


def _cases(keys):
    return [pytest.param(seed, index, pair, marks=[KNOWN[(seed, index, pair)]] if (seed, index, pair) in KNOWN else [],
                         id=f"seed{seed}-scene{index}-{pair[0]}-{pair[1]}")
            for seed, index in keys for pair in PAIRS]


def _check(seed, index, pair):
    record = _scene(seed, index)
    verdicts = [p for p in record["pairs"] if p[:2] == pair]
    if not verdicts:  # one of the two does not take the scene (the registry decides)
        statuses = {name: record["runs"][name]["status"] for name in pair}
        assert "unsupported" in statuses.values(), statuses
        return
    a, b, outcome, difference, allowed = verdicts[0]
    assert outcome != "no estimate", (record["code"], record["runs"][a]["method"], record["runs"][b]["method"])
    assert difference <= allowed, audit.reproducer(record["drawn"], record["runs"], a, b)


@pytest.mark.parametrize("seed, index, pair", _cases([(SEED, i) for i in FAST] + [UNITS[::2]]))
def test_pairs_agree_within_their_estimates(seed, index, pair):
    _check(seed, index, pair)


@pytest.mark.slow
@pytest.mark.parametrize("seed, index, pair", _cases([(SEED, i) for i in range(SCENES) if i not in FAST]))
def test_pairs_agree_within_their_estimates_slow(seed, index, pair):
    _check(seed, index, pair)


def test_every_solver_takes_the_two_rod_scenes():
    # the registry's three solvers all take two rods on a line, cold, hard, two materials or with a bath
    for index in FAST:
        assert {run["status"] for run in _scene(SEED, index)["runs"].values()} == {"ok"}, index


def test_audit_sees_a_wrong_estimate():
    # the audit's own check fails where it should: a pair whose difference exceeds the summed estimates
    runs = {"delay": {"status": "ok", "restitution": 0.5, "estimate": 1e-10},
            "fem": {"status": "ok", "restitution": 0.5 + 3e-10, "estimate": 1e-10},
            "modal": {"status": "unsupported"}}
    assert audit.compare(runs) == [("delay", "fem", "disagree", pytest.approx(3e-10), 2e-10)]
