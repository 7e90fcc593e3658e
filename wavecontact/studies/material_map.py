"""Restitution of two rods of different materials over the plane of their two ratios.

With the impedance ratio ``Z_2 / Z_1`` and the transit-time ratio ``T_1 / T_2``
(``T_i = 2 l_i / c_i``) fixed, the delay equation has no other parameter but
``kappa = alpha V mu / Z_s`` (:mod:`wavecontact.delay.parameters`).  The map is
epsilon on a grid of the two ratios, in the hard-core limit (the exact
max-plus recursion) or at finite ``kappa`` (the delay equation).  Two lines are
known in closed form for hard contact (docs/theory.md, "Two materials"):

* equal impedances: ``epsilon = min(T_1/T_2, T_2/T_1)`` (the paper's ``gamma``);
* equal transit times: ``epsilon = 1`` whatever the impedances.

The points call the delay package's hard-core recursion and the delay
equation directly (not through :func:`wavecontact.solve`, whose scene
building and histories would cost as much as the hard-core solve itself).
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError
from ..progress import Progress
from ..solvers import solver_for
from ..solvers.base import MATERIAL_RATIOS

__all__ = ["MAX_POINTS", "MaterialMap", "material_map", "special_line_restitution"]

MAX_POINTS = 1_000_000  # bound on the grid size, checked before any work


def special_line_restitution(impedance_ratio, time_ratio):
    """Hard-core epsilon on the known lines, ``nan`` elsewhere.

    ``min(T_1/T_2, T_2/T_1)`` where ``Z_2 = Z_1``; ``1`` where ``T_1 = T_2``.
    """
    z = np.asarray(impedance_ratio, dtype=float)
    t = np.asarray(time_ratio, dtype=float)
    out = np.full(np.broadcast(z, t).shape, np.nan)
    out = np.where(np.isclose(z, 1.0, rtol=1e-12), np.minimum(t, 1.0 / t), out)
    return np.where(np.isclose(t, 1.0, rtol=1e-12), 1.0, out)


def _hard_point(point):
    return solver_for(MATERIAL_RATIOS).restitution_of_ratios(point[0], point[1], math.inf)


def _soft_point(point, kappa, rtol):
    return solver_for(MATERIAL_RATIOS).restitution_of_ratios(point[0], point[1], kappa, rtol)


@dataclass
class MaterialMap:
    """epsilon over ``impedance_ratios x time_ratios`` for one ``kappa``.

    Attributes
    ----------
    impedance_ratios, time_ratios : ndarray
        ``Z_2 / Z_1`` (rows) and ``T_1 / T_2`` (columns).
    kappa : float
        ``alpha V mu / Z_s``; ``inf`` for hard contact.
    restitution : ndarray, shape (rows, columns)
    rtol : float or None
        Tolerance of the delay solver (``None`` in the hard-core limit, exact to round-off).
    wall_time_s : float
        Time to compute the map (s).
    """

    impedance_ratios: np.ndarray
    time_ratios: np.ndarray
    kappa: float
    restitution: np.ndarray
    rtol: float | None
    wall_time_s: float

    def special_line_deviation(self) -> dict:
        """Largest ``|epsilon - closed form|`` on each known line the grid contains (hard core only)."""
        if math.isfinite(self.kappa):
            return {}
        z, t = np.meshgrid(self.impedance_ratios, self.time_ratios, indexing="ij")
        known = special_line_restitution(z, t)
        out = {}
        for name, mask in (("equal impedances", np.isclose(z, 1.0, rtol=1e-12)),
                           ("equal transit times", np.isclose(t, 1.0, rtol=1e-12))):
            if mask.any():
                out[name] = float(np.max(np.abs(self.restitution[mask] - known[mask])))
        return out

    def table(self, max_rows: int = 9, max_columns: int = 9) -> str:
        """A Markdown table of epsilon on an evenly thinned subgrid (at most ``max_rows x max_columns``)."""
        rows = _thin(self.impedance_ratios.size, max_rows)
        columns = _thin(self.time_ratios.size, max_columns)
        kappa = "inf (hard core)" if math.isinf(self.kappa) else f"{self.kappa:g}"
        lines = [
            (f"epsilon for kappa = {kappa}: rows Z2/Z1, columns T1/T2 "
            f"({self.restitution.size} points in {self.wall_time_s:.2f} s)"),
            "",
            "| Z2/Z1 \\ T1/T2 | " + " | ".join(f"{self.time_ratios[j]:.3g}" for j in columns) + " |",
            "|---|" + "---|" * len(columns),
        ]
        for i in rows:
            values = " | ".join(f"{self.restitution[i, j]:.4f}" for j in columns)
            lines.append(f"| {self.impedance_ratios[i]:.3g} | {values} |")
        deviations = self.special_line_deviation()
        if deviations:
            lines.append("")
            lines.extend(f"largest deviation from the closed form on the line of {name}: {value:.1e}"
                         for name, value in deviations.items())
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {
            "impedance_ratios": self.impedance_ratios.tolist(),
            "time_ratios": self.time_ratios.tolist(),
            "kappa": "inf" if math.isinf(self.kappa) else self.kappa,
            "restitution": self.restitution.tolist(),
            "rtol": self.rtol,
            "wall_time_s": self.wall_time_s,
            "special_line_deviation": self.special_line_deviation(),
        }

    def save(self, path) -> None:
        """Write the map as JSON (``path``, no pickle)."""
        with open(path, "w") as handle:
            json.dump(self.to_dict(), handle)

    @classmethod
    def load(cls, path) -> MaterialMap:
        with open(path) as handle:
            data = json.load(handle)
        kappa = math.inf if data["kappa"] == "inf" else float(data["kappa"])
        return cls(np.asarray(data["impedance_ratios"]), np.asarray(data["time_ratios"]), kappa,
                   np.asarray(data["restitution"]), data["rtol"], data["wall_time_s"])


def _thin(size: int, most: int) -> np.ndarray:
    if size <= most:
        return np.arange(size)
    return np.unique(np.round(np.linspace(0, size - 1, most)).astype(int))


def _ratios(name, values):
    values = np.atleast_1d(np.asarray(values, dtype=float))
    if values.ndim != 1 or values.size == 0:
        raise InvalidParameterError(f"{name} must be a non-empty 1-D sequence")
    for value in values:  # refuses values outside [1e-6, 1e6], naming the ratio
        if name == "impedance_ratios":
            solver_for(MATERIAL_RATIOS).check_ratios(value, 1.0)
        else:
            solver_for(MATERIAL_RATIOS).check_ratios(1.0, value)
    return values


def material_map(impedance_ratios, time_ratios, kappa: float = math.inf, *, rtol: float = 1e-8,
                 workers: int | None = None, progress: bool | None = None) -> MaterialMap:
    """epsilon on the grid ``impedance_ratios x time_ratios``.

    Parameters
    ----------
    impedance_ratios : array_like
        ``Z_2 / Z_1`` values in [1e-6, 1e6].
    time_ratios : array_like
        ``T_1 / T_2`` values in [1e-6, 1e6].
    kappa : float
        ``alpha V mu / Z_s`` in (0, inf]; ``inf`` is the hard-core limit.
    rtol : float
        Accuracy of the delay solver at finite ``kappa`` (absolute, in epsilon).
    workers : int or None
        Threads for finite ``kappa`` (the compiled kernel releases the GIL);
        default: the number of cores.  The hard-core recursion runs in one thread.
    progress : bool or None
        tqdm bar on stderr (default: when stderr is a terminal).

    Returns
    -------
    MaterialMap
    """
    impedance_ratios = _ratios("impedance_ratios", impedance_ratios)
    time_ratios = _ratios("time_ratios", time_ratios)
    try:
        kappa = float(kappa)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"kappa must be a number in (0, inf], got {kappa!r}") from None
    if not kappa > 0.0:
        raise InvalidParameterError(f"kappa must lie in (0, inf], got {kappa!r}")
    size = impedance_ratios.size * time_ratios.size
    if size > MAX_POINTS:
        raise InvalidParameterError(f"the map may have at most {MAX_POINTS} points, got {size}")
    points = [(float(z), float(t)) for z in impedance_ratios for t in time_ratios]
    hard = math.isinf(kappa)
    if hard:
        one = _hard_point
        workers = 1
        one(points[0])  # compile or load the kernel before the clock starts
    else:
        _soft_point(points[0], kappa, rtol)  # compile or load the kernel, refuse a bad rtol early

        def one(point):
            return _soft_point(point, kappa, rtol)

        workers = max(1, int(workers or os.cpu_count() or 1))
    if progress is None:
        progress = sys.stderr.isatty()
    started = time.perf_counter()
    with ThreadPoolExecutor(max_workers=workers) as pool:
        results = map(one, points) if workers == 1 else pool.map(one, points)
        values = np.empty(size)
        with Progress(size, f"material map (kappa = {kappa:g})", unit="point", enabled=progress) as bar:
            for k, value in enumerate(results):
                values[k] = value
                bar.advance()
    seconds = time.perf_counter() - started
    return MaterialMap(impedance_ratios, time_ratios, kappa, values.reshape(impedance_ratios.size, time_ratios.size),
                       None if hard else rtol, seconds)
