"""The finite-element solver's choice of mesh, contact scheme and gap treatment (fem/schemes.py),
case by case from a table, and that build_setup follows it."""

import math

import pytest

import wavecontact as wc
from wavecontact.errors import InvalidParameterError
from wavecontact.fem.schemes import (
    FORCE_MAX_COST,
    GAP_SUBSTEPS_LINEAR,
    GAP_SUBSTEPS_QUARTIC,
    choose_scheme,
    gap_treatment,
    wants_lattice_mesh,
)
from wavecontact.fem.simulation import build_setup

# requested, exact lattice, exponential, alpha V h / c, mesh step, force step, user step -> scheme, step
SCHEME_TABLE = [
    ("auto", True, True, 0.1, 1.0, 0.5, False, "characteristic", 1.0),  # the exact lattice wins
    ("auto", True, False, 0.0, 1.0, 0.0, False, "characteristic", 1.0),  # for any law
    ("auto", False, False, 0.0, 1.0, 0.0, False, "interface", 1.0),  # hard or penalty off the lattice
    ("auto", False, True, 2.0, 1.0, 0.5, False, "interface", 1.0),  # the mesh does not resolve the force
    ("auto", False, True, 0.5, 0.4, 0.5, False, "force", 0.4),  # the mesh's step resolves the contact
    ("auto", False, True, 0.5, 1.0, 0.5, False, "force", 0.5),  # a step twice smaller does
    ("auto", False, True, 0.5, 1.0, 1.0 / FORCE_MAX_COST, False, "force", 1.0 / FORCE_MAX_COST),  # at the cap
    ("auto", False, True, 0.5, 1.0, 0.2, False, "interface", 1.0),  # too dear: more than 4 times the steps
    ("auto", False, True, 0.5, 1.0, 0.5, True, "interface", 1.0),  # a user step is never reduced
    ("auto", False, True, 0.5, 0.5, 0.5, True, "force", 0.5),  # ... but used if it resolves the contact
    ("force", False, True, 2.0, 1.0, 0.3, False, "force", 0.3),  # forced: at the contact-resolving step
    ("force", False, True, 2.0, 1.0, 0.3, True, "force", 1.0),  # forced with a user step: as given
    ("interface", True, True, 0.1, 1.0, 0.5, False, "interface", 1.0),
    ("splitting", False, False, 0.0, 1.0, 0.0, False, "splitting", 1.0),
    ("characteristic", True, True, 0.1, 1.0, 0.5, False, "characteristic", 1.0),
]


@pytest.mark.parametrize("requested, exact, exponential, resolution, mesh, force, user, scheme, step", SCHEME_TABLE)
def test_scheme_table(requested, exact, exponential, resolution, mesh, force, user, scheme, step):
    chosen = choose_scheme(requested, exact_lattice=exact, exponential=exponential, mesh_resolution=resolution,
                           mesh_step=mesh, force_step=force, user_step=user)
    assert chosen == (scheme, step)


@pytest.mark.parametrize(
    "requested, exact, exponential, message",
    [
        ("characteristic", False, True, "characteristic"),
        ("force", False, False, "exponential"),
        ("leapfrog", False, True, "scheme must be one of"),
    ],
)
def test_scheme_refusals(requested, exact, exponential, message):
    with pytest.raises(InvalidParameterError, match=message):
        choose_scheme(requested, exact_lattice=exact, exponential=exponential, mesh_resolution=0.1,
                      mesh_step=1.0, force_step=0.5, user_step=False)


# scheme, exponential, alpha V dt, fewest nodes of a rod -> substeps, centered
GAP_TABLE = [
    ("characteristic", True, 1.0, 100, GAP_SUBSTEPS_QUARTIC, True),  # resolved: quartic, sub-stepped
    ("characteristic", True, 10.0, 100, GAP_SUBSTEPS_QUARTIC, True),  # the threshold itself
    ("characteristic", True, 10.5, 100, 1, True),  # unresolved: constant rate (one-jump fronts still read)
    ("characteristic", False, 0.0, 100, 1, True),  # hard or penalty
    ("characteristic", True, 1.0, 4, GAP_SUBSTEPS_LINEAR, False),  # rods too short for five step means
    ("characteristic", False, 0.0, 4, 1, False),
    ("force", True, 1.0, 100, 1, False),  # only the lattice reads incoming rates
    ("interface", True, 1.0, 100, 1, False),
]


@pytest.mark.parametrize("scheme, exponential, collision_steps, nodes, substeps, centered", GAP_TABLE)
def test_gap_treatment_table(scheme, exponential, collision_steps, nodes, substeps, centered):
    assert gap_treatment(scheme, exponential, collision_steps, nodes) == (substeps, centered)


# order, mass, dt / (h/c), courant, scheme -> matched mesh for the lattice
MESH_TABLE = [
    (1, "lumped", None, None, "auto", True),
    (1, "lumped", 1.0, None, "auto", True),  # a user step equal to the travel time
    (1, "lumped", 0.9, None, "auto", False),
    (1, "lumped", None, 0.9, "auto", False),
    (1, "lumped", None, None, "interface", False),
    (1, "lumped", None, None, "characteristic", True),
    (1, "consistent", None, None, "auto", False),
    (2, "lumped", None, None, "auto", False),
]


@pytest.mark.parametrize("order, mass, ratio, courant, scheme, matched", MESH_TABLE)
def test_mesh_table(order, mass, ratio, courant, scheme, matched):
    assert wants_lattice_mesh(order, mass, ratio, courant, scheme) is matched


@pytest.mark.parametrize(
    "kappa, options, scheme",
    [
        (100.0, {}, "characteristic"),
        (math.inf, {}, "characteristic"),
        (20.0, {"order": 2}, "force"),  # alpha V h / c = 0.32
        (100.0, {"order": 2}, "interface"),  # 1.6: the mesh does not resolve the force
        (1e6, {"order": 2}, "interface"),
        (math.inf, {"mass": "consistent"}, "interface"),
        (20.0, {"courant": 0.9}, "force"),
    ],
)
def test_build_setup_follows_the_tables(kappa, options, scheme):
    setup = build_setup(wc.two_rods(0.6, kappa), elements=50, **options)
    codes = {"characteristic": 0, "interface": 1, "splitting": 2, "force": 3}
    assert setup.scheme == codes[scheme]
    remainder = setup.far_theta[1] > 0.0  # 5 N / 3 = 83.3 elements on the long rod
    assert remainder == (scheme == "characteristic")  # elsewhere the long rod is meshed whole
    total = sum(d.lumped_mass.sum() for d in setup.rods)
    assert total == pytest.approx(sum(rod.mass for rod in wc.two_rods(0.6, kappa).rods), rel=1e-12)
