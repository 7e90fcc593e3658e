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
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..bath.model import ThermalBath
from ..errors import InvalidParameterError, WavecontactError
from ..io.checkpoint import read_checkpoint, write_checkpoint
from ..progress import Progress
from ..scene import validate_gamma_kappa

__all__ = ["ENSEMBLE_DELAY_OPTIONS", "ENSEMBLE_RTOL", "MAX_SAMPLES", "EnsembleResult", "EnsembleSpec", "ensemble", "run_batch", "sample_collision",
           "sample_restitution", "sample_seed"]

MAX_SAMPLES = 10_000_000
# The delay solver's default rtol in an ensemble at finite kappa.  The step control is pessimistic
# (its rtol bounds a sum of local error estimates): at rtol 1e-3 the samples of the Fig. 8 set differ
# from rtol 1e-10 by at most a few 1e-5 and their mean by about 1e-6, far below the ~6e-3 standard
# error of a 2500-sample mean (docs/bath.md, "The thermal delay solve"; benchmarks/ensemble_accuracy.py).
ENSEMBLE_RTOL = 1e-3
# The delay solver's defaults in an ensemble at finite kappa: the end nodes of the Lobatto rule are the
# step's ends (6 evaluations of the exponent a step instead of 8, at the same measured accuracy), and noise
# tables with 16 nodes per period of the fastest mode move the samples by about 1e-6 (32: 6e-8).
ENSEMBLE_DELAY_OPTIONS = {"rtol": ENSEMBLE_RTOL, "quadrature": "lobatto-kronrod", "noise_resolution": 16}
_BATCH_SCHEMA = "wavecontact.ensemble_batch"
_SCHEMA = "wavecontact.ensemble"
_VERSION = 2  # 2: batches keep each sample's error estimate
_SOLVERS = ("delay", "modal", "fem")


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
    solver : {'delay', 'modal', 'fem'}
        Solver of each collision.
    options : dict
        Solver options (JSON values only).  The delay solver at finite kappa gets
        ``ENSEMBLE_DELAY_OPTIONS`` (``rtol = ENSEMBLE_RTOL``, the Lobatto-Kronrod rule, 16 noise
        table nodes per period of the fastest mode) where they are not given.
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
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not low <= value <= high:
                raise InvalidParameterError(f"{name} must be an integer in [{low}, {high}], got {value!r}")
            object.__setattr__(self, name, int(value))
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise InvalidParameterError(f"seed must be a non-negative integer, got {self.seed!r}")
        object.__setattr__(self, "seed", int(self.seed))
        if self.solver not in _SOLVERS:
            raise InvalidParameterError(f"solver must be one of {', '.join(_SOLVERS)}, got {self.solver!r}")
        if self.energy_split and math.isinf(kappa):
            raise InvalidParameterError(
                "energy_split needs a finite kappa (the hard-core grid gives only the total); kappa >= 50 is "
                "in the kappa-independent regime")
        if self.solver == "delay" and math.isinf(kappa) and set(self.options) - {"hard_core_resolution"}:
            raise InvalidParameterError(
                "the hard-core mode (kappa = inf) takes only the option hard_core_resolution, not "
                f"{', '.join(sorted(set(self.options) - {'hard_core_resolution'}))}")
        if self.solver == "delay" and math.isfinite(kappa):
            object.__setattr__(self, "options", {**ENSEMBLE_DELAY_OPTIONS, **self.options})
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
    """:func:`sample_collision` through ``solve`` (the energy split, the modal and FE solvers)."""
    from ..api import solve
    from ..bath.collide import thermal_scene, vibration_energy_gain

    scene = thermal_scene(spec.gamma, spec.kappa, spec.bath, sample_seed(spec.seed, index))
    options = dict(spec.options)
    if spec.solver == "delay":
        options.setdefault("energy_split", spec.energy_split)
    result = solve(scene, spec.solver, **options)
    gain = (0.0, 0.0)
    if spec.energy_split:
        gain = tuple(float(x) for x in vibration_energy_gain(result, scene))
    error = result.error_estimate
    return float(result.restitution), gain, math.nan if error is None else float(error)


