"""The hard-core collision law of the vibration rule, tabulated over every state a pair can reach.

A pair of rods (length ratio ``gamma``) meets with translational energy
``E_tr`` while both baths are at ``T_B``.  The state variable is

    x = E_tr / (E_tr + T_B)  in (0, 1],

``x = 1`` cold baths, ``x -> 0`` a slow pair in warm baths.  Per
``(gamma, x)`` the :class:`CollisionLaw` holds

* the quantile function of ``epsilon^2 = E'_tr / E_tr``;
* per probability level ``u``, the conditional mean of the short rod's
  vibration gain given that ``epsilon^2`` lies at level ``u``, in units of
  ``E_tr + T_B`` (the long rod takes the rest of ``(1 - epsilon^2) E_tr``,
  so energy is conserved in every draw).  A per-sample quantity: no ratio of
  means, finite and well conditioned at ``gamma = 1``.

Grid in ``log10 x`` from ``LOG_X_MIN`` to 0.  What the solver shows as
``x -> 0`` (docs/gas.md; ``python docs/gas_study.py vibration``, section 4b):
``E'_tr / (E_tr + T_B) -> 0``; ``epsilon^2`` itself levels off for some
``gamma`` (0.6) and keeps growing for others (0.85) down to ``x = 1e-5``,
so no single limit law in these variables exists.  Below the last row (``x < 10^LOG_X_MIN``) the rule therefore uses the
last row's law (``epsilon^2`` and the gain in units of ``E_tr + T_B``), and the
gas counts these draws (``GasResult.beyond_law``): a stated approximation,
never silent.

Samples come from :func:`wavecontact.gas.hardcore_collision.hard_core_collision`
(``kappa = inf``: the paper finds the statistics independent of ``kappa``
above about 50).  Files: ``.npz`` with a JSON ``schema`` (no pickle).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError
from ..io.files import atomic_write

__all__ = ["DEFAULT_LAW_FILE", "LOG_X_MIN", "REGENERATE", "CollisionLaw", "build_collision_law", "default_law",
           "load_law"]

SCHEMA_NAME = "wavecontact.collision_law"
SCHEMA_VERSION = 1
DEFAULT_LAW_FILE = "collision_law_hardcore.npz"
LOG_X_MIN = -4.0
REGENERATE = ("python -m wavecontact.gas.collision_law --gamma 0.6 0.7 0.8 0.9 0.95 1.0 "
              "--log-x 0 -0.02 -0.05 -0.1 -0.15 -0.25 -0.35 -0.5 -0.75 -1 -1.5 -2 -2.5 -3 -3.5 -4 "
              "--samples 400 --levels 41 --seed 2026 --resolution 16 --workers 2 "
              "--out wavecontact/data/collision_law_hardcore.npz")
MAX_LAW_SAMPLES = 2_000_000
_ARRAYS = ("gamma", "log_x", "probability", "eps2_quantiles", "gain_short")


@dataclass(frozen=True)
class CollisionLaw:
    """Quantiles of ``epsilon^2`` and conditional short-rod gains on a ``(gamma, log10 x)`` grid.

    Parameters
    ----------
    gamma : array_like (G,)
        Length ratios, strictly ascending in (0, 1].
    log_x : array_like (X,)
        ``log10(E_tr / (E_tr + T_B))``, strictly ascending, last value 0.
    probability : array_like (P,)
        Levels, strictly ascending from 0 to 1.
    eps2_quantiles : array_like (G, X, P)
        ``epsilon^2`` at each level (dimensionless, >= 0, non-decreasing in the level).
    gain_short : array_like (G, X, P)
        Mean gain of the short rod's vibrations given the level, in units of ``E_tr + T_B``.
    bath_modes, samples_per_point, seed : int
        How the law was computed.
    """

    gamma: np.ndarray
    log_x: np.ndarray
    probability: np.ndarray
    eps2_quantiles: np.ndarray
    gain_short: np.ndarray
    bath_modes: int = 250
    samples_per_point: int = 0
    seed: int = 0
    resolution: int = 8

    def __post_init__(self):
        for name in _ARRAYS:
            try:
                array = np.array(getattr(self, name), dtype=np.float64, order="C")
            except (TypeError, ValueError):
                raise InvalidParameterError(f"collision law {name} must be an array of numbers") from None
            if not np.all(np.isfinite(array)):
                raise InvalidParameterError(f"collision law {name} must be finite")
            array.setflags(write=False)
            object.__setattr__(self, name, array)
        for name in ("gamma", "log_x", "probability"):
            values = getattr(self, name)
            if values.ndim != 1 or values.size < 1 or np.any(np.diff(values) <= 0):
                raise InvalidParameterError(f"collision law {name} must be a strictly ascending 1-D array")
        if self.gamma[0] <= 0 or self.gamma[-1] > 1:
            raise InvalidParameterError("collision law gamma must lie in (0, 1]")
        if self.log_x[-1] != 0.0:
            raise InvalidParameterError("collision law log_x must end at 0 (cold baths)")
        if self.probability.size < 2 or self.probability[0] != 0 or self.probability[-1] != 1:
            raise InvalidParameterError("collision law probability must run from 0 to 1 with >= 2 levels")
        shape = (self.gamma.size, self.log_x.size, self.probability.size)
        for name in ("eps2_quantiles", "gain_short"):
            if getattr(self, name).shape != shape:
                raise InvalidParameterError(f"collision law {name} must have shape {shape}")
        if np.any(self.eps2_quantiles < 0) or np.any(np.diff(self.eps2_quantiles, axis=-1) < 0):
            raise InvalidParameterError("collision law eps2_quantiles must be >= 0 and non-decreasing")
        for name in ("bath_modes", "samples_per_point", "seed", "resolution"):
            value = getattr(self, name)
            if isinstance(value, bool) or int(value) != value or value < 0:
                raise InvalidParameterError(f"collision law {name} must be an integer >= 0, got {value!r}")
            object.__setattr__(self, name, int(value))

    def arrays(self):
        """``(gamma, log_x, probability, eps2_quantiles, gain_short)`` as C-contiguous float64 (kernel form)."""
        return tuple(np.ascontiguousarray(getattr(self, name)) for name in _ARRAYS)

    def _row(self, gamma, x):
        g = float(gamma)
        if not self.gamma[0] <= g <= self.gamma[-1]:
            raise InvalidParameterError(f"gamma must lie in [{self.gamma[0]:g}, {self.gamma[-1]:g}], got {g:g}")
        if not 0.0 < x <= 1.0:
            raise InvalidParameterError(f"x = E_tr/(E_tr + T_B) must lie in (0, 1], got {x!r}")
        lx = max(math.log10(x), self.log_x[0])
        values = []
        for grid, v in ((self.gamma, g), (self.log_x, lx)):
            i = int(np.clip(np.searchsorted(grid, v, side="right") - 1, 0, max(grid.size - 2, 0)))
            w = 0.0 if grid.size == 1 else (v - grid[i]) / (grid[i + 1] - grid[i])
            values += [i, w]
        return values

    def draw(self, gamma, x, u):
        """``(epsilon^2, gain_short)`` at level ``u`` for a pair at ``(gamma, x)`` (as the gas kernel does)."""
        ig, wg, ix, wx = self._row(gamma, x)
        k = min(int(u * (self.probability.size - 1)), self.probability.size - 2)
        wu = (u - self.probability[k]) / (self.probability[k + 1] - self.probability[k])
        out = []
        for array in (self.eps2_quantiles, self.gain_short):
            total = 0.0
            for dg, fg in ((0, 1 - wg), (1, wg)):
                for dx, fx in ((0, 1 - wx), (1, wx)):
                    a = array[min(ig + dg, self.gamma.size - 1), min(ix + dx, self.log_x.size - 1)]
                    total += fg * fx * ((1 - wu) * a[k] + wu * a[k + 1])
            out.append(total)
        return out[0], out[1]

    def metadata(self) -> dict:
        return {"name": SCHEMA_NAME, "version": SCHEMA_VERSION, "kappa": "inf", "solver": "hard-core max-plus",
                "bath_modes": self.bath_modes, "samples_per_point": self.samples_per_point, "seed": self.seed,
                "resolution": self.resolution,
                "units": "x = E_tr/(E_tr+T_B); eps2 = E'_tr/E_tr; gain_short in units of E_tr + T_B",
                "regenerate": REGENERATE}

    def save(self, path):
        """Write ``.npz`` (arrays plus a JSON ``schema``)."""
        path = Path(path)
        if path.suffix.lower() != ".npz":
            raise InvalidParameterError(f"collision law path must end in .npz, got {path.name!r}")
        arrays = {name: getattr(self, name) for name in _ARRAYS}
        schema = np.array(json.dumps(self.metadata()))
        atomic_write(path, lambda handle: np.savez(handle, schema=schema, **arrays))
        return path


def load_law(path) -> CollisionLaw:
    """Read a :class:`CollisionLaw` written by :meth:`CollisionLaw.save` (``allow_pickle=False``)."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            document = {name: data[name] for name in data.files}
        meta = json.loads(str(document.pop("schema")))
    except (ValueError, OSError, KeyError, json.JSONDecodeError) as exc:
        raise InvalidParameterError(f"{path.name}: not a readable collision law ({exc})") from None
    if meta.get("name") != SCHEMA_NAME or meta.get("version") != SCHEMA_VERSION:
        raise InvalidParameterError(f"{path.name} is not a {SCHEMA_NAME} v{SCHEMA_VERSION} file")
    missing = [name for name in _ARRAYS if name not in document]
    if missing:
        raise InvalidParameterError(f"{path.name} lacks the array(s) {', '.join(missing)}")
    return CollisionLaw(**{name: document[name] for name in _ARRAYS}, bath_modes=meta["bath_modes"],
                        samples_per_point=meta["samples_per_point"], seed=meta["seed"],
                        resolution=meta.get("resolution", 8))


