"""Delay kernels' history look-ups (wavecontact/delay/kernels.py) and the energy split's use of them.

``locate_from`` walks from a hint where ``locate`` bisects; both must name the same stored step for
every time and hint, compiled and in pure Python, and the per-rod energy split, which walks, must
equal the same quadrature written here with a fresh bisection for every point.
"""

from __future__ import annotations

import functools
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from wavecontact._jit import NUMBA_ENABLED
from wavecontact.bath.noise import NoiseTables
from wavecontact.delay import kernels
from wavecontact.delay.energy_split import NODES, WEIGHTS, vibration_energy_gain
from wavecontact.delay.solver import _integrate, solve_delay_equation


@pytest.mark.parametrize("compiled", [True, False])
def test_locate_from_names_the_step_bisection_finds(compiled):
    locate = kernels.locate if compiled else kernels.locate.py_func
    walk = kernels.locate_from if compiled else kernels.locate_from.py_func
    rng = np.random.default_rng(np.random.SeedSequence(7))
    for _ in range(12):
        t = np.cumsum(rng.exponential(size=rng.integers(2, 40)))
        t -= t[0]
        last = t.size - 1
        # times on the nodes, between them, past the end; hints anywhere in range
        for s in np.concatenate([t, t[:-1] + 0.5 * np.diff(t), [t[-1] + 1.0], rng.uniform(0.0, t[-1], 10)]):
            for hint in {*range(0, last, 3), last - 1}:
                assert walk(t, last, s, hint) == locate(t, last, s)


def _split_by_bisection(kappa, t, w, d1, d2, delays):
    """Delta E_i of wavecontact.delay.energy_split (cold), each point found by bisection (hermite5)."""
    last = t.size - 1
    gain = np.zeros(2)
    for j in range(last):
        for part in range(2):
            a = t[j] + (t[j + 1] - t[j]) * part / 2
            b = t[j] + (t[j + 1] - t[j]) * (part + 1) / 2
            for node, weight in zip(NODES, WEIGHTS):
                s = a + (b - a) * node
                value, slope, _ = kernels.hermite5(t, w, d1, d2, last, s)
                if slope == 0.0:
                    continue
                for i in range(2):
                    memory = 0.0
                    n = 1
                    while s - n * delays[i] > t[0]:
                        memory += kernels.hermite5(t, w, d1, d2, last, s - n * delays[i])[1]
                        n += 1
                    gain[i] += weight * (b - a) * slope * (0.5 * slope + memory - value / delays[i])
    return gain / (2.0 * kappa * kappa)


@pytest.mark.parametrize("gamma, kappa, rtol", [(0.6, 20.0, 1e-4), (0.3, 1e3, 1e-6)])
def test_energy_split_walk_equals_bisection(gamma, kappa, rtol):
    t, w, d1, *_ = solve_delay_equation(gamma, kappa, rtol=rtol)
    d2 = np.gradient(d1, t)  # any smooth-enough third column: both sides interpolate the same data
    delays = np.array([1.0 + gamma, 1.0 + 1.0 / gamma])
    empty = NoiseTables.empty()
    ours = vibration_energy_gain(kappa, t, w, d1, d2, delays, empty.periods, empty.values, empty.slopes,
                                 NODES, WEIGHTS, 2)
    assert np.array_equal(ours, _split_by_bisection(kappa, t, w, d1, d2, delays))


@pytest.mark.parametrize("compiled", [True, False])
def test_sturdy_curvature_replaces_only_what_round_off_hides(compiled):
    sturdy = kernels._sturdy_curvature if compiled else kernels._sturdy_curvature.py_func
    # well conditioned: W'' = W' (g' - W') = 2 (5 - 2) = 6 whatever g'' says
    assert sturdy(2.0, 1.0, 5.0, 7.0, 0.5, 3.0) == 6.0
    # a force plateau at kappa ~ 1e6: g - W ~ 1e6 - 1e6 leaves W' = 8e5 uncertain by ~1e-4,
    # so W'(g' - W') = 80 is round-off around g'' = 0, and g'' is taken
    slope, g, w, drift = 8e5, 1.4e6, 1.4e6 - np.log(8e5), 1.4e6
    assert sturdy(slope, g, slope + 1e-4, 0.0, w, drift) == 0.0
    # ... but not a g'' that the exact formula rules out
    exact = slope * ((slope + 1e-4) - slope)
    assert sturdy(slope, g, slope + 1e-4, 1e5, w, drift) == exact
    # no g'' (tabulated noise: NaN): the exact formula
    assert sturdy(slope, g, slope + 1e-4, np.nan, w, drift) == exact


@pytest.mark.parametrize("rule, degree, embedded_degree", [("gauss-kronrod", 11, 5), ("lobatto-kronrod", 9, 5)])
def test_quadrature_rules_integrate_polynomials_to_their_degree(rule, degree, embedded_degree):
    # the coefficient identities of each pair on [0, 1]: exact up to its degree, not one beyond
    nodes, kronrod, embedded = kernels.QUADRATURE_RULES[rule]
    for weights, top in ((kronrod, degree), (embedded, embedded_degree)):
        errors = [abs(np.sum(weights * nodes**k) - 1.0 / (k + 1)) for k in range(top + 2)]
        assert max(errors[: top + 1]) < 1e-15
        assert errors[top + 1] > 1e-12  # far above round-off: the degree is exactly top
    if rule == "lobatto-kronrod":
        assert nodes.min() == 0.0 and nodes.max() == 1.0  # the end nodes the kernel takes from the step's ends


