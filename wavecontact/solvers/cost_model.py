"""The cost-and-error model behind ``solver="auto"``: data written by ``python benchmarks/cost_model.py``.

Nothing here is a measured number: the model is the file ``wavecontact/data/cost_model.json``,
which the benchmark regenerates.  It holds

``ladders``
    the resolutions tried per solver (FE ``elements``, modal ``modes``, delay ``rtol``);
``points``
    the calibration runs: scene class, solver, resolution, the scene's features, the error
    estimate the run reported and its CPU time (seconds, ``time.process_time``, error estimate
    included);
``fits``
    per scene class and solver, least-squares fits of ``log10(error estimate)`` and of
    ``log10(CPU seconds)`` on :data:`FEATURES`, each with ``margin``: the :data:`MARGIN_QUANTILE`
    quantile of the residuals of its calibration points (decades), added to the prediction, and
    ``largest_residual``.

:func:`fit_points` turns ``points`` into ``fits`` deterministically, so that the benchmark's
``--check`` can verify the stored fits are what its points give.
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..contact import LAW_EXPONENTIAL, LAW_PENALTY
from ..errors import InvalidParameterError, UnsupportedSceneError
from ..scene import Scene

__all__ = [
    "DATA_PATH",
    "FEATURES",
    "FORMAT",
    "LINE_CLASSES",
    "CostModel",
    "Prediction",
    "fit_points",
    "load_model",
    "scene_class",
    "scene_features",
]

#: The model's file (written by ``python benchmarks/cost_model.py``).
DATA_PATH = Path(__file__).resolve().parents[1] / "data" / "cost_model.json"
#: Version of the file's layout.
FORMAT = 1
#: Regressors of both fits, in order (``resolution``: elements, modes, or rtol).
FEATURES = ("1", "log10 kappa", "log10 resolution", "log10 (1/time ratio)", "log10 (1 + vibration energy / E_tr)")
#: Smallest error estimate a fit sees (the solvers' round-off floor): points below are raised to it.
ERROR_FLOOR = 1e-13


#: Classes of the line scenes beyond the paper's two rods (:attr:`Scene.is_line_scene`), in the order
#: :func:`line_scene_class` tests them.
LINE_CLASSES = ("line_rigid", "line_tapered", "line_stepped", "line_chain")


def line_scene_class(scene: Scene) -> str:
    """The class of a line scene: ``'line_rigid'`` (a rigid body among the bodies), ``'line_tapered'``
    (a tapered segment), ``'line_stepped'`` (a rod of several segments), else ``'line_chain'`` (uniform
    rods: three or more, per-pair laws, or walls)."""
    from ..bodies import PiecewiseRod, RigidBody, body_segments

    if any(isinstance(body, RigidBody) for body in scene.rods):
        return "line_rigid"
    if any(segment.tapered for body in scene.rods for segment in body_segments(body)):
        return "line_tapered"
    if any(isinstance(body, PiecewiseRod) and len(body.segments) > 1 for body in scene.rods):
        return "line_stepped"
    return "line_chain"


def scene_class(scene: Scene) -> str:
    """The scene class the model is calibrated per: ``'hard'``, ``'penalty'``, ``'thermal'``,
    ``'two_materials'`` or ``'cold'`` (two rods of one material, exponential law); a line scene's
    :func:`line_scene_class`; ``'other'`` for anything else (rings, other laws), for which the model
    has no data."""
    if scene.is_line_scene:
        return line_scene_class(scene)
    if scene.is_ring or len(scene.rods) != 2:
        return "other"
    contact = scene.contact
    if contact.hard:
        return "hard" if scene.vibrations is None else "other"
    if contact.code == LAW_PENALTY:
        return "penalty" if scene.is_cold else "other"
    if contact.code != LAW_EXPONENTIAL:
        return "other"
    if scene.vibrations is not None:
        return "thermal"
    if not scene.is_cold:
        return "other"
    if not scene.rods[0].same_material(scene.rods[1]):
        return "two_materials"
    return "cold"


def scene_features(scene: Scene) -> dict:
    """``kappa`` (``alpha V mu / Z_s``; the paper's kappa for two rods of one material; 1 for the hard
    core), ``time_ratio`` (shorter over longer round trip, gamma for one material) and
    ``vibration_energy`` (of both rods' initial vibrations, over ``E_tr``; 0 when cold)."""
    if scene.is_line_scene:
        return _line_features(scene)
    if scene.is_ring or len(scene.rods) != 2:
        raise UnsupportedSceneError("the cost model describes two rods on a line")
    trips = sorted(rod.round_trip_time for rod in scene.rods)
    time_ratio = trips[0] / trips[1]
    if "two_rods" in scene.metadata:
        kappa = float(scene.metadata["two_rods"].kappa)
    elif scene.contact.code == LAW_EXPONENTIAL:  # alpha V mu / Z_s, as the delay equation defines it
        (rod_1, rod_2), speed = scene.rods, abs(scene.velocities[0] - scene.velocities[1])
        series = rod_1.impedance * rod_2.impedance / (rod_1.impedance + rod_2.impedance)
        kappa = scene.contact.alpha * speed * (rod_1.mass * rod_2.mass / (rod_1.mass + rod_2.mass)) / series
    else:
        kappa = 1.0
    if not math.isfinite(kappa):
        kappa = 1.0
    energy = 0.0
    if scene.vibrations is not None:
        masses = [rod.mass for rod in scene.rods]
        reduced = masses[0] * masses[1] / (masses[0] + masses[1])
        speed = abs(scene.velocities[0] - scene.velocities[1])
        energy = float(np.sum(scene.vibrations.vibration_energy())) / (0.5 * reduced * speed**2)
    return {"kappa": kappa, "time_ratio": time_ratio, "vibration_energy": energy}


def _line_features(scene: Scene) -> dict:
    """A line scene's features: none vary (``kappa`` 1, ``time_ratio`` 1, no vibrations).  Each line class
    is calibrated on three scenes, too few to fit a slope in a scene feature without extrapolating it wildly
    outside them: the fit is in the resolution alone, and its margin covers the spread between scenes."""
    del scene
    return {"kappa": 1.0, "time_ratio": 1.0, "vibration_energy": 0.0}


def _row(features: dict, resolution: float) -> list:
    return [1.0, math.log10(features["kappa"]), math.log10(resolution), math.log10(1.0 / features["time_ratio"]),
            math.log10(1.0 + features["vibration_energy"])]


def _value(fit: dict, row: list) -> float:
    """``10^(row . coef + margin)``, in plain floats (a prediction costs microseconds, not a NumPy call's)."""
    return 10.0 ** (sum(x * c for x, c in zip(row, fit["coef"])) + fit["margin"])


#: Quantile of a fit's residuals added to its predictions: nine in ten calibration runs are at or below
#: the prediction; a run above it is refined (and logged as a miss), which costs less than predicting
#: every run as if it were the worst.
MARGIN_QUANTILE = 0.9


def least_squares(rows: list, values: list) -> tuple:
    """``(coefficients, residuals)`` of the least-squares fit of ``values`` on ``rows``, the minimum-norm
    solution (a feature constant over the rows gets no weight beyond what the intercept takes); the
    coefficients rounded to 10 digits as the model files store them."""
    a, y = np.array(rows), np.array(values)
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    return [round(float(c), 10) for c in coef], y - a @ coef


def _fit(rows: list, values: list) -> dict:
    """:func:`least_squares`, and the :data:`MARGIN_QUANTILE` of the residuals as the margin."""
    coef, residual = least_squares(rows, values)
    margin = max(float(np.quantile(residual, MARGIN_QUANTILE)), 0.0)
    return {"coef": coef, "margin": round(margin, 10),
            "largest_residual": round(float(residual.max()), 10)}


def fit_points(points: list) -> dict:
    """``fits[class][solver] = {'error': ..., 'cost': ...}`` from the calibration ``points``
    (each a dict with ``class``, ``solver``, ``resolution``, ``features``, ``estimate``, ``cpu_s``;
    failed runs have ``estimate`` None and enter neither fit)."""
    groups: dict = {}
    for point in points:
        if point["estimate"] is None or not math.isfinite(point["estimate"]):
            continue
        groups.setdefault((point["class"], point["solver"]), []).append(point)
    fits: dict = {}
    for (kind, solver), members in sorted(groups.items()):
        rows = [_row(p["features"], p["resolution"]) for p in members]
        error = [math.log10(max(p["estimate"], ERROR_FLOOR)) for p in members]
        cost = [math.log10(p["cpu_s"]) for p in members]
        fits.setdefault(kind, {})[solver] = {"error": _fit(rows, error), "cost": _fit(rows, cost),
                                             "runs": len(members)}
    return fits


_RESOLUTION_NAMES: dict = {}  # solver name -> the option that sets its resolution, read once from the registry


@dataclass(frozen=True)
class Prediction:
    """The model's prediction for one solver at one resolution (error estimate and CPU seconds,
    margins included)."""

    solver: str
    resolution: float
    error: float
    cpu_s: float

    @property
    def option(self) -> dict:
        """The solver option that sets the resolution."""
        name = _RESOLUTION_NAMES.get(self.solver)
        if name is None:
            from . import get_solver

            name = _RESOLUTION_NAMES[self.solver] = get_solver(self.solver).resolution
        return {name: int(self.resolution) if name in ("elements", "modes") else float(self.resolution)}

    def text(self) -> str:
        (name, value), = self.option.items()
        return f"{self.solver}: {name}={value:g}"


class CostModel:
    """The stored model (see the module docstring); :func:`load_model` reads it once."""

    def __init__(self, data: dict):
        if not isinstance(data, dict) or data.get("format") != FORMAT:
            raise InvalidParameterError(f"cost model data must have format {FORMAT}; regenerate it with "
                                        "python benchmarks/cost_model.py")
        self.data = data
        self.ladders = {name: [float(v) for v in values] for name, values in data["ladders"].items()}
        self.fits = data["fits"]
        self._candidates: dict = {}

    def classes(self) -> list:
        """The scene classes the model has data for."""
        return sorted(self.fits)

    def predict(self, kind: str, solver: str, features: dict, resolution: float) -> Prediction | None:
        """The prediction for a scene of class ``kind`` (None where the model has no fit)."""
        fit = self.fits.get(kind, {}).get(solver)
        if fit is None:
            return None
        row = _row(features, resolution)
        return Prediction(solver, resolution, _value(fit["error"], row), _value(fit["cost"], row))

    def candidates(self, kind: str, solver: str, features: dict) -> list:
        """Predictions along the solver's ladder, coarsest first (remembered per scene: sweeps of one
        scene class ask again and again)."""
        key = (kind, solver, *features.values())  # scene_features gives its keys in one order
        cached = self._candidates.get(key)
        if cached is None:
            ladder = self.ladders.get(solver, [])
            if solver == "delay":
                ladder = sorted(ladder, reverse=True)
            cached = [p for p in (self.predict(kind, solver, features, r) for r in ladder) if p is not None]
            if len(self._candidates) >= 1024:
                self._candidates.clear()
            self._candidates[key] = cached
        return cached


def load_model(path=None) -> CostModel:
    """The cost model from ``path`` (default :data:`DATA_PATH`), read once per path."""
    return _load(str(path or DATA_PATH))


@functools.lru_cache(maxsize=4)
def _load(path: str) -> CostModel:
    try:
        with open(path, encoding="utf-8") as handle:
            data = json.load(handle)
    except (OSError, ValueError) as error:
        raise InvalidParameterError(f"cannot read the cost model {path}: {error}; regenerate it with "
                                    "python benchmarks/cost_model.py") from None
    return CostModel(data)
