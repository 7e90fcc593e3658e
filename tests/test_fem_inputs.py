"""Refused inputs and honest failures of the finite-element solver."""

import math

import numpy as np
import pytest

import wavecontact as wc
from wavecontact import InvalidParameterError, Rod, Scene, SolverFailure


@pytest.mark.parametrize("elements", [0, -5, 2.5, "800", True])
def test_refuses_bad_element_counts(elements):
    with pytest.raises(InvalidParameterError, match="elements"):
        wc.collide(0.6, 100, solver="fem", elements=elements)


@pytest.mark.parametrize("order", [0, 3, 1.5])
def test_refuses_bad_orders(order):
    with pytest.raises(InvalidParameterError, match="order"):
        wc.collide(0.6, 100, solver="fem", elements=20, order=order)


def test_refuses_bad_mass_and_scheme():
    with pytest.raises(InvalidParameterError, match="mass"):
        wc.collide(0.6, 100, solver="fem", elements=20, mass="diagonal")
    with pytest.raises(InvalidParameterError, match="scheme"):
        wc.collide(0.6, 100, solver="fem", elements=20, scheme="magic")
    with pytest.raises(InvalidParameterError, match="characteristic"):
        wc.collide(0.6, 100, solver="fem", elements=20, order=2, scheme="characteristic")
    with pytest.raises(InvalidParameterError, match="unknown option"):
        wc.collide(0.6, 100, solver="fem", element=20)
    with pytest.raises(InvalidParameterError, match="exponential"):
        wc.collide(0.6, math.inf, solver="fem", elements=20, scheme="force")
    with pytest.raises(InvalidParameterError, match="gap_quadrature"):
        wc.collide(0.6, 100, solver="fem", elements=20, gap_quadrature="simpson")


def test_refuses_a_step_above_the_stable_limit():
    h = 0.8 / 100
    with pytest.raises(InvalidParameterError, match="stable step"):
        wc.collide(0.6, 100, solver="fem", elements=100, dt=1.01 * h)
    with pytest.raises(InvalidParameterError, match="stable step"):
        wc.collide(0.6, 100, solver="fem", elements=100, mass="consistent", dt=0.6 * h)
    with pytest.raises(InvalidParameterError, match="dt"):
        wc.collide(0.6, 100, solver="fem", elements=100, dt=-1.0)
    # at the limit and below it is accepted
    ok = wc.collide(0.6, 100, solver="fem", elements=100, dt=h)
    assert math.isfinite(ok.restitution)
    ok = wc.collide(0.6, 100, solver="fem", elements=100, dt=0.5 * h)
    assert ok.restitution == pytest.approx(0.6467, abs=2e-3)


def test_refuses_bad_nodes():
    with pytest.raises(InvalidParameterError, match="nodes"):
        wc.collide(0.6, 100, solver="fem", nodes=(np.array([0.0, 0.5, 0.4, 0.8]), np.linspace(0, 4 / 3, 10)))
    with pytest.raises(InvalidParameterError, match="rod length"):
        wc.collide(0.6, 100, solver="fem", nodes=(np.linspace(0, 0.7, 10), np.linspace(0, 4 / 3, 10)))


def test_user_nodes_are_used():
    rng = np.random.default_rng(3)
    jitter = [np.concatenate([[0.0], rng.uniform(-0.2, 0.2, n - 1), [0.0]]) for n in (100, 150)]
    nodes = tuple((np.arange(n + 1) + j) * length / n for n, j, length in zip((100, 150), jitter, (0.8, 4 / 3)))
    result = wc.collide(0.6, 100, solver="fem", nodes=nodes)
    assert result.work["elements"] == [100, 150]
    assert result.restitution == pytest.approx(0.6467, abs=5e-3)


def test_initial_velocity_field_is_used():
    # a rod already vibrating collides differently from a cold one
    cold = wc.solve(wc.two_rods(0.6, 100), "fem", elements=100).restitution
    scene = wc.two_rods(0.6, 100, initial_velocity=(lambda s: 0.05 * np.cos(np.pi * s / 0.8), None))
    warm = wc.solve(scene, "fem", elements=100)
    assert abs(warm.restitution - cold) > 1e-4
    assert warm.diagnostics["momentum_drift"] < 1e-12


def test_rods_moving_apart_are_refused():
    scene = Scene(rods=(Rod(1.0), Rod(1.0)), velocities=(-1.0, 1.0), contact=wc.Hard())
    with pytest.raises(InvalidParameterError, match="approach"):
        wc.solve(scene, "fem", elements=10)


def test_unstable_scheme_raises_instead_of_returning_garbage():
    # the impulse splitting cannot follow a contact this stiff: the energy watchdog must stop it
    with pytest.raises(SolverFailure, match="energy"):
        wc.collide(0.6, 1e6, solver="fem", elements=100, order=2, scheme="splitting")


@pytest.mark.parametrize("order, mass", [(1, "consistent"), (2, "lumped"), (2, "consistent")])
def test_every_discretization_is_stable_for_stiff_contact(order, mass):
    errors = []
    for elements in (100, 400):
        result = wc.collide(0.6, 1e6, solver="fem", elements=elements, order=order, mass=mass)
        errors.append(abs(result.restitution - 0.6000139))  # Eq. 23 at kappa = 1e6
        assert result.diagnostics["energy_drift"] < 0.05
    assert errors[1] < errors[0] < 1e-2
