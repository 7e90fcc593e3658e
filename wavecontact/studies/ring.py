"""Many successive collisions of two rods on a ring (the paper's Sec. III): running them.

Two rods start maximally far apart on a ring with a cold oscillator bath and
approach each other at relative speed ``V = 1``.  They collide again and
again (through either pair of facing ends) and the translational energy
``E_tr`` drains into the rods' vibrations until equipartition.  This module
runs that experiment through the solver contract
(``get_solver(solver).simulate(scene, options)``, :mod:`wavecontact.solvers.base`),
records one row per collision (:class:`RingRun`), and checkpoints the run
(:mod:`wavecontact.io.checkpoint`) so that an interrupted run resumes to
the same result bit for bit.  The statistics the paper reports are computed
by :mod:`wavecontact.studies.ring_statistics`.

Units are those of :func:`wavecontact.scene.two_rods_on_a_ring`: ``rho = c = A = 1``,
effective length ``l = 1``, approach speed ``V = 1``, reduced mass
``mu = 1/2``, so the initial translational energy (all the energy there
is, the bath being cold) is ``mu V^2 / 2 = 1/4``.
"""

from __future__ import annotations

import csv
import json
import math
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..analytic import equilibrium_translational_energy
from ..errors import CheckpointError, InvalidParameterError, require_integer, require_positive
from ..io.checkpoint import RowChunks, read_checkpoint, write_checkpoint
from ..io.files import atomic_write, check_output_directory
from ..io.run_controller import KeywordGroup, RunController
from ..limits import Limits, check_study_cost, ring_cost
from ..result import to_jsonable
from ..scene import two_rods_on_a_ring
from ..solvers import get_solver
from ..solvers.auto_ring import CollisionChecks, RingChoice, choose_modes
from .ring_statistics import RingStatistics, relative_modal_energies, ring_statistics, spectral_entropy

__all__ = [
    "CHECKPOINT_NAME",
    "DATA_CSV_NAME",
    "DATA_NPZ_NAME",
    "RingRun",
    "RingRunSettings",
    "run_ring",
]

CHECKPOINT_NAME = "checkpoint.npz"
DATA_NPZ_NAME = "ring.npz"
DATA_CSV_NAME = "ring.csv"
_CHECKPOINT_SCHEMA = "wavecontact.ring"
_CHECKPOINT_VERSION = 3  # 3: the rows in chunk files (RowChunks), 2: in the checkpoint
_PAIR_NAMES = ("near", "far")


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
        """The paper's numbers for this run (:func:`~wavecontact.studies.ring_statistics.ring_statistics`)."""
        return ring_statistics(self, transient=transient, max_lag=max_lag, window=window)

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

        def write(handle):  # not compressed: the modal energies, most of the bytes, do not compress (5.3 MB of 5.5)
            np.savez(handle, **payload)

        return atomic_write(Path(path), write, binary=True)

    @classmethod
    def load_npz(cls, path) -> RingRun:
        """Read a file written by :meth:`save_npz` (refused in one line unless it is a complete, valid ring run)."""
        try:
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
        except FileNotFoundError:
            raise CheckpointError(f"{path}: no such file") from None
        except (OSError, ValueError, EOFError, KeyError, TypeError, zipfile.BadZipFile) as exc:
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise CheckpointError(f"{path} is not a ring run written by RingRun.save_npz ({reason})") from None
        try:
            _validate(scalars["gamma"], scalars["kappa"], scalars["modes"], 1, 1)
            check_rows(arrays, scalars["modes"])
            if not isinstance(metadata, dict):
                raise InvalidParameterError("metadata_json is not a JSON object")
        except InvalidParameterError as exc:
            raise CheckpointError(f"{path} is not a valid ring run: {exc}") from None
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

        return atomic_write(Path(path), write, binary=False)


# ----------------------------------------------------------------------------
# Running and checkpointing
# ----------------------------------------------------------------------------


