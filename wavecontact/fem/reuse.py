"""The two rods' discretizations and stable step of recent meshes, reused from one solve to the next.

A finite-element solve spends most of its time at small and moderate sizes (a few thousand nodes) in
the set-up: scikit-fem's assembly and the inertia bisection of the stable step take about 4 ms per
mesh, the time loop at 800 elements about 2 ms (docs/performance.md).  The error estimate's runs
(``N/2``, ``N/4``) repeat that set-up on their own meshes, and a sweep of ``kappa`` or of thermal
realisations at one ``gamma`` meets the same meshes again, whose matrices depend on the rods and the
mesh only (not on the contact, the velocities or the initial fields).  So the discretizations and
their stable step are kept for the last :data:`RECENT` meshes the solver built itself
(``nodes=None``), each of at most :data:`MOST_NODES` nodes: at most about 25 MB held.  They are the
same numbers a new assembly gives (the same function of the same inputs), so results stay
bit-identical; nothing downstream writes into a discretization (tests/test_fem_reuse.py checks it
for every scheme).
"""

from __future__ import annotations

import threading
from collections import OrderedDict

import numpy as np

from .discretization import discretize_rod
from .stability import stable_step

__all__ = ["MOST_NODES", "RECENT", "clear", "discretized_rods"]

#: meshes kept (the requested run and its Richardson levels, N/2 and N/4, with room for a sweep's next N)
RECENT = 8
#: largest mesh kept (nodes of both rods); beyond it the time loop dominates the solve anyway
MOST_NODES = 20_000

_RECENT: OrderedDict = OrderedDict()
#: solves on threads (a thread pool, dask's threaded workers) share the kept meshes: one at a time in the table
_LOCK = threading.Lock()


def discretized_rods(rods, vertices, order: int, mass: str, remainder, reuse: bool = True) -> tuple:
    """``((left, right), stable step)``: :func:`~wavecontact.fem.discretization.discretize_rod` of each rod
    on its vertices and :func:`~wavecontact.fem.stability.stable_step` of the pair, from the last
    :data:`RECENT` meshes where the same rods, vertices, order, mass and remainders were built before.

    ``reuse`` False (a user's mesh) always builds anew and keeps nothing.
    """
    if not reuse:
        built = tuple(discretize_rod(rod, v, order, mass, r) for rod, v, r in zip(rods, vertices, remainder))
        return built, stable_step(built)
    key = (order, mass, *((rod, r, np.shape(v), np.asarray(v, dtype=float).tobytes())
                          for rod, v, r in zip(rods, vertices, remainder)))
    with _LOCK:
        known = _RECENT.get(key)
        if known is not None:
            _RECENT.move_to_end(key)
            return known
    built = tuple(discretize_rod(rod, v, order, mass, r) for rod, v, r in zip(rods, vertices, remainder))
    known = (built, stable_step(built))
    if sum(d.n_nodes for d in built) <= MOST_NODES:
        with _LOCK:
            _RECENT[key] = known
            while len(_RECENT) > RECENT:
                _RECENT.popitem(last=False)
    return known


def clear() -> None:
    """Forget every kept mesh."""
    with _LOCK:
        _RECENT.clear()
