"""The outcome of one collision, the same for every solver."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["CollisionResult", "to_jsonable"]


@dataclass
class CollisionResult:
    """Everything a solver reports about one two-body collision.

    Times are dimensionless (``tau = t c / l``) and velocities are in units
    of the approach speed ``V`` when the scene is the paper's two-rod setting;
    otherwise they are in the scene's own units.

    Attributes
    ----------
    restitution : float
        ``epsilon = |v_rel after| / |v_rel before|`` of the centres of mass.
    solver : str
        Name of the solver that produced the result.
    gamma, kappa : float or None
        The paper's numbers when the scene has them (``kappa = inf``: hard).
    wall_time_s : float
        Wall-clock time of the solve (s), set-up included.
    time : ndarray
        Sample times of the histories.
    relative_velocity : ndarray
        Relative centre-of-mass velocity ``v2 - v1`` at ``time`` (starts at
        ``-V``, ends at ``+epsilon V``).
    contact_force : ndarray or None
        Contact force at ``time`` (force units; ``mu V c / l`` in the
        dimensionless setting), if the solver tracks it.
    contact_start, contact_duration : float or None
        When the contact force first becomes appreciable and how long it lasts.
    error_estimate : float or None
        The solver's own estimate of ``|epsilon - epsilon_exact|``.
    work : dict
        Cost counters (``steps``, ``element_steps``, ``modes`` ...).
    diagnostics : dict
        Conservation checks (``energy_drift``, ``momentum_drift`` ...).
    extra : dict
        Solver-specific data (energies per rod, fields, modal energies ...).
    """

    restitution: float
    solver: str
    wall_time_s: float
    time: np.ndarray
    relative_velocity: np.ndarray
    gamma: float | None = None
    kappa: float | None = None
    contact_force: np.ndarray | None = None
    contact_start: float | None = None
    contact_duration: float | None = None
    error_estimate: float | None = None
    work: dict = field(default_factory=dict)
    diagnostics: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)

    @property
    def velocity_increase(self) -> np.ndarray:
        """The paper's ``W(tau) = kappa (v_rel(tau) / V + 1)`` (dimensionless).

        Only defined for a finite ``kappa``.
        """
        if self.kappa is None or not math.isfinite(self.kappa):
            raise ValueError("W(tau) needs a finite kappa; use relative_velocity in the hard limit")
        return self.kappa * (np.asarray(self.relative_velocity) + 1.0)

    def summary(self) -> dict:
        """The scalar outcome as a JSON-ready dict (no histories)."""
        out = {
            "restitution": self.restitution,
            "solver": self.solver,
            "gamma": self.gamma,
            "kappa": self.kappa,
            "wall_time_s": self.wall_time_s,
            "contact_start": self.contact_start,
            "contact_duration": self.contact_duration,
            "error_estimate": self.error_estimate,
            "work": dict(self.work),
            "diagnostics": dict(self.diagnostics),
        }
        return to_jsonable(out)

    def to_json(self, **kwargs) -> str:
        """One JSON object with :meth:`summary`; ``inf`` is written as ``"inf"``."""
        return json.dumps(self.summary(), **kwargs)

    def save_npz(self, path) -> None:
        """Save scalars and histories to a NumPy ``.npz`` archive."""
        arrays = {"time": np.asarray(self.time), "relative_velocity": np.asarray(self.relative_velocity)}
        if self.contact_force is not None:
            arrays["contact_force"] = np.asarray(self.contact_force)
        np.savez(path, summary=json.dumps(self.summary()), **arrays)


def to_jsonable(value):
    """Make floats, numpy scalars and infinities JSON-safe (``inf`` -> ``"inf"``)."""
    if isinstance(value, dict):
        return {k: to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        number = float(value)
        if math.isinf(number):
            return "inf" if number > 0 else "-inf"
        if math.isnan(number):
            return "nan"
        return number
    return value
