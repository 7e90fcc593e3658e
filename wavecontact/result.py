"""The outcome of a collision, the same for every solver.

One rule for what a solver does not track: a scalar it does not know is NaN
(``error_estimate``, ``gamma`` and ``kappa`` of a scene that is not the
paper's, a drift it does not measure), a history it does not record is
``None``.  Every key of ``diagnostics`` means the same for every solver.
"""

from __future__ import annotations

import enum
import json
import math
from dataclasses import dataclass, field

import numpy as np

from .errors import InvalidParameterError
from .io.files import to_jsonable  # re-exported: results and studies write JSON through it

__all__ = [
    "CONTACT_FORCE_FRACTION",
    "CollisionRecord",
    "CollisionResult",
    "Outcome",
    "contact_window",
    "to_jsonable",
]

#: The contact window is where the force exceeds this fraction of its peak (every solver).
CONTACT_FORCE_FRACTION = 1e-2

_RESULT_SCHEMA = "wavecontact.collision_result"
_RESULT_VERSION = 1


class Outcome(str, enum.Enum):
    """How a solve ended; only ``SEPARATED`` comes with a result, the others with a
    :class:`~wavecontact.errors.SolverFailure` whose ``outcome`` says which."""

    SEPARATED = "separated"
    STEP_LIMIT = "step_limit"
    TIME_LIMIT = "time_limit"
    NON_FINITE = "non_finite"
    STEP_UNDERFLOW = "step_underflow"
    ENERGY_DRIFT = "energy_drift"
    NEVER_MEET = "never_meet"
    NOT_CONVERGED = "not_converged"

    @property
    def message(self) -> str:
        return _OUTCOME_MESSAGES[self]


_OUTCOME_MESSAGES = {
    Outcome.SEPARATED: "the rods separated and the contact force vanished",
    Outcome.STEP_LIMIT: "the step limit was reached before the rods separated",
    Outcome.TIME_LIMIT: "the rods had not separated by the time limit",
    Outcome.NON_FINITE: "a non-finite value appeared in the state",
    Outcome.STEP_UNDERFLOW: "the step size underflowed (the contact is too stiff for this resolution)",
    Outcome.ENERGY_DRIFT: "the energy drifted beyond the tolerance",
    Outcome.NEVER_MEET: "the rods never come within range of the contact force",
    Outcome.NOT_CONVERGED: "an implicit stage did not converge",
}


def contact_window(time, force, sampling: str | None = "point") -> tuple:
    """First time and duration of ``force > CONTACT_FORCE_FRACTION * max(force)``.

    Parameters
    ----------
    time, force : ndarray
        The force history.
    sampling : {'point', 'interval'}
        ``'point'``: ``force[i]`` is the force at ``time[i]``; ``'interval'``:
        it is the mean over ``(time[i-1], time[i]]`` (a time-stepping solver),
        so the window opens at ``time[i-1]``.

    Returns
    -------
    (float, float)
        NaN, NaN when there is no force history or no force.
    """
    if force is None:
        return math.nan, math.nan
    force = np.asarray(force, dtype=float)
    peak = float(force.max()) if force.size else math.nan
    if not peak > 0.0:
        return math.nan, math.nan
    above = force > CONTACT_FORCE_FRACTION * peak
    first, last = int(above.argmax()), force.size - 1 - int(above[::-1].argmax())
    if sampling == "interval" and first > 0:
        begin = float(time[first - 1])
    else:
        begin = float(time[first])
    return begin, float(time[last]) - begin


