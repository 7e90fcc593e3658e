"""Solver registry: every solver is an object behind the contract of :mod:`.base`.

Each solver lives in its own package (``wavecontact.delay``, ``wavecontact.fem``,
``wavecontact.modal``) and is imported on first use.  A new solver is its package
plus one line in :data:`_MODULES`; studies, the CLI and plotting find it here
(:data:`SOLVER_NAMES`, :func:`solvers_with`), never by naming it.
"""

from __future__ import annotations

import contextlib
import importlib

from ..errors import InvalidParameterError
from .base import CAPABILITIES

__all__ = ["SOLVER_NAMES", "get_solver", "registered", "solver_for", "solver_names", "solvers_with"]

# name -> module holding ``SOLVER``; the order is the order of listings (help, comparisons)
_MODULES = {
    "delay": "wavecontact.delay.solver",
    "fem": "wavecontact.fem.solver",
    "modal": "wavecontact.modal.solver",
}
SOLVER_NAMES = tuple(_MODULES)
#: the solvers registered for a while by :func:`registered` (tests), after the shipped ones
_TEMPORARY: dict = {}


def solver_names() -> tuple:
    """Names of every registered solver, in registry order (the shipped ones, then any :func:`registered`)."""
    return SOLVER_NAMES + tuple(name for name in _TEMPORARY if name not in _MODULES)


def get_solver(name: str):
    """Return the solver registered as ``name`` (an object satisfying :class:`.base.Solver`)."""
    if not isinstance(name, str) or name not in _MODULES and name not in _TEMPORARY:
        raise InvalidParameterError(f"solver must be one of {', '.join(solver_names())}, got {name!r}")
    module = _TEMPORARY.get(name) or _MODULES[name]
    return importlib.import_module(module).SOLVER


def solvers_with(capability: str) -> tuple:
    """Names of the registered solvers offering ``capability`` (:data:`.base.CAPABILITIES`), in registry order."""
    if capability not in CAPABILITIES:
        raise InvalidParameterError(f"capability must be one of {', '.join(map(repr, CAPABILITIES))}, "
                                    f"got {capability!r}")
    return tuple(name for name in solver_names() if capability in get_solver(name).capabilities)


def solver_for(capability: str):
    """The first registered solver offering ``capability`` (what a study uses for it)."""
    names = solvers_with(capability)
    if not names:
        raise InvalidParameterError(f"no registered solver offers {capability!r}")
    return get_solver(names[0])


@contextlib.contextmanager
def registered(name: str, module: str):
    """Register the solver ``module.SOLVER`` as ``name`` while the block runs (tests: a new solver
    goes through every contract test without being shipped)."""
    if name in _MODULES or name in _TEMPORARY:
        raise InvalidParameterError(f"a solver named {name!r} is already registered")
    _TEMPORARY[name] = module
    try:
        yield get_solver(name)
    finally:
        del _TEMPORARY[name]
