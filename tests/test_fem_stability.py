"""The stable step's eigenvalue with the counts it can take as known equals the plain bisection to the last bit."""

import math

import numpy as np
import pytest

from wavecontact import Rod
from wavecontact.fem import stability
from wavecontact.fem.discretization import discretize_rod, matched_nodes, uniform_nodes
from wavecontact.fem.stability import banded_mass, count_below, largest_eigenvalue, stable_step


def _plain_bisection(disc, rtol=1e-13):
    """The bisection as it was, a Sturm count at every shift."""
    stiffness = np.ascontiguousarray(disc.stiffness_bands)
    mass = np.ascontiguousarray(banded_mass(disc))
    upper, lower = stability._element_bound(disc) * (1.0 + 1e-9), 0.0
    while upper - lower > rtol * upper:
        middle = 0.5 * (lower + upper)
        if count_below(stiffness, mass, middle) >= disc.n_nodes:
            upper = middle
        else:
            lower = middle
    return upper


def _rods():
    rng = np.random.default_rng(29)
    rods = []
    for gamma in (0.6, 0.6 + 1e-6, 0.3, 0.97):
        step = gamma / 800
        rods.append((f"matched short gamma {gamma}", Rod(gamma), matched_nodes(gamma, step, False), "left"))
        rods.append((f"matched long gamma {gamma}", Rod(1.0 / gamma), matched_nodes(1.0 / gamma, step, True), "right"))
    for elements in (1, 2, 7, 200):
        rods.append((f"uniform {elements}", Rod(1.3, density=2.0, youngs_modulus=5.0), uniform_nodes(1.3, elements), None))
    for k in range(4):
        graded = np.cumsum(np.concatenate([[0.0], rng.uniform(0.2, 1.0, int(rng.integers(5, 300)))]))
        rods.append((f"graded {k}", Rod(2.0), graded / graded[-1] * 2.0, None))
    return rods


@pytest.mark.parametrize("name, rod, vertices, remainder", _rods(), ids=[r[0] for r in _rods()])
@pytest.mark.parametrize("mass", ["lumped", "consistent"])
def test_largest_eigenvalue_equals_plain_bisection_bit_for_bit(name, rod, vertices, remainder, mass):
    del name
    disc = discretize_rod(rod, vertices, 1, mass, remainder)
    assert largest_eigenvalue(disc) == _plain_bisection(disc)


def _matched_pair(gamma, elements, order=1, mass="lumped"):
    step = gamma / elements
    return (discretize_rod(Rod(gamma), matched_nodes(gamma, step, False), order, mass, "left"),
            discretize_rod(Rod(1.0 / gamma), matched_nodes(1.0 / gamma, step, True), order, mass, "right"))


@pytest.mark.parametrize("gamma", [0.6, 0.6 + 1e-6, 0.3, 1.0])
@pytest.mark.parametrize("order, mass", [(1, "lumped"), (1, "consistent"), (2, "lumped")])
def test_stable_step_equals_plain_bisection_of_every_rod(gamma, order, mass):
    rods = _matched_pair(gamma, 200, order, mass)
    assert stable_step(rods) == 2.0 / math.sqrt(max(_plain_bisection(d) for d in rods))
    assert stable_step(rods[::-1]) == stable_step(rods)


def test_dominated_rod_is_not_bisected(monkeypatch):
    """The long rod's remainder mass puts its lambda_max ~1e-6 below the short rod's: one count settles it."""
    rods = _matched_pair(0.6, 800)
    sizes = []

    def counting(stiffness, mass, sigma):
        sizes.append(stiffness.shape[1])
        return count_below(stiffness, mass, sigma)

    monkeypatch.setattr(stability, "count_below", counting)
    stable_step(rods)
    assert sizes.count(rods[1].n_nodes) == 1 and 0 < sizes.count(rods[0].n_nodes) < 45 / 3


def test_most_counts_are_known(monkeypatch):
    """The bracket is confirmed on the long rod of the solver's mesh (by inverse iteration: its far end
    carries the remainder's mass): fewer than a third of the plain bisection's counts."""
    disc = discretize_rod(Rod(1.0 / 0.6), matched_nodes(1.0 / 0.6, 0.6 / 800, True), 1, "lumped", "right")
    counts = []

    def counting(*args):
        counts.append(args[2])
        return count_below(*args)

    monkeypatch.setattr(stability, "count_below", counting)
    value = largest_eigenvalue(disc)
    assert value == _plain_bisection(disc)  # the plain bisection's counts go to the real kernel
    assert 0 < len(counts) < 45 / 3


def test_unconfirmed_bracket_falls_back_to_every_count(monkeypatch):
    """Wrong estimates (here 1 % low) are not confirmed by their two counts: every shift is counted."""
    disc = discretize_rod(Rod(1.0), uniform_nodes(1.0, 50), 1, "lumped")
    for name in ("_inverse_iteration", "_rayleigh_quotient"):
        estimate = getattr(stability, name)
        monkeypatch.setattr(stability, name, lambda *args, estimate=estimate: 0.99 * estimate(*args))
    assert stability._known_answers(np.ascontiguousarray(disc.stiffness_bands),
                                    np.ascontiguousarray(banded_mass(disc)), 1e9) == (0.0, math.inf)
    assert largest_eigenvalue(disc) == _plain_bisection(disc)


def test_wider_bands_count_every_shift():
    disc = discretize_rod(Rod(1.0), uniform_nodes(1.0, 30), 2, "lumped")
    assert stability._known_answers(np.ascontiguousarray(disc.stiffness_bands),
                                    np.ascontiguousarray(banded_mass(disc)), 1e9) == (0.0, math.inf)
    assert largest_eigenvalue(disc) == _plain_bisection(disc)
