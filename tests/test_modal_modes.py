"""Rod modes: analytic against finite-element eigenmodes, residual compliance against direct sums."""

import math

import numpy as np
import pytest

from wavecontact import Rod
from wavecontact.errors import InvalidParameterError
from wavecontact.modal.modes import analytic_modes, fe_modes, uniform_residual_compliance


def test_analytic_modes_follow_the_free_free_formulas():
    rod = Rod(0.8, density=2.0, youngs_modulus=8.0, area=0.5)  # c = 2, m = 0.8
    modes = analytic_modes(rod, 6)
    nu = np.arange(1, 7)
    np.testing.assert_allclose(modes.omega, 2.0 * math.pi * nu / 0.8, rtol=1e-15)
    np.testing.assert_allclose(modes.left, math.sqrt(2.0 / 0.8))
    np.testing.assert_allclose(modes.right, (-1.0) ** nu * math.sqrt(2.0 / 0.8))


@pytest.mark.parametrize("order, elements, tolerance", [(2, 250, 1e-6), (2, 2000, 1e-9)])
def test_fe_eigenmodes_match_the_analytic_modes(order, elements, tolerance):
    """Dense (eigh, 501 unknowns) and sparse (eigsh + bordered solve, 4001) paths reproduce the continuum."""
    rod = Rod(1.3)
    exact = analytic_modes(rod, 8)
    fe = fe_modes(rod, 8, elements=elements, order=order)
    np.testing.assert_allclose(fe.omega, exact.omega, rtol=tolerance)
    np.testing.assert_allclose(fe.left, exact.left, rtol=1e-6)
    np.testing.assert_allclose(fe.right, exact.right, rtol=1e-6)
    np.testing.assert_allclose(fe.residual_compliance, exact.residual_compliance, rtol=1e-5)


def test_p1_eigenfrequencies_converge_at_second_order():
    rod = Rod(1.0)
    exact = analytic_modes(rod, 3).omega
    sizes = np.array([40, 80, 160, 320])
    errors = [abs(fe_modes(rod, 3, elements=int(n), order=1).omega[2] - exact[2]) / exact[2] for n in sizes]
    slope = -np.polyfit(np.log(sizes), np.log(errors), 1)[0]
    assert 1.9 < slope < 2.1


def test_residual_compliance_is_the_tail_of_the_modal_sum():
    rod = Rod(0.9, youngs_modulus=3.0, area=2.0)
    ea = 6.0
    for kept in (0, 1, 10, 75):
        c = uniform_residual_compliance(rod, kept)
        nu = np.arange(kept + 1, 2_000_001, dtype=float)
        # direct sum plus the integral estimate 1 / (n_max + 1/2) of what it leaves out
        direct_same = 2.0 * rod.length / (math.pi**2 * ea) * (np.sum(1.0 / nu**2) + 1.0 / (nu[-1] + 0.5))
        direct_alt = 2.0 * rod.length / (math.pi**2 * ea) * np.sum((-1.0) ** nu / nu**2)
        assert c[0, 0] == pytest.approx(direct_same, rel=1e-10)
        assert c[0, 1] == pytest.approx(direct_alt, abs=1e-12)
    # nothing kept: the inertia-relief compliance of a free rod pushed at one end, l / (3 EA)
    assert uniform_residual_compliance(rod, 0)[0, 0] == pytest.approx(rod.length / (3.0 * ea), rel=1e-14)


@pytest.mark.parametrize("bad", [0, -3, 2.5, True, "10"])
def test_mode_count_is_checked(bad):
    with pytest.raises(InvalidParameterError, match="modes"):
        analytic_modes(Rod(1.0), bad)
