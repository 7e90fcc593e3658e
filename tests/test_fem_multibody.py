"""The fem multi-body loop (wavecontact.fem.multibody) against independent checks.

Conservation laws, the two-rod loop on the same discretization, the hard-rod
restitution ``epsilon = l1 / l2`` (one material), Newton's cradle of equal
rods, Newton's laws for rigid bodies, and the observed convergence order on a
tapered bar.
"""

import math

import numpy as np
import pytest

from wavecontact import (
    CollisionResult,
    Exponential,
    Hard,
    ImpactResult,
    Penalty,
    PiecewiseRod,
    RigidBody,
    Rod,
    Scene,
    Segment,
    Wall,
    solve,
    two_rods,
)
from wavecontact.fem.multibody import run_line


def _energy(masses, velocities, internal=()):
    return sum(0.5 * m * v * v for m, v in zip(masses, velocities)) + sum(internal)


@pytest.mark.parametrize("law", [Exponential(40.0, 0.01), Penalty(300.0)])
def test_soft_chain_conserves_momentum_and_energy(law):
    scene = Scene(rods=(Rod(1.0), Rod(0.7), Rod(1.3)), velocities=(1.0, 0.0, -0.2), contact=law)
    run = run_line(scene, elements=100)
    masses = run["masses"]
    p0 = sum(m * v for m, v in zip(masses, scene.velocities))
    p1 = sum(m * v for m, v in zip(masses, run["velocities"]))
    assert abs(p1 - p0) < 1e-13
    e0 = _energy(masses, scene.velocities)
    e1 = _energy(masses, run["velocities"], run["internal_energies"])
    assert abs(e1 - e0) < 1e-3 * e0  # leapfrog energy, O(dt^2) while the soft contacts act
    assert all(c.intervals >= 1 for c in run["contacts"])


def test_hard_chain_on_the_lattice_conserves_momentum_and_energy():
    # (with a last rod longer than the pulse the lattice's velocities stay exact, but the discrete energy of the
    # step front left in it is O(h) off: 1.6e-3 at 40 elements, 7.8e-4 at 80)
    scene = Scene(rods=(Rod(1.0), Rod(0.5), Rod(1.0)), velocities=(1.0, 0.0, -0.2), contact=Hard(), gaps=(0.0, 0.0))
    run = run_line(scene, elements=40)
    masses = run["masses"]
    p0 = sum(m * v for m, v in zip(masses, scene.velocities))
    assert abs(sum(m * v for m, v in zip(masses, run["velocities"])) - p0) < 1e-12
    e0 = _energy(masses, scene.velocities)
    assert abs(_energy(masses, run["velocities"], run["internal_energies"]) - e0) < 1e-10 * e0


@pytest.mark.parametrize("gamma", [0.25, 0.5, 1.0])
def test_two_hard_rods_restitution_is_the_length_ratio(gamma):
    # one material, hard contact: epsilon = l1 / l2 (the short rod's wave returns first)
    scene = two_rods(gamma, math.inf, contact="hard")
    run = run_line(scene, elements=40)
    v1, v2 = run["velocities"]
    approach = scene.velocities[0] - scene.velocities[1]
    assert (v2 - v1) / approach == pytest.approx(gamma, abs=1e-12)


@pytest.mark.parametrize(("order", "mass"), [(1, "lumped"), (1, "consistent"), (2, "lumped"), (2, "consistent")])
def test_two_rods_agree_with_the_two_rod_loop(order, mass):
    # the same meshes, step and scheme (plain central differences with the force at the end nodes)
    scene = two_rods(0.6, 20.0)
    dt = 0.0015
    old = solve(scene, "fem", elements=100, order=order, mass=mass, scheme="force", dt=dt, estimate_error=False)
    run = run_line(scene, elements=100, order=order, mass=mass, dt=dt)
    v1, v2 = run["velocities"]
    approach = scene.velocities[0] - scene.velocities[1]
    assert (v2 - v1) / approach == pytest.approx(old.restitution, abs=1e-12)


def test_the_paper_scene_still_returns_a_collision_result():
    assert isinstance(solve(two_rods(0.6, math.inf, contact="hard"), "fem", elements=20), CollisionResult)


@pytest.mark.parametrize("count", [3, 5])
def test_newtons_cradle_of_equal_rods(count):
    scene = Scene(rods=(Rod(1.0),) * count, velocities=(1.0,) + (0.0,) * (count - 1), contact=Hard(),
                  gaps=(0.0,) * (count - 1))
    result = solve(scene, "fem", elements=30)
    assert isinstance(result, ImpactResult)
    np.testing.assert_allclose(result.velocities, (0.0,) * (count - 1) + (1.0,), atol=1e-12)
    assert max(result.internal_energies) < 1e-12
    for i, record in enumerate(result.contacts):  # each pair meets once, for one round trip 2 l / c, from t = i
        assert record.intervals == 1
        assert record.first_contact == pytest.approx(float(i), abs=1e-12)
        assert record.duration == pytest.approx(2.0, abs=1e-12)
        assert record.impulse == pytest.approx(1.0, abs=1e-12)


