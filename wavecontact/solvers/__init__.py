"""Solver registry: every solver is a module behind the interface of :mod:`.base`."""

from __future__ import annotations

import importlib

from ..errors import InvalidParameterError

__all__ = ["SOLVER_NAMES", "get_solver"]

_MODULES = {
    "delay": "wavecontact.solvers.delay",
    "fem": "wavecontact.solvers.fem",
    "modal": "wavecontact.solvers.modal",
}
SOLVER_NAMES = tuple(_MODULES)


def get_solver(name: str):
    """Return the solver module registered as ``name``."""
    if name not in _MODULES:
        raise InvalidParameterError(f"solver must be one of {', '.join(SOLVER_NAMES)}, got {name!r}")
    return importlib.import_module(_MODULES[name])
