"""The checks every command makes before any work: its output paths, its options' combinations.

One rule for all twelve commands: a run is refused, with a one-line message
naming the option, before it computes anything, if an output could not be
written where asked.  :func:`check_outputs` receives every path a command
will write (files, directories, and the files it writes inside those
directories) and refuses

* an empty path (``--out ""``);
* a file path that is a directory (``--plot DIR``: matplotlib would write ``DIR.png``),
  a FIFO, a device or any other non-regular file (a write would block or vanish);
* a file whose suffix is not one of the command's formats;
* a file whose folder does not exist, or a folder nobody may write in;
* a directory path that is a file;
* two options naming the same file (``bath-figure --json X.png --out X.png``).

The sizes and ranges are checked by :mod:`wavecontact.cli.costs` and the
option types of :mod:`wavecontact.cli.common`; :func:`refuse_unused` turns
an option the chosen variant would silently ignore into an error.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from ..errors import InvalidParameterError

__all__ = ["check_outputs", "refuse_unused"]


def _text(path) -> str:
    return repr(str(path))


def _refuse_special(option: str, path: Path) -> None:
    """A path that exists must be a regular file (never a directory, FIFO, socket or device)."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return
    except OSError as exc:
        raise InvalidParameterError(f"{option}: cannot use {_text(path)} ({exc.strerror})") from None
    if stat.S_ISDIR(mode):
        raise InvalidParameterError(f"{option}: {_text(path)} is a directory; give a file name")
    if not stat.S_ISREG(mode):
        raise InvalidParameterError(f"{option}: {_text(path)} exists and is not a regular file "
                                    "(a FIFO, socket or device); give an ordinary file name")
    if not os.access(path, os.W_OK):
        raise InvalidParameterError(f"{option}: cannot overwrite {_text(path)} (permission denied)")


def _nonempty(option: str, path) -> Path:
    if path is None or not str(path).strip():
        raise InvalidParameterError(f"{option}: empty path; give a name")
    return Path(path)


def _writable_folder(option: str, folder: Path, create: bool) -> None:
    """``folder`` must be a writable directory; with ``create`` it may be missing below a writable one."""
    folder = Path(os.path.abspath(folder))
    probe = folder
    if create:
        while not probe.exists() and probe != probe.parent:
            probe = probe.parent
    if not probe.exists():
        raise InvalidParameterError(f"{option}: directory {_text(folder)} does not exist")
    if not probe.is_dir():
        raise InvalidParameterError(f"{option}: {_text(probe)} is not a directory")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise InvalidParameterError(f"{option}: cannot write in {_text(probe)} (permission denied)")


def check_outputs(files=(), directories=()) -> None:
    """Refuse, before any work, every output that could not be written as asked.

    Parameters
    ----------
    files : iterable of (option, path, suffixes)
        Files the command writes; ``path`` None: not asked for (skipped);
        ``suffixes`` the allowed suffixes (lower case with the dot), empty: any.
        Their folder must exist.
    directories : iterable of (option, path, names)
        Output directories (created with their parents if missing) and the
        names of the files the command writes inside (checked as files).

    Raises
    ------
    InvalidParameterError
        The first problem found, naming its option.
    """
    owners = {}  # resolved path -> option that writes it

    def claim(option: str, path: Path) -> None:
        key = os.path.realpath(os.path.abspath(path))
        other = owners.get(key)
        owners[key] = option
        if other is not None:
            both = f"{option} names {_text(path)} twice" if other == option else \
                f"{other} and {option} name the same path {_text(path)}"
            raise InvalidParameterError(f"{both}; give each output its own name")

    for option, path, names in directories:
        if path is None:
            continue
        folder = _nonempty(option, path)
        if folder.exists() and not folder.is_dir():
            raise InvalidParameterError(f"{option}: {_text(folder)} exists and is not a directory")
        _writable_folder(option, folder, create=True)
        claim(option, folder)
        for name in names:
            inside = folder / name
            _refuse_special(option, inside)
            claim(option, inside)
    for option, path, suffixes in files:
        if path is None:
            continue
        target = _nonempty(option, path)
        _refuse_special(option, target)
        if suffixes and target.suffix.lower() not in suffixes:
            raise InvalidParameterError(f"{option}: {_text(target)} must end in one of {', '.join(suffixes)}")
        _writable_folder(option, target.parent, create=False)
        claim(option, target)


def refuse_unused(given: dict, reason: str) -> None:
    """Refuse options that were given but would be ignored.

    Parameters
    ----------
    given : dict
        ``{"--option": value}`` of the options the chosen variant does not use;
        a value of None or False means "not given".
    reason : str
        Why they are not used (``"with --rule glauber"``).
    """
    named = [option for option, value in given.items() if value is not None and value is not False]
    if named:
        raise InvalidParameterError(f"{', '.join(named)} {'is' if len(named) == 1 else 'are'} not used {reason}; "
                                    "leave it out")
