"""Many successive collisions of two rods on a ring (the paper's Sec. III).

Two rods start maximally far apart on a ring with a cold oscillator bath and
approach each other at relative speed ``V = 1``.  They collide again and
again (through either pair of facing ends) and the translational energy
``E_tr`` drains into the rods' vibrations until equipartition.  This module
runs that experiment on top of any object with the ring-simulation protocol
(``next_collision()``, ``get_state()``, ``set_state()``), records one row per
collision, checkpoints the run so that an interrupted run can be resumed to
the same result, and computes the statistics that the paper reports:

* ``E_tr`` before each collision against its equilibrium mean (Eq. 8) and
  the Boltzmann law of its fluctuations (Eq. 9, Kolmogorov-Smirnov test);
* relative modal energies ``w_i^nu = E_i^nu / E_bath`` and the normalised
  spectral entropy ``eta = 1 - h / ln(2N)`` (Eq. 10) against its
  equilibrium mean ``0.423 / ln(2N)`` (Eq. 11);
* the correlation ``C_eps(k)`` of successive restitution coefficients in the
  stationary state (Eq. 13).

Units are those of :func:`wavecontact.scene.two_rods`: ``rho = c = A = 1``,
effective length ``l = 1``, approach speed ``V = 1``, reduced mass
``mu = 1/2``, so the initial translational energy (all the energy there
is, the bath being cold) is ``mu V^2 / 2 = 1/4``.
"""

from __future__ import annotations

import csv
import json
import math
import os
import pickle
import tempfile
import time as _time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError, require_positive

__all__ = [
    "CHECKPOINT_NAME",
    "DATA_CSV_NAME",
    "DATA_NPZ_NAME",
    "RingRun",
    "RingStatistics",
    "decorrelation_stride",
    "default_transient",
    "equilibrium_spectral_entropy",
    "equilibrium_spectral_entropy_finite",
    "equilibrium_translational_energy",
    "ks_exponential",
    "relative_modal_energies",
    "relaxation_collisions",
    "restitution_correlation",
    "run_ring",
    "settling_index",
    "spectral_entropy",
]

CHECKPOINT_NAME = "checkpoint.pkl"
DATA_NPZ_NAME = "ring.npz"
DATA_CSV_NAME = "ring.csv"
_CHECKPOINT_FORMAT = 1
_PAIR_CODES = {"near": 0, "far": 1}
_PAIR_NAMES = ("near", "far")
#: ``1 - Euler's gamma``: mean of ``x ln x`` for an exponential variable of
#: mean 1, which is where the paper's 0.423 in Eq. 11 comes from.
ENTROPY_CONSTANT = 1.0 - 0.5772156649015329


# ----------------------------------------------------------------------------
# Equilibrium formulas
# ----------------------------------------------------------------------------


def equilibrium_translational_energy(modes: int, reduced_mass: float = 0.5, speed: float = 1.0) -> float:
    """Mean translational energy at equipartition, Eq. 8.

    ``<E_tr> = mu V^2 / (2 (2 N + 1))``: the initial energy ``mu V^2 / 2``
    shared equally among the relative motion and the ``2 N`` oscillators.

    Parameters
    ----------
    modes : int
        Modes per rod ``N`` (>= 1).
    reduced_mass : float
        ``mu`` (mass units); ``1/2`` in the units of ``two_rods``.
    speed : float
        Initial approach speed ``V`` (velocity units); 1 in those units.

    Returns
    -------
    float
        Energy (units of ``mu V^2`` when ``mu = V = 1``).
    """
    n = _require_modes(modes)
    mu = require_positive("reduced_mass", reduced_mass)
    v = require_positive("speed", speed)
    return mu * v * v / (2.0 * (2 * n + 1))


def equilibrium_spectral_entropy(modes: int) -> float:
    """Mean normalised spectral entropy at equipartition, Eq. 11.

    ``<eta> = 0.423 / ln(2 N)``, with ``0.423 = 1 - C_Euler``, the large-``N``
    value for modal energies that are independent and exponentially
    (Boltzmann) distributed.

    Parameters
    ----------
    modes : int
        Modes per rod ``N`` (>= 1).
    """
    n = _require_modes(modes)
    return 0.423 / math.log(2 * n)


