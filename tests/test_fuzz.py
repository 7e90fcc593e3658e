"""Fuzzing the public entry points (hypothesis): whatever the input, collide, solve and the
CLI either return a finite restitution in [0, 1 + error estimate] or raise a WavecontactError
(argparse's SystemExit for the CLI), within a time bound."""

import math
import time

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from wavecontact import Rod, Scene, collide, solve
from wavecontact.cli import main
from wavecontact.contact import Exponential, Hard, Penalty
from wavecontact.errors import WavecontactError

BOUND = 20.0  # CPU seconds per example, small resolutions (kernels compiled by the fixture below); CPU time, which load does not stretch
SMALL_WORK = 2e8  # max_work of every call: larger requests are refused (LimitError), not run

numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(min_value=1e-3, max_value=1e3),
    st.integers(min_value=-10, max_value=10**7),
    st.sampled_from([None, "1", "x", True, [1.0], 0, -1]),
)
gammas = st.one_of(st.floats(min_value=0.05, max_value=1.0), numbers)
kappas = st.one_of(st.floats(min_value=0.1, max_value=1e5), st.just(math.inf), numbers)


@pytest.fixture(scope="module", autouse=True)
def _compiled():
    """Compile (or load) every solver's kernels once, so the time bound measures the solve."""
    for solver, options in (("delay", {}), ("fem", {"elements": 10}), ("modal", {"modes": 10})):
        for kappa, contact in ((20.0, "exponential"), (math.inf, "hard"), (20.0, "penalty")):
            try:
                collide(0.6, kappa, solver=solver, contact=contact, **options)
            except WavecontactError:
                pass


def _options(solver, draw_value):
    return {"delay": {"rtol": draw_value},
            "fem": {"elements": draw_value, "order": 1},
            "modal": {"modes": draw_value, "history": False}}[solver]


def _check(result):
    assert math.isfinite(result.restitution)
    assert 0.0 <= result.restitution <= 1.0 + result.error_estimate
    assert result.error_estimate >= 0.0


small = st.one_of(st.integers(min_value=10, max_value=40), numbers)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(gamma=gammas, kappa=kappas, solver=st.sampled_from(["delay", "fem", "modal"]), value=small,
       contact=st.sampled_from(["exponential", "penalty", "hard", 3]))
def test_collide_never_raises_anything_else(gamma, kappa, solver, value, contact):
    if solver == "delay" and isinstance(value, int) and not isinstance(value, bool):
        value = 10.0 ** -(abs(value) % 12 + 2)
    start = time.process_time()
    try:
        result = collide(gamma, kappa, solver=solver, contact=contact, max_work=SMALL_WORK,
                         **_options(solver, value))
    except WavecontactError:
        pass
    else:
        _check(result)
    assert time.process_time() - start < BOUND


lengths = st.one_of(st.floats(min_value=0.3, max_value=3.0), numbers)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(l1=lengths, l2=lengths, v=numbers, law=st.sampled_from(["exp", "hard", "penalty"]),
       solver=st.sampled_from(["fem", "modal", "delay"]))
def test_solve_never_raises_anything_else(l1, l2, v, law, solver):
    start = time.process_time()
    try:
        contact = {"exp": lambda: Exponential(20.0, 1e-3), "hard": Hard, "penalty": Penalty}[law]()
        scene = Scene(rods=(Rod(l1), Rod(l2)), velocities=(v, 0.0), contact=contact)
        options = {"fem": {"elements": 20}, "modal": {"modes": 20}, "delay": {}}[solver]
        result = solve(scene, solver, max_work=SMALL_WORK, **options)
    except WavecontactError:
        pass
    else:
        _check(result)
    assert time.process_time() - start < BOUND


tokens = st.sampled_from(["--max-work", "2e8", "--gamma", "--kappa", "--solver", "--elements", "--modes", "--rtol", "--order",
                          "--tolerance", "--max-work", "--json", "0.6", "20", "inf", "nan", "-1", "1e300",
                          "fem", "modal", "delay", "12", "x", "0", "1e-12"])


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(argv=st.lists(tokens, max_size=8))
def test_cli_never_raises_anything_else(argv, capsys):
    start = time.process_time()
    try:
        code = main(["collide", *argv])
    except SystemExit as exit_:
        assert exit_.code in (0, 2)
    else:
        assert code in (0, 2)
    capsys.readouterr()
    assert time.process_time() - start < BOUND
