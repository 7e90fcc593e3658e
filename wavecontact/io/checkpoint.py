"""Checkpoints of long studies: NumPy arrays plus JSON, checked before anything is resumed.

A checkpoint is one ``.npz`` file (read with ``allow_pickle=False``: loading
it can never run code).  Next to the arrays it holds one JSON document,
``__checkpoint__``, with

``schema``
    what kind of run wrote it (``"wavecontact.ring"``, ...) and the format
    version of that kind;
``package_version``, ``kernel_digest``
    the wavecontact version and the digest of the compiled kernels'
    sources (:func:`wavecontact._jit.kernel_digest`): a run resumes bit for
    bit only with the same arithmetic;
``parameters``
    the run's parameters (JSON), compared with the resuming run's;
``checksum``
    SHA-256 over every array's name, dtype, shape and bytes.

:func:`read_checkpoint` applies these checks in that order and refuses a file
that fails one with a :class:`CheckpointError` whose one-line message names
the check and says what to do.

A run that records one row per step and checkpoints every so many steps keeps its rows in
:class:`RowChunks` next to the checkpoint: each checkpoint then writes only the rows new since the
last one (and merges a few earlier chunks), not every row again, so the cost of its checkpoints grows
with the run's length, not with its square.
"""

from __future__ import annotations

import functools
import hashlib
import json
import re
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .._jit import kernel_digest
from ..errors import CheckpointError
from .files import atomic_write

__all__ = ["CheckpointError", "RowChunks", "array_checksum", "read_checkpoint", "write_checkpoint"]

_META = "__checkpoint__"


@functools.cache
def _kernel_digest() -> str:
    """:func:`~wavecontact._jit.kernel_digest`, read once per process (it hashes every kernel module's source;
    the kernels this process runs were compiled from the sources it imported, so the first reading stands)."""
    return kernel_digest()


def _package_version() -> str:
    from .._version import __version__

    return __version__


def array_checksum(arrays: dict) -> str:
    """SHA-256 over the names, dtypes, shapes and bytes of ``arrays`` (sorted by name)."""
    digest = hashlib.sha256()
    for name in sorted(arrays):
        value = np.ascontiguousarray(arrays[name])
        digest.update(name.encode())
        digest.update(value.dtype.str.encode())
        digest.update(repr(value.shape).encode())
        digest.update(value.tobytes())
    return digest.hexdigest()


def write_checkpoint(path, schema: str, version: int, parameters: dict, arrays: dict) -> Path:
    """Write a checkpoint atomically.

    Parameters
    ----------
    path : path-like
        Destination (``.npz``).
    schema : str
        Kind of run, e.g. ``"wavecontact.ring"``.
    version : int
        Format version of that kind.
    parameters : dict
        JSON-serialisable parameters of the run.
    arrays : dict of str to ndarray
        The state; object arrays are refused.

    Returns
    -------
    Path
        The destination.
    """
    return _write(path, schema, version, parameters, arrays)[0]


def _write(path, schema: str, version: int, parameters: dict, arrays: dict) -> tuple:
    """:func:`write_checkpoint`, returning ``(path, checksum)``."""
    arrays = {name: np.asarray(value) for name, value in arrays.items()}
    for name, value in arrays.items():
        if value.dtype.hasobject:
            raise TypeError(f"checkpoint array {name!r} has dtype object; only plain arrays can be saved")
        if name == _META:
            raise ValueError(f"{_META!r} is reserved")
    meta = {
        "schema": schema,
        "version": int(version),
        "package_version": _package_version(),
        "kernel_digest": _kernel_digest(),
        "parameters": parameters,
        "checksum": array_checksum(arrays),
    }
    payload = dict(arrays)
    payload[_META] = np.asarray(json.dumps(meta, sort_keys=True))
    return atomic_write(path, lambda handle: np.savez(handle, **payload), binary=True), meta["checksum"]


