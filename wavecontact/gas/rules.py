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
:class:`VibrationLaw`
    the default vibration rule: ``epsilon^2`` and the short rod's gain drawn from the
    :class:`~wavecontact.gas.collision_law.CollisionLaw` at the pair's length ratio, its
    ``x = E_tr / (E_tr + T_pair)`` and the short rod's share ``s = T_short / (T_short + T_long)`` of the
    bath temperature; with a contact stiffness (``GasSimulation(contact_stiffness=alpha)``) blended with
    the soft (finite-kappa) law at each collision's ``kappa = alpha V l``.  Runs inside the kernel.
:class:`VibrationSolve`
    the same, but each collision asks a Python callable for
    ``(epsilon^2, share)``: the hook for solving a stochastic collision per
    event (slow; the law is its tabulated form).

Approximations of the vibration rules (see ``docs/gas.md``, "Approximations of the vibration rule"): the
law is tabulated (quantiles, conditional mean gains per level, linear interpolation between grid points);
without a contact stiffness every collision is in the hard-core limit; below the law's last ``x`` row, and
below its softest ``kappa`` row, the last row's law is used (counted); a draw that would take more energy
from a bath than it holds is capped (counted).  :class:`VibrationTable` (the older restitution-table rule)
assumes both rods at the pair's mean temperature and stops the run (status ``off_table``) outside its grid.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..errors import InvalidParameterError, require_finite, require_integer
from ..restitution_table import RestitutionTable
from . import kernels
from .collision_law import CollisionLaw, soft_corrections

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
        return (ratio, np.array([0.5]), probability, np.ascontiguousarray(quantiles[:, :, None, :]),
                np.ascontiguousarray(share[:, :, None, None]))

    def gamma_grid(self):
        return self.table.gamma

    def describe(self) -> dict:
        meta = self.table.metadata()
        return {"rule": "vibration", "kappa": meta["kappa"], "bath_modes": self.table.bath_modes,
                "solver": self.table.solver, "samples_per_point": self.table.samples_per_point,
                "table_seed": self.table.seed}


@dataclass(frozen=True)
class VibrationLaw:
    """``epsilon^2`` and the short rod's gain drawn from the :class:`CollisionLaw` (inside the kernel).

    Covers every pair state: the law's grid is in ``x = E_tr / (E_tr + T_pair)`` in (0, 1] and the short
    rod's share ``s = T_short / (T_short + T_long)`` in [0, 1] of the bath temperature; below its last ``x``
    row the last row's law is used and the draw is counted (``GasResult.beyond_law``).  The gains are
    conditional means per level of ``epsilon^2`` (the exchange between the baths beyond that mean is averaged
    out); a bath asked for more than it holds gives what it has, the other bath the rest (counted as
    ``bath_limited``).

    Parameters
    ----------
    law : CollisionLaw
        The hard-core law (``kappa = inf``), :func:`wavecontact.gas.default_law`.
    soft_law : CollisionLaw, optional
        A finite-kappa law (:func:`wavecontact.gas.default_soft_law`), used only when the simulation is given
        a ``contact_stiffness``: each collision then blends the two at its own ``kappa = alpha V l``.
    """

    law: CollisionLaw
    soft_law: CollisionLaw | None = None

    def __post_init__(self):
        if not isinstance(self.law, CollisionLaw) or not self.law.hard_core:
            raise InvalidParameterError("VibrationLaw needs a hard-core CollisionLaw (wavecontact.gas.default_law())")
        if self.soft_law is not None:
            if not isinstance(self.soft_law, CollisionLaw) or self.soft_law.hard_core:
                raise InvalidParameterError("VibrationLaw soft_law must be a finite-kappa CollisionLaw "
                                            "(wavecontact.gas.default_soft_law())")
            if self.soft_law.bath_modes != self.law.bath_modes:
                raise InvalidParameterError("VibrationLaw soft_law must have the hard-core law's bath_modes")

    code = kernels.RULE_LAW

    @property
    def bath_modes(self):
        return self.law.bath_modes

    def kernel_arrays(self):
        _z, log_x, share, probability, quantiles, gains = self.law.kernel_arrays()
        return log_x, share, probability, quantiles[0], gains[0]

    @cached_property
    def _soft_arrays(self):
        d_eps, d_gain = soft_corrections(self.law, self.soft_law)
        kappa, gamma, log_x, share, probability = self.soft_law.arrays()[:5]
        return kappa, gamma, log_x, share, probability, d_eps, d_gain

    def soft_arrays(self):
        """The soft law's ``(kappa, gamma, log_x, short_share, probability)`` and its corrections to the hard-core
        law ``(d_eps2, d_gain)`` (:func:`~wavecontact.gas.collision_law.soft_corrections`), for the kernel."""
        return self._soft_arrays if self.soft_law is not None else kernels.empty_soft_law()

    def gamma_grid(self):
        return self.law.gamma

    def describe(self) -> dict:
        out = {"rule": "vibration_law", "kappa": "inf", "bath_modes": self.law.bath_modes,
               "samples_per_point": self.law.samples_per_point, "law_seed": self.law.seed,
               "short_share_axis": self.law.short_share.size > 1}
        if self.soft_law is not None:
            out["soft_law"] = {"kappa": [float(k) for k in self.soft_law.kappa],
                               "samples_per_point": self.soft_law.samples_per_point, "seed": self.soft_law.seed}
        return out


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

    With a ``contact_stiffness`` the simulation calls ``draw(gamma, temperature_ratio, seed, kappa=kappa)``
    with this collision's ``kappa = alpha V l`` (see :func:`wavecontact.gas.contact_draw`).
    """

    draw: Callable
    bath_modes: int = 250
    name: str = "solve"
    per_rod: bool = False

    def __post_init__(self):
        if not callable(self.draw):
            raise InvalidParameterError("VibrationSolve draw must be callable")
        require_integer("bath_modes", self.bath_modes, 1)

    code = kernels.RULE_EXTERNAL

    def kernel_arrays(self):
        return kernels.empty_table()

    def gamma_grid(self):
        return np.array([1.0])

    def describe(self) -> dict:
        return {"rule": "solve", "name": self.name, "bath_modes": int(self.bath_modes), "per_rod": bool(self.per_rod)}


def rule_from_description(description: dict, table: RestitutionTable | None = None, soft_law=None):
    """Rebuild a fixed or table rule from :meth:`describe` (and the table or laws, for the vibration rules)."""
    kind = description.get("rule")
    if kind == "fixed":
        return FixedRestitution(description["restitution"])
    if kind == "vibration" and isinstance(table, RestitutionTable):
        return VibrationTable(table)
    if kind == "vibration_law" and isinstance(table, CollisionLaw):
        return VibrationLaw(table, soft_law)
    raise InvalidParameterError(f"cannot rebuild the collision rule {kind!r} from a description; pass it explicitly")
