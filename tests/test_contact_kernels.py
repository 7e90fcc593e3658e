"""The one compiled dispatch of the contact laws (wavecontact.contact_kernels), law by law.

Each law's compiled force, energy and stiffness must be its Python methods; the generic
solutions a new law gets for free (gap solve with compliance, two-body flow, massless-end gap)
are held to the closed forms of the penalty law and to a separately written integrator; the
delay equation for laws acting on overlap only is held to the exponential delay kernel.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import wavecontact as wc
from wavecontact import contact_kernels as ck
from wavecontact.contact import Exponential, Hertz, Penalty
from wavecontact.delay.law_kernels import STATUS_OK, integrate_overlap_delay
from wavecontact.delay.parameters import echoes_from_ratios
from wavecontact.delay.solver import solve_delay_equation

GAPS = np.array([-0.3, -1e-3, -1e-7, 0.0, 1e-4, 0.05, 0.7, 3.0])
# every law with a force law (Hard is a constraint: tests/test_contact.py)
LAWS = [Exponential(20.0, 0.5 / 400), Exponential(3.0, 2.0), Penalty(150.0), Hertz(7.0), Hertz(2e4)]


@pytest.mark.parametrize("law", LAWS, ids=lambda law: f"{law.name}-{law.kernel_parameters()}")
@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "python"])
def test_each_law_compiled_is_its_python_methods(law, compiled):
    functions = (ck.law_force, ck.law_potential, ck.law_stiffness)
    methods = (law.force, law.potential, law.stiffness_at)
    params = law.kernel_parameters()
    assert params[0] == law.code
    for function, method in zip(functions, methods):
        function = function if compiled else function.py_func
        for gap in GAPS:
            assert function(*params, float(gap)) == pytest.approx(float(method(gap)), rel=1e-14, abs=0.0)


@pytest.mark.parametrize("law", LAWS, ids=lambda law: law.name)
def test_stiffness_is_minus_the_slope_of_the_force_and_force_the_slope_of_the_energy(law):
    params = law.kernel_parameters()
    for gap in GAPS[GAPS != 0.0]:  # the penalty law has a kink at 0
        # central differences: relative steps on the Hertz law's kink scale, else above the round-off
        step = 1e-5 * abs(gap) if law.name == "hertz" else 1e-6 * max(abs(gap), 1e-2)
        slope = (ck.law_force(*params, gap + step) - ck.law_force(*params, gap - step)) / (2 * step)
        assert ck.law_stiffness(*params, gap) == pytest.approx(-slope, rel=1e-6, abs=1e-9)
        energy_slope = (ck.law_potential(*params, gap + step) - ck.law_potential(*params, gap - step)) / (2 * step)
        assert ck.law_force(*params, gap) == pytest.approx(-energy_slope, rel=1e-6, abs=1e-9)


@pytest.mark.parametrize("compliance", [0.0, 1e-3, 0.02, 1.0])
@pytest.mark.parametrize("gap", [-0.5, -1e-2, -1e-6, 0.0, 0.3])
def test_the_generic_series_solve_is_the_closed_form_of_the_penalty_law(gap, compliance):
    code, alpha, strength, stiffness = Penalty(40.0).kernel_parameters()
    generic = ck.series_response(gap, code, alpha, strength, stiffness, compliance)
    closed = ck.law_response(gap, code, alpha, strength, stiffness, compliance, math.nan)
    # force, energy and dF/dgap (the closed form reports no softening for a linear law)
    assert generic[:3] == pytest.approx(closed[:3], rel=1e-12, abs=1e-15)
    assert generic[3] == pytest.approx(1.0 + compliance * ck.law_stiffness(code, alpha, strength, stiffness,
                                                                          gap + compliance * generic[0]))


@pytest.mark.parametrize(("r", "rate"), [(0.05, -1.0), (-0.01, -0.5), (-0.02, 0.7), (0.0, -2.0), (0.3, 1.0)])
def test_the_generic_flow_and_gap_are_the_exact_penalty_ones(r, rate):
    code, alpha, strength, stiffness = Penalty(250.0).kernel_parameters()
    for dt in (1e-3, 0.04, 0.5):
        # two-body flow (m_inv = 2) and massless-end gap (compliance 0.01)
        assert ck.overlap_flow(code, r, rate, dt, 2.0, alpha, strength, stiffness) == pytest.approx(
            ck.penalty_flow(r, rate, dt, 2.0, stiffness), abs=1e-9)
        assert ck.overlap_gap(code, r, rate, dt, 0.01, alpha, strength, stiffness) == pytest.approx(
            ck.penalty_gap(r, rate, dt, 0.01, stiffness), abs=1e-9)


def test_the_overlap_delay_equation_is_the_exponential_kernel():
    """The generic delay integrator, fed the exponential force, against the exponential equation's own kernel."""
    gamma, kappa = 0.6, 20.0
    delays, weights = (np.array(x) for x in echoes_from_ratios(1.0, gamma))
    # paper units: mu = Z_s = 1/2, V = 1, so lambda = 1 and Z_s V = 1/2; B = mu / kappa^2
    law = Exponential(kappa, 0.5 / kappa**2)
    start = 2.5  # alpha r = 50: the force is exp(-50) of its scale
    w, _d, status = integrate_overlap_delay(law.code, law.alpha, law.strength, 0.0, 1.0, 0.5, start, delays,
                                            weights, 1.0 / (kappa * 400), 4.0 * delays.max(), 2_000_000)
    assert status == STATUS_OK
    reference = solve_delay_equation(gamma, kappa, rtol=1e-12)[1][-1] / kappa - 1.0
    assert abs((w[-1] - 1.0) - reference) < 1e-8
    assert abs(reference - 0.7530132413) < 1e-9  # MODEL.md section 5