@pytest.mark.parametrize("gamma, kappa", [(0.6, 10.0), (0.3, 1000.0)])
def test_lobatto_rule_converges_to_the_gauss_kronrod_reference(gamma, kappa):
    # cold collisions: both rules' errors stay below their estimates, and the Lobatto rule spends
    # fewer evaluations of the exponent a step (5 + 1 against 7 + 1)
    reference = solve_delay_equation(gamma, kappa, rtol=1e-12)
    for rtol in (1e-5, 1e-8):
        _t, w, _d1, _d2, error, work, _a0 = _integrate(gamma, kappa, rtol, None, None, None, 2_000_000, 1.0, None,
                                                      "lobatto-kronrod")
        assert abs(w[-1] - reference[1][-1]) / kappa <= error
        evaluations_per_step = work["evaluations"] / (work["steps"] + work["rejected_steps"])
        assert evaluations_per_step < 6.1



_COLD_COMPILE = """
import functools
import json
from wavecontact.delay import kernels
from wavecontact.delay.solver import solve_delay_equation
solve_delay_equation(0.6, 100.0)
noise = [kernels.table_value, kernels.span_is_free, kernels.noise_upper_bound, kernels.noise_curvature_bound,
         kernels.no_later_contact, kernels.comb_values]
print(json.dumps({"noise_kernels": {k.py_func.__name__: len(k.signatures) for k in noise},
                  "integrator": [str(s) for s in kernels._method_of_steps.signatures]}))
"""


@pytest.mark.skipif(not NUMBA_ENABLED, reason="kernels run as plain Python")
def test_a_cold_solve_compiles_none_of_the_noise_or_comb_code(tmp_path):
    """Compile time (docs/performance.md): on an empty numba cache a cold collision compiles the integrator's
    cold specialisation only, neither the noise tables' kernels nor the comb sums (seconds each)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "PYTHONPATH": str(Path(__file__).resolve().parent.parent)}
    done = subprocess.run([sys.executable, "-c", _COLD_COMPILE], env=env, capture_output=True, text=True, check=True)
    record = json.loads(done.stdout.splitlines()[-1])
    assert record["noise_kernels"] == dict.fromkeys(record["noise_kernels"], 0)
    (signature,) = record["integrator"]
    assert signature.count("none") == 3  # the series, the tables and direct_copies


def test_a_history_that_outgrows_its_buffers_resumes_bit_for_bit(monkeypatch):
    """The compiled integrator stops when its buffers are full and resumes in doubled ones
    (kernels.integrate_delay_equation): the result may not depend on where that happens."""
    reference = _integrate(0.6, 5.0, 1e-12, None, None, None, 2_000_000, 1.0, None)
    assert reference[0].size > kernels._FIRST_CAPACITY  # resumed at least once
    monkeypatch.setattr(kernels, "_FIRST_CAPACITY", 7)  # resumed some nine times
    resumed = _integrate(0.6, 5.0, 1e-12, None, None, None, 2_000_000, 1.0, None)
    for before, after in zip(reference[:4], resumed[:4]):
        np.testing.assert_array_equal(before, after)
    assert reference[4:] == resumed[4:]  # error estimate, work counts, gap


def test_a_first_answer_interpreted_gives_the_compiled_bits(monkeypatch):
    """The CLI's first answer runs the method of steps and the energy split as plain Python while numba has
    no compiled kernel for them (wavecontact._jit.answer_first): history, error estimate and energy split
    must be the compiled kernels' to the bit, over the softness, accuracy and length ratios it takes."""
    import wavecontact
    from wavecontact import _jit
    from wavecontact.delay import energy_split
    from wavecontact.delay import kernels as delay_kernels

    def collide_all(mode):
        def force(kernel, args, small, compile_later=False):
            return functools.partial(_jit._run_interpreted, kernel) if mode else kernel

        monkeypatch.setattr(delay_kernels, "prefer_interpreted", force)
        monkeypatch.setattr(energy_split, "prefer_interpreted", force)
        return [wavecontact.collide(gamma, kappa, "delay", rtol=rtol)
                for gamma in (1.0, 0.6, 0.25) for kappa in (5.0, 37.0, 100.0, 2500.0) for rtol in (1e-6, 1e-9)]

    interpreted, compiled = collide_all(True), collide_all(False)
    for a, b in zip(interpreted, compiled):
        case = (a.gamma, a.kappa, a.options["rtol"])
        assert a.restitution == b.restitution and a.error_estimate == b.error_estimate, case
        for name in ("time", "relative_velocity", "contact_force"):
            assert np.array_equal(getattr(a, name), getattr(b, name)), (case, name)
        assert np.array_equal(a.extra["vibration_energy_gain"], b.extra["vibration_energy_gain"]), case