class _Recorder:
    """Per-collision rows in NumPy arrays that grow by doubling (cheap appends, cheap slices)."""

    def __init__(self, modes: int, capacity: int = 256):
        self.modes = modes
        self.count = 0
        self.buffers = {name: self._empty(name, capacity) for name in RingRun._ARRAYS}

    def _empty(self, name: str, rows: int) -> np.ndarray:
        if name == "modal_energies":
            return np.empty((rows, 2, self.modes))
        return np.empty(rows, dtype=np.int8 if name == "pair" else float)

    def __len__(self):
        return self.count

    def add(self, record):
        energies = np.asarray(record.modal_energies, dtype=float)
        if energies.shape != (2, self.modes):
            raise ValueError(f"simulation returned modal energies of shape {energies.shape}, expected (2, {self.modes})")
        j = self.count
        b = self.buffers
        if j == b["time"].shape[0]:
            for name, values in b.items():
                grown = self._empty(name, 2 * j)
                grown[:j] = values
                b[name] = grown
        b["time"][j] = float(record.time)
        b["pair"][j] = int(record.pair)
        b["translational_energy"][j] = float(record.translational_energy_before)
        b["translational_energy_after"][j] = float(record.translational_energy_after)
        b["restitution"][j] = float(record.restitution)
        b["modal_energies"][j] = energies
        b["bath_energy"][j] = float(record.bath_energy)
        b["total_energy"][j] = float(record.total_energy)
        self.count = j + 1

    def rows(self, start: int, stop: int) -> dict:
        """Copies of rows ``start <= j < stop``."""
        return {name: values[start:stop].copy() for name, values in self.buffers.items()}

    def arrays(self) -> dict:
        return self.rows(0, self.count)

    def load(self, arrays: dict, count: int):
        for name in RingRun._ARRAYS:
            values = np.asarray(arrays[name])[:count]
            if name == "modal_energies" and values.shape[1:] != (2, self.modes):
                raise InvalidParameterError(f"checkpoint modal energies have shape {values.shape}")
            buffer = self._empty(name, max(count, 1))
            buffer[:count] = values
            self.buffers[name] = buffer
        self.count = count


def _validate(gamma, kappa, modes, collisions, checkpoint_every):
    try:
        g = float(gamma)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"gamma must be a number in (0, 1], got {gamma!r}") from None
    if not 0.0 < g <= 1.0:
        raise InvalidParameterError(f"gamma must lie in (0, 1], got {g!r}")
    k = require_positive("kappa", kappa, allow_inf=True)
    require_integer("modes", modes, 1)
    for name, value in (("collisions", collisions), ("checkpoint_every", checkpoint_every)):
        require_integer(name, value, 1)
    return g, k, int(modes), int(collisions), int(checkpoint_every)


def check_rows(arrays: dict, modes: int) -> int:
    """Refuse per-collision rows that no ring run can produce (a checkpoint or a ring.npz is user input).

    Returns the number of rows; raises :class:`InvalidParameterError` naming the array.
    """
    missing = [name for name in RingRun._ARRAYS if name not in arrays]
    if missing:
        raise InvalidParameterError(f"missing arrays {', '.join(missing)}")
    count = np.asarray(arrays["time"]).shape[0] if np.asarray(arrays["time"]).ndim == 1 else -1
    for name in RingRun._ARRAYS:
        value = np.asarray(arrays[name])
        shape = (count, 2, modes) if name == "modal_energies" else (count,)
        if count < 0 or value.shape != shape:
            raise InvalidParameterError(f"{name} has shape {value.shape}, expected {shape}")
        if name == "pair":
            if value.dtype.kind not in "iu" or np.any((value != 0) & (value != 1)):
                raise InvalidParameterError("pair must hold 0 (near ends) or 1 (far ends) only")
            continue
        if value.dtype.kind != "f" or not np.all(np.isfinite(value)):
            raise InvalidParameterError(f"{name} must hold finite numbers")
        if name != "time" and np.any(value < 0.0):
            raise InvalidParameterError(f"{name} must not be negative")
    if np.any(np.diff(arrays["time"]) < 0.0) or (count and arrays["time"][0] < 0.0):
        raise InvalidParameterError("the collision times must be >= 0 and non-decreasing")
    return int(count)


def _check_state(state: dict, stored: int) -> None:
    """A simulation state from a checkpoint: plain finite numbers, at the collision the rows end at."""
    for name, value in state.items():
        value = np.asarray(value)
        if value.dtype.kind not in "biuf":
            raise InvalidParameterError(f"state {name!r} is not numeric")
        if value.dtype.kind == "f" and not np.all(np.isfinite(value)):
            raise InvalidParameterError(f"state {name!r} holds NaN or infinite values")
    if "collisions" in state and int(np.asarray(state["collisions"])) != stored:
        raise InvalidParameterError(
            f"the state is at collision {int(np.asarray(state['collisions']))} but the rows end at {stored}")