@dataclass(frozen=True, repr=False)
class CollisionResult:
    """Everything a solver reports about one two-body collision.

    Times are dimensionless (``tau = t c / l``) and velocities are in units
    of the approach speed ``V`` when the scene is the paper's two-rod setting
    (:func:`wavecontact.two_rods`); otherwise they are in the scene's own units.
    Forces are in units of ``Z V = rho c A V`` in the paper's setting (the
    wave-theory plateau of equal rods is 1/2), else in the scene's force units.

    Attributes
    ----------
    restitution : float
        ``epsilon = |v_rel after| / |v_rel before|`` of the centres of mass.
    solver : str
        Name of the solver that produced the result.
    gamma, kappa : float
        The paper's numbers of the scene (``kappa = inf``: hard); NaN when the
        scene is not two rods of one material on a line.
    error_estimate : float
        The estimate of ``|epsilon - epsilon_exact|`` (docs/error_estimates.md): the delay solver's own,
        Richardson from a run at half the resolution for FE and modal; NaN if there is none.
    wall_time_s : float
        Wall-clock time of the solve (s), set-up included.
    time : ndarray
        Sample times of the histories.
    relative_velocity : ndarray
        Relative centre-of-mass velocity ``v2 - v1`` at ``time`` (starts at
        ``-V``, ends at ``+epsilon V``).
    contact_force : ndarray or None
        Contact force at ``time``, if the solver records it.
    contact_start, contact_duration : float
        Where the force exceeds ``CONTACT_FORCE_FRACTION`` of its peak
        (:func:`contact_window`); NaN without a force history.
    options : dict
        The validated solver options used.
    work : dict
        Cost counters (``steps`` for every solver; ``element_steps``,
        ``modes``, ``evaluations`` ... where they apply).
    diagnostics : dict
        ``energy_drift`` and ``momentum_drift`` (relative to the initial
        energy in the centre-of-mass frame and to ``mu V``, the reduced mass
        times the approach speed; NaN where the solver does not track them), ``includes_kernel_preparation`` (numba compiled or loaded
        kernels during the call, so ``wall_time_s`` is not the solver's cost), ``interpreted_kernels`` (a
        short call ran a kernel as plain Python because numba had none compiled for it yet: the same bits,
        a slower solve, no compilation; :func:`wavecontact._jit.prefer_interpreted`), ``error_estimate_method``
        (how ``error_estimate`` was obtained), ``error_estimate_seconds`` (its share of ``wall_time_s``)
        and ``error_estimate_levels`` (``(resolution, restitution)`` of the requested run and of the
        coarser runs a Richardson estimate used; empty otherwise) and ``error_estimate_rough`` (why the
        estimate is only an order of magnitude, which ``tolerance=`` then refuses; "" where it is a bound).
    extra : dict
        Solver-specific data (energies per rod, fields, modal energies ...).

    A result exists only for a collision that ended with the rods apart: every other ending
    (a step or time limit, a non-finite state ...) raises :class:`~wavecontact.errors.SolverFailure`,
    whose ``outcome`` names it.  :attr:`outcome` is therefore not a field but the constant
    ``Outcome.SEPARATED``, kept for the JSON and ``.npz`` records that name it.
    """

    restitution: float
    solver: str
    wall_time_s: float
    time: np.ndarray
    relative_velocity: np.ndarray
    gamma: float = math.nan
    kappa: float = math.nan
    contact_force: np.ndarray | None = None
    contact_start: float = math.nan
    contact_duration: float = math.nan
    error_estimate: float = math.nan
    options: dict = field(default_factory=dict)
    work: dict = field(default_factory=dict)
    diagnostics: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)

    def __post_init__(self):
        if not math.isfinite(self.restitution):
            raise InvalidParameterError(f"restitution must be finite, got {self.restitution!r}")

    @property
    def outcome(self) -> Outcome:
        """``Outcome.SEPARATED``: the only ending that returns a result (the others raise
        :class:`~wavecontact.errors.SolverFailure` with their outcome)."""
        return Outcome.SEPARATED

    def __repr__(self) -> str:
        error = "" if math.isnan(self.error_estimate) else f" ± {self.error_estimate:.1e}"
        where = "" if math.isnan(self.gamma) else f", gamma={self.gamma:g}, kappa={self.kappa:g}"
        return (f"CollisionResult(solver={self.solver!r}, restitution={self.restitution:.10g}{error}{where}, "
                f"outcome={self.outcome.value}, {1e3 * self.wall_time_s:.3g} ms)")

    @property
    def velocity_increase(self) -> np.ndarray:
        """The paper's ``W(tau) = kappa (v_rel(tau) / V + 1)`` (dimensionless).

        Only defined for a finite ``kappa``.
        """
        if math.isnan(self.kappa) or not math.isfinite(self.kappa):
            raise ValueError("W(tau) needs a finite kappa; use relative_velocity in the hard limit")
        return self.kappa * (np.asarray(self.relative_velocity) + 1.0)

    def summary(self) -> dict:
        """The scalar outcome as a JSON-ready dict (no histories)."""
        out = {
            "restitution": self.restitution,
            "error_estimate": self.error_estimate,
            "solver": self.solver,
            "outcome": self.outcome.value,
            "gamma": self.gamma,
            "kappa": self.kappa,
            "wall_time_s": self.wall_time_s,
            "contact_start": self.contact_start,
            "contact_duration": self.contact_duration,
            "options": _json_options(self.options),
            "work": dict(self.work),
            "diagnostics": dict(self.diagnostics),
        }
        return to_jsonable(out)

    def to_json(self, **kwargs) -> str:
        """One JSON object with :meth:`summary`; ``inf`` is written as ``"inf"``, NaN as ``"nan"``."""
        return json.dumps(self.summary(), **kwargs)

    # ------------------------------------------------------------------ files
    def save_npz(self, path) -> None:
        """Save everything the result carries to a NumPy ``.npz`` archive (no pickle).

        Arrays (histories, and arrays inside ``extra``, ``work``,
        ``diagnostics``) are stored as arrays, everything else as JSON; read
        it back with :meth:`load_npz`.
        """
        from .io.files import atomic_write, check_output_file

        path = check_output_file("path", path)  # a directory or an unwritable place: refused, named
        arrays = {"time": np.asarray(self.time), "relative_velocity": np.asarray(self.relative_velocity)}
        if self.contact_force is not None:
            arrays["contact_force"] = np.asarray(self.contact_force)
        scalars = {}
        for name in ("restitution", "solver", "wall_time_s", "gamma", "kappa", "contact_start",
                     "contact_duration", "error_estimate"):
            scalars[name] = getattr(self, name)
        scalars["outcome"] = self.outcome.value
        scalars["options"] = _json_options(self.options)
        for name in ("work", "diagnostics", "extra"):
            scalars[name] = _split_arrays(getattr(self, name), f"{name}/", arrays)
        document = {"schema": _RESULT_SCHEMA, "version": _RESULT_VERSION, "fields": to_jsonable(scalars)}
        payload = dict(arrays)
        payload["__result__"] = np.asarray(json.dumps(document))
        atomic_write(path, lambda handle: np.savez_compressed(handle, **payload), binary=True)

    @classmethod
    def load_npz(cls, path) -> CollisionResult:
        """Read a result written by :meth:`save_npz`."""
        try:
            with np.load(path, allow_pickle=False) as data:
                document = json.loads(str(data["__result__"]))
                arrays = {name: np.array(data[name]) for name in data.files if name != "__result__"}
        except (OSError, ValueError, KeyError, EOFError) as exc:
            raise InvalidParameterError(f"{path} is not a readable wavecontact result ({exc})") from None
        if not isinstance(document, dict) or document.get("schema") != _RESULT_SCHEMA:
            raise InvalidParameterError(f"{path} is not a wavecontact collision result")
        if document.get("version") != _RESULT_VERSION:
            raise InvalidParameterError(f"{path} has result format version {document.get('version')}, "
                                        f"this build reads {_RESULT_VERSION}")
        values = _from_jsonable(document["fields"])
        kwargs = {name: values[name] for name in ("restitution", "solver", "wall_time_s", "gamma", "kappa",
                                                  "contact_start", "contact_duration", "error_estimate")}
        for name in ("restitution", "wall_time_s", "gamma", "kappa", "contact_start", "contact_duration",
                     "error_estimate"):
            kwargs[name] = float(kwargs[name])
        if Outcome(values["outcome"]) is not Outcome.SEPARATED:  # no build writes another
            raise InvalidParameterError(f"{path} records the outcome {values['outcome']!r}, not a result")
        kwargs["options"] = values["options"]
        for name in ("work", "diagnostics", "extra"):
            kwargs[name] = _join_arrays(values[name], f"{name}/", arrays)
        return cls(time=arrays["time"], relative_velocity=arrays["relative_velocity"],
                   contact_force=arrays.get("contact_force"), **kwargs)


