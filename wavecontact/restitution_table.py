"""Tabulated law of the stochastic restitution, for collision rules of many-particle codes.

A :class:`RestitutionTable` holds, on a grid of length ratios ``gamma`` and
bath temperature ratios ``T_B / E_tr``, the quantile function of
``epsilon^2`` (the fraction of the pair's translational energy that survives
a collision), the split of the lost energy between the two rods' vibrations
that conserves energy on average (``rod1_share``, what the gas's collision rule
uses) and, for tables computed from ensembles, each rod's mean vibrational
energy gain with its standard error (``rod_gain``, ``rod_gain_standard_error``).  Tables are produced from ensembles of stochastic
collisions (the thermal-bath study) and consumed by event-driven gases
(:mod:`wavecontact.gas`), which draw ``epsilon^2`` by inverse-transform
sampling.

Interpolation is linear in the probability level and bilinear in
``(gamma, temperature_ratio)`` *between quantile functions*: the quantile at
level ``u`` of an off-grid point is the bilinear mix of the four corner
quantiles at ``u``.  The result is again a non-decreasing quantile function,
so sampling stays exact for grid points and monotone in ``u`` everywhere.

Files: ``.npz`` (arrays plus a JSON ``schema`` string; loaded with
``allow_pickle=False``), ``.json`` (lists) and ``.csv`` (long format,
written only: it does not carry ``rod1_share`` nor the gains).
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import InvalidParameterError, require_integer
from .io.files import atomic_write

__all__ = ["SCHEMA_NAME", "SCHEMA_VERSION", "RestitutionTable", "load"]

SCHEMA_NAME = "wavecontact.restitution_table"
SCHEMA_VERSION = 1

_ARRAYS = ("gamma", "temperature_ratio", "probability", "eps2_quantiles", "rod1_share")
_COLUMNS = {
    "gamma": "length ratio l1/l2 of the pair, l1 <= l2 (dimensionless, in (0, 1])",
    "temperature_ratio": "bath temperature over the pair's translational energy T_B/E_tr (dimensionless, >= 0)",
    "probability": "probability level u of the quantile function (dimensionless, in [0, 1])",
    "eps2_quantile": "epsilon^2 below which a fraction u of collisions lies (dimensionless, >= 0)",
    "rod1_share": "sum of rod 1's (the short rod's) vibrational gains over the sum of both rods' gains, per "
    "(gamma, temperature_ratio) (dimensionless; the split of the lost energy that conserves energy on average; "
    "outside [0, 1] where a bath gives energy back on balance, as near T_B/E_tr = 1)",
    "rod_gain": "optional, shape (G, R, 2): each rod's mean vibrational energy gain per collision, in units of E_tr "
    "(negative where its bath gives energy back)",
    "rod_gain_standard_error": "optional, shape (G, R, 2): the standard error of rod_gain (units of E_tr)",
}
_OPTIONAL = ("rod_gain", "rod_gain_standard_error")


def _ascending(name, values, *, strict=True):
    if values.ndim != 1 or values.size == 0:
        raise InvalidParameterError(f"restitution table {name} must be a non-empty 1-D array, got shape {values.shape}")
    if not np.all(np.isfinite(values)):
        raise InvalidParameterError(f"restitution table {name} must be finite")
    steps = np.diff(values)
    if np.any(steps <= 0) if strict else np.any(steps < 0):
        raise InvalidParameterError(f"restitution table {name} must be strictly ascending")


@dataclass(frozen=True)
class RestitutionTable:
    """Quantile functions of ``epsilon^2`` on a ``(gamma, T_B/E_tr)`` grid.

    Parameters
    ----------
    gamma : array_like, shape (G,)
        Length ratios ``l1/l2``, strictly ascending in (0, 1].
    temperature_ratio : array_like, shape (R,)
        Bath temperature over the pair's translational energy ``T_B/E_tr``
        (both in the same energy unit), strictly ascending, >= 0.
    probability : array_like, shape (P,)
        Probability levels, strictly ascending, first 0 and last 1, P >= 2.
    eps2_quantiles : array_like, shape (G, R, P)
        ``eps2_quantiles[g, r, k]`` is the ``probability[k]`` quantile of
        ``epsilon^2`` (dimensionless, finite, >= 0, non-decreasing in k).
    rod1_share : array_like, shape (G, R)
        ``sum Delta E_1 / sum (Delta E_1 + Delta E_2)`` over the collisions of a point: the
        split of the lost translational energy between rod 1's (the short rod's) and rod 2's
        vibrations that conserves energy on average, finite. It is a fraction in [0, 1] only
        where both rods gain on balance (always for a cold bath); where a bath gives energy
        back (``T_B > 0``) the denominator may be near zero or negative: read ``rod_gain``.
    kappa : float
        Hardness ``alpha V l / c`` the table was computed at (``inf``: hard core).
    bath_modes : int
        Modes per rod of the bath (>= 1).
    samples_per_point : int
        Collisions behind each quantile function (>= 0; 0 for analytic tables).
    solver : str
        Name of the solver (or model) that produced the samples.
    seed : int
        Root seed of the ensemble (>= 0).
    rod_gain : array_like, shape (G, R, 2), optional
        Each rod's mean vibrational energy gain per collision, in units of ``E_tr``
        (None: not recorded, as for analytic tables).
    rod_gain_standard_error : array_like, shape (G, R, 2), optional
        Standard error of ``rod_gain`` (units of ``E_tr``); given with ``rod_gain``.
    """

    gamma: np.ndarray
    temperature_ratio: np.ndarray
    probability: np.ndarray
    eps2_quantiles: np.ndarray
    rod1_share: np.ndarray
    kappa: float = math.inf
    bath_modes: int = 250
    samples_per_point: int = 0
    solver: str = "unknown"
    seed: int = 0
    rod_gain: np.ndarray | None = None
    rod_gain_standard_error: np.ndarray | None = None

    def __post_init__(self):
        values = {}
        for name in _ARRAYS:
            try:
                array = np.array(getattr(self, name), dtype=np.float64, order="C")
            except (TypeError, ValueError):
                raise InvalidParameterError(f"restitution table {name} must be an array of numbers") from None
            array.setflags(write=False)
            values[name] = array
        gamma, ratio, prob = values["gamma"], values["temperature_ratio"], values["probability"]
        _ascending("gamma", gamma)
        if gamma[0] <= 0.0 or gamma[-1] > 1.0:
            raise InvalidParameterError("restitution table gamma must lie in (0, 1]")
        _ascending("temperature_ratio", ratio)
        if ratio[0] < 0.0:
            raise InvalidParameterError("restitution table temperature_ratio must be >= 0")
        _ascending("probability", prob)
        if prob.size < 2 or prob[0] != 0.0 or prob[-1] != 1.0:
            raise InvalidParameterError("restitution table probability must start at 0, end at 1 and have >= 2 levels")
        shape = (gamma.size, ratio.size, prob.size)
        quantiles = values["eps2_quantiles"]
        if quantiles.shape != shape:
            raise InvalidParameterError(f"restitution table eps2_quantiles must have shape {shape}, got {quantiles.shape}")
        if not np.all(np.isfinite(quantiles)) or np.any(quantiles < 0.0):
            raise InvalidParameterError("restitution table eps2_quantiles must be finite and >= 0")
        if np.any(np.diff(quantiles, axis=-1) < 0.0):
            raise InvalidParameterError("restitution table eps2_quantiles must be non-decreasing in probability")
        share = values["rod1_share"]
        if share.shape != shape[:2]:
            raise InvalidParameterError(f"restitution table rod1_share must have shape {shape[:2]}, got {share.shape}")
        if not np.all(np.isfinite(share)):
            raise InvalidParameterError("restitution table rod1_share must be finite")
        if (self.rod_gain is None) != (self.rod_gain_standard_error is None):
            raise InvalidParameterError("restitution table rod_gain and rod_gain_standard_error go together")
        if self.rod_gain is not None:
            for name in _OPTIONAL:
                array = np.array(getattr(self, name), dtype=np.float64, order="C")
                if array.shape != shape[:2] + (2,) or not np.all(np.isfinite(array)):
                    raise InvalidParameterError(f"restitution table {name} must be finite with shape {shape[:2] + (2,)}, "
                                                f"got {array.shape}")
                array.setflags(write=False)
                values[name] = array
            if np.any(values["rod_gain_standard_error"] < 0.0):
                raise InvalidParameterError("restitution table rod_gain_standard_error must be >= 0")
        for name, array in values.items():
            object.__setattr__(self, name, array)
        kappa = float(self.kappa)
        if math.isnan(kappa) or kappa <= 0.0:
            raise InvalidParameterError(f"restitution table kappa must lie in (0, inf], got {self.kappa!r}")
        object.__setattr__(self, "kappa", kappa)
        for name, low in (("bath_modes", 1), ("samples_per_point", 0), ("seed", 0)):
            number = getattr(self, name)
            object.__setattr__(self, name, require_integer(f"restitution table {name}", number, low))
        object.__setattr__(self, "solver", str(self.solver))

    # ------------------------------------------------------------------ lookup
    def _corners(self, gamma, temperature_ratio):
        """Grid indices and weights of the bilinear mix; refuses points off the grid."""
        g = np.asarray(gamma, dtype=float)
        r = np.asarray(temperature_ratio, dtype=float)
        for name, values, grid in (("gamma", g, self.gamma), ("temperature_ratio", r, self.temperature_ratio)):
            if not np.all(np.isfinite(values)) or np.any(values < grid[0]) or np.any(values > grid[-1]):
                raise InvalidParameterError(
                    f"{name} must lie in the table's range [{grid[0]:g}, {grid[-1]:g}], got {values.min():g}..{values.max():g}"
                )
        ig, wg = _bracket(self.gamma, g)
        ir, wr = _bracket(self.temperature_ratio, r)
        return ig, wg, ir, wr

    def quantile(self, gamma, temperature_ratio, probability):
        """``epsilon^2`` at the probability levels ``probability`` (broadcast with the point).

        Parameters
        ----------
        gamma, temperature_ratio : float or array_like
            Point inside the grid (dimensionless).
        probability : float or array_like
            Levels in [0, 1].

        Returns
        -------
        ndarray
            The interpolated quantiles of ``epsilon^2`` (dimensionless).
        """
        u = np.asarray(probability, dtype=float)
        if not np.all((u >= 0.0) & (u <= 1.0)):
            raise InvalidParameterError("probability must lie in [0, 1]")
        ig, wg, ir, wr = self._corners(gamma, temperature_ratio)
        ig, wg, ir, wr, u = np.broadcast_arrays(ig, wg, ir, wr, u)
        k = np.clip(np.searchsorted(self.probability, u, side="right") - 1, 0, self.probability.size - 2)
        wu = (u - self.probability[k]) / (self.probability[k + 1] - self.probability[k])
        q = self.eps2_quantiles
        total = np.zeros(u.shape)
        for dg, fg in ((0, 1.0 - wg), (1, wg)):
            for dr, fr in ((0, 1.0 - wr), (1, wr)):
                gi = np.minimum(ig + dg, self.gamma.size - 1)
                ri = np.minimum(ir + dr, self.temperature_ratio.size - 1)
                corner = (1.0 - wu) * q[gi, ri, k] + wu * q[gi, ri, k + 1]
                total += fg * fr * corner
        return total

    def sample(self, rng, gamma, temperature_ratio, size=None):
        """Draw ``epsilon^2`` by inverse-transform sampling.

        Parameters
        ----------
        rng : numpy.random.Generator
            Source of the uniform levels (one per draw).
        gamma, temperature_ratio : float or array_like
            Point(s) inside the grid (dimensionless).
        size : int or tuple, optional
            Number of draws; default: the broadcast shape of the point.

        Returns
        -------
        float or ndarray
            ``epsilon^2`` (dimensionless).
        """
        if size is None:
            size = np.broadcast(np.asarray(gamma), np.asarray(temperature_ratio)).shape
        u = rng.random(size)
        out = self.quantile(gamma, temperature_ratio, u)
        return float(out) if np.ndim(out) == 0 else out

    def mean_eps2(self, gamma, temperature_ratio):
        """Mean of ``epsilon^2`` (the integral of the interpolated quantile function)."""
        levels = self.probability
        q = self.quantile(np.asarray(gamma)[..., None], np.asarray(temperature_ratio)[..., None], levels)
        out = np.sum(0.5 * (q[..., 1:] + q[..., :-1]) * np.diff(levels), axis=-1)
        return float(out) if np.ndim(out) == 0 else out

    def mean_restitution(self, gamma, temperature_ratio):
        """Mean of ``epsilon = sqrt(epsilon^2)``, exact for the piecewise-linear quantile function.

        For DEM codes that take one constant restitution per pair.
        """
        levels = self.probability
        q = self.quantile(np.asarray(gamma)[..., None], np.asarray(temperature_ratio)[..., None], levels)
        a, b = q[..., :-1], q[..., 1:]
        width = np.diff(levels)
        flat = np.abs(b - a) <= 1e-14 * np.maximum(1.0, np.abs(a))
        # int_0^1 sqrt(a + (b - a) s) ds = 2/3 (b^1.5 - a^1.5) / (b - a)
        with np.errstate(divide="ignore", invalid="ignore"):
            sloped = (2.0 / 3.0) * (b**1.5 - a**1.5) / (b - a)
        pieces = np.where(flat, np.sqrt(0.5 * (a + b)), sloped)
        out = np.sum(pieces * width, axis=-1)
        return float(out) if np.ndim(out) == 0 else out

    def share(self, gamma, temperature_ratio):
        """Bilinearly interpolated ``rod1_share`` at a point of the grid."""
        ig, wg, ir, wr = self._corners(gamma, temperature_ratio)
        s = self.rod1_share
        g1 = np.minimum(ig + 1, self.gamma.size - 1)
        r1 = np.minimum(ir + 1, self.temperature_ratio.size - 1)
        out = ((1 - wg) * ((1 - wr) * s[ig, ir] + wr * s[ig, r1]) + wg * ((1 - wr) * s[g1, ir] + wr * s[g1, r1]))
        return float(out) if np.ndim(out) == 0 else out

    def arrays(self):
        """``(gamma, temperature_ratio, probability, eps2_quantiles, rod1_share)`` as C-contiguous float64.

        The plain-array form that numba kernels take.
        """
        return tuple(np.ascontiguousarray(getattr(self, name)) for name in _ARRAYS)

    # --------------------------------------------------------------------- I/O
    def metadata(self) -> dict:
        """The scalar fields and the file schema, JSON-ready (``kappa = inf`` as the string ``"inf"``)."""
        return {
            "name": SCHEMA_NAME,
            "version": SCHEMA_VERSION,
            "columns": _COLUMNS,
            "units": "dimensionless: energies in the pair's translational energy E_tr, lengths as a ratio",
            "kappa": self.kappa if math.isfinite(self.kappa) else "inf",
            "bath_modes": self.bath_modes,
            "samples_per_point": self.samples_per_point,
            "solver": self.solver,
            "seed": self.seed,
        }

    def _write_csv(self, handle):
        handle.write(f"# {SCHEMA_NAME} v{SCHEMA_VERSION}; kappa={self.metadata()['kappa']}, "
                     f"bath_modes={self.bath_modes}, solver={self.solver}; all columns dimensionless\n")
        writer = csv.writer(handle)
        writer.writerow(["gamma", "temperature_ratio", "probability", "eps2_quantile"])
        for i, g in enumerate(self.gamma):
            for j, r in enumerate(self.temperature_ratio):
                for k, u in enumerate(self.probability):
                    writer.writerow([repr(float(g)), repr(float(r)), repr(float(u)),
                                     repr(float(self.eps2_quantiles[i, j, k]))])

    def save(self, path):
        """Write ``.npz``, ``.json`` or ``.csv`` (chosen by the suffix); returns the path."""
        path = Path(path)
        suffix = path.suffix.lower()
        names = _ARRAYS + (_OPTIONAL if self.rod_gain is not None else ())
        if suffix == ".npz":
            arrays = {name: getattr(self, name) for name in names}
            schema = np.array(json.dumps(self.metadata()))
            atomic_write(path, lambda handle: np.savez(handle, schema=schema, **arrays))
        elif suffix == ".json":
            document = dict(self.metadata(), **{name: getattr(self, name).tolist() for name in names})
            text = json.dumps(document, indent=1) + "\n"
            atomic_write(path, lambda handle: handle.write(text), binary=False)
        elif suffix == ".csv":
            atomic_write(path, self._write_csv, binary=False)
        else:
            raise InvalidParameterError(f"restitution table path must end in .npz, .json or .csv, got {path.name!r}")
        return path


def _bracket(grid, x):
    """Lower index and weight of ``x`` in ``grid`` (single-point grids give weight 0)."""
    if grid.size == 1:
        return np.zeros(np.shape(x), dtype=np.intp), np.zeros(np.shape(x))
    i = np.clip(np.searchsorted(grid, x, side="right") - 1, 0, grid.size - 2)
    w = (x - grid[i]) / (grid[i + 1] - grid[i])
    return i, w


def _from_document(document, source):
    meta = document.get("schema", document)
    if meta.get("name") != SCHEMA_NAME or meta.get("version") != SCHEMA_VERSION:
        raise InvalidParameterError(
            f"{source} is not a {SCHEMA_NAME} v{SCHEMA_VERSION} file (found {meta.get('name')!r} v{meta.get('version')!r})"
        )
    missing = [name for name in _ARRAYS if name not in document]
    if missing:
        raise InvalidParameterError(f"{source} lacks the array(s) {', '.join(missing)}")
    kappa = meta.get("kappa")
    try:
        return RestitutionTable(
            **{name: document[name] for name in _ARRAYS},
            **{name: document[name] for name in _OPTIONAL if name in document},
            kappa=math.inf if kappa == "inf" else kappa,
            bath_modes=meta.get("bath_modes"),
            samples_per_point=meta.get("samples_per_point"),
            solver=meta.get("solver"),
            seed=meta.get("seed"),
        )
    except InvalidParameterError as exc:
        raise InvalidParameterError(f"{source}: {exc}") from None
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(f"{source}: malformed restitution table ({exc})") from None


def load(path) -> RestitutionTable:
    """Read a table written by :meth:`RestitutionTable.save` (``.npz`` or ``.json``).

    Raises
    ------
    InvalidParameterError
        Wrong suffix, schema name or version, missing arrays, or arrays that fail validation.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".npz":
        try:
            with np.load(path, allow_pickle=False) as data:
                document = {name: data[name] for name in data.files}
                schema = json.loads(str(document.pop("schema"))) if "schema" in document else {}
        except (ValueError, OSError, json.JSONDecodeError) as exc:
            raise InvalidParameterError(f"{path.name}: not a readable restitution table ({exc})") from None
        document["schema"] = schema
    elif suffix == ".json":
        try:
            document = json.loads(path.read_text())
        except (OSError, json.JSONDecodeError) as exc:
            raise InvalidParameterError(f"{path.name}: not a readable restitution table ({exc})") from None
        if not isinstance(document, dict):
            raise InvalidParameterError(f"{path.name}: a restitution table JSON file holds one object")
    else:
        raise InvalidParameterError(f"restitution table path must end in .npz or .json, got {path.name!r}")
    return _from_document(document, path.name)


RestitutionTable.load = staticmethod(load)
