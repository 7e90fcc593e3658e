"""The end response's energy bookkeeping against an independent modal sum."""

import itertools
import math

import numpy as np
import pytest

from wavecontact import Rod
from wavecontact.modal.end_response import end_parameters, forced_energy


def _records(starts, widths, coefficients):
    """Step records (t0, h, I(t0), a_0 .. a_{s-1}) of a piecewise-polynomial force."""
    rows, impulse = [], 0.0
    for t0, h, a in zip(starts, widths, coefficients):
        rows.append([t0, h, impulse, *a])
        impulse += h * sum(c / (j + 1) for j, c in enumerate(a))
    return np.array(rows)


@pytest.mark.parametrize("duration_in_round_trips", [0.4, 2.7])
def test_forced_energy_is_the_sum_over_all_modes(duration_in_round_trips):
    """A force pulse F = D^2 x (1 - x) on [0, D] (recorded as three uneven steps) pushes a rod from rest.
    The energy it leaves, from the autocorrelation at lags n T, must equal the rigid part I^2 / (2 m) plus
    every free-free mode's (1/m) |int F exp(i omega_nu t) dt|^2 summed directly (20000 modes)."""
    rod = Rod(0.8, density=2.0, youngs_modulus=5.0, area=1.5)
    trip = 2.0 * rod.length / rod.wave_speed
    duration = duration_in_round_trips * trip
    # the pulse's polynomial re-expanded on each step: x = (t0 + y h) / D
    cuts = np.array([0.0, 0.3, 0.45, 1.0]) * duration
    coefficients = []
    for t0, t1 in itertools.pairwise(cuts):
        h, a = t1 - t0, t0 / duration
        b = h / duration  # F = D^2 (a + b y)(1 - a - b y)
        coefficients.append([duration**2 * a * (1 - a), duration**2 * b * (1 - 2 * a), -duration**2 * b * b])
    records = _records(cuts[:-1], np.diff(cuts), coefficients)
    impulse = duration**3 / 6.0
    nu = np.arange(1, 20001)
    a = 1j * math.pi * nu * rod.wave_speed / rod.length  # int_0^D t^k exp(a t) dt in closed form
    e = np.exp(a * duration)
    first = e * (duration / a - 1.0 / a**2) + 1.0 / a**2
    second = e * (duration**2 / a - 2.0 * duration / a**2 + 2.0 / a**3) - 2.0 / a**3
    spectrum = np.abs(duration * first - second) ** 2
    expected = impulse**2 / (2.0 * rod.mass) + float(np.sum(spectrum)) / rod.mass
    assert forced_energy(records, rod) == pytest.approx(expected, rel=1e-10)


def test_end_parameters_of_two_rods():
    a, b = Rod(1.0, density=2.0, youngs_modulus=8.0), Rod(1.5)
    ends = end_parameters(a, b, 0.5, 0.1, -1.0, 2.0, 0.3)
    np.testing.assert_allclose(ends[:5], [1 / 4 + 1 / 1, 2 / 4, 2 / 1, 1.0, 3.0])
    np.testing.assert_allclose(ends[5:], [0.5, 0.1, -1.0, 2.0, 0.3, 0.1])
