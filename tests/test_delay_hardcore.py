"""The hard-core max-plus recursion for two materials against the wave theory of impact."""

import numpy as np
import pytest

import wavecontact
from wavecontact.analytic import two_material_impact
from wavecontact.delay.hardcore import closest_return, contact_intervals, hard_core_history
from wavecontact.delay.parameters import echoes_from_ratios
from wavecontact.errors import InvalidParameterError

GRID = [(z, t) for z in (0.01, 0.1, 0.5, 1.0, 2.0, 10.0, 100.0) for t in (0.1, 0.3, 0.6, 1.0, 1.7, 4.0, 10.0)]


def _rods(impedance_ratio, time_ratio):
    """Rod 1: Z = 1, T = 2; rod 2 with wave speed 1 and the requested ratios."""
    return wavecontact.Rod(1.0), wavecontact.Rod(1.0 / time_ratio, density=impedance_ratio, youngs_modulus=impedance_ratio)


def _dimensionless_theory(impedance_ratio, time_ratio):
    """two_material_impact (written from the wave picture) in the delay equation's units."""
    rods = _rods(impedance_ratio, time_ratio)
    impact = two_material_impact(*rods, 1.0)
    z1, z2 = (rod.impedance for rod in rods)
    series = z1 * z2 / (z1 + z2)
    time_unit = rods[0].mass * rods[1].mass / (rods[0].mass + rods[1].mass) / series
    steps = [(a / time_unit, b / time_unit, force / series) for a, b, force in impact["steps"]]
    return impact["restitution"], impact["duration"] / time_unit, steps


@pytest.mark.parametrize("impedance_ratio, time_ratio", GRID)
def test_recursion_agrees_with_the_wave_theory(impedance_ratio, time_ratio):
    delays, weights = echoes_from_ratios(impedance_ratio, time_ratio)
    knots_t, knots_w = hard_core_history(delays, weights)
    restitution, duration, steps = _dimensionless_theory(impedance_ratio, time_ratio)
    assert knots_w[-1] - 1.0 == pytest.approx(restitution, abs=1e-12)
    (start, end), = contact_intervals(knots_t, knots_w, delays, weights)
    assert start == 0.0
    # the contact lasts while the force is above round-off (steps R^k fall below it in long contacts)
    last = max(b for a, b, force in steps if force * (b - a) > 1e-13)
    assert end == pytest.approx(last, abs=1e-12)
    assert last == duration or steps[-1][2] * (steps[-1][1] - steps[-1][0]) < 1e-13
    # the force (slope of w, units Z_s V) on each step of the theory, where it is above round-off
    for a, b, force in steps:
        if force > 1e-9:
            left, right = a + 0.25 * (b - a), b - 0.25 * (b - a)
            rise = np.interp(right, knots_t, knots_w) - np.interp(left, knots_t, knots_w)
            assert rise / (right - left) == pytest.approx(force, rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("impedance_ratio, time_ratio", GRID)
def test_the_gap_never_closes_again(impedance_ratio, time_ratio):
    """docs/theory.md proves that the relative end velocity is >= 0 after the
    contact; the exact recursion must see a gap that never shrinks."""
    delays, weights = echoes_from_ratios(impedance_ratio, time_ratio)
    knots_t, knots_w = hard_core_history(delays, weights)
    assert closest_return(knots_t, knots_w, delays, weights) == np.inf


def test_random_pairs_have_one_contact():
    """Impedance ratios 1e-3..1e3 and transit-time ratios 1e-2..1e2, drawn
    from a fixed seed: one contact each, and the gap only grows after it."""
    rng = np.random.default_rng(np.random.SeedSequence(14).spawn(1)[0])
    for impedance_ratio, time_ratio in 10.0 ** rng.uniform([-3, -2], [3, 2], size=(60, 2)):
        delays, weights = echoes_from_ratios(impedance_ratio, time_ratio)
        knots_t, knots_w = hard_core_history(delays, weights)
        assert len(contact_intervals(knots_t, knots_w, delays, weights)) == 1
        assert closest_return(knots_t, knots_w, delays, weights) == np.inf


def test_a_gap_that_opens_splits_the_contacts():
    """contact_intervals on a made-up history (no solution of the recursion:
    physical ones never separate twice) that rises, stays flat while the
    bracket drops below it (a gap of 0.1 at tau = 0.3), and rises again."""
    knots_t = np.array([0.0, 0.2, 0.6, 0.7])
    knots_w = np.array([0.0, 0.2, 0.2, 0.3])
    delays, weights = np.array([0.2, 100.0]), np.array([2.0, 0.0])
    assert contact_intervals(knots_t, knots_w, delays, weights) == [(0.0, 0.2), (0.6, 0.7)]
    # a flat stretch where no gap opens is part of the same contact
    assert contact_intervals(knots_t, knots_w, np.array([5.0, 100.0]), weights, tau_free=0.2 - 0.6) == [(0.0, 0.7)]


def test_extreme_ratios_are_refused_before_work_starts():
    delays, weights = echoes_from_ratios(1e-6, 1e-6)  # force steps down by 1 - 2e-6 per echo
    with pytest.raises(InvalidParameterError, match="max_windows"):
        hard_core_history(delays, weights)


@pytest.mark.parametrize("compiled", [True, False])
def test_the_kinks_are_sorted_as_numpy_sorts_them(compiled):
    """hardcore_kernels._sorted (a merge sort numba compiles fast) against np.sort: random, tied, sorted and
    reversed values, every prefix length up to 40."""
    from wavecontact.delay.hardcore_kernels import _smallest, _sorted

    sort = _sorted if compiled else _sorted.py_func
    smallest = _smallest if compiled else _smallest.py_func
    rng = np.random.default_rng(np.random.SeedSequence(3))
    for values in (rng.uniform(0.0, 5.0, 40), np.round(rng.uniform(0.0, 5.0, 40), 1), np.arange(40.0),
                   np.arange(40.0)[::-1].copy()):
        for count in range(1, 41):
            assert np.array_equal(sort(values, count), np.sort(values[:count]))
            assert smallest(values[:count]) == values[:count].min()
    assert sort(np.empty(3), 0).size == 0


def test_the_interpreted_recursion_gives_the_compiled_bits_on_every_pair_of_materials(monkeypatch):
    """A short recursion runs as plain Python while numba has no compiled kernel for it (a first answer
    without compiling); the kinks must be the compiled kernel's to the bit, for every pair of the grid."""
    from wavecontact import _jit
    from wavecontact.delay import hardcore
    from wavecontact.delay.hardcore_kernels import max_plus_history

    histories = {}
    for mode in ("interpreted", "compiled"):
        if mode == "interpreted":
            monkeypatch.setattr(hardcore, "prefer_interpreted", lambda kernel, args, small: _jit.interpreted(kernel))
        else:
            monkeypatch.setattr(hardcore, "prefer_interpreted", lambda kernel, args, small: kernel)
        histories[mode] = [hard_core_history(*echoes_from_ratios(z, t)) for z, t in GRID]
    assert _jit.interpreted(max_plus_history) is not max_plus_history.py_func  # a clone calling clones
    for (z, t), interpreted, compiled in zip(GRID, histories["interpreted"], histories["compiled"]):
        for a, b in zip(interpreted, compiled):
            assert a.dtype == b.dtype and np.array_equal(a, b), (z, t)