def default_law() -> CollisionLaw:
    """The law shipped with the package (see :data:`REGENERATE`)."""
    with resources.as_file(resources.files("wavecontact") / "data" / DEFAULT_LAW_FILE) as path:
        return load_law(path)


def level_means(order_values, values, probability):
    """Mean of ``values`` per probability level, samples ranked by ``order_values``.

    Sample ``i`` of ``n`` (in ascending order) sits at rank level ``(i + 1/2)/n``;
    level ``u_k`` averages the samples within half a level spacing of it (the
    first and last levels a half bin).  The levels' trapezoid mean equals the
    plain mean when every bin holds samples.
    """
    order = np.argsort(order_values, kind="stable")
    ranked = np.asarray(values, dtype=float)[order]
    n = ranked.size
    rank = (np.arange(n) + 0.5) / n
    edges = np.concatenate([[0.0], 0.5 * (probability[1:] + probability[:-1]), [1.0]])
    out = np.empty(probability.size)
    for k in range(probability.size):
        inside = (rank >= edges[k]) & (rank < edges[k + 1])
        if not np.any(inside):
            raise InvalidParameterError(f"{n} samples leave probability level {probability[k]:g} empty: "
                                        "use more samples or fewer levels")
        out[k] = ranked[inside].mean()
    return out


