"""A one-dimensional gas of rods whose collisions take their restitution from the vibrations (paper Sec. VIII).

* :mod:`.model`       -- the rods' state (:class:`RodGas`, :func:`random_gas`, length distributions);
* :mod:`.rules`       -- collision rules as values (fixed restitution, restitution table, a solve per collision);
* :mod:`.kernels`     -- the event loop (indexed heap of neighbour-pair collision times, numba);
* :mod:`.simulation`  -- runs in chunks, histories, collapse detection, checkpoint and resume;
* :mod:`.kick_table`  -- an analytic stand-in restitution table for demonstrations;
* :mod:`.reference`   -- a plain-Python heapq event loop (test reference and benchmark baseline).
"""

from .kick_table import thermal_kick_table
from .model import EqualLengths, RodGas, UniformLengths, random_gas
from .rules import FixedRestitution, VibrationSolve, VibrationTable
from .simulation import GasResult, GasSimulation

__all__ = [
    "EqualLengths",
    "FixedRestitution",
    "GasResult",
    "GasSimulation",
    "RodGas",
    "UniformLengths",
    "VibrationSolve",
    "VibrationTable",
    "random_gas",
    "thermal_kick_table",
]
