"""One controller for every long run: progress, checkpoint cadence, interrupts, the output lock.

A long study (a ring run, a rod gas, Markov chains, an ensemble) is its
physics plus this controller, in the spirit of py-pde's
``Controller``/trackers/storage: the study advances its state and tells the
controller how much work it did; the controller decides when a checkpoint is
due, draws the progress bar, turns SIGINT and SIGTERM into a clean stop at
the next consistent point, and keeps a second writer out of the output folder.

The rules it enforces
---------------------
* **A checkpoint only at a consistent point.**  The first SIGINT or SIGTERM
  only raises a flag; at the study's next call of :meth:`RunController.advance`
  (after a whole step) the checkpoint is written and the run ends with
  :class:`KeyboardInterrupt` and a one-line message.  A second signal stops at
  once (the last checkpoint stays valid).  A :class:`KeyboardInterrupt` raised
  inside a step (not by a signal the controller caught) writes nothing: the
  state may be half-updated, the last checkpoint is what a retry resumes.
* **Checkpoint cadence** by units of work (``every``: whenever the count
  crosses a multiple of it, so a resumed run checkpoints where an
  uninterrupted one does) and by wall time (``seconds``).
* **One writer per folder.**  :class:`OutputLock` creates ``.wavecontact.lock``
  (the writer's pid and host) with ``O_EXCL``; a second run into the same
  folder is refused with one line; a lock left by a process that no longer
  runs (same host) is taken over.
* **Durable before advanced.**  A study writes its outputs before it records
  them as done in a checkpoint (:func:`write_summary` writes JSON atomically
  through :func:`~wavecontact.io.files.atomic_write`).

Nothing numerical imports this module except the studies' run loops.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, fields
from pathlib import Path

from ..errors import InvalidParameterError, require_integer
from ..progress import Progress
from .files import atomic_write, to_jsonable

__all__ = ["LOCK_NAME", "BatchStore", "KeywordGroup", "OutputLock", "RunController", "RunSettings", "StopRequest",
           "claim_folder", "write_summary"]

LOCK_NAME = ".wavecontact.lock"


# ----------------------------------------------------------------------------
# The output lock
# ----------------------------------------------------------------------------


def _pid_alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except (ProcessLookupError, OverflowError):
        return False
    except PermissionError:  # alive, another user's
        return True
    return True


class OutputLock:
    """A lock file that keeps a second wavecontact run out of an output folder.

    Parameters
    ----------
    directory : path-like
        The output folder (created if needed).
    option : str
        The option that named the folder (``--out``), for the message.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     with OutputLock(folder):
    ...         try:
    ...             OutputLock(folder).acquire()
    ...         except InvalidParameterError as exc:
    ...             print(str(exc).split(" (")[0])
    --out: ... is in use by another wavecontact run
    """

    def __init__(self, directory, option: str = "--out"):
        self.directory = Path(directory)
        self.path = self.directory / LOCK_NAME
        self.option = option
        self._held = False

    def _owner(self) -> tuple:
        try:
            text = self.path.read_text()
        except (FileNotFoundError, UnicodeDecodeError):
            return None, None
        fields = text.split()
        try:
            return int(fields[0]), (fields[1] if len(fields) > 1 else None)
        except (ValueError, IndexError):
            return None, None

    def acquire(self) -> OutputLock:
        """Take the lock; refuse (:class:`InvalidParameterError`) if a live process holds it."""
        if self.directory.exists() and not self.directory.is_dir():
            raise InvalidParameterError(f"{self.option}: {str(self.directory)!r} exists and is not a directory")
        self.directory.mkdir(parents=True, exist_ok=True)
        host = socket.gethostname()
        for _attempt in range(3):
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                pid, owner_host = self._owner()
                if pid == os.getpid() and owner_host == host:
                    raise InvalidParameterError(
                        f"{self.option}: {str(self.directory)!r} is already used by this process's run") from None
                if pid is not None and (owner_host != host or _pid_alive(pid)):
                    where = f"pid {pid}" + ("" if owner_host == host else f" on {owner_host}")
                    raise InvalidParameterError(
                        f"{self.option}: {str(self.directory)!r} is in use by another wavecontact run ({where}, lock "
                        f"file {LOCK_NAME}); wait for it to end or choose another folder") from None
                # stale (its process ended) or unreadable: take it over
                try:
                    os.unlink(self.path)
                except FileNotFoundError:
                    pass
                continue
            with os.fdopen(fd, "w") as handle:
                handle.write(f"{os.getpid()} {host}\n")
            self._held = True
            return self
        raise InvalidParameterError(f"{self.option}: could not take the lock file {self.path}")

    def release(self) -> None:
        """Remove the lock file if this process holds it."""
        if self._held:
            self._held = False
            if self._owner()[0] == os.getpid():
                try:
                    os.unlink(self.path)
                except FileNotFoundError:
                    pass

    def __enter__(self):
        return self.acquire()

    def __exit__(self, *exc):
        self.release()
        return False


def claim_folder(directory, checkpoint_names, *, resume: bool, overwrite: bool, option: str = "--out") -> bool:
    """Decide what a run may do with an output folder that may hold a checkpoint.

    Parameters
    ----------
    directory : path-like
        The output folder.
    checkpoint_names : sequence of str
        The run's checkpoint files in that folder.
    resume : bool
        The run continues a checkpoint found there.
    overwrite : bool
        The user allowed replacing a checkpoint found there (it is deleted).

    Returns
    -------
    bool
        Whether a checkpoint is there to resume.

    Raises
    ------
    InvalidParameterError
        A checkpoint is there but neither ``resume`` nor ``overwrite`` was given,
        both were given, or ``resume`` was given and there is none.
    """
    directory = Path(directory)
    found = [name for name in checkpoint_names if (directory / name).is_file()]
    if resume and overwrite:
        raise InvalidParameterError("--resume and --overwrite exclude each other")
    if resume:
        if not found:
            raise InvalidParameterError(f"--resume: {option} {str(directory)!r} holds no checkpoint "
                                        f"({', '.join(checkpoint_names)})")
        return True
    if found:
        if not overwrite:
            raise InvalidParameterError(
                f"{option} {str(directory)!r} holds another run's checkpoint ({found[0]}); pass --resume to "
                "continue it or --overwrite to replace it")
        for name in found:
            (directory / name).unlink()
    return False


def write_summary(path, summary: dict) -> Path:
    """Write a run's summary as JSON, atomically, infinities as ``"inf"`` (:func:`~wavecontact.io.files.to_jsonable`)."""
    text = json.dumps(to_jsonable(summary), indent=2) + "\n"
    return atomic_write(path, lambda handle: handle.write(text), binary=False)


