"""The one small interface every solver implements.

A solver is a module with

``NAME``
    its registry name (``"delay"``, ``"fem"``, ``"modal"``);
``OPTIONS``
    a dict of every keyword option it accepts and its default;
``solve(scene, **options) -> CollisionResult``
    one collision of the scene, options already checked with
    :func:`check_options`.

Studies (convergence, comparisons, rings) use only this interface.
"""

from __future__ import annotations

import time

from ..errors import InvalidParameterError

__all__ = ["Stopwatch", "check_options"]


def check_options(solver_name: str, allowed: dict, given: dict) -> dict:
    """Merge ``given`` into the defaults ``allowed``, refusing unknown names."""
    unknown = sorted(set(given) - set(allowed))
    if unknown:
        raise InvalidParameterError(
            f"unknown option(s) {', '.join(map(repr, unknown))} for solver {solver_name!r}; "
            f"allowed: {', '.join(sorted(allowed)) or 'none'}"
        )
    merged = dict(allowed)
    merged.update(given)
    return merged


class Stopwatch:
    """Wall-clock timer: ``with Stopwatch() as sw: ...; sw.seconds``."""

    def __enter__(self):
        self._start = time.perf_counter()
        self.seconds = 0.0
        return self

    def __exit__(self, *exc):
        self.seconds = time.perf_counter() - self._start
        return False

