"""The scene model: the paper's two-rod builder and refusal of bad input."""

import math

import numpy as np
import pytest

from wavecontact import Exponential, Hard, Penalty, Rod, Scene, two_rod_parameters, two_rods
from wavecontact.errors import InvalidParameterError


@pytest.mark.parametrize("gamma", [0.1, 0.6, 1.0])
def test_two_rods_units(gamma):
    scene = two_rods(gamma, 50.0)
    short, long_ = scene.rods
    assert short.length / long_.length == pytest.approx(gamma)
    effective = 2 * short.length * long_.length / (short.length + long_.length)
    assert effective == pytest.approx(1.0)
    reduced_mass = short.mass * long_.mass / (short.mass + long_.mass)
    assert reduced_mass == pytest.approx(0.5)
    assert scene.momentum() == pytest.approx(0.0, abs=1e-15)
    assert scene.velocities[1] - scene.velocities[0] == pytest.approx(-1.0)
    assert scene.contact.alpha == 50.0
    # B = mu c^2 / (alpha l)^2 makes the delay equation hold without a shift
    assert scene.contact.strength == pytest.approx(0.5 / 50.0**2)
    params = two_rod_parameters(scene)
    assert params.round_trip_times == pytest.approx((1 + gamma, 1 + 1 / gamma))


def test_infinite_kappa_is_hard_contact():
    assert isinstance(two_rods(0.6, math.inf).contact, Hard)
    assert isinstance(two_rods(0.6, 10.0, contact="hard").contact, Hard)
    assert isinstance(two_rods(0.6, 10.0, contact="penalty").contact, Penalty)


def test_two_rod_parameters_of_a_general_scene():
    scene = Scene(rods=(Rod(0.8), Rod(4 / 3)), velocities=(0.5, -0.5), contact=Exponential(100.0))
    params = two_rod_parameters(scene)
    assert params.gamma == pytest.approx(0.6)
    assert params.kappa == pytest.approx(100.0)


@pytest.mark.parametrize("field", ["length", "density", "youngs_modulus", "area"])
@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), float("inf"), "abc"])
def test_rod_refuses_bad_properties(field, value):
    with pytest.raises(InvalidParameterError, match=field):
        Rod(**{"length": 1.0, field: value})


@pytest.mark.parametrize("value", [0.0, -2.0, float("nan"), float("inf")])
def test_contact_laws_refuse_bad_parameters(value):
    with pytest.raises(InvalidParameterError, match="alpha"):
        Exponential(value)
    with pytest.raises(InvalidParameterError, match="stiffness"):
        Penalty(value)


@pytest.mark.parametrize("velocity", [float("nan"), float("inf"), -float("inf")])
def test_scene_refuses_non_finite_velocities(velocity):
    with pytest.raises(InvalidParameterError, match="velocities"):
        Scene(rods=(Rod(1.0), Rod(1.0)), velocities=(velocity, 0.0), contact=Hard())