def _write_checkpoint(path: Path, parameters: dict, simulation, recorder: _Recorder, wall_time: float,
                      chunks: RowChunks):
    """The simulation's state and the chunk table in ``path``; the rows new since the last checkpoint in a chunk."""
    state = {f"state/{k}": np.asarray(v) for k, v in simulation.get_state().items()}

    def write(table):
        arrays = {**state, **table, "wall_time_s": np.asarray(float(wall_time))}
        write_checkpoint(path, _CHECKPOINT_SCHEMA, _CHECKPOINT_VERSION, parameters, arrays)

    chunks.save(len(recorder), recorder.rows, write)


def _resume(checkpoint: Path, arrays: dict, simulation, recorder: _Recorder, chunks: RowChunks) -> tuple:
    """Load a checkpoint's ``arrays`` and the rows it lists into ``simulation`` and ``recorder``; return
    ``(collisions stored, wall time before)``.  Its values are checked as strictly as user input, whatever its
    checksums say."""
    try:
        state = {key[len("state/"):]: value for key, value in arrays.items() if key.startswith("state/")}
        rows = chunks.load(arrays)
        stored = check_rows(rows, recorder.modes)
        _check_state(state, stored)
        wall_before = float(arrays["wall_time_s"])
        if not (np.asarray(arrays["wall_time_s"]).shape == () and math.isfinite(wall_before) and wall_before >= 0):
            raise InvalidParameterError("wall_time_s must be a finite number >= 0")
        simulation.set_state(state)
        recorder.load(rows, stored)
    except CheckpointError:
        raise
    except (KeyError, ValueError, IndexError, TypeError, InvalidParameterError) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise CheckpointError(
            f"checkpoint {checkpoint} is incomplete or invalid ({reason}); delete it to start afresh") from None
    return stored, wall_before


def _choice(gamma, kappa, collisions, modes, tolerance, static_correction):
    """The run's :class:`RingChoice` (None: ``modes`` given without a tolerance, as before)."""
    if isinstance(tolerance, RingChoice):
        if modes is not None and int(modes) != tolerance.modes:
            raise InvalidParameterError(f"modes={modes} contradicts the choice of N = {tolerance.modes} passed as tolerance")
        return tolerance
    if tolerance is None and modes is not None:
        return None
    return choose_modes(gamma, kappa, collisions, modes=modes, tolerance=tolerance, static_correction=static_correction)


def _accuracy(choice: RingChoice, checks, resumed_from: int, log) -> dict:
    """``metadata["accuracy"]``: the choice and the run's checks (this session's collisions only)."""
    accuracy = choice.as_dict()
    if checks is None:
        accuracy["checks"] = {"verdict": "not checked (a stand-in simulation)"}
        return accuracy
    accuracy["checks"] = checks.summary()
    if resumed_from:
        accuracy["checks"]["verdict"] += f" (collisions after {resumed_from} only: resumed from a checkpoint)"
    if (checks.above() or "model is wrong" in accuracy["checks"]["verdict"]) and log is not None:
        log(accuracy["checks"]["verdict"])
    return accuracy


