"""Contact laws between facing rod ends.

A contact law maps the end-to-end gap ``r`` (length; negative means overlap)
to a repulsive force (force units) that pushes the two ends apart.  Laws are
plain immutable values.  Compiled kernels see a law as the four numbers of
:meth:`ContactLaw.kernel_parameters` (one code table, shared by the FE, modal
and delay kernels); :mod:`wavecontact.contact_kernels` evaluates them, and its
tests hold it to the Python :meth:`~ContactLaw.force` and
:meth:`~ContactLaw.potential` methods, the reference.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import InvalidParameterError, require_positive

__all__ = [
    "LAW_EXPONENTIAL",
    "LAW_HARD",
    "LAW_HERTZ",
    "LAW_PENALTY",
    "ContactLaw",
    "Exponential",
    "Hard",
    "Hertz",
    "Penalty",
    "contact_from_name",
]

#: Kernel codes of the contact laws, shared by every compiled kernel.
LAW_EXPONENTIAL = 0
LAW_PENALTY = 1  # linear spring on overlap; a hard law is its limit of infinite stiffness
LAW_HARD = 2
LAW_HERTZ = 3  # K delta^(3/2) on overlap delta = -r (rounded ends)


class ContactLaw:
    """Base class: a repulsive force of the end-to-end gap.

    Besides its force and energy a law tells the solvers what they need to
    know about it through properties (no solver checks a law's class):
    :attr:`code` (its kernel code), :attr:`range`, :attr:`hard` (a
    constraint, no force law), :attr:`decay_rate` (``alpha`` of an
    exponential tail, 0 for laws acting on overlap only) and
    :attr:`stiffness_from_solver` (the solver picks the stiffness).
    """

    name = "abstract"
    code = -1
    hard = False
    stiffness_from_solver = False

    @property
    def decay_rate(self) -> float:
        """Inverse length of an exponential tail of the force (1/length); 0 for a law acting on overlap only."""
        return 0.0

    def stiffness_at(self, gap):
        """``-dF/dgap`` at gap ``gap`` (force/length, >= 0)."""
        raise NotImplementedError

    def force(self, gap):
        """Repulsive force (>= 0) at end-to-end gap ``gap`` (length units)."""
        raise NotImplementedError

    def potential(self, gap):
        """Interaction energy at gap ``gap`` (energy units); zero far apart."""
        raise NotImplementedError

    @property
    def range(self) -> float:
        """Distance over which the force decays (length units); 0 for hard contact."""
        raise NotImplementedError

    def kernel_parameters(self) -> tuple:
        """``(code, alpha, strength, stiffness)``: the law as compiled kernels see it.

        ``code`` is one of :data:`LAW_EXPONENTIAL`, :data:`LAW_PENALTY`,
        :data:`LAW_HARD`; unused numbers are 0 (``stiffness`` of a hard law is
        ``inf``, of a penalty law left to the solver ``nan``).
        """
        raise NotImplementedError


@dataclass(frozen=True)
class Exponential(ContactLaw):
    """The paper's potential ``V(r) = B exp(-alpha r)``.

    Parameters
    ----------
    alpha : float
        Inverse range of the potential (1/length), in (0, inf).
    strength : float
        Prefactor ``B`` (energy), in (0, inf).  ``B`` only shifts the gap at
        which the ends feel each other; it does not change the restitution.
    """

    alpha: float
    strength: float = 1.0
    name = "exponential"
    code = LAW_EXPONENTIAL

    def __post_init__(self):
        object.__setattr__(self, "alpha", require_positive("alpha", self.alpha))
        object.__setattr__(self, "strength", require_positive("strength (B)", self.strength))

    def force(self, gap):
        return self.alpha * self.strength * np.exp(-self.alpha * np.asarray(gap, dtype=float))

    def potential(self, gap):
        return self.strength * np.exp(-self.alpha * np.asarray(gap, dtype=float))

    def stiffness_at(self, gap):
        return self.alpha * self.alpha * self.strength * np.exp(-self.alpha * np.asarray(gap, dtype=float))

    @property
    def range(self) -> float:
        return 1.0 / self.alpha

    @property
    def decay_rate(self) -> float:
        return self.alpha

    def kernel_parameters(self) -> tuple:
        return LAW_EXPONENTIAL, float(self.alpha), float(self.strength), 0.0


@dataclass(frozen=True)
class Penalty(ContactLaw):
    """Linear spring acting on overlap only: ``F = k max(0, -r)``.

    Parameters
    ----------
    stiffness : float or None
        Spring constant ``k`` (force/length), in (0, inf).  ``None`` lets the
        solver choose one from its discretization (the FE solver uses
        ``E A / h`` of the stiffer facing element).
    """

    stiffness: float | None = None
    name = "penalty"
    code = LAW_PENALTY

    def __post_init__(self):
        if self.stiffness is not None:
            object.__setattr__(self, "stiffness", require_positive("stiffness", self.stiffness))

    def force(self, gap):
        if self.stiffness is None:
            raise InvalidParameterError("penalty stiffness is not set (None means: chosen by the solver)")
        return self.stiffness * np.maximum(0.0, -np.asarray(gap, dtype=float))

    def potential(self, gap):
        if self.stiffness is None:
            raise InvalidParameterError("penalty stiffness is not set (None means: chosen by the solver)")
        return 0.5 * self.stiffness * np.maximum(0.0, -np.asarray(gap, dtype=float)) ** 2

    def stiffness_at(self, gap):
        if self.stiffness is None:
            raise InvalidParameterError("penalty stiffness is not set (None means: chosen by the solver)")
        return np.where(np.asarray(gap, dtype=float) < 0.0, self.stiffness, 0.0)

    @property
    def range(self) -> float:
        return 0.0

    @property
    def stiffness_from_solver(self) -> bool:
        return self.stiffness is None

    def kernel_parameters(self) -> tuple:
        return LAW_PENALTY, 0.0, 0.0, math.nan if self.stiffness is None else float(self.stiffness)


@dataclass(frozen=True)
class Hard(ContactLaw):
    """Unilateral constraint: no overlap, no energy lost at the contact itself.

    The limit ``alpha -> inf`` of :class:`Exponential` (``kappa = inf``).
    """

    name = "hard"
    code = LAW_HARD
    hard = True

    def force(self, gap):
        raise InvalidParameterError("hard contact has no force law; it is a constraint")

    def potential(self, gap):
        return np.where(np.asarray(gap, dtype=float) < 0.0, math.inf, 0.0)

    @property
    def range(self) -> float:
        return 0.0

    def kernel_parameters(self) -> tuple:
        return LAW_HARD, 0.0, 0.0, math.inf


@dataclass(frozen=True)
class Hertz(ContactLaw):
    """Hertz contact of rounded ends: ``F = K delta^(3/2)`` for the overlap ``delta = max(0, -r)``.

    The ends of Sears' rods are spherical caps; two elastic spheres pressed
    together by ``delta`` push back with ``K delta^(3/2)`` (Hertz), ``K``
    fixed by the radii and the materials.  Its dimensionless stiffness is
    ``k_H = K mu^(3/2) V^(1/2) / Z_s^(5/2)`` (docs/theory.md).

    Parameters
    ----------
    stiffness : float
        ``K`` (force/length^(3/2)), in (0, inf).
    """

    stiffness: float
    name = "hertz"
    code = LAW_HERTZ

    def __post_init__(self):
        object.__setattr__(self, "stiffness", require_positive("stiffness", self.stiffness))

    def force(self, gap):
        overlap = np.maximum(0.0, -np.asarray(gap, dtype=float))
        return self.stiffness * overlap * np.sqrt(overlap)

    def potential(self, gap):
        overlap = np.maximum(0.0, -np.asarray(gap, dtype=float))
        return 0.4 * self.stiffness * overlap * overlap * np.sqrt(overlap)

    def stiffness_at(self, gap):
        overlap = np.maximum(0.0, -np.asarray(gap, dtype=float))
        return 1.5 * self.stiffness * np.sqrt(overlap)

    @property
    def range(self) -> float:
        return 0.0

    def kernel_parameters(self) -> tuple:
        return LAW_HERTZ, 0.0, 0.0, float(self.stiffness)


def contact_from_name(name: str, alpha: float, strength: float = 1.0) -> ContactLaw:
    """Build a contact law from its name (``exponential``, ``penalty``, ``hard``).

    ``alpha = inf`` always gives :class:`Hard`.
    """
    if name not in ("exponential", "penalty", "hard"):
        raise InvalidParameterError(
            f"contact must be one of 'exponential', 'penalty', 'hard', got {name!r}"
        )
    if name == "hard" or math.isinf(alpha):
        return Hard()
    if name == "penalty":
        return Penalty()
    return Exponential(alpha, strength)