# ----------------------------------------------------------------------------
# Interrupts
# ----------------------------------------------------------------------------


class StopRequest:
    """SIGINT and SIGTERM as a flag while active (main thread only; elsewhere nothing changes).

    The first signal sets :attr:`signal_name` and says on stderr that the run stops after the
    step in progress (a compiled kernel is never interrupted half-way); a second one raises
    :class:`KeyboardInterrupt` at once.
    """

    SIGNALS = ("SIGINT", "SIGTERM")

    def __init__(self, active: bool = True):
        self.signal_name = None
        self._previous = {}
        self._active = active  # False: nothing to keep, so a signal ends the run at once as usual

    @property
    def requested(self) -> bool:
        return self.signal_name is not None

    def _handle(self, number, _frame):
        if self.signal_name is not None:
            raise KeyboardInterrupt
        self.signal_name = signal.Signals(number).name
        print(f"wavecontact: {self.signal_name} received; stopping after the step in progress (send it again "
              "to stop at once)", file=sys.stderr, flush=True)

    def __enter__(self):
        if self._active and threading.current_thread() is threading.main_thread():
            for name in self.SIGNALS:
                number = getattr(signal, name)
                self._previous[number] = signal.signal(number, self._handle)
        return self

    def __exit__(self, *exc):
        for number, handler in self._previous.items():
            signal.signal(number, handler)
        self._previous.clear()
        return False


