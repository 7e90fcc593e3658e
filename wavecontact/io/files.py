"""Writing files safely: atomic replacement, ordinary permissions, paths checked before work.

Every file wavecontact writes goes through :func:`atomic_write`, so an
interrupted run never leaves a half-written file where a complete one is
expected, and the file gets the permissions any other program of the user
would give it (``0o666`` less the umask), not the ``0o600`` of a temporary file.
"""

from __future__ import annotations

import enum
import math
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError

__all__ = ["FIGURE_SUFFIXES", "atomic_write", "check_figure_path", "check_output_directory", "check_output_file",
           "to_jsonable"]

#: Figure formats the plotting functions write (matplotlib would silently add ``.png`` to any other name).
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write(path, write: Callable, binary: bool = True) -> Path:
    """Write ``path`` through a temporary file in the same directory, then ``os.replace``.

    Parameters
    ----------
    path : path-like
        Destination; its directory is created if needed.
    write : callable
        ``write(handle)`` fills the open temporary file.
    binary : bool
        Open the temporary file in binary (default) or text mode.

    Returns
    -------
    Path
        The destination.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb" if binary else "w", **({} if binary else {"newline": ""})) as handle:
            write(handle)
            handle.flush()
            os.fsync(handle.fileno())
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return path


def check_output_file(option: str, path, suffixes: tuple = ()) -> Path:
    """Refuse an output file path before any work is done.

    Parameters
    ----------
    option : str
        The option's name as the user typed it (``--plot``), for the message.
    path : path-like
        The file to be written.
    suffixes : tuple of str
        Allowed suffixes (lower case, with the dot); empty: any.

    Raises
    ------
    InvalidParameterError
        If the path is a directory, its parent exists but is not a writable
        directory, or its suffix is not allowed.
    """
    path = Path(path)
    if path.is_dir():
        raise InvalidParameterError(f"{option}: {str(path)!r} is a directory; give a file name")
    if suffixes and path.suffix.lower() not in suffixes:
        raise InvalidParameterError(f"{option}: {str(path)!r} must end in one of {', '.join(suffixes)}")
    parent = _existing_ancestor(path.parent)
    if not parent.is_dir():
        raise InvalidParameterError(f"{option}: {str(parent)!r} is not a directory")
    if not os.access(parent, os.W_OK):
        raise InvalidParameterError(f"{option}: cannot write in {str(parent)!r} (permission denied)")
    return path


def check_figure_path(option: str, path) -> Path:
    """:func:`check_output_file` for a figure (:data:`FIGURE_SUFFIXES`) whose directory must exist."""
    path = check_output_file(option, path, FIGURE_SUFFIXES)
    if not path.parent.is_dir():
        raise InvalidParameterError(f"{option}: directory {str(path.parent)!r} does not exist")
    return path


def check_output_directory(option: str, path) -> Path:
    """Refuse an output directory before any work is done (a file there, or no permission)."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InvalidParameterError(f"{option}: {str(path)!r} exists and is not a directory")
    parent = _existing_ancestor(path)
    if not parent.is_dir():
        raise InvalidParameterError(f"{option}: {str(parent)!r} is not a directory")
    if not os.access(parent, os.W_OK):
        raise InvalidParameterError(f"{option}: cannot write in {str(parent)!r} (permission denied)")
    return path


def _existing_ancestor(path: Path) -> Path:
    path = Path(os.path.abspath(path))
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def to_jsonable(value):
    """Make floats, numpy scalars and infinities JSON-safe (``inf`` -> ``"inf"``, NaN -> ``"nan"``)."""
    if isinstance(value, dict):
        return {k: to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, (np.bool_,)):
        return bool(value)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, enum.Enum):
        return value.value
    if isinstance(value, (float, np.floating)):
        number = float(value)
        if math.isinf(number):
            return "inf" if number > 0 else "-inf"
        if math.isnan(number):
            return "nan"
        return number
    return value
