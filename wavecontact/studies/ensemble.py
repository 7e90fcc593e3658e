"""Ensembles of thermal collisions: the law of epsilon (Sec. VI), from a laptop to a Dask cluster.

Sample ``j`` of an ensemble with seed ``s`` draws its bath realisation from
``numpy.random.SeedSequence(s).spawn(n)[j]`` (built directly as
``SeedSequence(s, spawn_key=(j,))``, the same object), so every sample is
fixed by ``(s, j)`` alone: the samples are bit-identical whatever the
executor, the number of workers or the batch size.  Work goes out in batches
of consecutive samples; with an output directory every finished batch is
saved (``.npz``, no pickle) next to a JSON description of the run, and a run
started again with the same parameters resumes from there.
"""

from __future__ import annotations

import concurrent.futures
import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..bath.model import ThermalBath
from ..errors import AccuracyError, InvalidParameterError, WavecontactError, require_integer
from ..io.files import atomic_write
from ..io.run_controller import BatchStore, RunController, RunSettings, write_summary
from ..scene import validate_gamma_kappa
from ..solvers import get_solver, solvers_with
from ..solvers.base import ENERGY_SPLIT, HARD_CORE_THERMAL, THERMAL_BATCH

__all__ = ["GRID_BIAS_SAMPLES", "MAX_SAMPLES", "EnsembleResult", "EnsembleSpec",
           "GridBias", "ensemble", "grid_bias", "grid_bias_indices", "run_batch", "sample_collision", "sample_seed"]

MAX_SAMPLES = 10_000_000
GRID_BIAS_SAMPLES = 64  # least number of hard-core samples rerun on the finer grid to state the grid bias
_BATCH_SCHEMA = "wavecontact.ensemble_batch"
_SCHEMA = "wavecontact.ensemble"
_VERSION = 2  # 2: batches keep each sample's error estimate


def __getattr__(name):
    # ENSEMBLE_DELAY_OPTIONS, ENSEMBLE_RTOL: the batch defaults of the solver that samples thermal
    # batches (``batch_defaults``: rtol 1e-3, the Lobatto-Kronrod rule, 16 noise table nodes per period),
    # read from the registry when first asked for
    if name in ("ENSEMBLE_DELAY_OPTIONS", "ENSEMBLE_RTOL"):
        from ..solvers import solver_for
        from ..solvers.base import THERMAL_BATCH

        defaults = dict(solver_for(THERMAL_BATCH).batch_defaults)
        return defaults if name == "ENSEMBLE_DELAY_OPTIONS" else defaults["rtol"]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def sample_seed(seed: int, index: int) -> np.random.SeedSequence:
    """The seed of sample ``index``: ``SeedSequence(seed).spawn(index + 1)[index]``."""
    return np.random.SeedSequence(int(seed), spawn_key=(int(index),))


