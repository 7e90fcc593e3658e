"""Solver registry: every solver is an object behind the contract of :mod:`.base`.

Each solver lives in its own package (``wavecontact.delay``, ``wavecontact.fem``,
``wavecontact.modal``) and is imported on first use.
"""

from __future__ import annotations

import importlib

from ..errors import InvalidParameterError

__all__ = ["SOLVER_NAMES", "get_solver"]

_MODULES = {
    "delay": "wavecontact.delay.solver",
    "fem": "wavecontact.fem.solver",
    "modal": "wavecontact.modal.solver",
}
SOLVER_NAMES = tuple(_MODULES)


def get_solver(name: str):
    """Return the solver registered as ``name`` (an object satisfying :class:`.base.Solver`)."""
    if not isinstance(name, str) or name not in _MODULES:
        raise InvalidParameterError(f"solver must be one of {', '.join(SOLVER_NAMES)}, got {name!r}")
    return importlib.import_module(_MODULES[name]).SOLVER
