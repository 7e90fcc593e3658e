"""The modal solver's end-response error estimate and the set-up it shares between runs."""

import math

import numpy as np
import pytest

import wavecontact as wc
from wavecontact import two_rods
from wavecontact.bath import ThermalBath
from wavecontact.bath.collide import thermal_scene
from wavecontact.modal import solver as modal
from wavecontact.modal.end_response import forced_energies

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


def _numpy_forced_energy(records, rod, points=6):
    """The omitted-mode energy's lag sums written with numpy (union1d, searchsorted, sum), as the solver
    computed them before its compiled kernel: the reference for the kernel's bits."""
    points = max(points, records.shape[1] - 3)
    nodes, weights = np.polynomial.legendre.leggauss(points)
    starts = records[:, 0]
    bounds = np.append(starts, starts[-1] + records[-1, 1])
    trip = 2.0 * rod.length / rod.wave_speed

    def force_at(times):
        index = np.searchsorted(starts, times, side="right") - 1
        inside = (index >= 0) & (times <= bounds[-1])
        index = np.clip(index, 0, starts.size - 1)
        x = np.clip((times - starts[index]) / records[index, 1], 0.0, 1.0)
        force = np.zeros_like(times)
        for j in range(records.shape[1] - 1, 2, -1):
            force = force * x + records[:, j].take(index)
        return np.where(inside, force, 0.0)

    total = 0.0
    for n in range(int((bounds[-1] - bounds[0]) // trip) + 1):
        shift = n * trip
        edges = np.union1d(bounds, bounds[(bounds - shift > bounds[0]) & (bounds - shift < bounds[-1])] - shift)
        edges = edges[edges <= bounds[-1] - shift]
        if edges.size < 2:
            continue
        left, width = edges[:-1], np.diff(edges)
        times = (left[:, None] + width[:, None] * 0.5 * (nodes + 1.0)).ravel()
        quadrature = (width[:, None] * 0.5 * weights).ravel()
        total += (1.0 if n == 0 else 2.0) * float(np.sum(quadrature * force_at(times) * force_at(times + shift)))
    return total / rod.impedance


@pytest.mark.parametrize("gamma, kappa", SCENES + [(1.0, 0.3)])
def test_forced_energies_are_numpys_lag_sums_bit_for_bit(gamma, kappa):
    """The compiled lag sums (one kernel, numpy's pairwise order written out) against the same sums in numpy,
    on the force records of real collisions (hundreds of terms per lag: the pairwise halving is used)."""
    scene = two_rods(gamma, kappa)
    system, _ = modal._build(scene, 20, "end-response", "analytic", None, 1, 0.0125)
    _, _, (records, _, _) = modal._run_collocation(system, 6, 1e-3, np.empty((0, 3)), [])
    assert records.shape[0] > 25
    expected = [_numpy_forced_energy(records, rod) for rod in system.rods]
    assert forced_energies(records, system.rods) == expected