def test_a_separately_written_rigid_integrator_agrees_with_the_generic_flow():
    """Two point masses with a stiff spring on overlap: solve_ivp (DOP853) against overlap_flow."""
    code, alpha, strength, stiffness = Penalty(1e3).kernel_parameters()
    m_inv = 3.0

    def rhs(_t, y):
        return [y[1], m_inv * stiffness * max(0.0, -y[0])]

    reference = solve_ivp(rhs, (0.0, 0.2), [0.01, -0.4], method="DOP853", rtol=1e-12, atol=1e-14,
                          max_step=1e-3).y[:, -1]
    assert ck.overlap_flow(code, 0.01, -0.4, 0.2, m_inv, alpha, strength, stiffness) == pytest.approx(
        tuple(reference), abs=1e-9)


@pytest.mark.parametrize(("r", "rate"), [(0.02, -1.0), (-0.01, -0.5), (-0.02, 0.7)])
def test_the_generic_hertz_flow_and_gap_agree_with_dop853(r, rate):
    """DOP853 inside the overlap, stopped where the ends part (the force's kink), then the exact drift.

    The generic solutions take 200 RK4 sub-steps per time scale: about (1/200)^4 = 6e-10 of the scale.
    """
    code, alpha, strength, stiffness = Hertz(2e3).kernel_parameters()
    m_inv, compliance, dt = 3.0, 0.5, 0.05

    def force(x):
        return stiffness * max(0.0, -x) ** 1.5

    def parted(_t, y):
        return y[0]

    parted.terminal, parted.direction = True, 1
    start = max(r, 0.0) / -rate if r > 0.0 else 0.0  # a drift to touching first
    y0 = min(r, 0.0)
    flow = solve_ivp(lambda _t, y: [y[1], m_inv * force(y[0])], (start, dt), [y0, rate], method="DOP853",
                     rtol=1e-13, atol=1e-16, events=parted)
    flow_end = (flow.y[1, -1] * (dt - flow.t[-1]) if flow.status == 1 else flow.y[0, -1], flow.y[1, -1])
    gap = solve_ivp(lambda _t, y: [rate + compliance * force(y[0])], (start, dt), [y0], method="DOP853",
                    rtol=1e-13, atol=1e-16, events=parted)
    gap_end = rate * (dt - gap.t[-1]) if gap.status == 1 else gap.y[0, -1]
    assert ck.overlap_flow(code, r, rate, dt, m_inv, alpha, strength, stiffness) == pytest.approx(
        flow_end, abs=1e-9)
    assert ck.overlap_gap(code, r, rate, dt, compliance, alpha, strength, stiffness) == pytest.approx(
        gap_end, abs=1e-9)


def test_penalty_contact_in_the_delay_equation_is_the_modal_and_fem_solution():
    """The overlap-law delay solver on the penalty law of two_rods(0.6, 10) (k = kappa / 2), against the
    modal solver's exact ends and the FE characteristic lattice."""
    results = {name: wc.collide(0.6, 10, solver=name, contact="penalty", **options)
               for name, options in (("delay", {}), ("modal", {"modes": 20}), ("fem", {"elements": 800}))}
    restitution = {name: result.restitution for name, result in results.items()}
    assert abs(restitution["delay"] - restitution["modal"]) < 1e-8, restitution
    assert abs(restitution["delay"] - restitution["fem"]) < 1e-6, restitution