@dataclass(frozen=True)
class RingRunSettings(KeywordGroup):
    """How a ring run runs and where it writes (:func:`run_ring`); none of it changes a result.

    :func:`run_ring` also takes these fields one by one as keywords (``run_ring(..., out_dir="ring",
    progress=False)``); :meth:`~wavecontact.io.run_controller.KeywordGroup.gather` turns them into this object.

    Parameters
    ----------
    out_dir : path, optional
        Directory for the checkpoint (``checkpoint.npz``, its rows in a few
        ``checkpoint.rows-START-STOP.npz``: :class:`~wavecontact.io.checkpoint.RowChunks`) and the data
        (``ring.npz``, ``ring.csv``), locked against a second run while this
        one writes (:class:`~wavecontact.io.run_controller.OutputLock`).  If it
        holds a checkpoint of the same run, the run resumes from there; a
        checkpoint of another run (unless ``overwrite``), of another build of
        the kernels, or one that fails its checksum or holds values no run can
        produce is refused (:class:`~wavecontact.errors.CheckpointError`).
        ``None``: nothing is written.
    checkpoint_every : int
        Write a checkpoint whenever the collision count reaches a multiple of this (and at the end); each
        writes the state and the rows since the last one (with a few earlier rows merged into one chunk).
    progress : bool
        Show a progress bar on stderr.
    callback : callable, optional
        ``callback(index, record)`` after every collision (0-based index,
        a :class:`~wavecontact.result.CollisionRecord`).  An exception raised
        there (e.g. ``KeyboardInterrupt``) ends the run; the last checkpoint
        stays valid.
    log : callable, optional
        Receives one-line messages (e.g. that a checkpoint was resumed).
    overwrite : bool
        Replace a checkpoint of another run found in ``out_dir`` instead of refusing it.
    checkpoint_seconds : float or None
        Also write a checkpoint when this much wall time (s) has passed since the last one.
    """

    out_dir: object = None
    checkpoint_every: int = 100
    progress: bool = True
    overwrite: bool = False
    checkpoint_seconds: float | None = 600.0
    callback: Callable | None = None
    log: Callable[[str], None] | None = None