def equilibrium_spectral_entropy_finite(modes: int) -> float:
    """Exact mean of ``eta`` for ``2 N`` independent exponential modal energies.

    Then ``w`` is uniform on the simplex and the mean of ``h`` is
    ``psi(2N + 1) - psi(2) = H_(2N) - 1`` (``psi`` the digamma function,
    ``H`` the harmonic number), so ``<eta> = 1 - (H_(2N) - 1) / ln(2N)
    = (1 - C_Euler - 1/(4N) + O(N^-2)) / ln(2N)``; Eq. 11 is its leading term.

    Parameters
    ----------
    modes : int
        Modes per rod ``N`` (>= 1).
    """
    from scipy.special import digamma

    n = _require_modes(modes)
    return 1.0 - float(digamma(2 * n + 1) - digamma(2)) / math.log(2 * n)


def _require_modes(modes) -> int:
    if isinstance(modes, bool) or not isinstance(modes, (int, np.integer)) or modes < 1:
        raise InvalidParameterError(f"modes must be an integer >= 1, got {modes!r}")
    return int(modes)


# ----------------------------------------------------------------------------
# Statistics of one run (pure functions of arrays)
# ----------------------------------------------------------------------------


def relative_modal_energies(modal_energies) -> np.ndarray:
    """Relative modal energies ``w_i^nu = E_i^nu / E_bath``.

    Parameters
    ----------
    modal_energies : array_like, shape (..., 2, N)
        Energy of mode ``nu`` of rod ``i`` (energy units); the last two axes
        are (rod, mode).  ``E_bath`` is their sum over both rods and all modes.

    Returns
    -------
    ndarray, same shape
        ``w`` summing to 1 over the last two axes; all zeros where the bath
        holds no energy at all (cold bath), where ``w`` is undefined.
    """
    energies = np.asarray(modal_energies, dtype=float)
    if energies.ndim < 2:
        raise InvalidParameterError(
            f"modal_energies must have shape (..., rods, modes), got shape {energies.shape}"
        )
    if not np.all(np.isfinite(energies)) or np.any(energies < 0.0):
        raise InvalidParameterError("modal_energies must be finite and >= 0")
    total = energies.sum(axis=(-2, -1), keepdims=True)
    safe = np.where(total > 0.0, total, 1.0)
    return np.where(total > 0.0, energies / safe, 0.0)


def spectral_entropy(relative_energies) -> np.ndarray:
    """Normalised spectral entropy ``eta = 1 - h / ln(M)``, Eq. 10.

    ``h = -sum w ln w`` over the last two axes (rod, mode), ``M`` the number
    of entries there (``2 N``), with ``0 ln 0 = 0``.  ``eta = 0`` for exact
    equipartition, ``eta = 1`` when one mode holds everything or the bath
    is empty (``h = 0`` at the cold start, as in the paper).

    Parameters
    ----------
    relative_energies : array_like, shape (..., 2, N)
        ``w`` from :func:`relative_modal_energies` (each spectrum sums to 1
        or is all zeros).

    Returns
    -------
    ndarray of shape (...) or float
    """
    w = np.asarray(relative_energies, dtype=float)
    if w.ndim < 2:
        raise InvalidParameterError(f"relative_energies must have shape (..., rods, modes), got {w.shape}")
    count = w.shape[-1] * w.shape[-2]
    if count < 2:
        raise InvalidParameterError("the spectral entropy needs at least two modes in all")
    if np.any(w < 0.0) or not np.all(np.isfinite(w)):
        raise InvalidParameterError("relative modal energies must be finite and >= 0")
    positive = w > 0.0
    terms = np.where(positive, w * np.log(np.where(positive, w, 1.0)), 0.0)
    h = -terms.sum(axis=(-2, -1))
    eta = 1.0 - h / math.log(count)
    return eta if np.ndim(eta) else float(eta)


