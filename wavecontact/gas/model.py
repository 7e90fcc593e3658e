"""The state of a one-dimensional gas of rods: lengths, positions, velocities and bath temperatures.

Units: rods of one material with density, cross-section and wave speed 1, so
a rod's mass equals its length; velocities are centre-of-mass velocities;
a bath temperature is an energy per vibration mode (a rod with ``M`` modes at
temperature ``T`` holds vibration energy ``M T``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError, require_integer, require_positive

__all__ = ["DEFAULT_LENGTHS", "AlternatingLengths", "EqualLengths", "RodGas", "UniformLengths", "random_gas"]

MAX_RODS = 10_000_000


@dataclass(frozen=True)
class UniformLengths:
    """Rod lengths uniformly distributed in ``[shortest, longest]`` (length unit of the gas)."""

    shortest: float = 0.5
    longest: float = 1.0

    def __post_init__(self):
        low = require_positive("shortest rod length", self.shortest)
        high = require_positive("longest rod length", self.longest)
        if high < low:
            raise InvalidParameterError(f"longest rod length must be >= shortest ({low:g}), got {high:g}")

    def draw(self, rng, size):
        """``size`` lengths from ``rng`` (a ``numpy.random.Generator``)."""
        return rng.uniform(self.shortest, self.longest, size)

    @property
    def smallest_ratio(self) -> float:
        """The smallest length ratio ``gamma`` two rods can have."""
        return self.shortest / self.longest


@dataclass(frozen=True)
class EqualLengths:
    """All rods of one length (in the hard-core limit they collide elastically: use a fixed rule)."""

    length: float = 1.0

    def __post_init__(self):
        require_positive("rod length", self.length)

    def draw(self, rng, size):
        return np.full(size, float(self.length))

    @property
    def smallest_ratio(self) -> float:
        return 1.0


@dataclass(frozen=True)
class AlternatingLengths:
    """Rods of two lengths in turn, ``short, long, short, ...``: every neighbour pair has ``gamma = short / long``.

    The set-up of Aspelmeier, Giese and Zippelius's gas (PRE 57, 857 (1998)): one length ratio for every
    collision (theirs 4/5).  On a ring use an even number of rods, or the pair across the ring's seam is two
    short rods (``gamma = 1``).  Draws no random numbers.
    """

    short: float = 0.8
    long: float = 1.0

    def __post_init__(self):
        low = require_positive("short rod length", self.short)
        high = require_positive("long rod length", self.long)
        if not low < high:
            raise InvalidParameterError(f"long rod length must exceed the short one ({low:g}), got {high:g}")

    def draw(self, rng, size):
        return np.where(np.arange(size) % 2 == 0, float(self.short), float(self.long))

    @property
    def smallest_ratio(self) -> float:
        return self.short / self.long


@dataclass(frozen=True)
class RodGas:
    """Rods on a ring (periodic) or in a box with elastic walls at 0 and ``system_length``.

    Parameters
    ----------
    lengths : array_like, shape (N,)
        Rod lengths (> 0); the mass of a rod equals its length.
    positions : array_like, shape (N,)
        Centres, ascending, rods not overlapping (and inside the box).  On a
        ring, rod 0 follows rod N-1 across the point ``system_length == 0``.
    velocities : array_like, shape (N,)
        Centre-of-mass velocities, finite.
    bath_temperatures : array_like, shape (N,)
        Temperatures of the rods' vibrations (energy per mode, >= 0).
    system_length : float
        Circumference of the ring or length of the box.
    boundary : {"ring", "walls"}
    """

    lengths: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    bath_temperatures: np.ndarray
    system_length: float
    boundary: str = "ring"

    def __post_init__(self):
        arrays = {}
        for name in ("lengths", "positions", "velocities", "bath_temperatures"):
            a = np.array(getattr(self, name), dtype=np.float64).ravel()
            if not np.all(np.isfinite(a)):
                raise InvalidParameterError(f"gas {name} must be finite")
            a.setflags(write=False)
            arrays[name] = a
        n = arrays["lengths"].size
        if not 2 <= n <= MAX_RODS:
            raise InvalidParameterError(f"number of rods must lie in [2, {MAX_RODS}], got {n}")
        for name, a in arrays.items():
            if a.size != n:
                raise InvalidParameterError(f"gas {name} must have one entry per rod ({n}), got {a.size}")
        if np.any(arrays["lengths"] <= 0):
            raise InvalidParameterError("gas lengths must be > 0")
        if np.any(arrays["bath_temperatures"] < 0):
            raise InvalidParameterError("gas bath_temperatures must be >= 0")
        if self.boundary not in ("ring", "walls"):
            raise InvalidParameterError(f"boundary must be 'ring' or 'walls', got {self.boundary!r}")
        box = require_positive("system_length", self.system_length)
        x, lengths = arrays["positions"], arrays["lengths"]
        gaps = np.diff(x) - 0.5 * (lengths[1:] + lengths[:-1])
        if self.boundary == "ring":
            wrap = x[0] + box - x[-1] - 0.5 * (lengths[0] + lengths[-1])
            gaps = np.append(gaps, wrap)
        else:
            gaps = np.concatenate([[x[0] - 0.5 * lengths[0]], gaps, [box - x[-1] - 0.5 * lengths[-1]]])
        if np.any(gaps < 0):
            raise InvalidParameterError("gas positions must be ascending with the rods not overlapping"
                                        + (" and inside the box" if self.boundary == "walls" else ""))
        for name, a in arrays.items():
            object.__setattr__(self, name, a)
        object.__setattr__(self, "system_length", box)

    @property
    def rods(self) -> int:
        return self.lengths.size

    @property
    def masses(self) -> np.ndarray:
        return self.lengths

    @property
    def free_length(self) -> float:
        """The length not covered by rods."""
        return self.system_length - float(self.lengths.sum())

    def kinetic_energy(self) -> float:
        return float(0.5 * np.sum(self.masses * self.velocities**2))


DEFAULT_LENGTHS = UniformLengths(0.5, 1.0)


def random_gas(rods, *, seed, lengths=DEFAULT_LENGTHS, packing_fraction=0.1, temperature=1.0,
               bath_temperature=0.0, boundary="ring") -> RodGas:
    """A homogeneous gas: random lengths, random free spaces, Maxwellian velocities with zero momentum.

    Parameters
    ----------
    rods : int
        Number of rods N (2 ... 10^7).
    seed : int or numpy.random.SeedSequence
        Root of the random stream (one stream for the whole set-up).
    lengths : object with ``draw(rng, size)``
        Length distribution (:class:`UniformLengths`, :class:`EqualLengths`, or your own).
    packing_fraction : float
        Total rod length over the system length, in (0, 1).
    temperature : float
        Granular temperature ``<m v^2>`` of the initial velocities (> 0).
    bath_temperature : float
        Initial temperature of every bath (>= 0).
    boundary : {"ring", "walls"}
    """
    rods = require_integer("rods", rods, 2, MAX_RODS)
    fraction = float(packing_fraction)
    if not 0.0 < fraction < 1.0:
        raise InvalidParameterError(f"packing_fraction must lie in (0, 1), got {packing_fraction!r}")
    temperature = require_positive("temperature", temperature)
    if not (math.isfinite(float(bath_temperature)) and float(bath_temperature) >= 0):
        raise InvalidParameterError(f"bath_temperature must be finite and >= 0, got {bath_temperature!r}")
    sequence = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    rng = np.random.Generator(np.random.PCG64(sequence))
    length = np.asarray(lengths.draw(rng, rods), dtype=float)
    if length.shape != (rods,) or not np.all(np.isfinite(length)) or np.any(length <= 0):
        raise InvalidParameterError("the length distribution must give N finite positive lengths")
    box = float(length.sum()) / fraction
    # the free length split into N random gaps; gap k follows rod k, the last one split between the
    # two ends (on a ring it is simply the gap between rod N-1 and rod 0)
    gaps = rng.exponential(1.0, rods)
    gaps *= (box - length.sum()) / gaps.sum()
    before = np.concatenate([[0.0], np.cumsum(length + gaps)[:-1]])
    left_ends = before + 0.5 * gaps[-1]
    centres = left_ends + 0.5 * length
    velocity = rng.standard_normal(rods) * np.sqrt(temperature / length)
    if boundary == "ring":
        velocity -= np.sum(length * velocity) / length.sum()
    scale = math.sqrt(temperature * rods / np.sum(length * velocity**2))
    return RodGas(length, centres, velocity * scale, np.full(rods, float(bath_temperature)), box, boundary)
