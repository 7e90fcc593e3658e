"""Limits before work (wavecontact/limits.py): every oversized or endless request is refused
fast, with the estimate and the option that raises the limit, before anything is allocated."""

import math
import time

import pytest

import wavecontact
from wavecontact import Rod, Scene, collide, solve
from wavecontact.cli import main
from wavecontact.contact import Hard
from wavecontact.errors import InvalidParameterError, LimitError, WavecontactError
from wavecontact.limits import KAPPA_MAX, KAPPA_MIN, Cost, Limits, available_memory, check_cost

FAST = 1.0  # seconds: a refusal must come well before any real work


@pytest.fixture(scope="module", autouse=True)
def _warm():
    """Import every solver once, so the timings below measure the refusal only."""
    collide(0.6, math.inf)
    for name in ("fem", "modal"):
        wavecontact.solvers.get_solver(name)


def refused(call, *match):
    start = time.process_time()
    with pytest.raises(WavecontactError) as info:
        call()
    elapsed = time.process_time() - start
    assert elapsed < FAST, f"refusal took {elapsed:.2f} s"
    message = str(info.value)
    assert "\n" not in message
    for word in match:
        assert word in message, message
    return info.value


def test_modes_ten_million_is_refused():
    refused(lambda: collide(0.6, 20, solver="modal", modes=10**7), "modes", "20000")


def test_ring_with_a_hundred_thousand_modes_is_refused(capsys, tmp_path):
    start = time.process_time()
    code = main(["ring", "--gamma", "0.6", "--kappa", "100", "--modes", "100000", "--collisions", "10",
                 "--out", str(tmp_path / "ring")])
    assert time.process_time() - start < FAST
    assert code == 2
    assert "modes" in capsys.readouterr().err


def test_rods_of_lengths_one_and_a_billionth_are_refused_by_memory():
    scene = Scene(rods=(Rod(1.0), Rod(1e-9)), velocities=(1.0, 0.0), contact=Hard())
    error = refused(lambda: solve(scene, "fem"), "max_memory", "nodes")
    assert isinstance(error, LimitError)


def test_tiny_gamma_is_refused_by_every_solver_or_bounded():
    refused(lambda: collide(1e-6, 20), "gamma", "square")
    refused(lambda: collide(1e-6, 20, solver="fem"), "max_")
    # the modal solver keeps a fixed number of modes per rod: it ends (or is refused) quickly
    start = time.process_time()
    try:
        collide(1e-6, 20, solver="modal", modes=20)
    except WavecontactError:
        pass
    assert time.process_time() - start < 10.0


def test_fem_courant_and_dt_too_small_are_refused():
    refused(lambda: collide(0.6, 20, solver="fem", courant=1e-9), "courant")
    refused(lambda: collide(0.6, 20, solver="fem", courant=1e-6), "max_")
    refused(lambda: collide(0.6, 20, solver="fem", dt=1e-12), "max_", "dt")


def test_end_time_beyond_the_step_limit_is_refused():
    error = refused(lambda: collide(0.6, 20, end_time=1e9), "end_time", "max_steps")
    assert isinstance(error, LimitError)


def test_a_million_elements_is_refused_with_the_estimate_and_the_option():
    error = refused(lambda: collide(0.6, 20, solver="fem", elements=10**6), "max_work=", "updates")
    assert isinstance(error, LimitError)


def test_limits_can_be_raised_explicitly():
    # the refusal of a million elements comes from max_work: raising it passes the check
    # (checked on the estimate alone; the run itself would take hours)
    fem = wavecontact.solvers.get_solver("fem")
    cost = fem.estimate_cost(wavecontact.two_rods(0.6, 20), fem.Options(elements=10**6))
    check_cost("fem", cost, Limits(max_work=2 * cost.work, max_memory=2 * cost.memory))
    with pytest.raises(LimitError, match="max_memory"):
        check_cost("fem", Cost(steps=1, work=1, memory=10.0), Limits(max_memory=5.0))