@dataclass(frozen=True)
class EnsembleSpec:
    """What an ensemble computes (all of it is saved with the samples).

    Parameters
    ----------
    gamma, kappa : float
        The paper's numbers (``kappa = inf``: the stochastic hard-core mode).
    temperature : float or pair
        ``T_B / E_tr`` (per rod if a pair), >= 0.
    samples : int
        Number of collisions, in [1, 10^7].
    seed : int
        Non-negative; sample ``j`` uses :func:`sample_seed` ``(seed, j)``.
    bath_modes : int
        ``nu_max``, in [1, 100000].
    solver : str
        Solver of each collision (a name of :func:`wavecontact.solvers.solver_names`).
    options : dict
        Solver options (JSON values only).  At finite kappa the solver's ``batch_defaults`` fill in
        what is not given (the delay solver's ``ENSEMBLE_DELAY_OPTIONS``: ``rtol = ENSEMBLE_RTOL``,
        the Lobatto-Kronrod rule, 16 noise table nodes per period of the fastest mode).
    batch_size : int
        Samples per task, in [1, 100000].
    energy_split : bool
        Also keep each rod's vibrational energy gain per sample (delay
        solver at finite kappa, modal, fem).
    """

    gamma: float
    kappa: float
    temperature: object
    samples: int
    seed: int
    bath_modes: int = 250
    solver: str = "delay"
    options: dict = field(default_factory=dict)
    batch_size: int = 256
    energy_split: bool = False

    def __post_init__(self):
        gamma, kappa = validate_gamma_kappa(self.gamma, self.kappa)
        object.__setattr__(self, "gamma", gamma)
        object.__setattr__(self, "kappa", kappa)
        bath = ThermalBath(self.temperature, self.bath_modes)  # validates temperature and modes
        object.__setattr__(self, "temperature", bath.temperature)
        for name, low, high in (("samples", 1, MAX_SAMPLES), ("batch_size", 1, 100_000)):
            object.__setattr__(self, name, require_integer(name, getattr(self, name), low, high))
        object.__setattr__(self, "seed", require_integer("seed", self.seed, 0, allowed="a non-negative integer"))
        solver = get_solver(self.solver)  # refuses an unknown name, listing the registered ones
        if self.energy_split and not solver.offers(ENERGY_SPLIT):
            raise InvalidParameterError(f"energy_split needs a solver that splits the energy per rod: "
                                        f"{', '.join(solvers_with(ENERGY_SPLIT))}, not {self.solver!r}")
        if self.energy_split and math.isinf(kappa):
            raise InvalidParameterError(
                "energy_split needs a finite kappa (the hard-core grid gives only the total); kappa >= 50 is "
                "in the kappa-independent regime")
        if _hard_core(self) and set(self.options) - {"hard_core_resolution"}:
            raise InvalidParameterError(
                "the hard-core mode (kappa = inf) takes only the option hard_core_resolution, not "
                f"{', '.join(sorted(set(self.options) - {'hard_core_resolution'}))}")
        if math.isfinite(kappa):
            object.__setattr__(self, "options", {**solver.batch_defaults, **self.options})
        try:
            json.dumps(self.options)
        except TypeError:
            raise InvalidParameterError("ensemble solver options must be JSON values (numbers, strings)") from None

    @property
    def bath(self) -> ThermalBath:
        return ThermalBath(self.temperature, self.bath_modes)

    def batches(self) -> list:
        """``(start, stop)`` of every batch."""
        return [(i, min(i + self.batch_size, self.samples)) for i in range(0, self.samples, self.batch_size)]

    def describe(self) -> dict:
        out = asdict(self)
        out["kappa"] = "inf" if math.isinf(self.kappa) else self.kappa
        out["temperature"] = list(self.temperature)
        return out


def sample_collision(spec: EnsembleSpec, index: int) -> tuple:
    """``(epsilon, (Delta E_1, Delta E_2), error_estimate)`` of sample ``index``.

    The gains are zero unless ``spec.energy_split``; the error estimate is the
    solver's (NaN where it gives none: the hard-core mode, a solver without one).
    """
    _start, values, gains, errors = run_batch(asdict(spec), index, index + 1)
    return float(values[0]), (float(gains[0, 0]), float(gains[0, 1])), float(errors[0])


def _solved_collision(spec: EnsembleSpec, index: int) -> tuple:
    """:func:`sample_collision` through ``solve`` (the energy split, solvers without thermal batches)."""
    from ..api import solve
    from ..bath.collide import thermal_scene

    scene = thermal_scene(spec.gamma, spec.kappa, spec.bath, sample_seed(spec.seed, index))
    options = dict(spec.options)
    if "energy_split" in get_solver(spec.solver).Options.__dataclass_fields__:
        options.setdefault("energy_split", spec.energy_split)  # a solver that computes the split on request
    result = solve(scene, spec.solver, **options)
    gain = (0.0, 0.0)
    if spec.energy_split:
        gain = tuple(float(x) for x in result.extra["vibration_energy_gain"])
    error = result.error_estimate
    return float(result.restitution), gain, math.nan if error is None else float(error)