def test_scene_refuses_overlap_and_short_rings():
    with pytest.raises(InvalidParameterError, match="overlap"):
        Scene(rods=(Rod(1.0), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(), gaps=(-0.1,))
    with pytest.raises(InvalidParameterError, match="ring_circumference"):
        Scene(rods=(Rod(1.0), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(), ring_circumference=1.5)
    with pytest.raises(InvalidParameterError, match="add up"):
        Scene(rods=(Rod(1.0), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(), ring_circumference=4.0, gaps=(1.0, 0.5))
    ring = Scene(rods=(Rod(1.0), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(), ring_circumference=4.0, gaps=(1.0, 1.0))
    assert ring.is_ring


def test_scene_refuses_wrong_counts_and_fields():
    with pytest.raises(InvalidParameterError, match="at least 2"):
        Scene(rods=(Rod(1.0),), velocities=(1.0,), contact=Hard())
    with pytest.raises(InvalidParameterError, match="one entry per rod"):
        Scene(rods=(Rod(1.0), Rod(1.0)), velocities=(1.0,), contact=Hard())
    with pytest.raises(InvalidParameterError, match="initial_velocity"):
        Scene(rods=(Rod(1.0), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(), initial_velocity=(1.0, None))
    with pytest.raises(InvalidParameterError, match="contact"):
        Scene(rods=(Rod(1.0), Rod(1.0)), velocities=(1.0, 0.0), contact="hard")


def test_two_rods_refuses_mismatched_contact_and_bad_gamma():
    with pytest.raises(InvalidParameterError, match="kappa"):
        two_rods(0.6, 10.0, contact=Exponential(20.0))
    with pytest.raises(InvalidParameterError, match="contact must be one of"):
        two_rods(0.6, 10.0, contact="sticky")
    with pytest.raises(InvalidParameterError, match="gamma"):
        two_rods(1.2, 10.0)


def test_a_velocity_too_small_to_square_is_refused_not_solved():
    """Hypothesis found v = 1.6e-223: its kinetic energy underflows to 0 and the FE watchdog divided 0 by 0.
    Speeds are 0 or of magnitude in [1e-30, 1e30]."""
    from wavecontact.contact import Hard
    from wavecontact.errors import InvalidParameterError
    from wavecontact.scene import Rod, Scene

    with pytest.raises(InvalidParameterError, match=r"velocities\[0\] must lie in 0 or a magnitude"):
        Scene(rods=(Rod(1.0), Rod(1.0)), velocities=(1.6e-223, 0.0), contact=Hard())
    assert Scene(rods=(Rod(1.0), Rod(1.0)), velocities=(-1e-30, 0.0), contact=Hard()).velocities == (-1e-30, 0.0)


@pytest.mark.parametrize(("gamma", "kappa", "contact"), [
    (0.6, 100.0, "exponential"), (1.0, 0.01, "exponential"), (1e-6, 1e7, "exponential"), (0.3, math.inf, "exponential"),
    (0.6, 20.0, "penalty"), (0.6, math.inf, "penalty"), (0.6, 20.0, "hard"), (0.6173, 4000.0, Exponential(4000.0))])
def test_two_rods_builds_what_the_checking_constructors_build(gamma, kappa, contact):
    """two_rods validates its numbers once and builds the cold scene without the Scene's and the Rods' checks:
    the result must be the scene that Scene(...) and Rod(...) build and normalize from the same numbers."""
    scene = two_rods(gamma, kappa, contact=contact)
    rods = tuple(Rod(rod.length) for rod in scene.rods)
    checked = Scene(rods=rods, velocities=scene.velocities, contact=scene.contact, metadata=dict(scene.metadata))
    assert scene == checked and type(scene) is Scene
    for name in ("rods", "velocities", "contact", "gaps", "ring_circumference", "initial_displacement",
                 "initial_velocity", "metadata", "vibrations", "walls"):
        assert getattr(scene, name) == getattr(checked, name), name
        assert type(getattr(scene, name)) is type(getattr(checked, name)), name
    for rod, twin in zip(scene.rods, checked.rods):
        assert [type(getattr(rod, n)) for n in ("length", "density", "youngs_modulus", "area")] == [float] * 4
        assert rod == twin
    assert all(type(v) is float for v in scene.velocities)
    assert not scene.is_line_scene and not scene.is_ring and scene.is_cold


@pytest.mark.parametrize(("gamma", "message"), [(1e-31, "rod length"), (6e-31, r"velocities\[1\]")])
def test_two_rods_keeps_the_magnitude_checks_it_does_once(gamma, message):
    # gamma below about 1e-30 makes the long rod too long, then the short rod's speed too small to square
    with pytest.raises(InvalidParameterError, match=message):
        two_rods(gamma, 100.0)
    assert two_rods(2e-30, 100.0).velocities[1] == pytest.approx(-2e-30)


def test_a_thermal_scene_checks_gamma_and_kappa_once_and_is_the_scene_two_rods_builds(monkeypatch):
    """thermal_scene needs the rods' lengths before it draws their vibrations; it must not validate the two
    numbers a second time on the way, and must build what two_rods builds from the same draw."""
    from wavecontact import scene as scene_module
    from wavecontact.bath import ThermalBath
    from wavecontact.bath import collide as collide_module
    from wavecontact.bath.collide import thermal_scene
    from wavecontact.bath.model import seed_sequence

    bath = ThermalBath(1.0, 40)
    expected = two_rods(0.6, 100.0, vibrations=bath.draw((0.8, 0.8 / 0.6), seed_sequence(3)))
    calls = []
    original = scene_module.validate_gamma_kappa
    counting = lambda *a: calls.append(a) or original(*a)
    monkeypatch.setattr(scene_module, "validate_gamma_kappa", counting)
    monkeypatch.setattr(collide_module, "validate_gamma_kappa", counting, raising=False)  # a copy imported there
    built = thermal_scene(0.6, 100.0, bath, 3)
    assert calls == [(0.6, 100.0)]
    assert built.rods == expected.rods and built.gaps == expected.gaps and built.velocities == expected.velocities
    for name in ("displacement", "velocity_amplitude"):
        for got, want in zip(getattr(built.vibrations, name), getattr(expected.vibrations, name)):
            np.testing.assert_array_equal(got, want)
