"""The bounds the commands check before work hold for the runs they bound, and refuse with bound and advice."""

import math

import pytest

from wavecontact.cli import costs
from wavecontact.errors import LimitError
from wavecontact.limits import Cost, Limits, check_study_cost


@pytest.mark.parametrize("gamma", [0.2, 0.6, 1.0])
@pytest.mark.parametrize("kappa", [0.01, 0.1, 1.0, 100.0, 1e4, math.inf])
def test_ring_collisions_take_at_most_the_stated_steps_per_mode(gamma, kappa):
    """ring_cost counts ring_steps(kappa, N) steps per collision: the integrator's own step counter stays below."""
    from wavecontact.scene import two_rods_on_a_ring
    from wavecontact.solvers import get_solver

    engine = get_solver("modal")
    for modes in (8, 40):
        simulation = engine.simulate(two_rods_on_a_ring(gamma, kappa), engine.options({"modes": modes}))
        steps = [simulation.next_collision().steps for _ in range(3)]
        assert max(steps) <= costs.ring_steps(kappa, modes), (gamma, kappa, modes, steps)


def test_ring_cost_adds_every_mode_count_and_copy():
    per_mode = costs.RING_STEPS_PER_MODE + costs.RING_SOFT_STEPS_PER_MODE / 4.0
    one = costs.ring_cost(4.0, [10], 7)
    assert one.work == pytest.approx(per_mode * 10 * 20 * 7, rel=1e-12)
    both = costs.ring_cost(4.0, [10, 20], 7, copies=3)
    assert both.work == pytest.approx(3 * (one.work + per_mode * 20 * 40 * 7), rel=1e-12)


def test_compare_cost_is_the_sum_of_the_solvers_own_estimates():
    from wavecontact.scene import two_rods
    from wavecontact.solvers import get_solver
    from wavecontact.studies.compare import default_methods

    total = 0.0
    for method in default_methods(100.0):
        engine = get_solver(method.solver)
        cost = engine.total_cost(two_rods(0.6, 100.0), engine.options(dict(method.options)), True)
        total += 0.0 if cost is None else cost.work
    assert costs.compare_cost(0.6, 100.0, 3).work == pytest.approx(3 * total, rel=1e-12)


def test_a_study_above_the_bound_is_refused_with_the_bound_the_estimate_and_the_way_on():
    with pytest.raises(LimitError) as caught:
        check_study_cost("demo: 9 runs", Cost(0.0, 3e11, 1.0, "9 x 3.3e10"), Limits(), "use fewer --runs")
    message = str(caught.value)
    assert "3e+11" in message and "max_work = 2e+11" in message and "--runs" in message
    assert "--max-work 3e+11" in message
    check_study_cost("demo", Cost(0.0, 3e11, 1.0), Limits(max_work=4e11), "")  # raised bound: accepted
    with pytest.raises(LimitError, match="memory|GiB|TiB"):
        check_study_cost("demo", Cost(0.0, 1.0, 2.0**60), Limits(), "use fewer --runs")


def test_run_ring_refuses_records_that_cannot_fit_before_any_collision():
    from wavecontact.studies.ring import run_ring

    def no_simulation(scene, options):
        raise AssertionError("the simulation was built: the refusal came after the work had started")

    with pytest.raises(LimitError, match="collisions"):
        run_ring(0.6, 100.0, 20, 10**12, progress=False, simulation_factory=no_simulation)
