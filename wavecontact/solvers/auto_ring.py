"""The ring's modes per rod from a tolerance on each collision's restitution (``wavecontact ring`` without ``--modes``).

The ring (:func:`wavecontact.studies.ring.run_ring`) keeps ``N`` modes per rod with the static correction
for the omitted ones.  Truncating the modes changes each collision's restitution ``eps_j``; the *per-collision
restitution error* of collision ``j`` is the change of ``eps_j`` when the same collision, from the same
state, is computed with the omitted modes kept (at rest where the run has none).

* **Prediction** (:class:`RingModel`): the :data:`ERROR_QUANTILE` quantile of the per-collision error over a
  run's collisions, and the CPU seconds per collision, as least-squares fits of their logarithms in
  ``log10 kappa``, ``log10 N`` and ``log10 (1/gamma)`` (hard contact: a fit of its own, without ``kappa``),
  each with the largest residual of its calibration points added.  Nothing here is a measured number: the
  fits are the file ``wavecontact/data/ring_model.json``, which ``python benchmarks/ring_model.py``
  regenerates from its calibration runs.
* **Choice** (:func:`choose_modes`): the fewest modes predicted to meet the tolerance (the cost grows with
  ``N``), checked against the limits before any work; a tolerance that no ``N`` within the limits meets is
  refused with the modes and the work it would need.
* **Check during the run** (:class:`CollisionChecks`): every :data:`CHECK_EVERY`-th collision (and the
  first) is run again from the state before it with ``2 N`` modes (the added ones at rest);
  ``ESTIMATE_FACTOR |eps_N - eps_2N|`` is that collision's error estimate (a bound where the error falls at
  least like ``1/N``).  Estimates above the tolerance are reported, and so is a model that is wrong (more
  than ``1 - ERROR_QUANTILE`` of the checked collisions above it).
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError, LimitError, require_positive
from ..limits import Limits, check_study_cost, ring_cost
from .cost_model import least_squares

__all__ = [
    "CHECK_EVERY",
    "DATA_PATH",
    "DEFAULT_TOLERANCE",
    "ERROR_QUANTILE",
    "ESTIMATE_FACTOR",
    "RingChoice",
    "RingModel",
    "choose_modes",
    "fit_points",
    "load_ring_model",
]

#: The model's file (written by ``python benchmarks/ring_model.py``).
DATA_PATH = Path(__file__).resolve().parents[1] / "data" / "ring_model.json"
#: Version of the file's layout.
FORMAT = 1
#: Tolerance on the per-collision restitution error when none is given (absolute, on ``eps_j``).
DEFAULT_TOLERANCE = 1e-2
#: The predicted per-collision error is the level this share of a run's collisions stays below (the warm
#: collisions' errors are heavy-tailed: docs/ring.md).
ERROR_QUANTILE = 0.9
#: ``|eps_N - eps_2N|`` times this bounds the error of ``eps_N`` where it falls at least like ``1/N``.
ESTIMATE_FACTOR = 2.0
#: Collisions between two checks of the run (the first collision is always checked; 0: none).
CHECK_EVERY = 100
#: Most modes per rod a choice may take (the modal solver's ``modes`` option's bound).
MAX_MODES = 20_000


def _row(kappa: float, gamma: float, modes: float) -> tuple:
    """``(class, regressors)``: ``'hard'`` for ``kappa = inf`` (``1, log10 (1/gamma), log10 N``), else ``'soft'``
    (``1, log10 (1/gamma), log10 (N/kappa)``: the modes per unit of softness set the error, docs/ring.md)."""
    if math.isinf(kappa):
        return "hard", [1.0, math.log10(1.0 / gamma), math.log10(modes)]
    return "soft", [1.0, math.log10(1.0 / gamma), math.log10(modes / kappa)]


def _cost_row(kappa: float, gamma: float, modes: float) -> list:
    """Regressors of the cost fit: ``1, log10 N, log10 (1/gamma)`` and, soft, ``log10 kappa``."""
    row = [1.0, math.log10(modes), math.log10(1.0 / gamma)]
    return row if math.isinf(kappa) else [*row, math.log10(kappa)]


def _fit(rows: list, values: list) -> dict:
    """:func:`~wavecontact.solvers.cost_model.least_squares`; the margin is the largest residual (every
    calibration point at or below the fit)."""
    coef, residual = least_squares(rows, values)
    return {"coef": coef, "margin": round(max(float(residual.max()), 0.0), 10),
            "rms_residual": round(float(np.sqrt(np.mean(residual**2))), 10)}


def fit_points(points: list, soft_from: float) -> dict:
    """``fits[class] = {'error': ..., 'cost': ...}`` from calibration ``points`` (dicts with ``gamma``,
    ``kappa`` (``"inf"`` for hard contact), ``modes``, ``error_quantile`` and ``cpu_s_per_collision``).

    The soft error fit takes the points with ``N / kappa >= soft_from`` only, where the error falls with the
    modes (below, it saturates at about 0.1-0.3 and the fit's extrapolation lies above it); the cost fits take
    every point."""
    groups: dict = {}
    for point in points:
        kappa = math.inf if point["kappa"] == "inf" else float(point["kappa"])
        kind, row = _row(kappa, float(point["gamma"]), float(point["modes"]))
        inside = kind == "hard" or point["modes"] / kappa >= soft_from
        groups.setdefault(kind, []).append((row, _cost_row(kappa, float(point["gamma"]), float(point["modes"])),
                                            point, inside))
    fits = {}
    for kind, members in sorted(groups.items()):
        fitted = [(row, p) for row, _c, p, inside in members if inside]
        fits[kind] = {
            "error": _fit([row for row, _p in fitted], [math.log10(max(p["error_quantile"], 1e-16)) for _r, p in fitted]),
            "cost": _fit([c for _r, c, _p, _i in members], [math.log10(p["cpu_s_per_collision"]) for *_x, p, _i in members]),
            # the saturation: no prediction above the largest measured quantile of the class
            "ceiling": max(p["error_quantile"] for *_x, p, _i in members),
            "cost_modes": [min(p["modes"] for *_x, p, _i in members), max(p["modes"] for *_x, p, _i in members)],
            "runs": len(fitted),
            "range": [round(min(row[-1] for row, _p in fitted), 10), round(max(row[-1] for row, _p in fitted), 10)],
        }
    return fits


class RingModel:
    """The stored model (module docstring); :func:`load_ring_model` reads it once."""

    def __init__(self, data: dict):
        if not isinstance(data, dict) or data.get("format") != FORMAT or "fits" not in data:
            raise InvalidParameterError(f"ring model data must have format {FORMAT}; regenerate it with "
                                        "python benchmarks/ring_model.py")
        self.data = data
        self.fits = data["fits"]

    def fit(self, kappa: float, gamma: float) -> dict:
        kind = _row(kappa, gamma, 1.0)[0]
        if kind not in self.fits:
            raise InvalidParameterError(f"the ring model has no calibration for {kind} contact; give the modes")
        return self.fits[kind]

    def predict(self, gamma: float, kappa: float, modes: float) -> tuple:
        """``(per-collision error quantile, CPU seconds per collision)`` predicted at ``modes`` per rod (the
        CPU time None outside the calibrated modes)."""
        fit = self.fit(kappa, gamma)
        error = 10.0 ** (sum(x * c for x, c in zip(_row(kappa, gamma, modes)[1], fit["error"]["coef"]))
                         + fit["error"]["margin"])
        low, high = fit["cost_modes"]
        cost = None
        if low <= modes <= high:  # the cost per collision grows faster than the fit's power beyond the points
            cost = 10.0 ** (sum(x * c for x, c in zip(_cost_row(kappa, gamma, modes), fit["cost"]["coef"]))
                            + fit["cost"]["margin"])
        return min(error, fit["ceiling"]), cost

    def modes_for(self, gamma: float, kappa: float, tolerance: float) -> int | None:
        """The fewest modes per rod predicted to meet ``tolerance`` (None: the error does not fall with N)."""
        fit = self.fit(kappa, gamma)
        coef = fit["error"]["coef"]
        if not coef[-1] < 0.0:
            return None
        row = _row(kappa, gamma, 1.0)[1]  # the last regressor is log10 N plus a constant
        at_one = sum(x * c for x, c in zip(row, coef)) + fit["error"]["margin"]
        needed = 10.0 ** ((math.log10(tolerance) - at_one) / coef[-1])
        if not needed < 10 * MAX_MODES:
            return 10 * MAX_MODES
        modes = max(1, math.ceil(needed - 1e-9))
        while modes > 1 and self.predict(gamma, kappa, modes - 1)[0] <= tolerance:  # round-off of the inversion
            modes -= 1
        while self.predict(gamma, kappa, modes)[0] > tolerance:
            modes += 1
        return modes


@functools.lru_cache(maxsize=4)
def load_ring_model(path=None) -> RingModel:
    """The ring model from ``path`` (default :data:`DATA_PATH`), read once per path."""
    path = Path(path or DATA_PATH)
    try:
        return RingModel(json.loads(path.read_text(encoding="utf-8")))
    except (OSError, ValueError) as error:
        raise InvalidParameterError(f"cannot read the ring model {path}: {error}; regenerate it with "
                                    "python benchmarks/ring_model.py") from None


@dataclass(frozen=True)
class RingChoice:
    """The modes of a ring run and why.

    Attributes
    ----------
    modes : int
        Modes per rod ``N``.
    tolerance : float or None
        Tolerance on the per-collision restitution error (absolute).
    predicted_error : float or None
        The model's :data:`ERROR_QUANTILE` quantile of the per-collision error at ``modes`` (None: no model).
    predicted_cpu_s : float or None
        The model's CPU seconds for the run's collisions (checks not included; None outside the calibrated modes).
    reason : str
        One line: how ``modes`` was chosen.
    chosen : bool
        True when the tolerance chose ``modes``, False when the caller gave them.
    """

    modes: int
    tolerance: float | None
    predicted_error: float | None
    predicted_cpu_s: float | None
    reason: str
    chosen: bool

    def as_dict(self) -> dict:
        return asdict(self)


def _extrapolation(model: RingModel, gamma: float, kappa: float, modes: int) -> str:
    """"" or why the prediction at ``modes`` is an extrapolation (outside the error fit's points)."""
    low, high = model.fit(kappa, gamma)["range"]
    value = _row(kappa, gamma, modes)[1][-1]
    if low - 1e-9 <= value <= high + 1e-9:
        return ""
    what = "N" if math.isinf(kappa) else "N / kappa"
    return (f"; extrapolated: {what} = {10.0 ** value:.3g} is outside the calibrated "
            f"{10.0 ** low:.3g}-{10.0 ** high:.3g}")


def _cpu_text(cpu, collisions: int) -> str:
    return "" if cpu is None else f", {cpu * collisions:.3g} s CPU for {collisions} collisions"


def choose_modes(gamma: float, kappa: float, collisions: int, *, modes=None, tolerance=None,
                 static_correction: bool = True, max_work=None, model=None) -> RingChoice:
    """The modes per rod of a ring run: ``modes`` if given, else the fewest predicted to meet ``tolerance``.

    Parameters
    ----------
    gamma, kappa : float
        Length ratio and softness of the ring (:func:`wavecontact.scene.two_rods_on_a_ring`).
    collisions : int
        Collisions of the run (for its cost).
    modes : int or None
        Modes per rod given by the caller (kept; the prediction at them is still reported).
    tolerance : float or None
        Tolerance on the per-collision restitution error; None: :data:`DEFAULT_TOLERANCE`.
    static_correction : bool
        The run's static correction (the model is calibrated with it).
    max_work : float or None
        Bound on the run's estimated work (:class:`wavecontact.limits.Limits`).
    model : RingModel, optional
        Default: the stored one.

    Raises
    ------
    LimitError
        Before any work, when the modes the tolerance needs are over the limits (with those modes and
        their work).
    InvalidParameterError
        Without ``modes``, when the model cannot choose them (no static correction, no calibration).
    """
    tolerance = DEFAULT_TOLERANCE if tolerance is None else require_positive("tolerance", tolerance)
    if not static_correction:
        if modes is None:
            raise InvalidParameterError("without the static correction the ring's modes cannot be chosen from a "
                                        "tolerance (the model is calibrated with it); give the modes")
        return RingChoice(int(modes), tolerance, None, None, f"N = {int(modes)} given; no error model without "
                          "the static correction", False)
    model = model or load_ring_model()
    if modes is not None:
        modes = int(modes)
        error, cpu = model.predict(gamma, kappa, modes)
        verdict = "meets" if error <= tolerance else "does NOT meet"
        return RingChoice(modes, tolerance, error, None if cpu is None else cpu * collisions,
                          f"N = {modes} given; predicted per-collision error {error:.2g} ({ERROR_QUANTILE:.0%} of "
                          f"collisions) {verdict} tolerance {tolerance:g}"
                          f"{_extrapolation(model, gamma, kappa, modes)}", False)
    needed = model.modes_for(gamma, kappa, tolerance)
    if needed is None:
        raise InvalidParameterError(f"tolerance={tolerance:g}: the ring model's per-collision error does not fall "
                                    "with the modes at this kappa; give the modes")
    error, cpu = model.predict(gamma, kappa, needed)
    if needed > MAX_MODES:
        count = f"more than {10 * MAX_MODES}" if error > tolerance else f"N = {needed}"
        raise LimitError(f"ring: tolerance={tolerance:g} on the per-collision restitution needs {count} modes "
                         f"per rod{_extrapolation(model, gamma, kappa, needed)}, more than the {MAX_MODES} modes the "
                         "modal solver takes; raise the tolerance")
    what = (f"ring: tolerance={tolerance:g} on the per-collision restitution needs N = {needed} modes per rod "
            f"(predicted error {error:.2g}{_cpu_text(cpu, collisions)}{_extrapolation(model, gamma, kappa, needed)})")
    check_study_cost(what, ring_cost(kappa, [needed], collisions), Limits(max_work=max_work),
                     "raise the tolerance or use fewer collisions")
    reason = (f"N = {needed}: the fewest modes predicted to meet tolerance {tolerance:g} on the per-collision "
              f"restitution ({ERROR_QUANTILE:.0%} of collisions; predicted {error:.2g}, N = {needed - 1} "
              f"predicted {model.predict(gamma, kappa, needed - 1)[0]:.2g})"
              if needed > 1 else f"N = 1 is predicted to meet tolerance {tolerance:g} (predicted {error:.2g})")
    return RingChoice(needed, tolerance, error, None if cpu is None else cpu * collisions,
                      reason + _extrapolation(model, gamma, kappa, needed), True)


def padded_state(state: dict, modes: int, reference) -> dict:
    """``state`` of a ring simulation with ``modes`` per rod, as a state of ``reference`` (more modes per rod):
    the extra modes at rest."""
    out = dict(state)
    more = int(reference.modes)
    for key in ("q", "v"):
        values = np.asarray(state[key], dtype=float)
        padded = np.zeros(2 * more)
        padded[:modes] = values[:modes]
        padded[more:more + modes] = values[modes:]
        out[key] = padded
    out["parameters"] = reference.get_state()["parameters"]
    return out


class CollisionChecks:
    """The checks of one ring run: which collisions, their error estimates, and what they say of the model.

    Parameters
    ----------
    simulate : callable
        ``simulate(scene, options)`` of the run's solver.
    scene : Scene
        The ring scene.
    options : SolverOptions
        The run's solver options.
    tolerance : float
        Tolerance on the per-collision restitution error.
    predicted : float or None
        The model's :data:`ERROR_QUANTILE` quantile of the per-collision error at the run's modes.
    every : int or None
        Collisions between checks (the first collision is always checked); None: :data:`CHECK_EVERY`; 0: none.
    """

    def __init__(self, simulate, scene, options, tolerance: float, predicted=None, every=None):
        self.every = CHECK_EVERY if every is None else int(every)
        self.tolerance = float(tolerance)
        self.predicted = None if predicted is None else float(predicted)
        self.modes = int(options.modes)
        self.reference = simulate(scene, options.replace(modes=2 * self.modes)) if self.every > 0 else None
        self.note = ""
        if self.reference is not None and not self._usable():
            self.every, self.reference = 0, None
            self.note = " (the simulation's state has no modal coordinates to check with more modes)"
        self.collisions: list = []
        self.estimates: list = []

    def due(self, index: int) -> bool:
        """Whether collision ``index`` (0-based) is checked."""
        return self.every > 0 and index % self.every == 0

    def _usable(self) -> bool:
        """Whether the simulation's state holds modal coordinates to pad (a stand-in's may not)."""
        state = self.reference.get_state()
        return all(np.shape(state.get(key)) == (4 * self.modes,) for key in ("q", "v")) and \
            getattr(self.reference, "modes", None) == 2 * self.modes

    def estimate(self, state: dict, restitution: float) -> float:
        """The error estimate of the collision that followed ``state`` and gave ``restitution``: ``ESTIMATE_FACTOR
        |eps_N - eps_2N|``, ``eps_2N`` from ``state`` with twice the modes (the added ones at rest)."""
        self.reference.set_state(padded_state(state, self.modes, self.reference))
        finer = self.reference.next_collision().restitution
        return ESTIMATE_FACTOR * abs(float(restitution) - float(finer))

    def add(self, index: int, state: dict, restitution: float) -> float:
        """Check collision ``index`` (0-based), which followed ``state`` and gave ``restitution``."""
        estimate = self.estimate(state, restitution)
        self.collisions.append(int(index) + 1)
        self.estimates.append(float(estimate))
        return estimate

    def above(self) -> list:
        """Collisions (1-based) whose estimate exceeds the tolerance."""
        return [c for c, e in zip(self.collisions, self.estimates) if e > self.tolerance]

    def verdict(self) -> str:
        """One line: how the checked collisions compare with the tolerance and with the model's prediction (the
        model is wrong for the run when more than ``1 - ERROR_QUANTILE`` of them are above its prediction)."""
        count, above = len(self.estimates), self.above()
        if not count:
            return "no collision checked" + self.note
        text = (f"{len(above)} of {count} checked collisions have error estimates above tolerance {self.tolerance:g} "
                f"(largest {max(self.estimates):.2g})")
        if self.predicted is None:
            return text
        beyond = sum(e > self.predicted for e in self.estimates)
        if beyond > (1.0 - ERROR_QUANTILE) * count:
            return (text + f"; {beyond} above the predicted {self.predicted:.2g}, more than the "
                    f"{1.0 - ERROR_QUANTILE:.0%} the model allows: the model is wrong here")
        return text + f"; {beyond} above the predicted {self.predicted:.2g} (the model allows {1.0 - ERROR_QUANTILE:.0%})"

    def summary(self) -> dict:
        return {"every": self.every, "collisions": list(self.collisions), "estimates": list(self.estimates),
                "largest": max(self.estimates) if self.estimates else None, "above_tolerance": self.above(),
                "verdict": self.verdict()}
