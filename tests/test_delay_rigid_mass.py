"""wavecontact.delay.rigid_mass against the Saint-Venant reference (tests/references/saint_venant.py)."""

import math

import numpy as np
import pytest
from references.saint_venant import saint_venant

from wavecontact.contact import Exponential, Hard
from wavecontact.delay.rigid_mass import richardson, rigid_mass_on_rod

STEPS = (50, 100, 200)


@pytest.mark.parametrize("ratio", [0.25, 1.0, 4.0])
def test_hard_contact_second_order_within_its_estimate(ratio):
    length, Z, c, V = 1.5, 2.0, 3.0, 0.7
    m_rod = Z * length / c
    ref = saint_venant(mass=ratio * m_rod, rod_length=length, impedance=Z, wave_speed=c, velocity=V)
    runs = [rigid_mass_on_rod(ratio * m_rod, length, Z, c, V, law=Hard(), steps_per_round_trip=k) for k in STEPS]
    errors = [abs(r.mass_velocity - ref.mass_velocity) for r in runs]
    order = -np.polyfit(np.log(STEPS), np.log(errors), 1)[0]
    assert 1.9 < order < 2.1, errors
    estimate = richardson(runs[-1].mass_velocity, runs[-2].mass_velocity)
    assert errors[-1] <= 1.5 * estimate  # Richardson with the observed order 2 (1.5: the safety of the solvers)
    final = runs[-1]
    assert final.rod_velocity == pytest.approx(ref.rod_velocity, abs=10 * estimate)
    assert final.rod_internal_energy == pytest.approx(ref.rod_internal_energy, abs=10 * estimate * V * m_rod)
    assert len(final.intervals) == 1 and final.intervals[0] == pytest.approx(ref.intervals[0], abs=2 * (2 * length / c) / STEPS[-1])


def test_galilean_invariance_and_momentum():
    a = rigid_mass_on_rod(1.0, 1.0, 1.0, 1.0, 1.0, law=Hard(), steps_per_round_trip=64)
    b = rigid_mass_on_rod(1.0, 1.0, 1.0, 1.0, 1.75, rod_velocity=0.75, law=Hard(), steps_per_round_trip=64)
    assert b.mass_velocity - 0.75 == pytest.approx(a.mass_velocity, abs=1e-14)
    assert b.rod_velocity - 0.75 == pytest.approx(a.rod_velocity, abs=1e-14)
    assert a.mass_velocity + a.rod_velocity == pytest.approx(1.0, abs=1e-14)


def test_exponential_law_tends_to_the_hard_limit():
    """alpha V l / c = 1e2, 1e3, 1e4: the mass's velocity approaches V exp(-2m/M), the error falling ~ 1/alpha."""
    hard = math.exp(-2.0)
    gaps = [abs(rigid_mass_on_rod(1.0, 1.0, 1.0, 1.0, 1.0, gap=25.0 / a, law=Exponential(a),
                                  steps_per_round_trip=max(400, int(4 * a))).mass_velocity - hard)
            for a in (1e2, 1e3, 1e4)]
    assert gaps[0] > gaps[1] > gaps[2]
    assert gaps[2] < 2e-3