# ----------------------------------------------------------------------------
# The controller
# ----------------------------------------------------------------------------


class RunController:
    """Owns a long run's loop bookkeeping: progress, checkpoint cadence, interrupts, the output lock.

    Parameters
    ----------
    total : int
        Units of work of the whole run (collisions, samples, chains).
    description, unit : str
        Label and unit of the progress bar.
    out_dir : path-like or None
        Output folder, locked (:class:`OutputLock`) while the run is active; None: nothing is written.
    save : callable or None
        ``save()`` writes a checkpoint of the current (consistent) state; None: the study keeps
        no checkpoint of its own (its finished pieces are durable already).
    every : int or None
        Checkpoint whenever the work done crosses a multiple of ``every`` units.
    seconds : float or None
        Checkpoint when this much wall time has passed since the last one.
    progress : bool or None
        Show a tqdm bar on stderr (None: when stderr is a terminal).
    log : callable or None
        Receives one-line messages.
    describe_resume : callable or None
        ``describe_resume(done)``: the message logged when a run is interrupted with a checkpoint
        after ``done`` units (default: "interrupted; run again to resume from the checkpoint after
        {unit} {done}").
    """

    def __init__(self, total: int, description: str, unit: str = "it", *, out_dir=None, save: Callable | None = None,
                 every: int | None = None, seconds: float | None = None, progress: bool | None = False,
                 log: Callable[[str], None] | None = None,
                 describe_resume: Callable[[int], str] | None = None, option: str = "--out"):
        if every is not None:
            require_integer("checkpoint cadence", every, 1)
        if seconds is not None and not float(seconds) > 0:
            raise InvalidParameterError(f"checkpoint interval must be > 0 seconds, got {seconds!r}")
        self.total = int(total)
        self.done = 0  # a resumed run says how much it holds with resumed()
        self.every = None if every is None else int(every)
        self.seconds = None if seconds is None else float(seconds)
        self.save = save
        self.log = log
        self.unit = unit
        self.last_checkpoint = None
        self._describe_resume = describe_resume
        self._description = description
        self._progress = progress
        self._lock = None if out_dir is None else OutputLock(out_dir, option)
        # a run with nothing to keep (no checkpoint, no output folder) is not worth a second Ctrl-C
        self._stop = StopRequest(active=save is not None or out_dir is not None)
        self._bar = None
        self._last_save_time = None
        self._started = None

    # -- context ---------------------------------------------------------------

    def __enter__(self):
        if self._lock is not None:
            self._lock.acquire()
        try:
            self._stop.__enter__()
            self._bar = Progress(self.total, self._description, unit=self.unit, enabled=self._progress,
                                 initial=min(self.done, self.total))
        except BaseException:
            self._release()
            raise
        self._started = self._last_save_time = time.monotonic()
        return self

    def __exit__(self, kind, value, traceback):
        if kind is not None and issubclass(kind, KeyboardInterrupt) and self.log is not None:
            self.log(self._interrupt_message())
        self._release()
        return False

    def _release(self):
        if self._bar is not None:
            self._bar.close()
            self._bar = None
        self._stop.__exit__()
        if self._lock is not None:
            self._lock.release()

    @property
    def elapsed(self) -> float:
        """Wall time since the run (this session) started, in s."""
        return 0.0 if self._started is None else time.monotonic() - self._started

    @property
    def stop_requested(self) -> bool:
        """A SIGINT or SIGTERM arrived; the study should reach a consistent point and call :meth:`advance`."""
        return self._stop.requested

    def _interrupt_message(self) -> str:
        if self.last_checkpoint:
            if self._describe_resume is not None:
                return self._describe_resume(self.last_checkpoint)
            return f"interrupted; run again to resume from the checkpoint after {self.unit} {self.last_checkpoint}"
        if self.save is not None:
            return "interrupted before the first checkpoint; a new run will start from the beginning"
        return "interrupted"

    # -- the loop --------------------------------------------------------------

    def _due(self, before: int) -> bool:
        if self.every is not None and (self.done // self.every > before // self.every or self.done == self.total):
            return True
        return self.seconds is not None and time.monotonic() - self._last_save_time >= self.seconds

    def advance(self, count: int = 1, *, consistent: bool = True) -> None:
        """Record ``count`` more units of work; checkpoint when due; stop on a caught signal.

        Parameters
        ----------
        count : int
            Units just finished.
        consistent : bool
            The study's state is a consistent point (a checkpoint may be written now).

        Raises
        ------
        KeyboardInterrupt
            After SIGINT or SIGTERM, once the checkpoint of this consistent point is written.
        """
        before = self.done
        self.done += int(count)
        if self._bar is not None:
            self._bar.advance(count)
        if not consistent:
            return
        stopping = self._stop.requested
        if self.save is not None and (stopping or self._due(before)) and self.last_checkpoint != self.done:
            self.checkpoint()
        if stopping:
            raise KeyboardInterrupt

    def resumed(self, done: int) -> None:
        """The run continues a checkpoint holding ``done`` units of work."""
        step = int(done) - self.done
        self.done = self.last_checkpoint = int(done)
        if self._bar is not None:
            self._bar.advance(max(0, min(self.done, self.total) - min(self.done - step, self.total)))

    def checkpoint(self) -> None:
        """Write a checkpoint now (the study's ``save``)."""
        if self.save is None:
            return
        self.save()
        self.last_checkpoint = self.done
        self._last_save_time = time.monotonic()

    def describe(self, text: str) -> None:
        """Change the progress bar's label."""
        if self._bar is not None:
            self._bar.describe(text)


# ----------------------------------------------------------------------------
# Storage of a batched run (ensembles, Markov chains)
# ----------------------------------------------------------------------------


class KeywordGroup:
    """A frozen dataclass of settings that a function also takes as flat keywords (its fields one by one).

    :meth:`gather` is the one path from either spelling to the object: ``f(..., group=Group(a=1))``
    and ``f(..., a=1)`` give the same ``Group``.
    """

    @classmethod
    def gather(cls, given, keywords: dict, name: str = "run"):
        """``given`` (None: the defaults) with the fields given one by one in ``keywords``, which loses them.

        Parameters
        ----------
        given : instance of this class or None
            The object passed as ``name=``.
        keywords : dict
            The function's other keywords; this class's fields are taken out of it.
        name : str
            The function's keyword for the object (for messages).

        Raises
        ------
        InvalidParameterError
            ``given`` is not an instance of this class, or a field is given both ways.
        """
        taken = {f.name: keywords.pop(f.name) for f in fields(cls) if f.name in keywords}
        if given is None:
            return cls(**taken)
        if not isinstance(given, cls):
            raise InvalidParameterError(f"{name} must be a {cls.__name__}, got {type(given).__name__}")
        if taken:
            raise InvalidParameterError(f"{', '.join(taken)}: give it in {name}={cls.__name__}(...) or as a keyword, "
                                        "not both")
        return given


@dataclass(frozen=True)
class RunSettings(KeywordGroup):
    """How a batched study runs, apart from what it computes (:func:`~wavecontact.studies.ensemble.ensemble`,
    :func:`~wavecontact.studies.markov.markov_chains`); none of it changes a result.

    The studies also take these fields one by one as keywords (``ensemble(..., executor=pool, out="runs")``):
    :meth:`~KeywordGroup.gather` turns them into this object, the one path both spellings take.

    Parameters
    ----------
    executor : concurrent.futures.Executor, dask.distributed.Client or None
        Where batches run; None runs them here, one after the other.
    batch_size : int or None
        Units of work (samples, chains) per task; None: the study's default.
    out : path-like or None
        Folder for the run's description and its finished batches, locked against a second run while
        this one writes; the same call again resumes from the batches there.  None: nothing is written.
    progress : bool or None
        Show a progress bar (tqdm) on stderr; None: when stderr is a terminal.
    overwrite : bool
        Replace another run's description and batches found in ``out``.
    """

    executor: object = None
    batch_size: int | None = None
    out: object = None
    progress: bool | None = False
    overwrite: bool = False


class BatchStore:
    """The finished batches of a batched run: one checkpoint file per batch next to a JSON description.

    A batch is durable once its file is written (atomically, checksummed); a run started again with
    the same description skips the batches on disk, so an interrupt loses at most the batches in
    progress.  Each batch's contents are checked on reading (``check``), whatever its checksum says.

    Parameters
    ----------
    directory : path-like
        The output folder.
    description_name : str
        File of the run's description (``ensemble.json``).
    description : dict
        JSON description of the run (schema, version, parameters); another one on disk is refused.
    batch_name : callable
        ``batch_name(start) -> str``, the file of the batch that begins at ``start``.
    batch_pattern : str
        Glob of every batch file (what ``overwrite`` deletes).
    batch_schema : str
        Checkpoint schema of a batch file.
    version : int
        Checkpoint format version of a batch file.
    batch_parameters : callable
        ``batch_parameters(start, stop) -> dict`` stored with (and checked against) each batch.
    check : callable
        ``check(arrays, start, stop)`` returns the batch's values, raising :class:`InvalidParameterError`
        for any value no run can produce.
    kind : str
        What the run is, for messages (``"an ensemble"``).
    """

    def __init__(self, directory, description_name: str, description: dict, batch_name: Callable,
                 batch_pattern: str, batch_schema: str, version: int, batch_parameters: Callable, check: Callable, kind: str):
        self.directory = Path(directory)
        self.description_path = self.directory / description_name
        self.description = description
        self.batch_name = batch_name
        self.batch_pattern = batch_pattern
        self.batch_schema = batch_schema
        self.version = version
        self.batch_parameters = batch_parameters
        self.check = check
        self.kind = kind

    def open(self, batches, overwrite: bool = False) -> dict:
        """Create or check the folder; return ``{start: values}`` of the batches already finished.

        A folder holding another run's description is refused unless ``overwrite`` (then its
        description and batch files are deleted).
        """
        from .checkpoint import read_checkpoint

        path = self.description_path
        if path.exists():
            try:
                found = json.loads(path.read_text())
            except (OSError, ValueError):
                found = None
            if found != self.description:
                if not overwrite:
                    what = (f"holds {path.name}, which is not a description of {self.kind}" if found is None else
                            f"holds {self.kind} with other parameters")
                    raise InvalidParameterError(f"{self.directory} {what}; choose another --out, the same parameters "
                                                "to resume, or --overwrite to replace it")
                for stale in self.directory.glob(self.batch_pattern):
                    stale.unlink()
                path.unlink()
        if not path.exists():
            text = json.dumps(self.description, indent=1)
            atomic_write(path, lambda handle: handle.write(text), binary=False)
        done = {}
        for start, stop in batches:
            batch = self.directory / self.batch_name(start)
            if batch.exists():
                arrays, _meta = read_checkpoint(batch, self.batch_schema, self.version,
                                                self.batch_parameters(start, stop))
                try:
                    done[start] = self.check(arrays, start, stop)
                except (KeyError, ValueError, TypeError) as exc:
                    reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                    if isinstance(exc, KeyError):
                        reason = f"missing {reason}"
                    from ..errors import CheckpointError

                    raise CheckpointError(f"{batch} is not a valid finished batch ({reason}); delete it to "
                                          "recompute that batch") from None
        return done

    def save(self, start: int, stop: int, arrays: dict) -> Path:
        """Write one finished batch (atomically)."""
        from .checkpoint import write_checkpoint

        return write_checkpoint(self.directory / self.batch_name(start), self.batch_schema, self.version,
                                self.batch_parameters(start, stop), arrays)