def _point(task):
    from .hardcore_collision import hard_core_collision

    gamma, log_x, seeds, modes, resolution = task
    x = 10.0**log_x
    ratio = (1.0 - x) / x
    samples = np.array([hard_core_collision(gamma, ratio, s, bath_modes=modes, resolution=resolution)
                        for s in seeds])
    return samples[:, 0], samples[:, 1] * x  # eps2; short rod's gain in units of E_tr + T_B


def point_samples(gamma, log_x, samples, seed, *, bath_modes=250, resolution=8):
    """``(eps2, gain_short)`` of ``samples`` hard-core collisions at one grid point (seeds spawned from ``seed``)."""
    seeds = np.random.SeedSequence(seed).spawn(int(samples)) if not isinstance(seed, np.random.SeedSequence) \
        else seed.spawn(int(samples))
    return _point((float(gamma), float(log_x), seeds, bath_modes, resolution))


def build_collision_law(gammas, log_xs, samples, seed, *, levels=41, bath_modes=250, resolution=8, executor=None):
    """Tabulate the hard-core collision law (one ensemble per ``(gamma, log10 x)`` point).

    Point ``a`` (row-major over ``gammas`` x ``log_xs``) uses child ``a`` of
    ``SeedSequence(seed).spawn(points)``, and its sample ``i`` child ``i`` of that.
    """
    gammas, log_xs = np.asarray(gammas, float), np.asarray(log_xs, float)
    if gammas.size * log_xs.size * int(samples) > MAX_LAW_SAMPLES:
        raise InvalidParameterError(f"a collision law may hold at most {MAX_LAW_SAMPLES} collisions in all")
    if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)) or not 2 <= levels <= int(samples):
        raise InvalidParameterError(f"levels must be an integer in [2, samples], got {levels!r}")
    probability = np.linspace(0.0, 1.0, int(levels))
    points = [(g, lx) for g in gammas for lx in log_xs]
    children = np.random.SeedSequence(int(seed)).spawn(len(points))
    tasks = [(float(g), float(lx), child.spawn(int(samples)), int(bath_modes), int(resolution))
             for (g, lx), child in zip(points, children)]
    results = list(executor.map(_point, tasks)) if executor is not None else [_point(t) for t in tasks]
    shape = (gammas.size, log_xs.size, probability.size)
    quantiles, gains = np.empty(shape), np.empty(shape)
    for a, (eps2, gain) in enumerate(results):
        g, x = divmod(a, log_xs.size)
        quantiles[g, x] = np.quantile(eps2, probability)
        gains[g, x] = level_means(eps2, gain, probability)
    return CollisionLaw(gammas, log_xs, probability, quantiles, gains, bath_modes=int(bath_modes),
                        samples_per_point=int(samples), seed=int(seed), resolution=int(resolution))


