"""Soft contact laws between two rigid sides in the fem multi-body loop (issue 26, item 1).

No rod takes part in such a contact, so the mesh cannot resolve it: the loop gives it its own steps
over ``pi / sqrt(k w)`` and the error estimate halves them with the elements.  References are closed
forms of point masses, written here independently of the package:

* a rigid mass on a Hertz wall, ``F = K delta^(3/2)``: elastic rebound ``-V`` and contact duration
  ``T = (4/5) B(2/5, 1/2) delta_max / V`` with ``delta_max = (5 M V^2 / (4 K))^(2/5)``;
* two rigid bodies with a penalty spring ``k``: the velocities of an elastic collision, duration
  ``pi sqrt(mu / k)`` with ``mu`` the reduced mass (half a period of the relative oscillation);
* two rigid bodies with the exponential law started far out of its range: the elastic velocities.
"""

import json
import math

import pytest
from scipy.special import beta

from wavecontact import Exponential, Hertz, Penalty, RigidBody, Scene, Wall, solve
from wavecontact.cli import main


def _elastic(m1, m2, u1, u2):
    return ((m1 - m2) / (m1 + m2) * u1 + 2 * m2 / (m1 + m2) * u2,
            2 * m1 / (m1 + m2) * u1 + (m2 - m1) / (m1 + m2) * u2)


def _assert_within_estimate(result, expected, slack=0.0):
    """Every velocity within the reported estimate (relative to the largest initial speed), and the
    estimate small: 200 steps over the contact's time scale leave errors of order 1e-6."""
    scale = max(abs(v) for v in result.initial_velocities)
    bound = result.error_estimate * scale
    assert 0.0 < result.error_estimate < 1e-4
    for got, want in zip(result.velocities, expected):
        assert abs(got - want) <= bound + slack


def test_rigid_mass_on_a_hertz_wall_rebounds_elastically_in_the_closed_form_time():
    mass, speed, stiffness = 2.0, 1.5, 400.0
    scene = Scene(rods=(RigidBody(mass),), velocities=(speed,), contact=(),
                  walls=(None, Wall(gap=0.3, contact=Hertz(stiffness))))
    result = solve(scene, "fem")
    _assert_within_estimate(result, (-speed,))
    delta_max = (5.0 * mass * speed**2 / (4.0 * stiffness)) ** 0.4
    duration = 0.8 * beta(0.4, 0.5) * delta_max / speed
    record = result.contacts[0]
    assert record.intervals == 1
    assert record.duration == pytest.approx(duration, abs=2.0 * result.work["dt"])
    assert record.duration / result.work["dt"] >= 50  # the contact is resolved, not stepped over
    assert record.impulse == pytest.approx(2.0 * mass * speed, rel=1e-4)


def test_two_rigid_bodies_with_a_penalty_spring_collide_elastically_in_half_a_period():
    m1, m2, u1, u2, k = 1.0, 3.0, 1.0, -0.5, 300.0
    scene = Scene(rods=(RigidBody(m1), RigidBody(m2)), velocities=(u1, u2), contact=Penalty(k), gaps=(0.3,))
    result = solve(scene, "fem")
    _assert_within_estimate(result, _elastic(m1, m2, u1, u2))
    reduced = m1 * m2 / (m1 + m2)
    assert result.contacts[0].duration == pytest.approx(math.pi * math.sqrt(reduced / k), abs=2.0 * result.work["dt"])
    assert result.contacts[0].intervals == 1


def test_two_rigid_bodies_with_the_exponential_law_collide_elastically():
    """Started at gap 1 the law's potential (exp(-20) of its strength) is 2.1e-9 of its strength."""
    m1, m2, u1, u2 = 1.0, 3.0, 1.0, -0.5
    scene = Scene(rods=(RigidBody(m1), RigidBody(m2)), velocities=(u1, u2), contact=Exponential(20.0),
                  gaps=(1.0,))
    result = solve(scene, "fem")
    # the potential at the start, exp(-20), shifts v1 by exp(-20) m2 / ((m1 + m2) mu (u1 - u2)) = 1.4e-9
    _assert_within_estimate(result, _elastic(m1, m2, u1, u2), slack=2e-9)


def test_a_scene_file_with_a_soft_wall_under_a_rigid_body_gives_a_result(tmp_path, capsys):
    scene = tmp_path / "rigid_wall_soft.toml"
    scene.write_text('[[body]]\nmass = 2.0\nvelocity = 1.5\n\n[walls.right]\ngap = 0.3\n'
                     'contact = { law = "penalty", stiffness = 300.0 }\n')
    code = main(["solve", str(scene), "--json"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "Traceback" not in captured.err
    record = json.loads(captured.out)
    assert record["velocities"][0] == pytest.approx(-1.5, abs=record["error_estimate"] * 1.5)


def test_a_given_step_is_coarsened_in_the_estimate_of_a_rigid_soft_contact():
    """With ``dt`` given the estimate's runs take 2 dt and 4 dt there: it still bounds the step's error."""
    mass, speed = 2.0, 1.5
    scene = Scene(rods=(RigidBody(mass),), velocities=(speed,), contact=(),
                  walls=(None, Wall(gap=0.3, contact=Penalty(300.0))))
    result = solve(scene, "fem", dt=0.005)
    assert [n for n, _ in result.diagnostics["error_estimate_levels"]] == [800, 400, 200]
    assert abs(result.velocities[0] + speed) <= result.error_estimate * speed
    assert result.error_estimate > 1e-6