def _hard_core(spec: EnsembleSpec) -> bool:
    """The stochastic hard-core mode: kappa = inf with a solver that offers it."""
    return math.isinf(spec.kappa) and get_solver(spec.solver).offers(HARD_CORE_THERMAL)


def _hard_core_batch(spec: EnsembleSpec, start: int, stop: int) -> np.ndarray:
    """epsilon of samples ``start`` to ``stop - 1`` in the stochastic hard-core mode (one batched call)."""
    from ..bath.streams import SpawnedSeeds

    resolution = _resolution(spec)
    seeds = SpawnedSeeds(spec.seed, start, stop)  # sample_seed(spec.seed, j) for j in start..stop-1
    return get_solver(spec.solver).hard_core_thermal_batch(spec.gamma, spec.temperature, seeds, spec.bath_modes,
                                                       resolution)


def _resolution(spec: EnsembleSpec) -> int:
    return spec.options.get("hard_core_resolution", 8)  # the hard-core grid's default points per period


@dataclass(frozen=True)
class GridBias:
    """The hard-core grid's bias of an ensemble mean, from a subset rerun on a finer grid.

    Attributes
    ----------
    value : float
        Estimated bias of the mean epsilon (dimensionless; the grid's epsilon minus the
        exact limit's, averaged), ``factor * mean(eps_r - eps_check)`` over the subset.
    standard_error : float
        Standard error of ``value`` (from the spread of the paired differences).
    samples : int
        Size of the subset (every ``stride``-th sample, from sample 0).
    stride : int
    resolution, check_resolution : int
        Points per period of the ensemble's grid and of the finer check grid.
    factor : float
        ``h_r / (h_r - h_check)`` (2 when the grid step halves): the first-order
        error of ``eps_r`` in units of the paired difference.
    check_restitution : ndarray
        epsilon of the subset on the check grid (the subset's own values are
        ``restitution[::stride]``).
    """

    value: float
    standard_error: float
    samples: int
    stride: int
    resolution: int
    check_resolution: int
    factor: float
    check_restitution: np.ndarray


