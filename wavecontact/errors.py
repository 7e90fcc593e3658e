"""Exceptions raised by wavecontact.

Every refusal names the offending field and the range it must lie in, so a
user can fix the call without reading the source.
"""

from __future__ import annotations

import math
import numbers

__all__ = [
    "AccuracyError",
    "CheckpointError",
    "InvalidParameterError",
    "LimitError",
    "SolverFailure",
    "UnsupportedSceneError",
    "WavecontactError",
    "require_finite",
    "require_integer",
    "require_positive",
]


class WavecontactError(Exception):
    """Base class of all errors raised on purpose by wavecontact."""


class InvalidParameterError(WavecontactError, ValueError):
    """A parameter is outside its allowed range (the message says which)."""


class UnsupportedSceneError(WavecontactError, ValueError):
    """The scene is valid but the chosen solver cannot model it."""


class CheckpointError(InvalidParameterError):
    """A checkpoint file failed a check (readable, schema, checksum, build, parameters)."""


class SolverFailure(WavecontactError, RuntimeError):
    """A solver detected that its result would be wrong (energy drift,
    unresolved contact, non-finite state) and refuses to return it.

    ``outcome`` is the :class:`wavecontact.result.Outcome` that says how the
    solve ended (None where no single one applies).
    """

    def __init__(self, message: str, outcome=None):
        super().__init__(message)
        self.outcome = outcome


class LimitError(InvalidParameterError):
    """A run would exceed a size or work limit; refused before anything is
    allocated or run.  The message gives the estimate and the option that
    raises the limit."""


class AccuracyError(WavecontactError, RuntimeError):
    """A result's error estimate exceeds the requested ``tolerance``.

    ``result`` is the rejected :class:`~wavecontact.result.CollisionResult`
    (for inspection), ``advice`` the resolution that should reach the tolerance.
    """

    def __init__(self, message: str, result=None, advice: str = ""):
        super().__init__(message)
        self.result = result
        self.advice = advice


def require_finite(name: str, value) -> float:
    """Return ``value`` as a float, refusing NaN, infinities and non-numbers."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(number):
        raise InvalidParameterError(f"{name} must be finite, got {number!r}")
    return number


def require_positive(name: str, value, *, allow_inf: bool = False) -> float:
    """Return ``value`` as a float if it is > 0 (and finite unless ``allow_inf``)."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a positive number, got {value!r}") from None
    if math.isnan(number) or number <= 0.0 or (math.isinf(number) and not allow_inf):
        allowed = "(0, inf]" if allow_inf else "(0, inf) and finite"
        raise InvalidParameterError(f"{name} must lie in {allowed}, got {number!r}")
    return number


MAGNITUDE_RANGE = (1e-30, 1e30)  # physical inputs: any consistent units, products stay in double range


def require_magnitude(name: str, value, *, signed: bool = False) -> float:
    """Return ``value`` as a float if its magnitude lies in :data:`MAGNITUDE_RANGE`.

    Positive quantities must lie in ``[1e-30, 1e30]``; with ``signed`` the value may
    also be zero or negative, ``0`` or ``1e-30 <= |value| <= 1e30`` (a velocity: smaller
    speeds underflow the energies computed from them).
    """
    low, high = MAGNITUDE_RANGE
    number = require_finite(name, value) if signed else require_positive(name, value)
    if abs(number) > high or (number != 0.0 and abs(number) < low):
        allowed = f"0 or a magnitude in [{low:g}, {high:g}]" if signed else f"[{low:g}, {high:g}]"
        raise InvalidParameterError(f"{name} must lie in {allowed} (any consistent units), got {number!r}")
    return number


def require_integer(name: str, value, low: int | None = None, high: int | None = None, *,
                    allowed: str | None = None) -> int:
    """Return ``value`` as an int if it is a whole number in ``[low, high]`` (either bound may be None).

    The one integer check of the package: ints, NumPy integers and floats with an integral value
    (``3.0``, as a JSON file or a command line may give it) pass; bools, other types, non-integral,
    NaN and infinite values are refused with :class:`InvalidParameterError` naming ``name`` and the
    range (``allowed``: that phrase instead of the one built from the bounds, e.g. ``"a non-negative
    integer or a numpy SeedSequence"``).
    """
    number = None
    whole = isinstance(value, numbers.Integral) or (
        isinstance(value, numbers.Real) and math.isfinite(value) and float(value).is_integer())
    if whole and not isinstance(value, bool):
        number = int(value)
    if number is None or (low is not None and number < low) or (high is not None and number > high):
        if allowed is None:
            if low is not None and high is not None:
                allowed = f"an integer in [{low}, {high}]"
            else:
                allowed = "an integer" if low is None else f"an integer >= {low}"
        raise InvalidParameterError(f"{name} must be {allowed}, got {value!r}")
    return number