def read_checkpoint(path, schema: str, version: int, parameters: dict | None = None) -> tuple:
    """Read and check a checkpoint written by :func:`write_checkpoint`.

    Parameters
    ----------
    path : path-like
        The checkpoint file.
    schema, version
        What the caller expects.
    parameters : dict, optional
        The resuming run's parameters; they must equal the stored ones.

    Returns
    -------
    (dict, dict)
        The arrays and the stored metadata.

    Raises
    ------
    CheckpointError
        Naming the failed check (readable, schema, version, checksum,
        package version, kernels, parameters) and what to do.
    """
    path = Path(path)
    remedy = "delete it (or choose another output directory) to start afresh"
    try:
        with np.load(path, allow_pickle=False) as data:
            names = list(data.files)
            if _META not in names:
                raise CheckpointError(f"checkpoint {path}: no {_META} record (not a wavecontact checkpoint); {remedy}")
            meta = json.loads(str(data[_META]))
            arrays = {name: np.array(data[name]) for name in names if name != _META}
    except CheckpointError:
        raise
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError, json.JSONDecodeError) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise CheckpointError(f"checkpoint {path} is unreadable ({reason}); {remedy}") from None
    if not isinstance(meta, dict) or not {"schema", "version", "checksum", "parameters"} <= set(meta):
        raise CheckpointError(f"checkpoint {path}: malformed {_META} record; {remedy}")
    if meta["schema"] != schema:
        raise CheckpointError(f"checkpoint {path} holds a {meta['schema']!r} run, not a {schema!r} run; {remedy}")
    if meta["version"] != version:
        raise CheckpointError(
            f"checkpoint {path} has format version {meta['version']}, this build reads version {version}; {remedy}"
        )
    if array_checksum(arrays) != meta["checksum"]:
        raise CheckpointError(f"checkpoint {path} fails its checksum (the file is corrupted); {remedy}")
    if meta.get("package_version") != _package_version():
        raise CheckpointError(
            f"checkpoint {path} was written by wavecontact {meta.get('package_version')}, this is "
            f"{_package_version()}: a resumed run would not equal an uninterrupted one; {remedy}"
        )
    if meta.get("kernel_digest") != _kernel_digest():
        raise CheckpointError(
            f"checkpoint {path} was written by a different build of the compiled kernels: a resumed run "
            f"would not equal an uninterrupted one; {remedy}"
        )
    if parameters is not None:
        stored = meta["parameters"]
        normalised = json.loads(json.dumps(parameters))
        if stored != normalised:
            differ = ", ".join(
                f"{k}={stored.get(k)!r} (now {v!r})" for k, v in normalised.items() if stored.get(k) != v
            ) or "different parameter names"
            raise CheckpointError(f"checkpoint {path} belongs to a different run: {differ}; {remedy}")
    return arrays, meta