def grid_bias_indices(samples: int) -> np.ndarray:
    """The samples rerun to state the grid bias: every ``k``-th from 0, ``k = max(1, samples // 64)``
    (64 to 127 of them, or all if fewer than 128)."""
    return np.arange(0, samples, max(1, samples // GRID_BIAS_SAMPLES))


def _check_resolution(grid_points, modes: int, resolution: int) -> int:
    """Points per period of the check grid: twice as many grid points per ``Gamma_1`` where
    the cap allows, else half as many (``grid_points(r)``: points per ``Gamma_1`` at ``r``)."""
    finer = min(8192, -(-2 * grid_points(resolution) // modes))
    if grid_points(finer) > grid_points(resolution):
        return finer
    return max(2, resolution // 2)


def grid_bias(spec: EnsembleSpec, restitution: np.ndarray) -> GridBias:
    """State the hard-core grid's bias of the mean of ``restitution`` (the samples of ``spec``).

    The samples of :func:`grid_bias_indices` run again, same seeds, on a grid with twice as
    many points per ``Gamma_1``.  The grid's error is first order in its step ``h``, so
    ``eps_r - eps_exact ~ (h_r / (h_r - h_check)) (eps_r - eps_check)`` per sample; the mean of
    that over the subset estimates the bias of the ensemble mean, and the spread of the paired
    differences gives its standard error.  Cost: 64 to 127 samples at about 1.7 times a
    sample's cost (docs/bath.md section 3).
    """
    solver = get_solver(spec.solver)
    resolution = _resolution(spec)
    modes = spec.bath_modes

    def grid_points(r):
        return solver.hard_core_grid_points(spec.gamma, modes, r)

    check = _check_resolution(grid_points, modes, resolution)
    factor = grid_points(check) / (grid_points(check) - grid_points(resolution))
    indices = grid_bias_indices(restitution.size)
    stride = int(indices[1] - indices[0]) if indices.size > 1 else 1
    checked = solver.hard_core_thermal_batch(
        spec.gamma, spec.temperature, [sample_seed(spec.seed, j) for j in indices], modes, check)
    differences = factor * (restitution[indices] - checked)
    error = float(np.std(differences, ddof=1)) / math.sqrt(indices.size) if indices.size > 1 else math.inf
    return GridBias(float(np.mean(differences)), error, int(indices.size), stride, int(resolution), int(check),
                    float(factor), checked)


def run_batch(spec_fields: dict, start: int, stop: int) -> tuple:
    """Samples ``start`` to ``stop - 1`` (a task: plain arguments, plain results).

    Returns ``(start, epsilon (n,), gains (n, 2), error estimates (n,))``.
    """
    spec = EnsembleSpec(**spec_fields)
    n = stop - start
    solver = get_solver(spec.solver)
    if _hard_core(spec):
        return start, _hard_core_batch(spec, start, stop), np.zeros((n, 2)), np.full(n, math.nan)
    if solver.offers(THERMAL_BATCH) and not spec.energy_split:
        # what solve() returns, without the scene and result objects around each sample
        seeds = [sample_seed(spec.seed, j) for j in range(start, stop)]
        values, errors = solver.thermal_restitutions(spec.gamma, spec.kappa, spec.bath, seeds,
                                                                  spec.options)
        return start, values, np.zeros((n, 2)), errors
    rows = [_solved_collision(spec, j) for j in range(start, stop)]
    return (start, np.array([r[0] for r in rows]), np.array([r[1] for r in rows], dtype=float).reshape(-1, 2),
            np.array([r[2] for r in rows]))


@dataclass
class EnsembleResult:
    """The samples of an ensemble and their statistics.

    Attributes
    ----------
    spec : EnsembleSpec
    restitution : ndarray
        epsilon of every sample, in sample order.
    vibration_energy_gain : ndarray (n, 2)
        Each rod's vibrational gain per sample (units with ``E_tr = 1/4``;
        zeros unless ``spec.energy_split``).
    error_estimate : ndarray (n,)
        The solver's estimate of each sample's error in epsilon (NaN where it
        gives none, as in the hard-core mode).
    grid_bias : GridBias or None
        The hard-core grid's bias of :attr:`mean`, stated from a subset rerun
        on a finer grid (``kappa = inf`` only; None otherwise).
    """

    spec: EnsembleSpec
    restitution: np.ndarray
    vibration_energy_gain: np.ndarray | None = None
    error_estimate: np.ndarray | None = None
    grid_bias: GridBias | None = None

    @property
    def largest_error_estimate(self) -> float | None:
        """The largest per-sample error estimate (None if the solver gives none; NaN if only some samples
        have one: the others' errors are unknown)."""
        if self.error_estimate is None or not np.any(np.isfinite(self.error_estimate)):
            return None
        return float(np.max(self.error_estimate))

    @property
    def total_error(self) -> float:
        """The mean's total error estimate: ``sqrt(SE^2 + bias^2 + SE_bias^2)`` with the stated grid bias
        (hard core), else the standard error alone (sampling error only)."""
        if self.grid_bias is None:
            return self.standard_error
        bias = self.grid_bias
        return math.sqrt(self.standard_error**2 + bias.value**2 + bias.standard_error**2)

    @property
    def rod1_share(self) -> float:
        """Share of the lost translational energy that went into rod 1's vibrations,
        ``sum Delta E_1 / sum (Delta E_1 + Delta E_2)`` over the samples (ratio of means)."""
        if not self.spec.energy_split:
            raise InvalidParameterError("rod1_share needs an ensemble run with energy_split=True")
        total = float(np.sum(self.vibration_energy_gain))
        if total == 0.0:
            raise InvalidParameterError("the samples lost no translational energy on balance: rod1_share is undefined")
        return float(np.sum(self.vibration_energy_gain[:, 0])) / total

    @property
    def mean(self) -> float:
        return float(np.mean(self.restitution))

    @property
    def std(self) -> float:
        """Sample standard deviation of epsilon (``ddof = 1``)."""
        return float(np.std(self.restitution, ddof=1)) if self.restitution.size > 1 else 0.0

    @property
    def standard_error(self) -> float:
        """Standard error of the mean, ``std / sqrt(n)``."""
        return self.std / math.sqrt(self.restitution.size)

    @property
    def std_standard_error(self) -> float:
        """Standard error of the standard deviation from the fourth moment
        (``sqrt((m4 - s^4) / n) / (2 s)``; no Gaussian assumption)."""
        n = self.restitution.size
        s = self.std
        if n < 4 or s == 0.0:
            return 0.0
        m4 = float(np.mean((self.restitution - self.mean) ** 4))
        return math.sqrt(max(m4 - s**4, 0.0) / n) / (2.0 * s)

    def density(self, bins: int = 40, confidence: float = 0.95):
        """Histogram density of ``epsilon^2`` with a normal-approximation band per bin.

        Returns
        -------
        edges, density, low, high : ndarray
        """
        from statistics import NormalDist

        x = self.restitution**2
        counts, edges = np.histogram(x, bins=bins)
        n = x.size
        width = np.diff(edges)
        p = counts / n
        z = NormalDist().inv_cdf(0.5 + confidence / 2.0)
        band = z * np.sqrt(p * (1.0 - p) / n)
        return edges, p / width, np.maximum(p - band, 0.0) / width, (p + band) / width

    def distribution(self, confidence: float = 0.95):
        """Empirical ``D(epsilon^2)`` with the Dvoretzky-Kiefer-Wolfowitz band.

        Returns
        -------
        x, D, low, high : ndarray
            Sorted ``epsilon^2`` and the distribution just after each value.
        """
        x = np.sort(self.restitution**2)
        n = x.size
        d = np.arange(1, n + 1) / n
        band = math.sqrt(math.log(2.0 / (1.0 - confidence)) / (2.0 * n))
        return x, d, np.clip(d - band, 0.0, 1.0), np.clip(d + band, 0.0, 1.0)

    def save(self, out) -> Path:
        """Write ``samples.npz`` (every epsilon, in sample order) and ``summary.json`` into ``out``."""
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        extra = {}
        if self.grid_bias is not None:
            extra = {"grid_bias_indices": grid_bias_indices(self.restitution.size),
                     "grid_bias_check_restitution": self.grid_bias.check_restitution}
        arrays = dict(restitution=self.restitution, vibration_energy_gain=self.vibration_energy_gain,
                      error_estimate=self.error_estimate, **extra)
        atomic_write(out / "samples.npz", lambda handle: np.savez(handle, **arrays))
        write_summary(out / "summary.json", self.summary())
        return out

    def summary(self) -> dict:
        spec = self.spec
        bias = self.grid_bias
        return {
            "mean": self.mean,
            "std": self.std,
            "standard_error": self.standard_error,
            "grid_bias": None if bias is None else bias.value,
            "grid_bias_standard_error": None if bias is None else bias.standard_error,
            "grid_bias_samples": 0 if bias is None else bias.samples,
            "grid_bias_check_resolution": None if bias is None else bias.check_resolution,
            "total_error": self.total_error,
            "std_standard_error": self.std_standard_error,
            "mean_eps2": float(np.mean(self.restitution**2)),
            "samples": int(self.restitution.size),
            "gamma": spec.gamma,
            "kappa": "inf" if math.isinf(spec.kappa) else spec.kappa,
            "temperature": spec.temperature[0] if spec.temperature[0] == spec.temperature[1] else list(spec.temperature),
            "bath_modes": spec.bath_modes,
            "seed": spec.seed,
            "solver": spec.solver,
            "options": dict(spec.options),
            "largest_error_estimate": self.largest_error_estimate,
        }


def _batch_path(out: Path, start: int) -> Path:
    return out / f"batch_{start:09d}.npz"


def _batch_parameters(spec: EnsembleSpec, start: int, stop: int) -> dict:
    return {"spec": spec.describe(), "start": int(start), "stop": int(stop)}


def _check_batch(spec: EnsembleSpec):
    """The values of a stored batch, refused unless a run of ``spec`` could have produced them."""

    def check(arrays, start, stop):
        values = np.asarray(arrays["restitution"])
        gains = np.asarray(arrays["vibration_energy_gain"])
        errors = np.asarray(arrays["error_estimate"])
        n = stop - start
        if values.shape != (n,) or gains.shape != (n, 2) or errors.shape != (n,):
            raise InvalidParameterError(f"arrays of shapes {values.shape}, {gains.shape}, {errors.shape}, "
                                        f"expected ({n},), ({n}, 2), ({n},)")
        if any(a.dtype.kind != "f" for a in (values, gains, errors)):
            raise InvalidParameterError("arrays must hold floating-point numbers")
        if not np.all(np.isfinite(values)) or np.any(values < 0.0):
            raise InvalidParameterError("restitution must be finite and >= 0")
        if not np.all(np.isfinite(gains)) or (not spec.energy_split and np.any(gains != 0.0)):
            raise InvalidParameterError("vibration_energy_gain must be finite (and zero without energy_split)")
        if np.any(np.isinf(errors)) or np.any(errors < 0.0):
            raise InvalidParameterError("error_estimate must be >= 0 or NaN (none)")
        return values.astype(float), gains.astype(float), errors.astype(float)

    return check


def _store(out, spec: EnsembleSpec) -> BatchStore:
    return BatchStore(out, "ensemble.json", {"schema": _SCHEMA, "version": _VERSION, "spec": spec.describe()},
                      lambda start: _batch_path(Path(out), start).name, "batch_*.npz", _BATCH_SCHEMA, _VERSION,
                      lambda start, stop: _batch_parameters(spec, start, stop), _check_batch(spec), "an ensemble")


def run_batches(pool, function, fields, batches, on_result) -> None:
    """Run ``function(fields, a, b)`` for every batch ``(a, b)``, here (``pool`` None) or on the executor,
    handing each result to ``on_result`` as it arrives; on any error the batches not started are cancelled."""
    if pool is None:
        for a, b in batches:
            on_result(function(fields, a, b))
        return
    futures = [pool.submit(function, fields, a, b) for a, b in batches]
    try:
        for future in concurrent.futures.as_completed(futures):
            on_result(future.result())
    except BaseException:
        for future in futures:
            future.cancel()
        raise


def _executor_for(executor):
    """A concurrent.futures executor; a dask.distributed Client is wrapped with pure=False."""
    if executor is None:
        return None
    if type(executor).__module__.startswith("distributed") and hasattr(executor, "get_executor"):
        return executor.get_executor(pure=False)  # equal arguments must not be deduplicated
    if not hasattr(executor, "submit"):
        raise InvalidParameterError("executor must be a concurrent.futures.Executor or a dask.distributed Client")
    return executor


def ensemble(gamma, kappa, bath_temperature, samples, seed, *, solver="delay", bath_modes=250, energy_split=False,
             tolerance=None, run: RunSettings | None = None, **options) -> EnsembleResult:
    """Collide ``samples`` independent realisations of the thermal bath.

    Parameters
    ----------
    gamma, kappa : float
        Length ratio in (0, 1] and softness in (0, inf] (``inf``: the
        stochastic hard-core mode of a solver that offers it).
    bath_temperature : float or pair
        ``T_B / E_tr`` >= 0 (per rod if a pair).
    samples : int
        Number of collisions, in [1, 10^7].
    seed : int
        Non-negative; fixes every sample (see module docstring).
    solver : str
        Solver of each collision (a name of :func:`wavecontact.solvers.solver_names`).
    bath_modes : int
        ``nu_max`` (default 250).
    energy_split : bool
        Keep each rod's vibrational gain per sample (finite kappa only).
    tolerance : float or None
        Hard-core mode only: largest acceptable grid bias of the mean (the stated
        bias plus two of its standard errors); a larger one raises
        :class:`~wavecontact.errors.AccuracyError` with a ``hard_core_resolution``
        that should meet it (the samples are kept on ``out`` all the same).
    run : RunSettings, optional
        How the ensemble runs: ``executor`` (where batches run; None: here, one after the other),
        ``batch_size`` (samples per task, default 256), ``out`` (folder for the description and the
        finished batches, locked against a second run while this one writes; a folder holding another
        ensemble is refused unless ``overwrite``, a batch whose values no run can produce is refused with
        :class:`~wavecontact.errors.CheckpointError`; SIGINT or SIGTERM end the run after the batch in
        progress, every finished batch is on disk), ``progress`` (a tqdm bar on stderr), ``overwrite``.
    **options
        Solver options (e.g. ``rtol=1e-6``; ``hard_core_resolution`` for ``kappa = inf``), and the
        fields of ``run`` given one by one (``executor=pool, out="runs"``;
        :meth:`~wavecontact.io.run_controller.KeywordGroup.gather`).

    Returns
    -------
    EnsembleResult
        With the hard-core mode, its ``grid_bias`` states the grid's bias of the mean
        (every ``samples // 64``-th sample rerun on a grid twice as fine).
    """
    options = dict(options)
    run = RunSettings.gather(run, options)
    spec = EnsembleSpec(gamma, kappa, bath_temperature, samples, seed, bath_modes, solver, options,
                        256 if run.batch_size is None else run.batch_size, energy_split)
    if tolerance is not None:
        if not _hard_core(spec):
            raise InvalidParameterError("tolerance (the grid bias of the mean) applies to the hard-core mode "
                                        "(kappa = inf) only; finite kappa takes rtol")
        if isinstance(tolerance, bool) or not isinstance(tolerance, (int, float)) or not 0.0 < tolerance < math.inf:
            raise InvalidParameterError(f"tolerance must be a number in (0, inf), got {tolerance!r}")
    if run.out is not None:
        from ..io.files import check_output_directory

        check_output_directory("out", run.out)  # a file there is refused by name, not a FileExistsError
    fields = asdict(spec)
    store = None if run.out is None else _store(run.out, spec)
    pool = _executor_for(run.executor)
    with RunController(spec.samples, "ensemble", unit="sample", out_dir=run.out, progress=bool(run.progress)) as bar:
        done = {} if store is None else store.open(spec.batches(), overwrite=run.overwrite)
        todo = [(a, b) for a, b in spec.batches() if a not in done]
        bar.resumed(spec.samples - sum(b - a for a, b in todo))

        def finish(start, values, gains, errors):
            done[start] = (values, gains, errors)
            if store is not None:
                store.save(start, start + values.size,
                           {"restitution": values, "vibration_energy_gain": gains, "error_estimate": errors})
            bar.advance(values.size)

        try:
            run_batches(pool, run_batch, fields, todo, lambda out: finish(*out))
        except WavecontactError:
            raise
        except OSError as exc:
            raise InvalidParameterError(f"ensemble could not reach its workers: {exc}") from None
    values, gains, errors = (np.concatenate([done[a][k] for a, _b in spec.batches()]) for k in range(3))
    result = EnsembleResult(spec, values, gains, errors, grid_bias(spec, values) if _hard_core(spec) else None)
    if tolerance is not None:
        _check_tolerance(result, float(tolerance))
    return result


def _check_tolerance(result: EnsembleResult, tolerance: float) -> None:
    """AccuracyError if the stated grid bias (plus two of its standard errors) exceeds ``tolerance``."""
    bias = result.grid_bias
    reach = abs(bias.value) + 2.0 * bias.standard_error
    if reach <= tolerance:
        return
    # first order: the bias falls like the grid step
    needed = min(8192, max(bias.resolution + 1, math.ceil(bias.resolution * reach / tolerance)))
    advice = f"hard_core_resolution={needed}"
    raise AccuracyError(
        f"ensemble: grid bias {bias.value:.2g} +- {bias.standard_error:.2g} of the mean epsilon exceeds "
        f"tolerance={tolerance:g} at hard_core_resolution={bias.resolution}; try {advice}",
        result=result, advice=advice)
