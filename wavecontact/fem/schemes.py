"""Which mesh, contact treatment and step a finite-element run uses: pure functions of plain numbers.

The rules (docs/fem.md sections 1, 3 and 4) in one place, each a function of
the few numbers it depends on, so that a table of cases can test them
(tests/test_fem_schemes.py).
"""

from __future__ import annotations

from ..errors import InvalidParameterError

__all__ = [
    "FORCE_MAX_COST",
    "FORCE_MESH_RESOLUTION",
    "GAP_SUBSTEPS_LINEAR",
    "GAP_SUBSTEPS_QUARTIC",
    "RESOLVED_COLLISION_STEPS",
    "SCHEMES",
    "choose_scheme",
    "gap_treatment",
    "wants_lattice_mesh",
]

SCHEMES = ("characteristic", "interface", "splitting", "force")
FORCE_MAX_COST = 4.0  # largest ratio of the mesh's step to the contact-resolving step
FORCE_MESH_RESOLUTION = 1.0  # largest alpha V h / c of the facing end elements for the force scheme
RESOLVED_COLLISION_STEPS = 10.0  # alpha V dt at or below which the lattice reconstructs the incoming rate
GAP_SUBSTEPS_QUARTIC = 32  # sub-steps of the gap equation with the quartic reconstruction
GAP_SUBSTEPS_LINEAR = 8  # with the linear one (rods of fewer than 5 nodes)


def wants_lattice_mesh(order: int, mass: str, step_ratio, courant, scheme: str) -> bool:
    """True if a run with these options is meant for the exact lattice.

    ``step_ratio`` is the user's ``dt`` over the element travel time ``h/c``
    (``None``: no ``dt`` given); the lattice needs it to be 1.

    Then the mesh is *matched* (elements of one wave travel time on both
    rods, the remainder of the long rod unmeshed and treated as a delay at
    its far end); otherwise each rod is meshed over its whole length with
    equal elements (*fitted*), since no other discretization gains anything
    from equal travel times.
    """
    at_travel_time = step_ratio is None or abs(step_ratio - 1.0) <= 1e-9
    return order == 1 and mass == "lumped" and at_travel_time and courant is None and scheme in ("auto", "characteristic")


def choose_scheme(
    requested: str,
    *,
    exact_lattice: bool,
    exponential: bool,
    mesh_resolution: float,
    mesh_step: float,
    force_step: float,
    user_step: bool,
) -> tuple:
    """Contact treatment and time step of a run.

    Parameters
    ----------
    requested : {'auto', 'characteristic', 'force', 'interface', 'splitting'}
    exact_lattice : bool
        P1 lumped with the facing elements crossed by a wave in exactly the step.
    exponential : bool
        The contact law is the exponential one (the only law the force scheme takes).
    mesh_resolution : float
        ``alpha V h / c`` of the longer facing element (dimensionless; ignored
        unless ``exponential``).
    mesh_step : float
        The step the mesh alone allows or the user gave (time).
    force_step : float
        Largest step at which plain central differences resolve the contact
        (time; 0 when not ``exponential``).
    user_step : bool
        ``mesh_step`` is the user's ``dt`` (it is then never reduced by 'auto').

    Returns
    -------
    (scheme, dt) : (str, float)

    'auto': 'characteristic' on the exact lattice; else 'force' where the
    facing elements resolve the exponential law and its step is at most
    ``FORCE_MAX_COST`` times smaller than the mesh's (a user step must already
    be within it); else 'interface'.
    """
    if requested not in ("auto",) + SCHEMES:
        raise InvalidParameterError(
            f"scheme must be one of 'auto', {', '.join(map(repr, SCHEMES))}, got {requested!r}"
        )
    if requested == "characteristic" and not exact_lattice:
        raise InvalidParameterError(
            "scheme='characteristic' needs order=1, mass='lumped' and dt equal to the travel time h/c "
            "of the elements at both facing ends (the default matched mesh with dt=None)"
        )
    if requested == "force":
        if not exponential:
            raise InvalidParameterError("scheme='force' needs the exponential contact law")
        return "force", mesh_step if user_step else min(mesh_step, force_step)
    if requested != "auto":
        return requested, mesh_step
    if exact_lattice:
        return "characteristic", mesh_step
    if not exponential or mesh_resolution > FORCE_MESH_RESOLUTION:
        return "interface", mesh_step  # hard or penalty, or the mesh does not resolve the force's rise
    if mesh_step <= force_step:
        return "force", mesh_step
    if not user_step and FORCE_MAX_COST * force_step >= mesh_step:
        return "force", force_step
    return "interface", mesh_step


def gap_treatment(scheme: str, exponential: bool, collision_steps: float, min_nodes: int) -> tuple:
    """How the lattice integrates the gap equation over a step: ``(substeps, centered)``.

    ``collision_steps`` is ``alpha V dt``.  ``centered``: both rods have at
    least 5 nodes, so the lattice reads the mean incoming rate of the two
    steps before and after this one (quartic reconstruction; the one-jump
    reconstruction of a front between lattice times).  ``substeps > 1``
    where an exponential contact is resolved (``alpha V dt <=
    RESOLVED_COLLISION_STEPS``): the rate is then reconstructed inside the
    step.  Only the characteristic scheme uses either.
    """
    if scheme != "characteristic":
        return 1, False
    centered = min_nodes >= 5
    if not (exponential and collision_steps <= RESOLVED_COLLISION_STEPS):
        return 1, centered
    return (GAP_SUBSTEPS_QUARTIC if centered else GAP_SUBSTEPS_LINEAR), centered