class RowChunks:
    """The rows of a long run in chunk files next to its checkpoint; each checkpoint writes only the new ones.

    A run that records one row per step (a ring run: one per collision) and holds its rows in its
    checkpoint rewrites every row at every checkpoint: a cost growing with the square of the run.
    Here the rows live in chunk files ``<checkpoint stem>.rows-<start>-<stop>.npz`` (rows
    ``start <= j < stop``), each a checkpoint of its own (:func:`write_checkpoint`: checksum, build,
    schema ``<schema>.rows``), and the checkpoint proper holds the run's state and the table of its
    chunks (:meth:`table`: their ranges and checksums), so its checksum covers the rows as well.
    A checkpoint writes one chunk, the rows since the last checkpoint merged with the chunks before
    them that are no longer than that (as the digits of a binary counter): ``c`` checkpoints leave at
    most ``log2(c) + 1`` chunk files and write each row at most ``log2(c) + 1`` times.

    :meth:`save` writes the new chunk, then the checkpoint that lists it, then deletes the chunks it
    replaced: an interruption anywhere leaves a checkpoint whose chunks all exist.  Chunk files that
    no checkpoint lists (left by an interrupted write) are deleted by :meth:`discard_unlisted`.

    Parameters
    ----------
    checkpoint : path-like
        The checkpoint file the chunks belong to.
    schema : str
        The run's checkpoint schema (the chunks get ``schema + ".rows"``).
    version : int
        Format version.
    """

    _TABLE = ("chunks/start", "chunks/stop", "chunks/checksum")

    def __init__(self, checkpoint, schema: str, version: int):
        self.checkpoint = Path(checkpoint)
        self.schema = f"{schema}.rows"
        self.version = int(version)
        self.chunks = []  # (start, stop, checksum), in order, covering rows 0 <= j < stop of the last

    @property
    def count(self) -> int:
        """Rows held in the chunks."""
        return self.chunks[-1][1] if self.chunks else 0

    def path(self, start: int, stop: int) -> Path:
        """The chunk file of rows ``start <= j < stop``."""
        return self.checkpoint.with_name(f"{self.checkpoint.stem}.rows-{start:09d}-{stop:09d}.npz")

    def _pattern(self):
        return re.compile(re.escape(self.checkpoint.stem) + r"\.rows-(\d{9})-(\d{9})\.npz")

    def table(self) -> dict:
        """The chunk table as arrays for the checkpoint (``chunks/start``, ``chunks/stop``, ``chunks/checksum``)."""
        start, stop, checksum = zip(*self.chunks) if self.chunks else ((), (), ())
        return {"chunks/start": np.array(start, dtype=np.int64), "chunks/stop": np.array(stop, dtype=np.int64),
                "chunks/checksum": np.array(checksum, dtype="<U64")}

    def save(self, count: int, rows: Callable[[int, int], dict], write_checkpoint: Callable[[dict], object]) -> None:
        """Write the rows up to ``count``: the new chunk, then the checkpoint, then delete the replaced chunks.

        Parameters
        ----------
        count : int
            Rows the run holds now (at least :attr:`count`).
        rows : callable
            ``rows(start, stop)``: the arrays of rows ``start <= j < stop`` (first axis the row).
        write_checkpoint : callable
            ``write_checkpoint(table)`` writes the checkpoint with :meth:`table`'s arrays among its own.
        """
        count = int(count)
        if count < self.count:
            raise ValueError(f"the run holds {count} rows, fewer than the {self.count} already written")
        replaced = []
        if count > self.count:
            start = self.count
            while self.chunks and self.chunks[-1][1] - self.chunks[-1][0] <= count - start:
                start = self.chunks[-1][0]
                replaced.append(self.chunks.pop())
            _path, checksum = _write(self.path(start, count), self.schema, self.version,
                                     {"start": start, "stop": count}, rows(start, count))
            self.chunks.append((start, count, checksum))
        write_checkpoint(self.table())
        for start, stop, _checksum in replaced:
            self.path(start, stop).unlink(missing_ok=True)

    def load(self, arrays: dict) -> dict:
        """The rows listed by a checkpoint's ``arrays`` (read with :func:`read_checkpoint`), concatenated.

        Each chunk must exist, pass :func:`read_checkpoint`'s checks and have the checksum the table
        lists; the table must cover rows ``0 <= j < stop`` without gaps.  The values themselves are the
        caller's to check.

        Raises
        ------
        CheckpointError
            A chunk is missing or fails a check (one line, naming it).
        ValueError
            The table is malformed or a chunk holds another number of rows than its range.
        """
        table = [np.asarray(arrays[name]) for name in self._TABLE]
        start, stop, checksum = table
        if (any(a.ndim != 1 or a.shape != start.shape for a in table) or start.dtype.kind not in "iu"
                or stop.dtype.kind not in "iu" or checksum.dtype.kind != "U"):
            raise ValueError("the chunk table is malformed")
        if start.size and (start[0] != 0 or np.any(stop <= start) or np.any(start[1:] != stop[:-1])):
            raise ValueError("the chunks do not cover the rows from the first without gaps")
        chunks = [(int(a), int(b), str(c)) for a, b, c in zip(start, stop, checksum)]
        parts = []
        for a, b, c in chunks:
            path = self.path(a, b)
            if not path.is_file():
                raise CheckpointError(f"checkpoint {self.checkpoint}: its rows file {path.name} is missing; delete "
                                      "the checkpoint (or choose another output directory) to start afresh")
            part, meta = read_checkpoint(path, self.schema, self.version, {"start": a, "stop": b})
            if meta["checksum"] != c:
                raise CheckpointError(f"checkpoint {self.checkpoint}: its rows file {path.name} is not the one it "
                                      "lists (another checksum); delete the checkpoint to start afresh")
            if any(np.ndim(value) < 1 or np.shape(value)[0] != b - a for value in part.values()):
                raise ValueError(f"the rows file {path.name} does not hold {b - a} rows")
            parts.append(part)
        names = set(parts[0]) if parts else set()
        if any(set(part) != names for part in parts):
            raise ValueError("the rows files hold different arrays")
        self.chunks = chunks
        return {name: np.concatenate([part[name] for part in parts]) for name in sorted(names)}

    def discard_unlisted(self) -> None:
        """Delete chunk files of this checkpoint that :attr:`chunks` does not list (stale ones)."""
        listed = {self.path(a, b).name for a, b, _c in self.chunks}
        pattern = self._pattern()
        for path in self.checkpoint.parent.glob(f"{self.checkpoint.stem}.rows-*.npz"):
            if pattern.fullmatch(path.name) and path.name not in listed:
                path.unlink(missing_ok=True)
