"""The collision law of the vibration rule, tabulated over every state a pair can reach.

A pair of rods (length ratio ``gamma``) meets with translational energy
``E_tr`` while the short rod's bath is at ``T_s`` and the long rod's at
``T_l`` (energy per mode).  The state variables are

    x = E_tr / (E_tr + T_pair) in (0, 1],   T_pair = (T_s + T_l) / 2,
    s = T_s / (T_s + T_l)      in [0, 1]    (0.5 when both baths are cold),

``x = 1`` cold baths, ``x -> 0`` a slow pair in warm baths; ``s`` says how
the thermal noise is split between the rods.  Each rod's term of the noise
(Eq. 17-19) is an independent Gaussian process whose variance is
proportional to that rod's own temperature, so the pair's noise is fixed by
its total strength (``x``) and its split (``s``); both axes are bounded, and
``s = 1/2`` is the one-temperature law of earlier versions.

Per ``(kappa, gamma, x, s)`` the :class:`CollisionLaw` holds

* the quantile function of ``epsilon^2 = E'_tr / E_tr``;
* per probability level ``u``, the conditional mean of the short rod's
  vibration gain given that ``epsilon^2`` lies at level ``u``, in units of
  ``E_tr + T_pair`` (the long rod takes the rest of ``(1 - epsilon^2) E_tr``,
  so energy is conserved in every draw).

Two laws ship with the package: the hard-core law (``kappa = inf``, fine grid,
samples from :func:`wavecontact.gas.hardcore_collision.hard_core_collision`)
and the soft law (a few finite ``kappa``, coarse grid, samples from the
finite-kappa delay solve with its per-rod energy split).  The gas adds the soft
law's change against the hard core, interpolated in kappa, to the hard-core
draw at the collision's own ``kappa = alpha V l`` (:func:`blend_draw`).

Grid in ``log10 x`` from ``log_x[0]`` to 0.  Below the last row the rule uses
the last row's law (counted, ``GasResult.beyond_law``); softer than the soft law's
softest row, that row's correction (counted, ``softer_than_law``).  The hard-core
solve's grid (points per period) may grow with ``sqrt(1/x)`` per row up to a cap,
one cap per ``gamma`` (:func:`row_resolutions`; the shipped law refines only its
``gamma = 1`` rows, where the exact answer ``eps^2 = 1`` makes the grid error
visible).  Files: ``.npz`` with a JSON ``schema`` (no pickle).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError, require_integer
from ..io.files import atomic_write

__all__ = ["DEFAULT_LAW_FILE", "DEFAULT_SOFT_LAW_FILE", "LAW_ARRAYS", "LOG_X_MIN", "REGENERATE", "REGENERATE_SOFT",
           "CollisionLaw", "LawGrid", "blend_draw", "build_collision_law", "default_law", "default_soft_law", "kappa_variable",
           "law_from_arrays", "load_law", "merge_kappa_rows", "parser", "row_resolutions", "soft_corrections", "solve_collision"]

SCHEMA_NAME = "wavecontact.collision_law"
SCHEMA_VERSION = 2  # 2: kappa and short-rod-share axes
DEFAULT_LAW_FILE = "collision_law_hardcore.npz"
DEFAULT_SOFT_LAW_FILE = "collision_law_soft.npz"
LOG_X_MIN = -4.0
REGENERATE = ("python -m wavecontact.gas.collision_law --kappa inf --gamma 0.6 0.7 0.8 0.9 0.95 1.0 "
              "--log-x 0 -0.02 -0.05 -0.1 -0.15 -0.25 -0.35 -0.5 -0.75 -1 -1.5 -2 -2.5 -3 -3.5 -4 "
              "--share 0 0.25 0.5 0.75 1 --samples 400 --levels 41 --seed 2026 --resolution 16 "
              "--resolution-cap 16 16 16 16 16 256 --workers 2 --out wavecontact/data/collision_law_hardcore.npz")
_SOFT_GRID = ("--gamma 0.6 0.8 1.0 --log-x 0 -0.15 -0.5 -1 -2 -3 -4 --share 0 0.5 1 --samples 64 --levels 17 "
              "--workers 2")
# the soft law's rows come from two builds (the kappa = 5 row was added later, with its own seed), merged along kappa
REGENERATE_SOFT = (f"python -m wavecontact.gas.collision_law --kappa 10 30 100 {_SOFT_GRID} --seed 2027 "
                   "--out soft_10_30_100.npz && "
                   f"python -m wavecontact.gas.collision_law --kappa 5 {_SOFT_GRID} --seed 2028 --out soft_5.npz && "
                   "python -m wavecontact.gas.collision_law --merge soft_5.npz soft_10_30_100.npz "
                   "--out wavecontact/data/collision_law_soft.npz")
MAX_LAW_SAMPLES = 2_000_000
MAX_SOFT_KAPPA_SAMPLES = 40_000  # finite-kappa solves take 10 ms to 1 s each
LAW_ARRAYS = ("kappa", "gamma", "log_x", "short_share", "probability", "eps2_quantiles", "gain_short")
_AXES = ("gamma", "log_x", "short_share", "probability")


def kappa_variable(kappa):
    """``z = ln(kappa) / kappa`` (0 for ``kappa = inf``): the variable the law is interpolated in along kappa.

    Eq. 23 of the paper, ``epsilon ~ gamma + ln(kappa (Gamma_2 - Gamma_1)) / kappa``, makes the cold law
    nearly linear in ``z`` at large ``kappa``; ``z`` decreases with ``kappa`` for ``kappa > e``.
    """
    kappa = float(kappa)
    return 0.0 if math.isinf(kappa) else math.log(kappa) / kappa


@dataclass(frozen=True)
class CollisionLaw:
    """Quantiles of ``epsilon^2`` and conditional short-rod gains on a ``(kappa, gamma, log10 x, s)`` grid.

    Parameters
    ----------
    kappa : array_like (K,)
        Contact softness ``alpha V l / c`` of the rows, strictly ascending, > e; ``inf`` (the hard
        core) only as the single row of a hard-core law.
    gamma : array_like (G,)
        Length ratios, strictly ascending in (0, 1].
    log_x : array_like (X,)
        ``log10(E_tr / (E_tr + T_pair))``, strictly ascending, last value 0.
    short_share : array_like (S,)
        ``s = T_short / (T_short + T_long)``, strictly ascending from 0 to 1 (or the single value 0.5:
        both rods at the pair's mean temperature).
    probability : array_like (P,)
        Levels, strictly ascending from 0 to 1.
    eps2_quantiles : array_like (K, G, X, S, P)
        ``epsilon^2`` at each level (dimensionless, >= 0, non-decreasing in the level).
    gain_short : array_like (K, G, X, S, P)
        Mean gain of the short rod's vibrations given the level, in units of ``E_tr + T_pair``.
    bath_modes, samples_per_point, seed, resolution : int
        How the law was computed (``resolution``: grid points per period of the hard-core solve).
    kappa_seeds : tuple of int, optional
        The seed of each kappa row when the rows come from separate builds (:func:`merge_kappa_rows`); empty
        when one build (``seed``) made them all.
    row_resolution : tuple, optional
        Grid points per period of the hard-core solve where they differ from ``resolution``
        (:func:`row_resolutions`): one integer per ``log_x`` row (the same for every ``gamma``), or one such
        tuple per ``gamma`` row (a cap per ``gamma``); empty when every point used ``resolution``.
    """

    kappa: np.ndarray
    gamma: np.ndarray
    log_x: np.ndarray
    short_share: np.ndarray
    probability: np.ndarray
    eps2_quantiles: np.ndarray
    gain_short: np.ndarray
    bath_modes: int = 250
    samples_per_point: int = 0
    seed: int = 0
    resolution: int = 8
    row_resolution: tuple = ()
    kappa_seeds: tuple = ()

    def __post_init__(self):
        for name in LAW_ARRAYS:
            try:
                array = np.array(getattr(self, name), dtype=np.float64, order="C")
            except (TypeError, ValueError):
                raise InvalidParameterError(f"collision law {name} must be an array of numbers") from None
            if np.any(np.isnan(array)) or (name != "kappa" and not np.all(np.isfinite(array))):
                raise InvalidParameterError(f"collision law {name} must be finite")
            array.setflags(write=False)
            object.__setattr__(self, name, array)
        for name in ("kappa",) + _AXES:
            values = getattr(self, name)
            if values.ndim != 1 or values.size < 1 or np.any(np.diff(values) <= 0):
                raise InvalidParameterError(f"collision law {name} must be a strictly ascending 1-D array")
        if self.kappa[0] <= math.e or (np.isinf(self.kappa[-1]) and self.kappa.size != 1):
            raise InvalidParameterError("collision law kappa must be finite values > e, or the single value inf")
        if self.gamma[0] <= 0 or self.gamma[-1] > 1:
            raise InvalidParameterError("collision law gamma must lie in (0, 1]")
        if self.log_x[-1] != 0.0:
            raise InvalidParameterError("collision law log_x must end at 0 (cold baths)")
        share = self.short_share
        if not (share.size == 1 and share[0] == 0.5) and not (share.size >= 2 and share[0] == 0 and share[-1] == 1):
            raise InvalidParameterError("collision law short_share must run from 0 to 1, or be the single value 0.5")
        if self.probability.size < 2 or self.probability[0] != 0 or self.probability[-1] != 1:
            raise InvalidParameterError("collision law probability must run from 0 to 1 with >= 2 levels")
        shape = self.shape
        for name in ("eps2_quantiles", "gain_short"):
            if getattr(self, name).shape != shape:
                raise InvalidParameterError(f"collision law {name} must have shape {shape}")
        if np.any(self.eps2_quantiles < 0) or np.any(np.diff(self.eps2_quantiles, axis=-1) < 0):
            raise InvalidParameterError("collision law eps2_quantiles must be >= 0 and non-decreasing")
        for name in ("bath_modes", "samples_per_point", "seed", "resolution"):
            value = getattr(self, name)
            object.__setattr__(self, name, require_integer(f"collision law {name}", value, 0))
        seeds = tuple(self.kappa_seeds)
        if seeds and (len(seeds) != self.kappa.size or not all(_is_count(v) or v == 0 for v in seeds)):
            raise InvalidParameterError(f"collision law kappa_seeds must hold {self.kappa.size} integers >= 0 "
                                        "(one per kappa row), or be empty")
        object.__setattr__(self, "kappa_seeds", tuple(int(v) for v in seeds))
        object.__setattr__(self, "row_resolution", _checked_row_resolution(self.row_resolution, self.gamma.size,
                                                                           self.log_x.size))

    def point_resolution(self, gamma_index, log_x_index) -> int:
        """Grid points per period the hard-core solve used at row ``(gamma_index, log_x_index)``."""
        rows = self.row_resolution
        if not rows:
            return self.resolution
        return rows[gamma_index][log_x_index] if isinstance(rows[0], tuple) else rows[log_x_index]

    def equal_temperature_slice(self) -> CollisionLaw:
        """The law restricted to its ``short_share = 1/2`` slice: both rods at the pair's mean
        temperature (the one-temperature law of earlier versions), for comparisons."""
        if 0.5 not in self.short_share:
            raise InvalidParameterError("this collision law has no short_share = 0.5 slice")
        middle = list(self.short_share).index(0.5)
        return replace(self, short_share=[0.5], eps2_quantiles=self.eps2_quantiles[:, :, :, middle:middle + 1],
                       gain_short=self.gain_short[:, :, :, middle:middle + 1])

    @property
    def shape(self):
        return (self.kappa.size, self.gamma.size, self.log_x.size, self.short_share.size, self.probability.size)

    @property
    def hard_core(self) -> bool:
        return bool(np.isinf(self.kappa[-1]))

    def arrays(self):
        """``(kappa, gamma, log_x, short_share, probability, eps2_quantiles, gain_short)``, C-contiguous float64."""
        return tuple(np.ascontiguousarray(getattr(self, name)) for name in LAW_ARRAYS)

    def kernel_arrays(self):
        """``(z, log_x, short_share, probability, eps2_quantiles, gain_short)`` for the gas kernel, with
        ``z = ln(kappa)/kappa`` per row (:func:`kappa_variable`)."""
        z = np.array([kappa_variable(k) for k in self.kappa])
        return (z,) + tuple(np.ascontiguousarray(getattr(self, name))
                            for name in ("log_x", "short_share", "probability", "eps2_quantiles", "gain_short"))

    def _weights(self, gamma, x, short_share):
        g = float(gamma)
        if not self.gamma[0] <= g <= self.gamma[-1]:
            raise InvalidParameterError(f"gamma must lie in [{self.gamma[0]:g}, {self.gamma[-1]:g}], got {g:g}")
        if not 0.0 < x <= 1.0:
            raise InvalidParameterError(f"x = E_tr/(E_tr + T_pair) must lie in (0, 1], got {x!r}")
        if not 0.0 <= short_share <= 1.0:
            raise InvalidParameterError(f"short_share = T_s/(T_s + T_l) must lie in [0, 1], got {short_share!r}")
        lx = max(math.log10(x), self.log_x[0])
        values = []
        for grid, v in ((self.gamma, g), (self.log_x, lx), (self.short_share, float(short_share))):
            i = int(np.clip(np.searchsorted(grid, v, side="right") - 1, 0, max(grid.size - 2, 0)))
            w = 0.0 if grid.size == 1 else (v - grid[i]) / (grid[i + 1] - grid[i])
            values.append((i, w))
        return values

    def draw(self, gamma, x, u, short_share=0.5, row=0, arrays=None):
        """``(epsilon^2, gain_short)`` at level ``u`` for a pair at ``(gamma, x, s)``, kappa row ``row``.

        Linear in the level, trilinear in ``(gamma, log10 x, s)``; a plain-Python statement of what the gas
        kernel computes.  ``arrays``: another pair of arrays on this law's grid to evaluate instead (the
        soft law's corrections, :func:`soft_corrections`).
        """
        (ig, wg), (ix, wx), (i_s, ws) = self._weights(gamma, x, short_share)
        top = self.probability.size - 1
        k = min(int(u * top), top - 1) if np.array_equal(self.probability, np.linspace(0, 1, top + 1)) else \
            int(np.clip(np.searchsorted(self.probability, u, side="right") - 1, 0, top - 1))
        wu = min(max((u - self.probability[k]) / (self.probability[k + 1] - self.probability[k]), 0.0), 1.0)
        out = []
        for array in (self.eps2_quantiles[row], self.gain_short[row]) if arrays is None else (arrays[0][row],
                                                                                                arrays[1][row]):
            total = 0.0
            for dg, fg in ((0, 1 - wg), (1, wg)):
                for dx, fx in ((0, 1 - wx), (1, wx)):
                    for ds, fs in ((0, 1 - ws), (1, ws)):
                        a = array[min(ig + dg, self.gamma.size - 1), min(ix + dx, self.log_x.size - 1),
                                  min(i_s + ds, self.short_share.size - 1)]
                        total += fg * fx * fs * ((1 - wu) * a[k] + wu * a[k + 1])
            out.append(total)
        return out[0], out[1]

    def metadata(self) -> dict:
        regenerate = REGENERATE if self.hard_core else REGENERATE_SOFT
        return {"name": SCHEMA_NAME, "version": SCHEMA_VERSION,
                "kappa": ["inf" if math.isinf(k) else float(k) for k in self.kappa],
                "solver": "hard-core max-plus" if self.hard_core else "delay (finite kappa, energy split)",
                "bath_modes": self.bath_modes, "samples_per_point": self.samples_per_point, "seed": self.seed,
                "resolution": self.resolution,
                "row_resolution": [list(r) if isinstance(r, tuple) else r for r in self.row_resolution],
                "kappa_seeds": list(self.kappa_seeds),
                "units": "x = E_tr/(E_tr+T_pair), T_pair = (T_short+T_long)/2; short_share = T_short/(T_short+T_long); "
                         "eps2 = E'_tr/E_tr; gain_short in units of E_tr + T_pair",
                "regenerate": regenerate}

    def save(self, path):
        """Write ``.npz`` (arrays plus a JSON ``schema``; ``kappa`` as its finite rows, ``inf`` in the schema)."""
        path = Path(path)
        if path.suffix.lower() != ".npz":
            raise InvalidParameterError(f"collision law path must end in .npz, got {path.name!r}")
        arrays = {name: getattr(self, name) for name in LAW_ARRAYS if name != "kappa"}
        schema = np.array(json.dumps(self.metadata()))
        atomic_write(path, lambda handle: np.savez(handle, schema=schema, **arrays))
        return path


def _is_count(value):
    return not isinstance(value, bool) and isinstance(value, (int, float, np.integer, np.floating)) \
        and int(value) == value and value >= 1


def _checked_row_resolution(rows, gammas, log_xs):
    """``row_resolution`` as a tuple of ints (per ``log_x`` row) or of tuples (per ``gamma`` row), or ``()``."""
    rows = tuple(tuple(r) if isinstance(r, (list, tuple, np.ndarray)) else r for r in rows)
    if not rows:
        return ()
    if all(_is_count(r) for r in rows) and len(rows) == log_xs:
        return tuple(int(r) for r in rows)
    if len(rows) == gammas and all(isinstance(r, tuple) and len(r) == log_xs and all(_is_count(v) for v in r)
                                   for r in rows):
        return tuple(tuple(int(v) for v in r) for r in rows)
    raise InvalidParameterError(f"collision law row_resolution must hold {log_xs} integers >= 1 (one per log_x "
                                f"row), or {gammas} such rows (one per gamma), or be empty")


def law_from_arrays(arrays: dict, meta: dict, where="collision law") -> CollisionLaw:
    """Rebuild a :class:`CollisionLaw` from its arrays (without ``kappa``) and :meth:`CollisionLaw.metadata`."""
    if meta.get("name") != SCHEMA_NAME or meta.get("version") != SCHEMA_VERSION:
        raise InvalidParameterError(f"{where} is not a {SCHEMA_NAME} v{SCHEMA_VERSION} file")
    missing = [name for name in LAW_ARRAYS if name != "kappa" and name not in arrays]
    if missing:
        raise InvalidParameterError(f"{where} lacks the array(s) {', '.join(missing)}")
    kappa = [math.inf if k == "inf" else float(k) for k in meta["kappa"]]
    return CollisionLaw(kappa, *(arrays[name] for name in LAW_ARRAYS[1:]), bath_modes=meta["bath_modes"],
                        samples_per_point=meta["samples_per_point"], seed=meta["seed"],
                        resolution=meta.get("resolution", 8), row_resolution=meta.get("row_resolution", ()),
                        kappa_seeds=tuple(meta.get("kappa_seeds", ())))


def load_law(path) -> CollisionLaw:
    """Read a :class:`CollisionLaw` written by :meth:`CollisionLaw.save` (``allow_pickle=False``)."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            document = {name: data[name] for name in data.files}
        meta = json.loads(str(document.pop("schema")))
    except (ValueError, OSError, KeyError, json.JSONDecodeError) as exc:
        raise InvalidParameterError(f"{path.name}: not a readable collision law ({exc})") from None
    return law_from_arrays(document, meta, path.name)


def _shipped(name) -> CollisionLaw:
    with resources.as_file(resources.files("wavecontact") / "data" / name) as path:
        return load_law(path)


def default_law() -> CollisionLaw:
    """The hard-core law shipped with the package (see :data:`REGENERATE`)."""
    return _shipped(DEFAULT_LAW_FILE)


def default_soft_law() -> CollisionLaw:
    """The finite-kappa law shipped with the package (see :data:`REGENERATE_SOFT`)."""
    return _shipped(DEFAULT_SOFT_LAW_FILE)


def soft_corrections(hard: CollisionLaw, soft: CollisionLaw):
    """What softness changes: the soft law's ``(eps2, gain)`` quantile rows minus the hard-core law's at the soft
    law's grid points and levels, arrays of the soft law's shape.

    The gas adds these (interpolated on the soft law's coarse grid) to the hard-core draw on its fine grid,
    so the strong dependence on ``(gamma, x, s)`` that both laws share comes from the fine grid and only the
    change with ``kappa`` from the coarse one.
    """
    d_eps, d_gain = np.empty(soft.shape), np.empty(soft.shape)
    for g, gamma in enumerate(soft.gamma):
        for b, log_x in enumerate(soft.log_x):
            for c, share in enumerate(soft.short_share):
                for p, u in enumerate(soft.probability):
                    e_hard, g_hard = hard.draw(gamma, 10.0**log_x, u, share)
                    d_eps[:, g, b, c, p] = soft.eps2_quantiles[:, g, b, c, p] - e_hard
                    d_gain[:, g, b, c, p] = soft.gain_short[:, g, b, c, p] - g_hard
    return d_eps, d_gain


def blend_draw(hard: CollisionLaw, soft: CollisionLaw, gamma, x, u, short_share, kappa, corrections=None):
    """``(epsilon^2, gain_short, softer)`` at softness ``kappa``: the plain-Python form of the gas kernel's draw.

    The hard-core draw plus the soft law's correction (:func:`soft_corrections`), interpolated linearly in
    ``z = ln(kappa)/kappa`` (:func:`kappa_variable`) between the soft rows and, above the stiffest, between
    it and zero (the hard core, ``z = 0``).  Below the softest row that row's correction is used and
    ``softer`` is True (the gas counts these draws).  ``epsilon^2`` is floored at 0.
    """
    corrections = soft_corrections(hard, soft) if corrections is None else corrections
    e_hard, g_hard = hard.draw(gamma, x, u, short_share)
    z = kappa_variable(kappa)
    rows = [kappa_variable(k) for k in soft.kappa]
    softer = False
    if kappa <= soft.kappa[0]:
        weights = {0: 1.0}
        softer = kappa < soft.kappa[0]
    elif z <= rows[-1]:
        weights = {len(rows) - 1: z / rows[-1]}
    else:
        r = max(i for i in range(len(rows)) if rows[i] >= z)
        w = (rows[r] - z) / (rows[r] - rows[r + 1])
        weights = {r: 1.0 - w, r + 1: w}
    d_eps = d_gain = 0.0
    for r, w in weights.items():
        e, g = soft.draw(gamma, x, u, short_share, r, arrays=corrections)
        d_eps += w * e
        d_gain += w * g
    return max(e_hard + d_eps, 0.0), g_hard + d_gain, softer


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


def pair_temperatures(log_x, short_share):
    """``(T_short, T_long) / E_tr`` of a pair at ``x = 10^log_x`` and ``s = short_share`` (mean ``(1 - x)/x``)."""
    x = 10.0**log_x
    mean = (1.0 - x) / x
    return 2.0 * short_share * mean, 2.0 * (1.0 - short_share) * mean


def solve_collision(gamma, kappa, temperatures, seed, modes, resolution):
    """``(eps2, short rod's gain in units of E_tr)`` of one collision, each rod at its own temperature.

    ``kappa = inf``: the hard-core split (:func:`wavecontact.gas.hardcore_collision.hard_core_collision`,
    ``resolution`` grid points per period); finite: :func:`wavecontact.collide` with the delay solver and its
    per-rod energy split.  ``temperatures = (T_short, T_long) / E_tr``; ``modes`` bath modes per rod.
    """
    if math.isinf(kappa):
        from .hardcore_collision import hard_core_collision

        eps2, gain_1, _gain_2 = hard_core_collision(gamma, 0.0, seed, bath_modes=modes, resolution=resolution,
                                                    temperatures=temperatures)
        return eps2, gain_1
    from ..api import collide

    cold = temperatures[0] == 0.0 and temperatures[1] == 0.0
    result = collide(gamma, kappa, "delay", bath_temperature=None if cold else temperatures, bath_modes=modes,
                     seed=seed, energy_split=True)
    gain = result.extra["vibration_energy_gain"]
    return float(result.restitution) ** 2, 4.0 * float(gain[0])  # the delay solver's energies have E_tr = 1/4


def _point(task):
    gamma, kappa, log_x, share, seeds, modes, resolution = task
    temperatures = pair_temperatures(log_x, share)
    samples = np.array([solve_collision(gamma, kappa, temperatures, s, modes, resolution) for s in seeds])
    return samples[:, 0], samples[:, 1] * 10.0**log_x  # eps2; short rod's gain in units of E_tr + T_pair


def point_samples(gamma, log_x, samples, seed, *, bath_modes=250, resolution=8, short_share=0.5, kappa=math.inf):
    """``(eps2, gain_short)`` of ``samples`` collisions at one grid point (seeds spawned from ``seed``).

    ``gain_short`` in units of ``E_tr + T_pair``; ``kappa = inf`` the hard core, else the finite-kappa delay solve.
    """
    seeds = np.random.SeedSequence(seed).spawn(int(samples)) if not isinstance(seed, np.random.SeedSequence) \
        else seed.spawn(int(samples))
    return _point((float(gamma), float(kappa), float(log_x), float(short_share), seeds, bath_modes, resolution))


def row_resolutions(log_xs, resolution, cap=None):
    """Grid points per period of the hard-core solve for each ``log10 x`` row.

    ``cap=None``: ``resolution`` for every row.  Otherwise ``min(cap, ceil(resolution * sqrt(1/x)))``:
    the max-plus grid's error is first order in the step and grows with the noise amplitude, about
    ``sqrt(T_B/E_tr)``, and ``1 + T_B/E_tr = 1/x``, so the rule keeps the step times the noise amplitude
    roughly fixed until the cap (docs/gas.md, "Grid error of the law").
    """
    log_xs = np.asarray(log_xs, float)
    if cap is None:
        return tuple(int(resolution) for _ in log_xs)
    require_integer("resolution cap", cap, resolution, allowed=f"an integer >= resolution ({resolution})")
    return tuple(int(min(int(cap), math.ceil(resolution * 10.0 ** (-lx / 2) - 1e-9))) for lx in log_xs)


def _caps_per_gamma(resolution_cap, gammas, resolution):
    """``None`` (fixed resolution), one cap for every ``gamma``, or one per ``gamma`` (a tuple of them)."""
    if resolution_cap is None:
        return None
    if isinstance(resolution_cap, (list, tuple, np.ndarray)):
        caps = tuple(resolution_cap)
        if len(caps) == 1:
            return caps * gammas.size
        if len(caps) != gammas.size:
            raise InvalidParameterError(f"give one resolution cap, or one per gamma ({gammas.size}), "
                                        f"got {len(caps)}")
        return caps
    return (resolution_cap,) * gammas.size


def _reusable(old, kappas, gammas, log_xs, shares, probability, samples, seed, bath_modes):
    """True when ``old`` was built on this grid with these seeds, so its points equal a fresh solve's."""
    if old is None:
        return False
    same_grid = all(a.shape == b.shape and np.array_equal(a, b) for a, b in
                    ((old.kappa, kappas), (old.gamma, gammas), (old.log_x, log_xs), (old.short_share, shares),
                     (old.probability, probability)))
    return same_grid and (old.samples_per_point, old.seed, old.bath_modes) == (int(samples), int(seed),
                                                                                 int(bath_modes))


@dataclass(frozen=True)
class LawGrid:
    """The points of a collision law to build: every ``(kappa, gamma, log10 x, s)`` of these axes.

    Parameters
    ----------
    gammas : sequence of float
        Length ratios in (0, 1].
    log_xs : sequence of float
        ``log10 x``, ``x = E_tr / (E_tr + T_pair)`` (0: cold).
    kappas : sequence of float
        Contact softness rows (``inf``: the hard core).
    short_shares : sequence of float
        The short rod's share ``s = T_s / (T_s + T_l)`` of the bath temperature.
    """

    gammas: tuple
    log_xs: tuple
    kappas: tuple = (math.inf,)
    short_shares: tuple = (0.5,)


def build_collision_law(grid: LawGrid, samples, seed, *, levels=41, bath_modes=250, resolution=8, resolution_cap=None,
                        executor=None, reuse=None, progress=None):
    """Tabulate the collision law (one ensemble per ``(kappa, gamma, log10 x, s)`` point of ``grid``).

    Point ``a`` (row-major over ``kappas`` x ``gammas`` x ``log_xs`` x ``short_shares``) uses child ``a`` of
    ``SeedSequence(seed).spawn(points)``, and its sample ``i`` child ``i`` of that.  Cold points (``x = 1``)
    are deterministic; they are solved like the others.  ``resolution_cap``: grid points per period grow
    with ``sqrt(1/x)`` up to the cap (:func:`row_resolutions`, stored per row); one cap, or a sequence with
    one per ``gamma`` (stored per ``gamma`` and row); ``None`` keeps ``resolution`` everywhere.

    ``reuse``: a law built earlier on the same grid with the same ``seed``, ``samples``, levels and
    ``bath_modes``: its points whose resolution equals the new one's are copied instead of solved (the same
    seeds at the same resolution give the same solves, so the result equals a full build; a law on another
    grid or seed is not used).  ``progress``: called with ``(points done, points to solve)``.
    """
    kappas, gammas, log_xs, shares = (np.asarray(a, float) for a in (grid.kappas, grid.gammas, grid.log_xs,
                                                                     grid.short_shares))
    caps = _caps_per_gamma(resolution_cap, gammas, resolution)
    per_point = {(g, lx): r for g, cap in zip(gammas.tolist(), caps or (None,) * gammas.size)
                 for lx, r in zip(log_xs.tolist(), row_resolutions(log_xs, resolution, cap))}
    total = kappas.size * gammas.size * log_xs.size * shares.size * int(samples)
    if total > MAX_LAW_SAMPLES:
        raise InvalidParameterError(f"a collision law may hold at most {MAX_LAW_SAMPLES} collisions in all")
    if np.any(np.isfinite(kappas)) and total > MAX_SOFT_KAPPA_SAMPLES:
        raise InvalidParameterError(f"a finite-kappa law may hold at most {MAX_SOFT_KAPPA_SAMPLES} collisions "
                                    "in all (each is a delay solve of 10 ms to 1 s)")
    levels = require_integer("levels", levels, 2, int(samples), allowed="an integer in [2, samples]")
    probability = np.linspace(0.0, 1.0, int(levels))
    shape = (kappas.size, gammas.size, log_xs.size, shares.size, probability.size)
    quantiles, gains = np.empty(shape), np.empty(shape)
    reusable = _reusable(reuse, kappas, gammas, log_xs, shares, probability, samples, seed, bath_modes)
    points = [(k, g, lx, s) for k in kappas for g in gammas for lx in log_xs for s in shares]
    children = np.random.SeedSequence(int(seed)).spawn(len(points))
    tasks = {}
    for a, ((k, g, lx, s), child) in enumerate(zip(points, children)):
        index = np.unravel_index(a, shape[:4])
        r = per_point[(g, lx)]
        if reusable and reuse.point_resolution(index[1], index[2]) == r:
            quantiles[index], gains[index] = reuse.eps2_quantiles[index], reuse.gain_short[index]
        else:
            tasks[a] = (float(g), float(k), float(lx), float(s), child.spawn(int(samples)), int(bath_modes), r)
    # dearest first (finer grids and warmer rows take longer), so two workers finish together
    order = sorted(tasks, key=lambda a: -tasks[a][6] * 10.0 ** (-tasks[a][2] / 2))
    mapped = executor.map(_point, [tasks[a] for a in order]) if executor is not None else \
        (_point(tasks[a]) for a in order)
    for done, (a, (eps2, gain)) in enumerate(zip(order, mapped), start=1):
        index = np.unravel_index(a, shape[:4])
        quantiles[index] = np.quantile(eps2, probability)
        gains[index] = level_means(eps2, gain, probability)
        if progress is not None:
            progress(done, len(order))
    if caps is None:
        rows = ()
    elif len(set(caps)) == 1:
        rows = tuple(per_point[(gammas[0], lx)] for lx in log_xs.tolist())
    else:
        rows = tuple(tuple(per_point[(g, lx)] for lx in log_xs.tolist()) for g in gammas.tolist())
    return CollisionLaw(kappas, gammas, log_xs, shares, probability, quantiles, gains, bath_modes=int(bath_modes),
                        samples_per_point=int(samples), seed=int(seed), resolution=int(resolution),
                        row_resolution=rows)


def merge_kappa_rows(laws) -> CollisionLaw:
    """One finite-kappa law from several built on the same ``(gamma, log10 x, s)`` grid, levels, sample count and
    bath, each with its own kappa rows and seed: the rows sorted by kappa, each row's seed kept
    (``kappa_seeds``).  Lets a soft law gain rows without re-solving the ones it has."""
    laws = list(laws)
    if len(laws) < 2:
        raise InvalidParameterError("merge needs at least two collision laws")
    first = laws[0]
    for law in laws:
        if law.hard_core:
            raise InvalidParameterError("only finite-kappa (soft) laws are merged along kappa")
        same = all(np.array_equal(getattr(law, name), getattr(first, name))
                   and getattr(law, name).shape == getattr(first, name).shape for name in _AXES)
        if not same or (law.samples_per_point, law.bath_modes) != (first.samples_per_point, first.bath_modes):
            raise InvalidParameterError("merged collision laws must share their gamma, log_x, short_share and "
                                        "probability grids, samples per point and bath modes")
    kappa = np.concatenate([law.kappa for law in laws])
    if np.unique(kappa).size != kappa.size:
        raise InvalidParameterError("merged collision laws must have distinct kappa rows")
    seeds = np.concatenate([law.kappa_seeds if law.kappa_seeds else [law.seed] * law.kappa.size for law in laws])
    order = np.argsort(kappa)
    stack = {name: np.concatenate([getattr(law, name) for law in laws])[order]
             for name in ("eps2_quantiles", "gain_short")}
    return CollisionLaw(kappa[order], first.gamma, first.log_x, first.short_share, first.probability,
                        stack["eps2_quantiles"], stack["gain_short"], bath_modes=first.bath_modes,
                        samples_per_point=first.samples_per_point, seed=int(seeds[order][0]),
                        resolution=first.resolution, kappa_seeds=tuple(int(v) for v in seeds[order]))


def parser():
    """The builder's command line (``python -m wavecontact.gas.collision_law``; :data:`REGENERATE`)."""
    import argparse

    p = argparse.ArgumentParser(prog="python -m wavecontact.gas.collision_law",
                                description="Tabulate the collision law of the gas's vibration rule.")
    p.add_argument("--kappa", type=float, nargs="+", default=[math.inf],
                   help="contact softness rows: inf (hard core, default) or finite values > e")
    p.add_argument("--merge", nargs="+", default=None, metavar="LAW",
                   help="instead of building: merge soft laws (same grid) along kappa into --out")
    p.add_argument("--gamma", type=float, nargs="+")
    p.add_argument("--log-x", type=float, nargs="+", help="log10 E_tr/(E_tr+T_pair), ascending or not")
    p.add_argument("--share", type=float, nargs="+", default=[0.5],
                   help="short rod's share T_s/(T_s+T_l) of the bath temperature (0 ... 1, or 0.5 alone)")
    p.add_argument("--samples", type=int)
    p.add_argument("--levels", type=int, default=41)
    p.add_argument("--seed", type=int)
    p.add_argument("--bath-modes", type=int, default=250)
    p.add_argument("--resolution", type=int, default=8, help="grid points per period (hard core only)")
    p.add_argument("--resolution-cap", type=int, nargs="+", default=None,
                   help="grow the resolution like sqrt(1/x) per log_x row up to this cap; one cap, or one per "
                        "gamma (default: fixed)")
    p.add_argument("--reuse", default=None,
                   help="a law built before on the same grid and seed: copy its points at the same resolution")
    p.add_argument("--workers", type=int, default=1)
    p.add_argument("--out", required=True)
    return p


def main(argv=None):
    import sys
    import time
    from concurrent.futures import ProcessPoolExecutor

    p = parser()
    args = p.parse_args(argv)
    if args.merge is not None:
        merge_kappa_rows([load_law(path) for path in args.merge]).save(args.out)
        print(f"wrote {args.out} (kappa rows of {', '.join(args.merge)})")
        return
    missing = [name for name in ("gamma", "log_x", "samples", "seed") if getattr(args, name) is None]
    if missing:
        p.error("building a law needs " + ", ".join("--" + name.replace("_", "-") for name in missing))
    start, cpu = time.perf_counter(), time.process_time()
    options = {"levels": args.levels, "bath_modes": args.bath_modes, "resolution": args.resolution,
               "resolution_cap": args.resolution_cap}
    grid = LawGrid(args.gamma, sorted(args.log_x), sorted(args.kappa), sorted(args.share))
    if args.reuse is not None:
        options["reuse"] = load_law(args.reuse)

    def progress(done, todo):
        if done == todo or done % max(1, todo // 40) == 0:
            print(f"{done}/{todo} points solved, {time.perf_counter() - start:.0f} s", file=sys.stderr, flush=True)

    options["progress"] = progress
    if args.workers > 1:
        with ProcessPoolExecutor(args.workers) as pool:
            law = build_collision_law(grid, args.samples, args.seed, executor=pool, **options)
    else:
        law = build_collision_law(grid, args.samples, args.seed, **options)
    law.save(args.out)
    import resource

    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    print(f"wrote {args.out} ({Path(args.out).stat().st_size / 1e3:.0f} kB) in {time.perf_counter() - start:.0f} s "
          f"wall, {time.process_time() - cpu + children.ru_utime + children.ru_stime:.0f} s CPU")


if __name__ == "__main__":
    main()