@dataclass(frozen=True)
class CollisionRecord:
    """One collision of a run of many (a ring), as a solver's ``simulate`` yields it.

    Energies in the scene's units (``mu V^2`` units with ``mu = 1/2`` for the
    paper's rods); time in ``l / c``.

    Attributes
    ----------
    index : int
        0-based number of the collision in the run.
    time : float
        When the pair came within reach of the force.
    pair : int
        Which pair of facing ends met (0: rod 0's right end and rod 1's left
        end, the *near* pair of two rods; 1: the far pair across the ring seam).
    translational_energy_before, translational_energy_after : float
        Relative translational energy ``mu v_rel^2 / 2`` before and after.
    restitution : float
        ``|v_rel after| / |v_rel before|``.
    modal_energies : ndarray, shape (rods, modes)
        Energy of every kept mode after the collision (read-only).
    bath_energy, total_energy : float
        Vibrational and total energy after the collision.
    steps : int
        Integrator steps of this collision.
    """

    index: int
    time: float
    pair: int
    translational_energy_before: float
    translational_energy_after: float
    restitution: float
    modal_energies: np.ndarray
    bath_energy: float
    total_energy: float
    steps: int

    def __post_init__(self):
        energies = np.array(self.modal_energies, dtype=float)
        energies.setflags(write=False)
        object.__setattr__(self, "modal_energies", energies)


