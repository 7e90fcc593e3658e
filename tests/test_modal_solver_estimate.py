"""The modal solver's end-response error estimate and the set-up it shares between runs."""

import math

import numpy as np
import pytest

import wavecontact as wc
from wavecontact import two_rods
from wavecontact.bath import ThermalBath
from wavecontact.bath.collide import thermal_scene
from wavecontact.modal import solver as modal
from wavecontact.modal.end_response import _pairwise_sum

# cold collisions across the regimes: soft, MODEL.md's, stiff, hard (gamma, kappa)
SCENES = [(0.3, 3.0), (0.6, 100.0), (0.85, 3000.0), (0.45, math.inf)]


@pytest.mark.parametrize("gamma, kappa", SCENES)
def test_the_estimate_run_at_one_mode_has_the_restitution_of_the_requested_modes(gamma, kappa):
    """With the end-response correction the gap is the whole rods' end response; the kept modes only ride
    along, so the estimate's run at one mode per rod must give the same restitution, bit for bit, as the
    same run at the requested 60 modes (the run the estimate used to make)."""
    scene = two_rods(gamma, kappa)
    options = modal.SOLVER.options({"modes": 60})
    finer = modal._finer_options(scene, options, 1e-3)
    assert finer.modes == 1 and finer.collocation_tolerance == pytest.approx(1e-4) and not finer.history
    one_mode, _ = modal._restitution_alone(scene, finer, modal._EXPONENT_STEP)
    requested = modal._collide(scene, finer.replace(modes=60), omitted_energy=False)
    assert one_mode == requested.restitution


@pytest.mark.parametrize("gamma, kappa", SCENES)
def test_the_estimate_bounds_the_error_against_the_delay_solver(gamma, kappa):
    """The default modal collide's estimate bounds its distance to the delay solver at rtol 1e-10 (plus that
    reference's own estimate)."""
    result = wc.collide(gamma, kappa, solver="modal", modes=60, history=False)
    reference = wc.collide(gamma, kappa, solver="delay", rtol=1e-10)
    assert "collocation tolerance" in result.diagnostics["error_estimate_method"]
    assert abs(result.restitution - reference.restitution) <= result.error_estimate + reference.error_estimate


def test_warm_rods_keep_their_modes_in_the_estimate_run():
    """A bath realisation lives in the kept modes: the estimate's run must keep them."""
    scene = thermal_scene(0.6, 100.0, ThermalBath(1.0, 20), 3)
    options = modal.SOLVER.options({"modes": 40})
    assert modal._finer_options(scene, options, 1e-3).modes == 40
    assert modal._system_key(scene, ()) is None  # warm systems are never shared


def test_repeated_collides_share_the_set_up_without_sharing_state():
    """The second collide of a scene starts from a copy of the first one's system: the same result bit for
    bit, the same as with the table emptied, and the kept system still at the start."""
    first = wc.collide(0.6, 100.0, solver="modal", modes=30)
    key = next(iter(k for k in modal._SYSTEM_CACHE if k[-1][0] == 30))
    start = modal._SYSTEM_CACHE[key][0]
    X, q = start.X.copy(), start.q.copy()
    second = wc.collide(0.6, 100.0, solver="modal", modes=30)
    modal._SYSTEM_CACHE.clear()
    fresh = wc.collide(0.6, 100.0, solver="modal", modes=30)
    for result in (second, fresh):
        assert result.restitution == first.restitution
        assert result.error_estimate == first.error_estimate
        np.testing.assert_array_equal(result.extra["modal_energies"], first.extra["modal_energies"])
        assert result.diagnostics["energy_drift"] == first.diagnostics["energy_drift"]
    np.testing.assert_array_equal(start.X, X)
    np.testing.assert_array_equal(start.q, q)


@pytest.mark.parametrize("count", [0, 1, 7, 8, 9, 127, 128, 129, 136, 1000, 4097])
def test_pairwise_sum_is_numpys_sum(count):
    """The omitted-mode energy's kernel sums in numpy's pairwise order: numpy's own sum is the reference."""
    values = np.random.default_rng(count).standard_normal(count) * np.logspace(-8, 8, count)
    assert 0.0 + _pairwise_sum(values, count) == float(np.sum(values))
