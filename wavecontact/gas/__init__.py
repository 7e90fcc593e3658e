"""A one-dimensional gas of rods whose collisions take their restitution from the vibrations (paper Sec. VIII).

* :mod:`.model`       -- the rods' state (:class:`RodGas`, :func:`random_gas`, length distributions);
* :mod:`.rules`       -- collision rules as values (fixed restitution, restitution table, a solve per collision);
* :mod:`.kernels`     -- the event loop (tournament tree of neighbour-pair collision times, numba);
* :mod:`.simulation`  -- runs in chunks, histories, collapse detection, checkpoint and resume;
* :mod:`.rod_table`   -- the restitution table computed from rod collisions that the gas uses by default,
  and the per-collision draw of :class:`VibrationSolve` from :func:`wavecontact.collide`;
* :mod:`.reference`   -- a plain-Python heapq event loop (test reference and benchmark baseline).
"""

from .model import EqualLengths, RodGas, UniformLengths, random_gas
from .rod_table import DEFAULT_TABLE_FILE, collision_draw, rod_table
from .rules import FixedRestitution, VibrationSolve, VibrationTable
from .simulation import GasResult, GasSimulation

__all__ = [
    "DEFAULT_TABLE_FILE",
    "EqualLengths",
    "FixedRestitution",
    "GasResult",
    "GasSimulation",
    "RodGas",
    "UniformLengths",
    "VibrationSolve",
    "VibrationTable",
    "collision_draw",
    "random_gas",
    "rod_table",
]