def test_rigid_body_against_a_wall_rebounds():
    scene = Scene(rods=(RigidBody(2.0),), velocities=(1.5,), contact=(), walls=(None, Wall(gap=0.3, contact=Hard())))
    result = solve(scene, "fem")
    assert result.velocities[0] == pytest.approx(-1.5, abs=1e-14)
    assert result.contacts[0].name == "right wall"
    assert result.contacts[0].impulse == pytest.approx(2 * 2.0 * 1.5, rel=1e-14)


def test_two_rigid_bodies_collide_elastically():
    m1, m2, u1, u2 = 1.0, 3.0, 1.0, -0.5
    scene = Scene(rods=(RigidBody(m1), RigidBody(m2)), velocities=(u1, u2), contact=Hard(), gaps=(0.3,))
    result = solve(scene, "fem")
    expected = ((m1 - m2) / (m1 + m2) * u1 + 2 * m2 / (m1 + m2) * u2,
                2 * m1 / (m1 + m2) * u1 + (m2 - m1) / (m1 + m2) * u2)
    np.testing.assert_allclose(result.velocities, expected, atol=1e-14)


def test_tapered_bar_converges_at_first_order_and_the_estimate_bounds_the_error():
    horn = PiecewiseRod((Segment(length=1.0, area=1.0, end_area=0.25),))
    scene = Scene(rods=(Rod(1.0), horn), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,))
    reference = np.array(run_line(scene, elements=1280)["velocities"])
    sizes = np.array([20, 40, 80, 160])
    errors = np.array([np.max(np.abs(np.array(run_line(scene, elements=n)["velocities"]) - reference))
                       for n in sizes])
    order = -np.polyfit(np.log(1.0 / sizes), np.log(errors), 1)[0] * -1.0
    assert 0.7 < order < 1.5, order
    result = solve(scene, "fem", elements=40)
    assert np.max(np.abs(np.array(result.velocities) - reference)) <= result.error_estimate * 1.0


def test_mixed_scene_runs_and_round_trips_through_json(tmp_path):
    hammer = RigidBody(mass=2.0)
    bar = PiecewiseRod((Segment(length=1.0, area=1.0), Segment(length=1.0, area=2.0)))
    scene = Scene(rods=(hammer, Rod(1.0), bar), velocities=(1.0, 0.0, 0.0), contact=(Hard(), Exponential(200.0, 1e-3)),
                  gaps=(0.0, None), walls=(None, Wall(gap=0.0, contact=Hard())))
    result = solve(scene, "fem", elements=20)
    assert len(result.contacts) == 3 and result.contacts[2].name == "right wall"
    assert result.internal_energies[0] == 0.0
    assert "body 0" in result.summary()
    loaded = ImpactResult.load(result.save(tmp_path / "impact.json"))
    assert loaded.velocities == result.velocities
    assert loaded.contacts == result.contacts
    assert loaded.error_estimate == result.error_estimate


def test_each_facing_pair_keeps_its_own_law():
    """Two pairs on one line that never meet each other (they part after their collisions; the contact between
    them never acts): rods 1 and 2 (one material) with hard contact, rods 1 and 1.5 with an exponential law.
    The hard pair ends at epsilon = l1 / l2 (wave theory of impact), the soft pair at the delay solver's epsilon
    for those rods and that law (an independent solver); every velocity within the loop's own error estimate."""
    law = Exponential(20.0, 0.01)
    scene = Scene(rods=(Rod(1.0), Rod(2.0), Rod(1.0), Rod(1.5)), velocities=(0.0, -1.0, 1.0, 0.0),
                  contact=(Hard(), Hard(), law), gaps=(0.0, 0.5, None))
    result = solve(scene, "fem", elements=100)

    def after(m1, m2, u1, u2, eps):  # momentum kept, relative velocity reversed and scaled by eps
        centre = (m1 * u1 + m2 * u2) / (m1 + m2)
        return centre - m2 / (m1 + m2) * eps * (u1 - u2), centre + m1 / (m1 + m2) * eps * (u1 - u2)

    soft = solve(Scene(rods=(Rod(1.0), Rod(1.5)), velocities=(1.0, 0.0), contact=law), "delay").restitution
    expected = after(1.0, 2.0, 0.0, -1.0, 0.5) + after(1.0, 1.5, 1.0, 0.0, soft)
    assert np.max(np.abs(np.asarray(result.velocities) - expected)) <= result.error_estimate
    assert [c.intervals for c in result.contacts] == [1, 0, 1]


def test_options_the_loop_does_not_take_are_refused():
    from wavecontact import InvalidParameterError

    scene = Scene(rods=(Rod(1.0),) * 3, velocities=(1.0, 0.0, 0.0), contact=Hard(), gaps=(0.0, 0.0))
    with pytest.raises(InvalidParameterError, match="not available for multi-body scenes"):
        solve(scene, "fem", elements=20, scheme="splitting")