def main(argv=None):
    import argparse
    import time
    from concurrent.futures import ProcessPoolExecutor

    p = argparse.ArgumentParser(prog="python -m wavecontact.gas.collision_law",
                                description="Tabulate the hard-core collision law of the gas's vibration rule.")
    p.add_argument("--gamma", type=float, nargs="+", required=True)
    p.add_argument("--log-x", type=float, nargs="+", required=True, help="log10 E_tr/(E_tr+T_B), ascending or not")
    p.add_argument("--samples", type=int, required=True)
    p.add_argument("--levels", type=int, default=41)
    p.add_argument("--seed", type=int, required=True)
    p.add_argument("--bath-modes", type=int, default=250)
    p.add_argument("--resolution", type=int, default=8)
    p.add_argument("--workers", type=int, default=1)
    p.add_argument("--out", required=True)
    args = p.parse_args(argv)
    start = time.perf_counter()
    log_xs = sorted(args.log_x)
    if args.workers > 1:
        with ProcessPoolExecutor(args.workers) as pool:
            law = build_collision_law(args.gamma, log_xs, args.samples, args.seed, levels=args.levels,
                                      bath_modes=args.bath_modes, resolution=args.resolution, executor=pool)
    else:
        law = build_collision_law(args.gamma, log_xs, args.samples, args.seed, levels=args.levels,
                                  bath_modes=args.bath_modes, resolution=args.resolution)
    law.save(args.out)
    print(f"wrote {args.out} in {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
