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
    """alpha V l / c = 1e2, 1e3, 3e3: the mass's velocity approaches V exp(-2m/M) within 1/alpha."""
    hard = math.exp(-2.0)
    alphas = (1e2, 1e3, 3e3)
    gaps = [abs(rigid_mass_on_rod(1.0, 1.0, 1.0, 1.0, 1.0, gap=25.0 / a, law=Exponential(a),
                                  steps_per_round_trip=max(400, int(4 * a))).mass_velocity - hard) for a in alphas]
    assert gaps[0] > gaps[1] > gaps[2]
    assert all(g < 1.0 / a for g, a in zip(gaps, alphas)), gaps


# -- solve(scene, solver="delay") on Saint-Venant's scene -------------------------------------------------------


@pytest.mark.parametrize("ratio", [0.25, 1.0, 4.0])
def test_delay_solver_takes_a_rigid_mass_on_a_rod_within_its_estimate(ratio):
    from wavecontact import RigidBody, Rod, Scene, solve

    ref = saint_venant(mass=ratio, rod_length=1.0, impedance=1.0, wave_speed=1.0, velocity=1.0)
    scene = Scene(rods=(RigidBody(mass=ratio), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,))
    result = solve(scene, solver="delay", rtol=1e-7)
    assert result.solver == "delay"
    error = np.max(np.abs(np.asarray(result.velocities) - [ref.mass_velocity, ref.rod_velocity]))
    assert error <= result.error_estimate <= 1e-7 * 1.0001, (error, result.error_estimate)
    (contact,) = result.contacts
    assert contact.intervals == 1 and contact.first_contact == 0.0
    assert contact.last_contact + result.work["dt"] == pytest.approx(ref.last_contact, abs=1e-12)
    assert result.internal_energies[1] == pytest.approx(ref.rod_internal_energy, abs=10 * result.error_estimate)


def test_delay_and_fem_agree_on_a_mirrored_scene_with_a_soft_law():
    """The rod on the left moving right into a resting mass, exponential law (alpha = 200): the delay
    module and the fem loop within the sum of their error estimates."""
    from wavecontact import RigidBody, Rod, Scene, solve

    scene = Scene(rods=(Rod(1.0), RigidBody(mass=2.0)), velocities=(1.0, 0.0), contact=Exponential(200.0),
                  gaps=(0.2,))
    delay = solve(scene, solver="delay", rtol=1e-5)
    fem = solve(scene, solver="fem", elements=400)
    difference = np.max(np.abs(np.asarray(delay.velocities) - fem.velocities))
    assert difference <= delay.error_estimate + fem.error_estimate, (difference, delay.error_estimate,
                                                                      fem.error_estimate)
    assert sum(m * v for m, v in zip(delay.masses, delay.velocities)) == pytest.approx(1.0, abs=1e-12)


def test_delay_solver_refuses_other_line_scenes_naming_fem():
    from wavecontact import PiecewiseRod, RigidBody, Rod, Scene, Segment, solve
    from wavecontact.errors import UnsupportedSceneError

    scenes = [
        Scene(rods=(Rod(1.0),) * 3, velocities=(1.0, 0.0, 0.0), contact=Hard(), gaps=(0.0, 0.0)),
        Scene(rods=(RigidBody(mass=1.0), PiecewiseRod((Segment(1.0, end_area=0.5),))), velocities=(1.0, 0.0),
              contact=Hard(), gaps=(0.0,)),
    ]
    for scene in scenes:
        with pytest.raises(UnsupportedSceneError, match="fem"):
            solve(scene, solver="delay")