def restitution_correlation(restitution, max_lag: int = 20, start: int = 0) -> np.ndarray:
    """Correlation function of successive restitution coefficients, Eq. 13.

    ``C(k) = mean_j (eps_j - <eps>) (eps_{j+k} - <eps>)`` over the collisions
    ``j >= start`` for which ``j + k`` is recorded, ``<eps>`` being the mean
    over the same stationary window.  ``C(0)`` is the variance; divide by it
    for the correlation coefficient.

    Parameters
    ----------
    restitution : array_like, shape (M,)
        ``eps_j`` of the collisions ``j = 0 .. M-1`` (dimensionless).
    max_lag : int
        Largest ``k``; needs at least two pairs at that lag.
    start : int
        First collision of the stationary state (``j_0``).

    Returns
    -------
    ndarray, shape (max_lag + 1,)
    """
    eps = np.asarray(restitution, dtype=float)
    if eps.ndim != 1:
        raise InvalidParameterError(f"restitution must be one-dimensional, got shape {eps.shape}")
    if not np.all(np.isfinite(eps)):
        raise InvalidParameterError("restitution must be finite")
    if int(max_lag) != max_lag or max_lag < 0:
        raise InvalidParameterError(f"max_lag must be an integer >= 0, got {max_lag!r}")
    if int(start) != start or start < 0:
        raise InvalidParameterError(f"start must be an integer >= 0, got {start!r}")
    window = eps[int(start):]
    if window.size < int(max_lag) + 2:
        raise InvalidParameterError(
            f"max_lag must be at most {window.size - 2} for {window.size} stationary collisions, got {max_lag}"
        )
    dev = window - window.mean()
    n = window.size
    return np.array([np.dot(dev[: n - k], dev[k:]) / (n - k) for k in range(int(max_lag) + 1)])


def settling_index(series, level: float, tolerance: float, window: int) -> int | None:
    """First index from which the mean of the next ``window`` values is within ``tolerance`` of ``level``.

    Returns ``None`` if that never happens (the series has not settled).
    """
    values = np.asarray(series, dtype=float)
    if int(window) != window or window < 1:
        raise InvalidParameterError(f"window must be an integer >= 1, got {window!r}")
    window = int(window)
    if values.size < window:
        return None
    cumulative = np.concatenate(([0.0], np.cumsum(values)))
    forward_mean = (cumulative[window:] - cumulative[:-window]) / window
    inside = np.nonzero(np.abs(forward_mean - level) <= tolerance)[0]
    return int(inside[0]) if inside.size else None


def relaxation_collisions(translational_energy, equilibrium: float, window: int = 20, z: float = 2.0):
    """Collisions until ``E_tr`` has relaxed to its stationary band.

    ``E_tr`` fluctuates with a standard deviation equal to its mean (Eq. 9),
    so the mean of ``window`` stationary values scatters by about
    ``equilibrium / sqrt(window)``.  The run counts as relaxed from the first
    collision ``j`` (0-based, i.e. the number of collisions that came before)
    whose forward window mean ``E_tr[j : j + window]`` lies within ``z``
    such standard errors of ``equilibrium``.

    Returns
    -------
    int or None
        ``None`` when the run never gets there.
    """
    level = require_positive("equilibrium", equilibrium)
    return settling_index(translational_energy, level, z * level / math.sqrt(window), window)


def ks_exponential(samples, mean: float):
    """Kolmogorov-Smirnov test of samples against the exponential law Eq. 9.

    The hypothesis is fully specified (the mean is Eq. 8's, not fitted), so
    the standard KS p-value applies to independent samples.

    Returns
    -------
    scipy.stats result with ``.statistic`` and ``.pvalue``
    """
    from scipy import stats

    values = np.asarray(samples, dtype=float)
    if values.ndim != 1 or values.size < 2:
        raise InvalidParameterError(f"samples must be one-dimensional with >= 2 values, got shape {values.shape}")
    scale = require_positive("mean", mean)
    return stats.kstest(values, "expon", args=(0.0, scale))


def decorrelation_stride(series, threshold: float = 0.1, max_stride: int = 50) -> int:
    """Smallest lag ``k >= 1`` at which the autocorrelation of ``series`` has fallen below ``threshold``.

    The KS p-value assumes independent samples; taking every ``k``-th value
    of a correlated series brings it closer to that.  The threshold is
    raised to ``3 / sqrt(n)`` when the series is too short to resolve it.
    Returns ``max_stride`` if the correlation never drops that far.
    """
    values = np.asarray(series, dtype=float)
    n = values.size
    if n < 4:
        return 1
    level = max(float(threshold), 3.0 / math.sqrt(n))
    dev = values - values.mean()
    variance = float(np.dot(dev, dev)) / n
    if variance == 0.0:
        return 1
    for k in range(1, min(int(max_stride), n - 2) + 1):
        if abs(float(np.dot(dev[: n - k], dev[k:])) / (n - k) / variance) < level:
            return k
    return int(max_stride)