def test_the_work_limit_counts_the_error_estimates_runs():
    # below 32 elements the FE estimate runs 2N elements (four times the work) and N/2:
    # a limit between the requested run's work and the total refuses the estimate, not the bare run
    fem = wavecontact.solvers.get_solver("fem")
    scene, options = wavecontact.two_rods(0.6, 20), fem.Options(elements=20)
    alone = fem.estimate_cost(scene, options).work
    total = fem.total_cost(scene, options, estimating=True).work
    assert total > 4 * alone  # the 2N run has twice the nodes and twice the steps
    limit = 2 * alone
    assert collide(0.6, 20, solver="fem", elements=20, max_work=limit, estimate_error=False).restitution > 0
    error = refused(lambda: collide(0.6, 20, solver="fem", elements=20, max_work=limit), "max_work=", "error estimate")
    assert isinstance(error, LimitError)


@pytest.mark.parametrize("kappa", [1e-6, 1e-3, 0.999 * KAPPA_MIN, 1.001 * KAPPA_MAX, 1e10, 1e300])
def test_kappa_outside_the_supported_range_is_refused_up_front(kappa):
    error = refused(lambda: collide(0.6, kappa), "kappa", "inf")
    assert "strength" not in str(error)


@pytest.mark.parametrize("kappa", [1e-3, 1.001 * KAPPA_MAX])
def test_two_rods_refuses_kappa_outside_the_range_where_the_scene_is_built(kappa):
    error = refused(lambda: wavecontact.two_rods(0.6, kappa), "kappa", "inf")
    assert "strength" not in str(error)


def test_kappa_is_checked_once_along_a_collide_call(monkeypatch):
    # issue 25: the range check runs where the Scene is built, not again in collide or the solver
    import wavecontact.limits
    import wavecontact.scene
    import wavecontact.solvers.base

    calls = []

    def counted(kappa, name="kappa"):
        calls.append(kappa)
        return wavecontact.limits.check_kappa(kappa, name)

    for module in (wavecontact.scene, wavecontact.solvers.base):
        monkeypatch.setattr(module, "check_kappa", counted)
    assert collide(0.6, 37.25).restitution > 0  # a kappa no other test builds: not a cached scene
    assert calls == [37.25]


def test_kappa_inside_the_range_runs():
    assert 0.0 < collide(0.6, 1e6).restitution - 0.6 < 2e-5  # Eq. 23: ln(kappa (Gamma_2 - Gamma_1))/kappa


@pytest.mark.parametrize("kappa", [KAPPA_MIN, 0.03, 0.1])
@pytest.mark.parametrize("gamma", [0.05, 0.6])
def test_epsilon_never_exceeds_one_by_more_than_its_estimate(gamma, kappa):
    result = collide(gamma, kappa)
    assert result.restitution - 1.0 <= result.error_estimate


def test_order_as_a_float_is_accepted_or_refused_cleanly():
    assert collide(0.6, 20, solver="fem", elements=20, order=1.0).options["order"] == 1
    refused(lambda: collide(0.6, 20, solver="fem", order=1.5), "order")


def test_limit_values_are_validated():
    for bad in (0, -1.0, math.nan, "a lot", True):
        with pytest.raises(InvalidParameterError, match="max_work"):
            collide(0.6, 20, max_work=bad)
    assert available_memory() > 0


@pytest.mark.parametrize("name", ["length", "density", "youngs_modulus", "area"])
def test_rod_quantities_outside_double_range_products_are_refused(name):
    # found by the fuzz test: a rod 1e304 long overflowed inside the FE set-up (c^2 / h^2)
    for value in (1e304, 1e-304):
        with pytest.raises(InvalidParameterError, match=f"rod {name} must lie in \\[1e-30, 1e\\+30\\]"):
            Rod(**{"length": 1.0, name: value})
    Rod(**{"length": 1.0, name: 1e30})


def test_velocity_beyond_the_range_is_refused():
    with pytest.raises(InvalidParameterError, match="velocities\\[0\\]"):
        Scene(rods=(Rod(1.0), Rod(1.0)), velocities=(1e31, 0.0), contact=Hard())


def test_modal_echo_sums_of_a_tiny_length_ratio_are_refused_before_work():
    # found by the fuzz test: rods 493.8 and 0.4 with hard contact ran for minutes, because each
    # collocation step of the end-response correction sums one echo per short-rod round trip
    scene = Scene(rods=(Rod(493.8), Rod(0.40)), velocities=(1.0, 0.0), contact=Hard())
    error = refused(lambda: solve(scene, "modal", modes=20, max_work=2e8), "echoes", "max_work=")
    assert isinstance(error, LimitError)
