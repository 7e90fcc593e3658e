"""The FE error estimate on scenes drawn as issue 23's probe drew them (gamma uniform in (0.05, 1], kappa
log-uniform in [1, 1e5], order, mass and 8 ... 400 elements at random), against the delay reference:
the too-fast guard of wavecontact.fem.error_estimate (runs that converge faster than their contact
scheme allows agree by accident) and the first order of the massless-end interface."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from wavecontact import collide
from wavecontact.fem import error_estimate
from wavecontact.fem import solver as fem_solver

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import error_estimates as sweep

SAFETY = error_estimate.ESTIMATE_SAFETY


def _rule(errors, x, scheme_order=None, elements=64, declared=2.0, characteristic=False):
    """The FE rule applied to restitutions ``eps* + errors[i]`` at elements, elements/2, elements/4."""
    levels = [(elements // 2**i, 0.5 + error) for i, error in enumerate(errors)]
    return error_estimate.estimate_from_levels(levels, x, declared, characteristic, scheme_order)


def _error_and_estimate(gamma, kappa, options):
    result = collide(gamma, kappa, solver="fem", **options)
    reference = collide(gamma, kappa)
    return abs(result.restitution - reference.restitution), result.error_estimate, reference.error_estimate


def test_issue_worst_case_is_bounded():
    # issue 23: P2 lumped on 65 elements at alpha V h / c = 1.9 (massless-end interface); errors +2.2e-4,
    # -1.64e-4, -1.65e-4 on 16, 32 and 65 elements: the error changed sign between the coarser runs and the
    # two finest agree to 7e-7 (observed order 9). The previous rule took that order as convergence and
    # reported 4.6e-7 against an error of 1.65e-4 (the delay solver's value is accurate to 1e-10)
    error, estimate, reference = _error_and_estimate(0.7558283840026945, 140.78066610311188,
                                                     {"elements": 65, "order": 2, "mass": "lumped"})
    assert error > 1e-4
    assert error <= estimate + reference <= 10.0 * error


def test_too_fast_convergence_carries_the_coarser_pair_down():
    # the worst case's errors: the finest difference 535 times below the coarser one
    errors = [-1.65e-4, -1.64e-4, 2.16e-4]
    estimate, rule = _rule(errors, 1.9, scheme_order=1.0)
    assert "faster than the scheme" in rule and "carried down" in rule
    assert abs(errors[0]) <= estimate <= 10.0 * abs(errors[0])


def test_third_order_convergence_is_not_read_as_too_fast():
    # the characteristic lattice converges at about third order where the error keeps one sign: that is
    # within TOO_FAST_MARGIN of the declared 2, and the estimate stays SAFETY |d0| / (2^2 - 1)
    errors = [-1e-9 * 8.0**i for i in range(3)]
    estimate, rule = _rule(errors, 0.3, characteristic=True)
    assert "faster" not in rule
    assert estimate == pytest.approx(SAFETY * 7e-9 / 3.0, rel=1e-12)


def test_interface_runs_are_measured_against_first_order():
    # issue 23's fresh sample (seed 41686): P1 consistent on 62 elements at alpha V h / c = 15.6 (interface),
    # errors +6.55e-3, +5.95e-3, -1.59e-3: observed order 3.65, below 2 + TOO_FAST_MARGIN but far above the
    # interface's first order; read as convergence, the estimate was 16 times below the error
    errors = [6.55e-3, 5.95e-3, -1.59e-3]
    as_declared, _ = _rule(errors, 15.6)
    estimate, rule = _rule(errors, 15.6, scheme_order=fem_solver.INTERFACE_ORDER)
    assert as_declared < abs(errors[0]) / 10.0
    assert abs(errors[0]) <= estimate <= 10.0 * abs(errors[0]) and "faster" in rule


def _probe_sample(count, seed):
    streams = [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(count)]
    return [sweep.draw("fem", index, stream, "probe") for index, stream in enumerate(streams)]


def _misses(samples):
    rows = [_error_and_estimate(s["gamma"], s["kappa"], s["options"]) for s in samples]
    misses = [(s, e, est) for s, (e, est, ref) in zip(samples, rows) if e > est + ref]
    return rows, misses


def test_probe_draws_seeded_subset():
    # 16 scenes drawn like the probe (seed 23, elements capped at 200 to keep the test fast): the estimate
    # bounds the error with coverage 0.99 on the acceptance sweep of seed 42654 (docs/error_estimates.md section 2);
    # here at most 2 misses of 16 (binomial, p = 0.05: P(3 or more) = 0.04) and none by more than 10x
    samples = _probe_sample(16, 23)
    for s in samples:
        s["options"]["elements"] = min(s["options"]["elements"], 200)
    _, misses = _misses(samples)
    assert len(misses) <= 2, misses
    assert all(e <= 10.0 * est for _, e, est in misses), misses


@pytest.mark.slow
def test_probe_draws_sweep():
    # 200 scenes of the probe's draws (seed 2323, several minutes): coverage >= 0.93 (0.95 less 1.5 standard
    # errors at p = 0.95) and no miss by more than 10x
    rows, misses = _misses(_probe_sample(200, 2323))
    assert 1.0 - len(misses) / len(rows) >= 0.93, misses
    assert all(e <= 10.0 * est for _, e, est in misses), misses
    assert not any(math.isnan(est) for _, est, _ in rows)