def default_transient(collisions: int, relaxation: int | None) -> int:
    """Collisions to discard before the stationary averages.

    The paper discards 500 of 4500 collisions.  Here: the larger of that
    fraction (1/9 of the run) and three relaxation times, at most half the
    run (half the run too when ``E_tr`` never relaxed).
    """
    half = collisions // 2
    if relaxation is None:
        return half
    return int(min(half, max(collisions // 9, 3 * relaxation)))


# ----------------------------------------------------------------------------
# The run record
# ----------------------------------------------------------------------------


@dataclass
class RingStatistics:
    """What the paper reads off a ring run (Sec. III, Fig. 1-3).

    Energies in the units of ``two_rods`` (initial ``E_tr = mu V^2/2 = 1/4``).
    ``transient`` collisions are discarded before every stationary average.
    Successive values of ``E_tr`` are correlated (``E_tr`` after one
    collision is ``E_tr`` before the next), so the Kolmogorov-Smirnov test of
    Eq. 9 uses every ``ks_stride``-th stationary value
    (:func:`decorrelation_stride`); ``ks_pvalue_all_samples`` is the same
    test on all of them, valid only if they were independent.  The standard
    error of the mean ``E_tr`` is likewise that of the thinned samples.
    Collision counts: ``relaxation_collisions`` from
    :func:`relaxation_collisions`; ``entropy_settling_collisions`` is the
    first collision after which ``eta`` lies within two stationary standard
    deviations of its stationary mean.
    """

    modes: int
    collisions: int
    transient: int
    equilibrium_translational_energy: float
    mean_translational_energy: float
    translational_energy_standard_error: float
    relaxation_collisions: int | None
    translational_energy_autocorrelation_lag1: float
    ks_stride: int
    ks_samples: int
    ks_statistic: float
    ks_pvalue: float
    ks_pvalue_all_samples: float
    equilibrium_spectral_entropy: float
    equilibrium_spectral_entropy_finite: float
    mean_spectral_entropy: float
    spectral_entropy_standard_error: float
    entropy_settling_collisions: int | None
    mean_restitution: float
    restitution_correlation: np.ndarray
    restitution_correlation_coefficient_lag1: float
    mean_relative_spectrum: np.ndarray
    energy_drift: float

    def as_dict(self) -> dict:
        """Plain JSON-ready dictionary."""
        out = {}
        for name, value in self.__dict__.items():
            out[name] = value.tolist() if isinstance(value, np.ndarray) else value
        return out


@dataclass
class RingRun:
    """One realisation of repeated collisions on a ring, one entry per collision.

    Attributes
    ----------
    gamma, kappa : float
        Length ratio ``l1/l2`` and softness ``alpha V l / c``.
    modes : int
        Modes per rod ``N``.
    static_correction : bool
        Whether the simulation adds back the omitted modes' static flexibility.
    reduced_mass : float
        ``mu`` (1/2 in the units of ``two_rods``).
    initial_energy : float
        Total energy of the system (``mu V^2 / 2`` for the cold start).
    time : ndarray (M,)
        Simulation time of each collision (``tau = t c / l``).
    pair : ndarray (M,) of int8
        0 when the near ends (short rod's right, long rod's left) collided,
        1 for the far ends across the ring.
    translational_energy : ndarray (M,)
        ``E_tr`` before each collision.
    translational_energy_after : ndarray (M,)
        ``E_tr`` after each collision.
    restitution : ndarray (M,)
        ``eps_j = V_(j+1) / V_(j)``.
    modal_energies : ndarray (M, 2, N)
        Energy of each mode of rod 1 (short) and rod 2 after each collision.
    bath_energy, total_energy : ndarray (M,)
        Vibrational and total energy after each collision (bookkeeping).
    wall_time_s : float
        Wall-clock time spent simulating (s), over all sessions of a resumed run.
    resumed_from : int
        Collisions loaded from a checkpoint (0 for a fresh run).
    """

    gamma: float
    kappa: float
    modes: int
    static_correction: bool
    reduced_mass: float
    initial_energy: float
    time: np.ndarray
    pair: np.ndarray
    translational_energy: np.ndarray
    translational_energy_after: np.ndarray
    restitution: np.ndarray
    modal_energies: np.ndarray
    bath_energy: np.ndarray
    total_energy: np.ndarray
    wall_time_s: float = 0.0
    resumed_from: int = 0
    metadata: dict = field(default_factory=dict)

    _ARRAYS = (
        "time",
        "pair",
        "translational_energy",
        "translational_energy_after",
        "restitution",
        "modal_energies",
        "bath_energy",
        "total_energy",
    )

    @property
    def n_collisions(self) -> int:
        return int(self.translational_energy.size)

    @property
    def E_tr(self) -> np.ndarray:
        """Alias of :attr:`translational_energy` (before each collision)."""
        return self.translational_energy

    def relative_modal_energies(self) -> np.ndarray:
        """``w_i^nu`` after each collision, shape (M, 2, N)."""
        return relative_modal_energies(self.modal_energies)

    def spectral_entropy(self) -> np.ndarray:
        """``eta`` after each collision, shape (M,)."""
        return np.asarray(spectral_entropy(self.relative_modal_energies()), dtype=float)

    def equilibrium_translational_energy(self) -> float:
        """Eq. 8 for this run's ``N`` and ``mu`` (``V = 1``)."""
        return equilibrium_translational_energy(self.modes, self.reduced_mass, 1.0)

    def statistics(self, transient: int | None = None, max_lag: int = 20, window: int = 20) -> RingStatistics:
        """The paper's numbers for this run.

        Parameters
        ----------
        transient : int, optional
            Collisions discarded before the stationary averages; default
            :func:`default_transient`.
        max_lag : int
            Largest lag of ``C_eps(k)`` (reduced if the run is short).
        window : int
            Window of :func:`relaxation_collisions`.
        """
        m = self.n_collisions
        if m < 4:
            raise InvalidParameterError(f"statistics need at least 4 collisions, got {m}")
        e_eq = self.equilibrium_translational_energy()
        relax = relaxation_collisions(self.translational_energy, e_eq, window=min(window, m))
        if transient is None:
            transient = default_transient(m, relax)
        if int(transient) != transient or not 0 <= transient <= m - 3:
            raise InvalidParameterError(f"transient must be an integer in [0, {m - 3}], got {transient!r}")
        transient = int(transient)
        stationary_energy = self.translational_energy[transient:]
        stride = decorrelation_stride(stationary_energy)
        ks = ks_exponential(stationary_energy[::stride], e_eq)
        ks_all = ks_exponential(stationary_energy, e_eq)
        energy_dev = stationary_energy - stationary_energy.mean()
        energy_rho1 = float(np.dot(energy_dev[:-1], energy_dev[1:]) / np.dot(energy_dev, energy_dev))
        eta = self.spectral_entropy()
        eta_stationary = eta[transient:]
        eta_tolerance = 2.0 * float(np.std(eta_stationary)) + 1e-15
        eta_settle = settling_index(eta, float(np.mean(eta_stationary)), eta_tolerance, 1)
        if eta_settle is not None:
            eta_settle += 1  # eta[j] is measured after collision j + 1
        lag = int(min(max_lag, m - transient - 2))
        corr = restitution_correlation(self.restitution, lag, transient)
        rho1 = float(corr[1] / corr[0]) if lag >= 1 and corr[0] > 0 else float("nan")
        spectrum = self.relative_modal_energies()[transient:].mean(axis=0)
        drift = float(np.max(np.abs(self.total_energy - self.initial_energy)) / self.initial_energy)
        return RingStatistics(
            modes=self.modes,
            collisions=m,
            transient=transient,
            equilibrium_translational_energy=e_eq,
            mean_translational_energy=float(np.mean(stationary_energy)),
            translational_energy_standard_error=float(
                np.std(stationary_energy, ddof=1) * math.sqrt(stride / stationary_energy.size)
            ),
            relaxation_collisions=relax,
            translational_energy_autocorrelation_lag1=energy_rho1,
            ks_stride=stride,
            ks_samples=int(stationary_energy[::stride].size),
            ks_statistic=float(ks.statistic),
            ks_pvalue=float(ks.pvalue),
            ks_pvalue_all_samples=float(ks_all.pvalue),
            equilibrium_spectral_entropy=equilibrium_spectral_entropy(self.modes),
            equilibrium_spectral_entropy_finite=equilibrium_spectral_entropy_finite(self.modes),
            mean_spectral_entropy=float(np.mean(eta_stationary)),
            spectral_entropy_standard_error=float(
                np.std(eta_stationary, ddof=1)
                * math.sqrt(decorrelation_stride(eta_stationary) / eta_stationary.size)
            ),
            entropy_settling_collisions=eta_settle,
            mean_restitution=float(np.mean(self.restitution[transient:])),
            restitution_correlation=corr,
            restitution_correlation_coefficient_lag1=rho1,
            mean_relative_spectrum=spectrum,
            energy_drift=drift,
        )

    # -- input / output -------------------------------------------------------

    def _scalars(self) -> dict:
        return {
            "gamma": float(self.gamma),
            "kappa": float(self.kappa),
            "modes": int(self.modes),
            "static_correction": bool(self.static_correction),
            "reduced_mass": float(self.reduced_mass),
            "initial_energy": float(self.initial_energy),
            "wall_time_s": float(self.wall_time_s),
            "resumed_from": int(self.resumed_from),
        }

    def save_npz(self, path) -> Path:
        """Write every array and scalar to a NumPy ``.npz`` file (atomically)."""
        payload = {name: getattr(self, name) for name in self._ARRAYS}
        payload["collision"] = np.arange(1, self.n_collisions + 1)
        payload["spectral_entropy"] = self.spectral_entropy()
        for key, value in self._scalars().items():
            payload[key] = np.asarray(value)
        payload["metadata_json"] = np.asarray(json.dumps(self.metadata))

        def write(handle):
            np.savez_compressed(handle, **payload)

        return _atomic_write(Path(path), write, binary=True)

    @classmethod
    def load_npz(cls, path) -> RingRun:
        """Read a file written by :meth:`save_npz`."""
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: np.array(data[name]) for name in cls._ARRAYS}
            scalars = {
                "gamma": float(data["gamma"]),
                "kappa": float(data["kappa"]),
                "modes": int(data["modes"]),
                "static_correction": bool(data["static_correction"]),
                "reduced_mass": float(data["reduced_mass"]),
                "initial_energy": float(data["initial_energy"]),
                "wall_time_s": float(data["wall_time_s"]),
                "resumed_from": int(data["resumed_from"]),
            }
            metadata = json.loads(str(data["metadata_json"]))
        return cls(**scalars, **arrays, metadata=metadata)

    def save_csv(self, path) -> Path:
        """One row per collision: number, time, pair, energies, restitution, eta."""
        eta = self.spectral_entropy()
        header = [
            "collision", "time", "pair", "E_tr_before", "E_tr_after", "restitution",
            "E_bath", "E_total", "spectral_entropy",
        ]

        def write(handle):
            writer = csv.writer(handle)
            writer.writerow(header)
            for j in range(self.n_collisions):
                writer.writerow([
                    j + 1,
                    repr(float(self.time[j])),
                    _PAIR_NAMES[int(self.pair[j])],
                    repr(float(self.translational_energy[j])),
                    repr(float(self.translational_energy_after[j])),
                    repr(float(self.restitution[j])),
                    repr(float(self.bath_energy[j])),
                    repr(float(self.total_energy[j])),
                    repr(float(eta[j])),
                ])

        return _atomic_write(Path(path), write, binary=False)


# ----------------------------------------------------------------------------
# Running and checkpointing
# ----------------------------------------------------------------------------


def _load_ring_simulation():
    """The default simulation class (imported late: the study knows no solver internals)."""
    from ..modal.ring import RingSimulation

    return RingSimulation


def _atomic_write(path: Path, write: Callable, binary: bool) -> Path:
    """Write through a temporary file in the same directory, then ``os.replace``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb" if binary else "w", **({} if binary else {"newline": ""})) as handle:
            write(handle)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return path


class _Recorder:
    """Per-collision rows accumulated in lists (cheap appends)."""

    def __init__(self, modes: int):
        self.modes = modes
        self.columns = {name: [] for name in RingRun._ARRAYS}

    def __len__(self):
        return len(self.columns["time"])

    def add(self, record: dict):
        energies = np.array(record["modal_energies"], dtype=float, copy=True)
        if energies.shape != (2, self.modes):
            raise ValueError(f"simulation returned modal energies of shape {energies.shape}, expected (2, {self.modes})")
        pair = record["pair"]
        if pair not in _PAIR_CODES:
            raise ValueError(f"simulation returned pair {pair!r}, expected 'near' or 'far'")
        c = self.columns
        c["time"].append(float(record["time"]))
        c["pair"].append(_PAIR_CODES[pair])
        c["translational_energy"].append(float(record["E_tr_before"]))
        c["translational_energy_after"].append(float(record["E_tr_after"]))
        c["restitution"].append(float(record["restitution"]))
        c["modal_energies"].append(energies)
        c["bath_energy"].append(float(record["E_bath"]))
        c["total_energy"].append(float(record["E_total"]))

    def arrays(self) -> dict:
        c = self.columns
        out = {}
        for name in RingRun._ARRAYS:
            if name == "modal_energies":
                out[name] = np.array(c[name], dtype=float).reshape(len(self), 2, self.modes)
            elif name == "pair":
                out[name] = np.array(c[name], dtype=np.int8)
            else:
                out[name] = np.array(c[name], dtype=float)
        return out

    def load(self, arrays: dict, count: int):
        for name in RingRun._ARRAYS:
            values = np.asarray(arrays[name])[:count]
            if name == "modal_energies":
                self.columns[name] = [np.array(v) for v in values]
            else:
                self.columns[name] = values.tolist()


def _validate(gamma, kappa, modes, collisions, checkpoint_every):
    try:
        g = float(gamma)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"gamma must be a number in (0, 1], got {gamma!r}") from None
    if not 0.0 < g <= 1.0:
        raise InvalidParameterError(f"gamma must lie in (0, 1], got {g!r}")
    k = require_positive("kappa", kappa, allow_inf=True)
    n = _require_modes(modes)
    for name, value in (("collisions", collisions), ("checkpoint_every", checkpoint_every)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise InvalidParameterError(f"{name} must be an integer >= 1, got {value!r}")
    return g, k, n, int(collisions), int(checkpoint_every)


def _run_parameters(gamma, kappa, modes, static_correction, circumference, seed) -> dict:
    return {
        "gamma": gamma,
        "kappa": kappa,
        "modes": modes,
        "static_correction": bool(static_correction),
        "circumference": None if circumference is None else float(circumference),
        "seed": seed,
    }


def _write_checkpoint(path: Path, parameters: dict, simulation, recorder: _Recorder, wall_time: float):
    payload = {
        "format": _CHECKPOINT_FORMAT,
        "parameters": parameters,
        "collisions": len(recorder),
        "simulation_state": simulation.get_state(),
        "arrays": recorder.arrays(),
        "wall_time_s": wall_time,
    }
    _atomic_write(path, lambda handle: pickle.dump(payload, handle, protocol=pickle.HIGHEST_PROTOCOL), binary=True)


def _read_checkpoint(path: Path, parameters: dict) -> dict:
    try:
        with open(path, "rb") as handle:
            payload = pickle.load(handle)
    except (pickle.UnpicklingError, EOFError, AttributeError, ImportError) as exc:
        raise InvalidParameterError(f"{path} is not a readable ring checkpoint ({exc}); delete it to start afresh") from None
    if not isinstance(payload, dict) or payload.get("format") != _CHECKPOINT_FORMAT:
        raise InvalidParameterError(f"{path} is not a ring checkpoint of format {_CHECKPOINT_FORMAT}")
    stored = payload["parameters"]
    if stored != parameters:
        differ = ", ".join(f"{k}={stored.get(k)!r} (now {v!r})" for k, v in parameters.items() if stored.get(k) != v)
        raise InvalidParameterError(
            f"{path} belongs to a different run: {differ}; use another output directory or delete the checkpoint"
        )
    return payload


def run_ring(
    gamma: float,
    kappa: float,
    modes: int,
    collisions: int,
    out_dir=None,
    checkpoint_every: int = 100,
    progress: bool = True,
    simulation_factory: Callable | None = None,
    *,
    static_correction: bool = True,
    circumference: float | None = None,
    seed: int | None = None,
    callback: Callable[[int, dict], None] | None = None,
    log: Callable[[str], None] | None = None,
) -> RingRun:
    """Run ``collisions`` successive collisions of two rods on a ring.

    Parameters
    ----------
    gamma : float
        Length ratio ``l1 / l2`` in (0, 1].
    kappa : float
        Softness ``alpha V l / c`` in (0, inf].
    modes : int
        Modes per rod ``N``.
    collisions : int
        Total number of collisions wanted (including any already in a checkpoint).
    out_dir : path, optional
        Directory for the checkpoint (``checkpoint.pkl``) and the data
        (``ring.npz``, ``ring.csv``).  If it holds a checkpoint of the same
        run, the run resumes from there; a checkpoint of another run is
        refused.  ``None``: nothing is written.
    checkpoint_every : int
        Write a checkpoint after every so many collisions (and at the end).
    progress : bool
        Show a tqdm progress bar on stderr.
    simulation_factory : callable, optional
        ``factory(gamma=, kappa=, modes=, static_correction=, circumference=,
        seed=)`` returning an object with ``next_collision()``,
        ``get_state()``, ``set_state(state)`` and the attributes
        ``reduced_mass`` and ``total_energy``.  Default:
        :class:`wavecontact.modal.ring.RingSimulation`.
    static_correction, circumference, seed
        Passed to the factory.
    callback : callable, optional
        ``callback(index, record)`` after every collision (0-based index).
        An exception raised there (e.g. ``KeyboardInterrupt``) ends the run;
        the last checkpoint stays valid.
    log : callable, optional
        Receives one-line messages (e.g. that a checkpoint was resumed).

    Returns
    -------
    RingRun
    """
    g, k, n, m, every = _validate(gamma, kappa, modes, collisions, checkpoint_every)
    factory = simulation_factory if simulation_factory is not None else _load_ring_simulation()
    parameters = _run_parameters(g, k, n, static_correction, circumference, seed)
    simulation = factory(
        gamma=g, kappa=k, modes=n, static_correction=bool(static_correction), circumference=circumference, seed=seed
    )
    recorder = _Recorder(n)
    wall_before = 0.0
    resumed_from = 0
    checkpoint = None
    if out_dir is not None:
        out_dir = Path(out_dir)
        if out_dir.exists() and not out_dir.is_dir():
            raise InvalidParameterError(f"out_dir {str(out_dir)!r} exists and is not a directory")
        out_dir.mkdir(parents=True, exist_ok=True)
        checkpoint = out_dir / CHECKPOINT_NAME
        if checkpoint.exists():
            payload = _read_checkpoint(checkpoint, parameters)
            resumed_from = int(payload["collisions"])
            simulation.set_state(payload["simulation_state"])
            recorder.load(payload["arrays"], resumed_from)
            wall_before = float(payload["wall_time_s"])
            if log is not None:
                log(f"resuming from checkpoint {checkpoint} at collision {resumed_from}")
    if resumed_from > m and log is not None:
        log(f"the checkpoint holds {resumed_from} collisions; keeping the first {m}")

    start = _time.perf_counter()
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=m, initial=min(resumed_from, m), unit="collision", desc="ring", dynamic_ncols=True)
    last_checkpoint = resumed_from if checkpoint is not None and resumed_from else None
    try:
        while len(recorder) < m:
            record = simulation.next_collision()
            recorder.add(record)
            if bar is not None:
                bar.update(1)
            if callback is not None:
                callback(len(recorder) - 1, record)
            done = len(recorder)
            if checkpoint is not None and (done % every == 0 or done == m):
                _write_checkpoint(
                    checkpoint, parameters, simulation, recorder, wall_before + _time.perf_counter() - start
                )
                last_checkpoint = done
    except KeyboardInterrupt:
        if log is not None:
            if last_checkpoint:
                log(f"interrupted; run again to resume from the checkpoint at collision {last_checkpoint}")
            elif checkpoint is not None:
                log("interrupted before the first checkpoint; a new run will start from the beginning")
        raise
    finally:
        if bar is not None:
            bar.close()
    wall = wall_before + _time.perf_counter() - start

    arrays = {name: values[:m] for name, values in recorder.arrays().items()}
    run = RingRun(
        gamma=g,
        kappa=k,
        modes=n,
        static_correction=bool(static_correction),
        reduced_mass=float(getattr(simulation, "reduced_mass", 0.5)),
        initial_energy=float(simulation.total_energy),
        wall_time_s=wall,
        resumed_from=min(resumed_from, m),
        metadata={"circumference": circumference, "seed": seed, "checkpoint_every": every},
        **arrays,
    )
    if out_dir is not None:
        run.save_npz(out_dir / DATA_NPZ_NAME)
        run.save_csv(out_dir / DATA_CSV_NAME)
    return run