# --------------------------------------------------------------------------- helpers
def _json_options(options: dict) -> dict:
    out = {}
    for name, value in options.items():
        if isinstance(value, (np.ndarray, list, tuple)) and value is not None:
            try:
                out[name] = np.asarray(value, dtype=float).tolist()
                continue
            except (TypeError, ValueError):
                pass
        if value is None or isinstance(value, (bool, int, float, str, np.integer, np.floating, np.bool_)):
            out[name] = value
        else:
            out[name] = repr(value)
    return to_jsonable(out)


def _split_arrays(value, prefix: str, arrays: dict):
    """Move every ndarray out of a nested dict/list into ``arrays``; leave a reference."""
    if isinstance(value, np.ndarray) and value.dtype != object:
        arrays[prefix.rstrip("/")] = value
        return {"__array__": prefix.rstrip("/")}
    if isinstance(value, dict):
        return {str(k): _split_arrays(v, f"{prefix}{k}/", arrays) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_split_arrays(v, f"{prefix}{i}/", arrays) for i, v in enumerate(value)]
    return value


def _join_arrays(value, prefix: str, arrays: dict):
    if isinstance(value, dict):
        if set(value) == {"__array__"}:
            return arrays[value["__array__"]]
        return {k: _join_arrays(v, f"{prefix}{k}/", arrays) for k, v in value.items()}
    if isinstance(value, list):
        return [_join_arrays(v, f"{prefix}{i}/", arrays) for i, v in enumerate(value)]
    return value


_SPECIAL = {"inf": math.inf, "-inf": -math.inf, "nan": math.nan}


def _from_jsonable(value):
    if isinstance(value, dict):
        return {k: _from_jsonable(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_from_jsonable(v) for v in value]
    if isinstance(value, str) and value in _SPECIAL:
        return _SPECIAL[value]
    return value

