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
"""

from __future__ import annotations

import hashlib
import json
import zipfile
from pathlib import Path

import numpy as np

from .._jit import kernel_digest
from ..errors import CheckpointError
from .files import atomic_write

__all__ = ["CheckpointError", "array_checksum", "read_checkpoint", "write_checkpoint"]

_META = "__checkpoint__"


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
    """
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
        "kernel_digest": kernel_digest(),
        "parameters": parameters,
        "checksum": array_checksum(arrays),
    }
    payload = dict(arrays)
    payload[_META] = np.asarray(json.dumps(meta, sort_keys=True))
    return atomic_write(path, lambda handle: np.savez(handle, **payload), binary=True)


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
    if meta.get("kernel_digest") != kernel_digest():
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
