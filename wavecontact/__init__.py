"""wavecontact: longitudinal collisions of elastic rods and their restitution.

Three solvers share one scene model and one entry point:

* ``fem``   -- finite elements (scikit-fem) with explicit time stepping;
* ``modal`` -- the Hamiltonian of rod modes (Giese & Zippelius 1996, Eq. 7);
* ``delay`` -- the delay-differential equation of the relative velocity (Eq. 16).

>>> import wavecontact
>>> result = wavecontact.collide(gamma=0.6, kappa=100)
>>> round(result.restitution, 6)
0.646697
"""

from ._version import __version__ as __version__
from .api import collide, solve
from .bodies import PiecewiseRod, RigidBody, Segment, Wall
from .contact import ContactLaw, Exponential, Hard, Hertz, Penalty
from .errors import InvalidParameterError, SolverFailure, UnsupportedSceneError, WavecontactError
from .impact_result import ContactRecord, ImpactResult
from .result import CollisionResult
from .scene import Rod, Scene, two_rod_parameters, two_rods
from .studies.ensemble import ensemble

__all__ = [
    "CollisionResult",
    "ContactLaw",
    "ContactRecord",
    "Exponential",
    "Hard",
    "Hertz",
    "ImpactResult",
    "InvalidParameterError",
    "Penalty",
    "PiecewiseRod",
    "RigidBody",
    "Rod",
    "Scene",
    "Segment",
    "SolverFailure",
    "UnsupportedSceneError",
    "Wall",
    "WavecontactError",
    "collide",
    "ensemble",
    "solve",
    "two_rod_parameters",
    "two_rods",
]
