"""Collision rules of the rod gas, as values.

A rule says how much of a colliding pair's translational energy
``E_tr = mu V^2 / 2`` survives (``epsilon^2``) and where the lost energy goes:

:class:`FixedRestitution`
    the textbook granular gas: ``epsilon = r`` always, the lost energy leaves
    the system (the rods have no baths).
:class:`VibrationTable`
    ``epsilon^2`` drawn from a :class:`~wavecontact.restitution_table.RestitutionTable`
    at the pair's length ratio and temperature ratio; the lost energy
    (negative when the baths give energy back) is split between the two
    rods' baths by the table's ``rod1_share``.  Runs inside the kernel.
:class:`VibrationSolve`
    the same, but each collision asks a Python callable for
    ``(epsilon^2, share)``: the hook for solving a stochastic collision per
    event (slow; the table is its tabulated form).

Approximations of the vibration rules (see ``docs/gas.md``): the table is
computed at one hardness ``kappa`` although the true ``kappa = alpha V l / c``
grows with the impact speed (harmless where the law no longer depends on
kappa, above about 50); the table assumes both rods at one bath temperature,
so a pair uses the mean of its two temperatures; a pair meeting at a
temperature ratio outside the table's grid stops the run (status
``off_table``: the table is never extrapolated or clipped); a draw that
would take more energy from a bath than it holds is capped (counted).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError, require_finite
from ..restitution_table import RestitutionTable
from . import kernels
from .collision_law import CollisionLaw

__all__ = ["FixedRestitution", "VibrationLaw", "VibrationSolve", "VibrationTable", "rule_from_description"]


@dataclass(frozen=True)
class FixedRestitution:
    """``epsilon = restitution`` in every collision (dimensionless, in [0, 1])."""

    restitution: float

    def __post_init__(self):
        r = require_finite("restitution", self.restitution)
        if not 0.0 <= r <= 1.0:
            raise InvalidParameterError(f"restitution must lie in [0, 1], got {r!r}")
        object.__setattr__(self, "restitution", r)

    code = kernels.RULE_FIXED
    bath_modes = 1

    def kernel_arrays(self):
        return kernels.empty_table()

    def gamma_grid(self):
        return np.array([1.0])

    def describe(self) -> dict:
        return {"rule": "fixed", "restitution": self.restitution}


@dataclass(frozen=True)
class VibrationTable:
    """``epsilon^2`` and the bath split drawn from a restitution table (inside the kernel)."""

    table: RestitutionTable

    def __post_init__(self):
        if not isinstance(self.table, RestitutionTable):
            raise InvalidParameterError("VibrationTable needs a RestitutionTable")
        # rod1_share is finite (RestitutionTable checks); it may lie outside [0, 1] where the mean lost energy
        # is near zero or negative (the baths give energy back): the kernel then caps draws so that no bath
        # goes below zero (counted as bath_limited)

    code = kernels.RULE_TABLE

    @property
    def bath_modes(self):
        return self.table.bath_modes

    def kernel_arrays(self):
        _, ratio, probability, quantiles, share = self.table.arrays()
        return ratio, probability, quantiles, np.ascontiguousarray(share[:, :, None])

    def gamma_grid(self):
        return self.table.gamma

    def describe(self) -> dict:
        meta = self.table.metadata()
        return {"rule": "vibration", "kappa": meta["kappa"], "bath_modes": self.table.bath_modes,
                "solver": self.table.solver, "samples_per_point": self.table.samples_per_point,
                "table_seed": self.table.seed}


@dataclass(frozen=True)
class VibrationLaw:
    """``epsilon^2`` and the short rod's gain drawn from the hard-core :class:`CollisionLaw` (inside the kernel).

    Covers every pair state: the law's grid is in ``x = E_tr / (E_tr + T_pair)`` in (0, 1]; below its
    last row the last row's law is used and the draw is counted (``GasResult.beyond_law``).  The gains
    are conditional means per level of ``epsilon^2`` (the exchange between the baths beyond that mean
    is averaged out); a bath asked for more than it holds gives what it has, the other bath the rest
    (counted as ``bath_limited``).
    """

    law: CollisionLaw

    def __post_init__(self):
        if not isinstance(self.law, CollisionLaw):
            raise InvalidParameterError("VibrationLaw needs a CollisionLaw (wavecontact.gas.default_law())")

    code = kernels.RULE_LAW

    @property
    def bath_modes(self):
        return self.law.bath_modes

    def kernel_arrays(self):
        _, log_x, probability, quantiles, gains = self.law.arrays()
        return log_x, probability, quantiles, gains

    def gamma_grid(self):
        return self.law.gamma

    def describe(self) -> dict:
        return {"rule": "vibration_law", "kappa": "inf", "bath_modes": self.law.bath_modes,
                "samples_per_point": self.law.samples_per_point, "law_seed": self.law.seed}


@dataclass(frozen=True)
class VibrationSolve:
    """One call of ``draw`` per collision (the 'exact' variant).

    Parameters
    ----------
    draw : callable
        ``draw(gamma, temperature_ratio, seed) -> (eps2, rod1_share)`` with
        ``gamma`` the pair's length ratio, ``temperature_ratio`` the pair's
        mean bath temperature over ``E_tr``, and ``seed`` a
        ``numpy.random.SeedSequence`` spawned for this collision (one per
        collision).  ``rod1_share`` is the short rod's part of the lost energy
        (any finite number: outside [0, 1] one bath gives while the other
        takes).  :func:`wavecontact.gas.collision_draw` solves a thermal
        collision with :func:`wavecontact.collide`.
    bath_modes : int
        Modes per rod (the baths' heat capacity).
    name : str
        Recorded in results and checkpoints; a resumed run must pass a rule with the same name.
    per_rod : bool
        Pass ``temperature_ratio`` as the pair ``(T_short, T_long) / E_tr`` instead of their mean.
    """

    draw: Callable
    bath_modes: int = 250
    name: str = "solve"
    per_rod: bool = False

    def __post_init__(self):
        if not callable(self.draw):
            raise InvalidParameterError("VibrationSolve draw must be callable")
        if isinstance(self.bath_modes, bool) or int(self.bath_modes) != self.bath_modes or self.bath_modes < 1:
            raise InvalidParameterError(f"bath_modes must be an integer >= 1, got {self.bath_modes!r}")

    code = kernels.RULE_EXTERNAL

    def kernel_arrays(self):
        return kernels.empty_table()

    def gamma_grid(self):
        return np.array([1.0])

    def describe(self) -> dict:
        return {"rule": "solve", "name": self.name, "bath_modes": int(self.bath_modes), "per_rod": bool(self.per_rod)}


def rule_from_description(description: dict, table: RestitutionTable | None = None):
    """Rebuild a fixed or table rule from :meth:`describe` (and the table, for the vibration rule)."""
    kind = description.get("rule")
    if kind == "fixed":
        return FixedRestitution(description["restitution"])
    if kind == "vibration" and isinstance(table, RestitutionTable):
        return VibrationTable(table)
    if kind == "vibration_law" and isinstance(table, CollisionLaw):
        return VibrationLaw(table)
    raise InvalidParameterError(f"cannot rebuild the collision rule {kind!r} from a description; pass it explicitly")