def run_ring(
    gamma: float,
    kappa: float,
    modes: int | None = None,
    collisions: int | None = None,
    *,
    tolerance=None,
    circumference: float | None = None,
    solver: str = "modal",
    solver_options: dict | None = None,
    simulation_factory: Callable | None = None,
    settings: RingRunSettings | None = None,
    **keywords,
) -> RingRun:
    """Run ``collisions`` successive collisions of two rods on a ring.

    Parameters
    ----------
    gamma : float
        Length ratio ``l1 / l2`` in (0, 1].
    kappa : float
        Softness ``alpha V l / c`` in (0, inf].
    modes : int or None
        Modes per rod ``N``; None: the fewest predicted to meet ``tolerance``
        (:func:`wavecontact.solvers.auto_ring.choose_modes`).
    collisions : int
        Total number of collisions wanted (including any already in a checkpoint); required.
    tolerance : float, RingChoice or None
        Tolerance on the per-collision restitution error (absolute, on each ``eps_j``), or a
        :class:`~wavecontact.solvers.auto_ring.RingChoice` made already.  Given (or ``modes`` None, which takes
        :data:`~wavecontact.solvers.auto_ring.DEFAULT_TOLERANCE`), the run's ``metadata["accuracy"]`` holds the
        modes, the predicted per-collision error and the reason, and every
        :data:`~wavecontact.solvers.auto_ring.CHECK_EVERY`-th collision (and the first) is checked against a run of
        it with twice the modes, which changes nothing in the run; None with ``modes`` given: neither.
    circumference : float, optional
        Ring circumference (see :func:`~wavecontact.scene.two_rods_on_a_ring`).
    solver : str
        A registered solver that can ``simulate`` a ring scene (``"modal"``).
    solver_options : dict, optional
        Further options of that solver (``static_correction`` (default True: add the omitted modes' static
        flexibility), ``step_accuracy`` ...).
    simulation_factory : callable, optional
        ``factory(scene, options) -> RepeatedCollisions`` instead of the
        solver's ``simulate`` (a stand-in with a known answer, in tests).
    settings : RingRunSettings, optional
        How the run runs and where it writes (:class:`RingRunSettings`: ``out_dir``, ``checkpoint_every``,
        ``checkpoint_seconds``, ``progress``, ``overwrite``, ``callback``, ``log``); none of it changes a result.
    **keywords
        The fields of :class:`RingRunSettings` one by one (``out_dir=..., progress=False``), the same as
        ``settings=RingRunSettings(...)`` (:meth:`~wavecontact.io.run_controller.KeywordGroup.gather`).

    Returns
    -------
    RingRun

    Notes
    -----
    SIGINT or SIGTERM end the run after the collision in progress, with a checkpoint of it
    (:class:`~wavecontact.io.run_controller.RunController`); a retry of the same call resumes there.
    """
    run_settings = RingRunSettings.gather(settings, keywords, "settings")
    if keywords:
        raise TypeError(f"run_ring() got an unexpected keyword argument {next(iter(keywords))!r}")
    out_dir, checkpoint_every, checkpoint_seconds = (run_settings.out_dir, run_settings.checkpoint_every,
                                                     run_settings.checkpoint_seconds)
    progress, overwrite, callback, log = (run_settings.progress, run_settings.overwrite, run_settings.callback,
                                          run_settings.log)
    if collisions is None:
        raise InvalidParameterError("collisions must be given (the number of collisions of the run)")
    g, k, _n, m, every = _validate(gamma, kappa, 1 if modes is None else modes, collisions, checkpoint_every)
    options = {"static_correction": True, **(solver_options or {})}
    choice = _choice(g, k, m, modes, tolerance, bool(options["static_correction"]))
    n = int(modes) if choice is None else choice.modes
    # every collision's record is held in memory until the end: refuse before any work what cannot fit
    check_study_cost(f"run_ring: {m} collisions at N = {n}", ring_cost(k, [n], m), Limits(max_work=float("inf")),
                     "use fewer collisions or modes")
    options["modes"] = n
    engine = get_solver(solver)
    options = engine.options(options)
    scene = two_rods_on_a_ring(g, k, circumference)
    parameters = {"gamma": g, "kappa": k, "circumference": scene.ring_circumference, "solver": solver,
                  "options": {key: value for key, value in options.as_dict().items()}}
    parameters = json.loads(json.dumps(to_jsonable(parameters), default=repr))
    checkpoint = chunks = None
    if out_dir is not None:
        out_dir = check_output_directory("out_dir", out_dir)
        checkpoint = out_dir / CHECKPOINT_NAME
        chunks = RowChunks(checkpoint, _CHECKPOINT_SCHEMA, _CHECKPOINT_VERSION)
    simulation = (simulation_factory or engine.simulate)(scene, options)
    checks = None
    if choice is not None and simulation_factory is None:
        checks = CollisionChecks(engine.simulate, scene, options, choice.tolerance, choice.predicted_error)
    recorder = _Recorder(n)
    wall_before = 0.0
    resumed_from = 0

    def save():
        _write_checkpoint(checkpoint, parameters, simulation, recorder, wall_before + run.elapsed, chunks)

    run = RunController(m, "ring", unit="collision", out_dir=out_dir, save=save if checkpoint else None,
                        every=every, seconds=checkpoint_seconds, progress=progress, log=log, option="out_dir")
    with run:
        if checkpoint is not None and checkpoint.exists():
            try:
                arrays, _meta = read_checkpoint(checkpoint, _CHECKPOINT_SCHEMA, _CHECKPOINT_VERSION, parameters)
            except CheckpointError:
                if not overwrite:
                    raise
                checkpoint.unlink()
            else:
                resumed_from, wall_before = _resume(checkpoint, arrays, simulation, recorder, chunks)
        if chunks is not None:
            chunks.discard_unlisted()  # chunks of a write interrupted before its checkpoint, or of a replaced run
        if resumed_from:
            run.resumed(resumed_from)
            if log is not None:
                if resumed_from > m:
                    log(f"the checkpoint {checkpoint} holds {resumed_from} collisions; keeping the first {m} "
                        f"(the checkpoint is left as it is)")
                else:
                    log(f"resuming from checkpoint {checkpoint} after collision {resumed_from}")
        while len(recorder) < m:
            state = simulation.get_state() if checks is not None and checks.due(len(recorder)) else None
            record = simulation.next_collision()
            recorder.add(record)
            if state is not None:
                checks.add(len(recorder) - 1, state, record.restitution)
            if callback is not None:
                callback(len(recorder) - 1, record)
            run.advance()
        wall = wall_before + run.elapsed

        arrays = recorder.rows(0, min(len(recorder), m))
        result = RingRun(
            gamma=g,
            kappa=k,
            modes=n,
            static_correction=bool(options.static_correction),
            reduced_mass=float(simulation.reduced_mass),
            initial_energy=float(simulation.total_energy),
            wall_time_s=wall,
            resumed_from=min(resumed_from, m),
            metadata={"circumference": scene.ring_circumference, "solver": solver, "checkpoint_every": every},
            **arrays,
        )
        if choice is not None:
            result.metadata["accuracy"] = _accuracy(choice, checks, resumed_from, log)
        if out_dir is not None:
            result.save_npz(out_dir / DATA_NPZ_NAME)
            result.save_csv(out_dir / DATA_CSV_NAME)
    return result