def _hard_core(spec: EnsembleSpec) -> bool:
    return spec.solver == "delay" and math.isinf(spec.kappa)


def _hard_core_batch(spec: EnsembleSpec, start: int, stop: int) -> np.ndarray:
    """epsilon of samples ``start .. stop - 1`` in the stochastic hard-core mode (one batched call)."""
    from ..bath.streams import SpawnedSeeds
    from ..solvers import get_solver

    resolution = spec.options.get("hard_core_resolution", 8)
    seeds = SpawnedSeeds(spec.seed, start, stop)  # sample_seed(spec.seed, j) for j in start..stop-1
    return get_solver("delay").hard_core_thermal_batch(spec.gamma, spec.temperature, seeds, spec.bath_modes,
                                                       resolution)


def sample_restitution(spec: EnsembleSpec, index: int) -> float:
    """epsilon of sample ``index`` of ``spec`` (one collision)."""
    return sample_collision(spec, index)[0]


def run_batch(spec_fields: dict, start: int, stop: int) -> tuple:
    """Samples ``start .. stop - 1`` (a task: plain arguments, plain results).

    Returns ``(start, epsilon (n,), gains (n, 2), error estimates (n,))``.
    """
    from ..solvers import get_solver

    spec = EnsembleSpec(**spec_fields)
    n = stop - start
    if _hard_core(spec):
        return start, _hard_core_batch(spec, start, stop), np.zeros((n, 2)), np.full(n, math.nan)
    if spec.solver == "delay" and not spec.energy_split:
        # what solve() returns, without the scene and result objects around each sample
        seeds = [sample_seed(spec.seed, j) for j in range(start, stop)]
        values, errors = get_solver("delay").thermal_restitutions(spec.gamma, spec.kappa, spec.bath, seeds,
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
    """

    spec: EnsembleSpec
    restitution: np.ndarray
    vibration_energy_gain: np.ndarray | None = None
    error_estimate: np.ndarray | None = None

    @property
    def largest_error_estimate(self) -> float | None:
        """The largest per-sample error estimate (None if the solver gives none)."""
        if self.error_estimate is None or not np.any(np.isfinite(self.error_estimate)):
            return None
        return float(np.nanmax(self.error_estimate))

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
        _atomic_savez(out / "samples.npz", restitution=self.restitution,
                      vibration_energy_gain=self.vibration_energy_gain, error_estimate=self.error_estimate)
        tmp = out / "summary.json.part"
        tmp.write_text(json.dumps(self.summary(), indent=1))
        os.replace(tmp, out / "summary.json")
        return out

    def summary(self) -> dict:
        spec = self.spec
        return {
            "mean": self.mean,
            "std": self.std,
            "standard_error": self.standard_error,
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


def _description_path(out: Path) -> Path:
    return out / "ensemble.json"


def _batch_path(out: Path, start: int) -> Path:
    return out / f"batch_{start:09d}.npz"


def _batch_parameters(spec: EnsembleSpec, start: int, stop: int) -> dict:
    return {"spec": spec.describe(), "start": int(start), "stop": int(stop)}


def _atomic_savez(path: Path, **arrays):
    tmp = path.with_name(path.name + ".part")
    with open(tmp, "wb") as handle:
        np.savez(handle, **arrays)
    os.replace(tmp, path)


def _prepare_output(out, spec: EnsembleSpec) -> dict:
    """Create or check ``out``; return the finished batches ``{start: samples}``."""
    out = Path(out)
    description = {"schema": _SCHEMA, "version": _VERSION, "spec": spec.describe()}
    path = _description_path(out)
    if path.exists():
        try:
            found = json.loads(path.read_text())
        except (OSError, ValueError):
            raise InvalidParameterError(f"{path} is not an ensemble description; choose another --out") from None
        if found != description:
            raise InvalidParameterError(
                f"{out} holds an ensemble with other parameters; choose another --out or the same parameters to resume"
            )
    else:
        out.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.name + ".part")
        tmp.write_text(json.dumps(description, indent=1))
        os.replace(tmp, path)
    done = {}
    for start, stop in spec.batches():
        batch = _batch_path(out, start)
        if batch.exists():
            arrays, _meta = read_checkpoint(batch, _BATCH_SCHEMA, _VERSION, _batch_parameters(spec, start, stop))
            try:
                values = np.asarray(arrays["restitution"], dtype=float)
                gains = np.asarray(arrays["vibration_energy_gain"], dtype=float)
                errors = np.asarray(arrays["error_estimate"], dtype=float)
            except KeyError:
                raise InvalidParameterError(f"{batch} is not a finished batch; delete it to recompute that batch") from None
            if values.shape != (stop - start,) or gains.shape != (stop - start, 2) or errors.shape != values.shape:
                raise InvalidParameterError(f"{batch} has the wrong size; delete it to recompute that batch")
            done[start] = (values, gains, errors)
    return done


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


def ensemble(gamma, kappa, bath_temperature, samples, seed, *, solver="delay", bath_modes=250, executor=None,
             batch_size=256, out=None, progress=False, energy_split=False, **options) -> EnsembleResult:
    """Collide ``samples`` independent realisations of the thermal bath.

    Parameters
    ----------
    gamma, kappa : float
        Length ratio in (0, 1] and softness in (0, inf] (``inf``: the
        stochastic hard-core mode of the delay solver).
    bath_temperature : float or pair
        ``T_B / E_tr`` >= 0 (per rod if a pair).
    samples : int
        Number of collisions, in [1, 10^7].
    seed : int
        Non-negative; fixes every sample (see module docstring).
    solver : {'delay', 'modal', 'fem'}
        Solver of each collision.
    bath_modes : int
        ``nu_max`` (default 250).
    executor : concurrent.futures.Executor, dask.distributed.Client or None
        Where batches run; ``None`` runs them here, one after the other.
    batch_size : int
        Samples per task.
    out : path or None
        Directory for the description and the finished batches (resume).
    progress : bool
        Show a progress bar (tqdm) on stderr.
    energy_split : bool
        Keep each rod's vibrational gain per sample (finite kappa only).
    **options
        Solver options (e.g. ``rtol=1e-6``).

    Returns
    -------
    EnsembleResult
    """
    spec = EnsembleSpec(gamma, kappa, bath_temperature, samples, seed, bath_modes, solver, dict(options), batch_size,
                        energy_split)
    done = {} if out is None else _prepare_output(out, spec)
    todo = [(a, b) for a, b in spec.batches() if a not in done]
    fields = asdict(spec)
    bar = Progress(spec.samples, "ensemble", unit="sample", enabled=bool(progress),
                   initial=spec.samples - sum(b - a for a, b in todo))

    def finish(start, values, gains, errors):
        done[start] = (values, gains, errors)
        if out is not None:
            write_checkpoint(_batch_path(Path(out), start), _BATCH_SCHEMA, _VERSION,
                             _batch_parameters(spec, start, start + values.size),
                             {"restitution": values, "vibration_energy_gain": gains, "error_estimate": errors})
        bar.advance(values.size)

    pool = _executor_for(executor)
    try:
        run_batches(pool, run_batch, fields, todo, lambda out: finish(*out))
    except WavecontactError:
        raise
    except OSError as exc:
        raise InvalidParameterError(f"ensemble could not reach its workers: {exc}") from None
    finally:
        bar.close()
    values, gains, errors = (np.concatenate([done[a][k] for a, _b in spec.batches()]) for k in range(3))
    return EnsembleResult(spec, values, gains, errors)
