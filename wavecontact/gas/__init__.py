"""A one-dimensional gas of rods whose collisions take their restitution from the vibrations (paper Sec. VIII).

* :mod:`.model`       -- the rods' state (:class:`RodGas`, :func:`random_gas`, length distributions);
* :mod:`.rules`       -- collision rules as values (fixed restitution, restitution table, a solve per collision);
* :mod:`.kernels`     -- the event loop (tournament tree of neighbour-pair collision times, numba);
* :mod:`.simulation`  -- runs in chunks, histories, collapse detection, checkpoint and resume;
* :mod:`.rod_table`   -- the restitution table computed from rod collisions that the gas uses by default,
  and the per-collision draw of :class:`VibrationSolve` from :func:`wavecontact.collide`;
* :mod:`.collision_law` -- the collision law in ``x = E_tr/(E_tr + T_pair)`` and the short rod's share
  ``s = T_short/(T_short + T_long)`` (every pair state): hard core, and a soft (finite-kappa) part for a gas
  with a contact stiffness; the default of the vibration rule; :mod:`.hardcore_collision` -- one hard-core thermal collision with the per-rod split;
* :mod:`.reference`   -- a plain-Python heapq event loop (test reference and benchmark baseline).
"""

from .collision_law import CollisionLaw, default_law, default_soft_law, load_law
from .hardcore_collision import hard_core_collision
from .model import AlternatingLengths, EqualLengths, RodGas, UniformLengths, random_gas
from .rod_table import DEFAULT_TABLE_FILE, collision_draw, contact_draw, hard_core_draw, rod_table
from .rules import FixedRestitution, VibrationLaw, VibrationSolve, VibrationTable
from .simulation import GasResult, GasSimulation, StoppingRules

__all__ = [
    "DEFAULT_TABLE_FILE",
    "AlternatingLengths",
    "CollisionLaw",
    "EqualLengths",
    "FixedRestitution",
    "GasResult",
    "GasSimulation",
    "RodGas",
    "StoppingRules",
    "UniformLengths",
    "VibrationLaw",
    "VibrationSolve",
    "VibrationTable",
    "collision_draw",
    "contact_draw",
    "default_law",
    "default_soft_law",
    "hard_core_collision",
    "hard_core_draw",
    "load_law",
    "random_gas",
    "rod_table",
]
