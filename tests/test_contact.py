"""Contact laws as values: one kernel encoding, held to the Python force/potential methods."""

from __future__ import annotations

import math

import numpy as np
import pytest

from wavecontact.contact import LAW_EXPONENTIAL, LAW_HARD, LAW_PENALTY, Exponential, Hard, Penalty
from wavecontact.contact_kernels import law_force, law_potential
from wavecontact.modal import kernels as modal_kernels
from wavecontact.modal.system import contact_parameters

GAPS = np.array([-0.3, -1e-3, 0.0, 1e-4, 0.05, 0.7, 3.0])
LAWS = [Exponential(20.0, 0.5 / 400), Exponential(3.0, 2.0), Penalty(150.0)]


def test_codes_come_from_the_law_objects():
    assert Exponential(2.0, 3.0).kernel_parameters() == (LAW_EXPONENTIAL, 2.0, 3.0, 0.0)
    assert Penalty(5.0).kernel_parameters() == (LAW_PENALTY, 0.0, 0.0, 5.0)
    code, _, _, stiffness = Penalty().kernel_parameters()
    assert code == LAW_PENALTY and math.isnan(stiffness)  # left to the solver
    assert Hard().kernel_parameters() == (LAW_HARD, 0.0, 0.0, math.inf)


@pytest.mark.parametrize("law", LAWS, ids=lambda law: law.name)
@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "python"])
def test_the_kernel_evaluation_is_the_python_law(law, compiled):
    force = law_force if compiled else law_force.py_func
    potential = law_potential if compiled else law_potential.py_func
    params = law.kernel_parameters()
    for gap in GAPS:
        assert force(*params, float(gap)) == pytest.approx(float(law.force(gap)), rel=1e-14, abs=0.0)
        assert potential(*params, float(gap)) == pytest.approx(float(law.potential(gap)), rel=1e-14, abs=0.0)


def test_hard_law_is_a_wall():
    params = Hard().kernel_parameters()
    assert law_force(*params, 0.1) == 0.0 and law_force(*params, -1e-9) == math.inf
    assert law_potential(*params, -1e-9) == math.inf == float(Hard().potential(-1e-9))


@pytest.mark.parametrize("law", LAWS, ids=lambda law: law.name)
def test_the_modal_kernel_without_compliance_is_the_python_law(law):
    code, alpha, strength, stiffness, _ = contact_parameters(law, force_scale=0.5, static_correction=True)
    for gap in GAPS:
        force, energy, _, _ = modal_kernels.contact_response(float(gap), code, alpha, strength, stiffness, 0.0)
        assert force == pytest.approx(float(law.force(gap)), rel=1e-13, abs=0.0)
        assert energy == pytest.approx(float(law.potential(gap)), rel=1e-13, abs=0.0)
